//! `cargo xtask tidy`: keeps the tuned constants' values in docs and code in step.
//!
//! docs/trajectory.md's section "Tuned constants" holds a table whose rows start
//! `` | `NAME` | value | ``. For each row this finds the one `const NAME: T = EXPR;` under
//! crates/trajectory/src/, evaluates `EXPR` (a number, or numbers and `std::f64::consts`
//! names joined by `*` or `/`) and fails, naming the constant, both values and both places, when
//! it differs from the documented value by more than the documented value's last printed digit
//! (0.65 stands for 0.645..0.655; 2.0944 for 2π/3). A constant listed twice, missing from the
//! code or defined twice there is an error too.
//!
//! It also holds docs/ARCHITECTURE.md's invariant "the pipeline is not CLI-aware":
//! crates/pipeline depends on no CLI, progress or plotting crate, and its sources neither print,
//! exit, write files nor name a command-line flag. crates/safe-output, whose job is writing
//! files, is held to the same but for writing ([`LIBRARIES_NOT_CLI_AWARE`]).
//!
//! And its mirror, "the CLI only speaks" ([`cli_not_pipeline`]): no file under crates/maobi/src
//! runs a program on the simulated arm or sweeps footprints itself ([`CLI_EXECUTION`]: the
//! pipeline's `run_sheet`, `run_footprints`, `execute_track` and `render_states` do), none but
//! the `robot` command (the edge that checks, exports and sends a program to an arm, and serves
//! the simulators) builds or times a program ([`CLI_PROGRAM`]), and no function there runs over
//! [`CLI_MAX_FN_LINES`] lines.
//!
//! And no function in a library crate's sources (`crates/*/src`, the CLI's excepted) runs over
//! [`LIBRARY_MAX_FN_LINES`] lines ([`library_functions_short`]).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

const DOC: &str = "docs/trajectory.md";
const SECTION: &str = "## Tuned constants";
const CODE_DIR: &str = "crates/trajectory/src";

/// One row of the docs table.
struct Documented {
    name: String,
    /// The value cell as written.
    text: String,
    value: f64,
    /// Half a unit of the last printed digit.
    tolerance: f64,
    line: usize,
}

/// One `const` definition in the code.
struct Defined {
    file: PathBuf,
    line: usize,
    expr: String,
}

pub(crate) fn run(args: &[String]) -> Result<()> {
    if let Some(a) = args.first() {
        bail!("tidy takes no arguments (got `{a}`)");
    }
    let root = crate::fixtures::root();
    let doc_path = root.join(DOC);
    let doc = std::fs::read_to_string(&doc_path).with_context(|| format!("reading {}", doc_path.display()))?;
    let rows = documented(&doc)?;
    if rows.is_empty() {
        bail!("{DOC}: no rows under `{SECTION}` (expected `| `NAME` | value | ... |`)");
    }
    let mut files = Vec::new();
    rust_files(&root.join(CODE_DIR), &mut files)?;
    let mut sources = Vec::new();
    for f in files {
        let text = std::fs::read_to_string(&f).with_context(|| format!("reading {}", f.display()))?;
        sources.push((f, text));
    }
    let mut problems = String::new();
    for row in &rows {
        let defs = definitions(&sources, &row.name);
        let def = match defs.as_slice() {
            [] => {
                let _ = writeln!(problems, "{DOC}:{}: `{}` is not a const under {CODE_DIR}", row.line, row.name);
                continue;
            }
            [d] => d,
            many => {
                let at: Vec<String> = many.iter().map(|d| format!("{}:{}", rel(&root, &d.file), d.line)).collect();
                let _ = writeln!(problems, "`{}` is defined {} times: {}", row.name, many.len(), at.join(", "));
                continue;
            }
        };
        let place = format!("{}:{}", rel(&root, &def.file), def.line);
        match eval(&def.expr) {
            Some(v) if (v - row.value).abs() <= row.tolerance => {}
            Some(v) => {
                let _ = writeln!(
                    problems,
                    "`{}`: the code says {} (= {v}) at {place}, {DOC}:{} says {}",
                    row.name, def.expr, row.line, row.text
                );
            }
            None => {
                let _ = writeln!(
                    problems,
                    "`{}` at {place}: cannot evaluate `{}` (write a number, or numbers and std::f64::consts joined by * or /)",
                    row.name, def.expr
                );
            }
        }
    }
    if !problems.is_empty() {
        bail!("tuned constants out of step between {DOC} and the code:\n{problems}");
    }
    println!("tidy: {} tuned constants in {DOC} agree with {CODE_DIR}", rows.len());
    for (dir, allowed) in LIBRARIES_NOT_CLI_AWARE {
        not_cli_aware(&root, dir, allowed)?;
        println!("tidy: {dir} knows no command line");
    }
    cli_not_pipeline(&root)?;
    println!(
        "tidy: {CLI_DIR} only speaks (no program run, no footprint swept, no function over {CLI_MAX_FN_LINES} lines)"
    );
    let n = library_functions_short(&root)?;
    println!("tidy: no function over {LIBRARY_MAX_FN_LINES} lines in the {n} library crates");
    Ok(())
}

/// The longest function a library crate may hold, lines (signature to closing brace, tests
/// included).
const LIBRARY_MAX_FN_LINES: usize = 120;

/// Fails naming every function over [`LIBRARY_MAX_FN_LINES`] lines in the sources of a library
/// crate (`crates/*/src`, all but the CLI's, which has its own limit); returns how many crates
/// it read.
fn library_functions_short(root: &Path) -> Result<usize> {
    let crates = root.join("crates");
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(&crates)
        .with_context(|| format!("listing {}", crates.display()))?
        .map(|e| e.map(|e| e.path().join("src")))
        .collect::<std::io::Result<_>>()?;
    dirs.retain(|d| d.is_dir() && !d.starts_with(root.join(CLI_DIR)));
    dirs.sort();
    let mut problems = Vec::new();
    for dir in &dirs {
        let mut files = Vec::new();
        rust_files(dir, &mut files)?;
        for f in files {
            let text = std::fs::read_to_string(&f).with_context(|| format!("reading {}", f.display()))?;
            for (line, name, n) in long_functions(&text, LIBRARY_MAX_FN_LINES) {
                problems.push(format!("{}:{line}: fn {name} is {n} lines", rel(root, &f)));
            }
        }
    }
    if !problems.is_empty() {
        bail!(
            "library functions over {LIBRARY_MAX_FN_LINES} lines (split them into named steps):\n{}",
            problems.join("\n")
        );
    }
    Ok(dirs.len())
}

const CLI_DIR: &str = "crates/maobi/src";

/// What no file of the CLI may name: running a program on the simulated arm (robot-io's
/// `execute_as_sent*`, `execute_program*`, `SendMotion`, `trace_to_states`) and sweeping
/// footprints (brush-model's `ForwardModel` and its `sweep`, bezier-raster's `track_stamps` and
/// `render_stamps`). Matched as text in code lines (comments skipped), so any path to them
/// (`robot_io::sim::execute_as_sent`, a `use` of the root re-export) is caught.
const CLI_EXECUTION: &[&str] = &[
    "execute_as_sent",
    "execute_program",
    "SendMotion",
    "trace_to_states",
    "ForwardModel",
    ".sweep(",
    "track_stamps",
    "render_stamps",
];

/// What only the `robot` command ([`CLI_ROBOT_FILE`]) may name: building, compacting and timing
/// a program (`build_program*`, `compact_program`, `check_blends`, `time_program*`) and
/// robot-io's `timing` and `sim` modules (the latter for serving the simulators, `maobi robot
/// sim`). Elsewhere a sheet's program is run through the pipeline's `run_sheet`.
const CLI_PROGRAM: &[&str] =
    &["build_program", "compact_program", "check_blends", "time_program", "robot_io::timing", "robot_io::sim"];

/// The command that talks to arms, exempt from [`CLI_PROGRAM`] only.
const CLI_ROBOT_FILE: &str = "cmd/robot.rs";

/// The longest function the CLI may hold, lines (signature to closing brace).
const CLI_MAX_FN_LINES: usize = 100;

/// Fails naming every place where the CLI runs a program, sweeps footprints, builds or times a
/// program outside the `robot` command, or holds a function over [`CLI_MAX_FN_LINES`] lines.
fn cli_not_pipeline(root: &Path) -> Result<()> {
    let dir = root.join(CLI_DIR);
    let mut files = Vec::new();
    rust_files(&dir, &mut files)?;
    let mut problems = Vec::new();
    for f in files {
        let text = std::fs::read_to_string(&f).with_context(|| format!("reading {}", f.display()))?;
        let robot = f.strip_prefix(&dir).is_ok_and(|r| r == Path::new(CLI_ROBOT_FILE));
        for (line, what) in pipeline_lines(&text, robot) {
            problems.push(format!("{}:{line}: {what}", rel(root, &f)));
        }
        for (line, name, n) in long_functions(&text, CLI_MAX_FN_LINES) {
            problems.push(format!("{}:{line}: fn {name} is {n} lines (at most {CLI_MAX_FN_LINES})", rel(root, &f)));
        }
    }
    if !problems.is_empty() {
        bail!("the CLI does pipeline work (docs/ARCHITECTURE.md, invariants):\n{}", problems.join("\n"));
    }
    Ok(())
}

/// `(line, what)` for each code line (comments skipped) naming a [`CLI_EXECUTION`] item, or a
/// [`CLI_PROGRAM`] one unless `robot`.
fn pipeline_lines(text: &str, robot: bool) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for (i, l) in text.lines().enumerate() {
        let code = l.trim_start();
        if code.starts_with("//") {
            continue;
        }
        let program: &[&str] = if robot { &[] } else { CLI_PROGRAM };
        if let Some(c) = CLI_EXECUTION.iter().chain(program).find(|c| code.contains(*c)) {
            out.push((i + 1, format!("`{c}`")));
        }
    }
    out
}

/// `(line, name, lines)` of each `fn` over `max` lines, from its `fn` line to the closing brace
/// at its indentation (rustfmt's layout: the body ends with a line holding only `}` at the
/// indentation of `fn`).
fn long_functions(text: &str, max: usize) -> Vec<(usize, String, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        let code = l.trim_start();
        let indent = &l[..l.len() - code.len()];
        let rest = ["pub(crate) ", "pub(super) ", "pub "].iter().find_map(|p| code.strip_prefix(p)).unwrap_or(code);
        let rest = ["const ", "async ", "unsafe "].iter().fold(rest, |r, p| r.strip_prefix(p).unwrap_or(r));
        let Some(sig) = rest.strip_prefix("fn ") else { continue };
        let name: String = sig.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
        // The signature ends at the first line ending with `{` (a body) or `;` (none).
        let Some(open) = (i..lines.len()).find(|&j| {
            let t = lines[j].trim_end();
            t.ends_with('{') || t.ends_with(';') || t.ends_with('}')
        }) else {
            continue;
        };
        if !lines[open].trim_end().ends_with('{') {
            continue;
        }
        let close = format!("{indent}}}");
        if let Some(end) = (open + 1..lines.len()).find(|&j| lines[j] == close) {
            let n = end - i + 1;
            if n > max {
                out.push((i + 1, name, n));
            }
        }
    }
    out
}

const PIPELINE_DIR: &str = "crates/pipeline";

/// Crates the pipeline must not depend on: command-line parsing, terminal progress, plotting,
/// the binary's allocator and signal handling, and `anyhow` (its errors are typed).
const CLI_CRATES: &[&str] = &["clap", "indicatif", "plotters", "mimalloc", "ctrlc", "anyhow"];

/// What the pipeline's sources must not do: print, exit, write files.
const CLI_CALLS: &[&str] =
    &["println!", "eprintln!", "print!(", "eprint!(", "process::exit", "fs::write", "File::create"];

/// The library crates held to "not CLI-aware", each with the [`CLI_CALLS`] it may make all the
/// same: safe-output writes files (its job: temporary file, then rename).
const LIBRARIES_NOT_CLI_AWARE: &[(&str, &[&str])] =
    &[(PIPELINE_DIR, &[]), ("crates/safe-output", &["fs::write", "File::create"])];

/// Fails naming every place where the crate in `dir` depends on a CLI crate, names a flag, or
/// makes a [`CLI_CALLS`] call (printing, exiting, writing a file) other than `allowed`.
fn not_cli_aware(root: &Path, dir: &str, allowed: &[&str]) -> Result<()> {
    let manifest = root.join(dir).join("Cargo.toml");
    let toml = std::fs::read_to_string(&manifest).with_context(|| format!("reading {}", manifest.display()))?;
    let mut problems =
        cli_dependencies(&toml).into_iter().map(|d| format!("{dir}/Cargo.toml: depends on `{d}`")).collect::<Vec<_>>();
    let mut files = Vec::new();
    rust_files(&root.join(dir).join("src"), &mut files)?;
    for f in files {
        let text = std::fs::read_to_string(&f).with_context(|| format!("reading {}", f.display()))?;
        for (line, what) in cli_lines(&text) {
            if !allowed.iter().any(|a| what == format!("`{a}`")) {
                problems.push(format!("{}:{line}: {what}", rel(root, &f)));
            }
        }
    }
    if !problems.is_empty() {
        bail!("{dir} is CLI-aware (docs/ARCHITECTURE.md, invariants):\n{}", problems.join("\n"));
    }
    Ok(())
}

/// The CLI crates among the `[dependencies]` (not dev-dependencies) of a manifest.
fn cli_dependencies(toml: &str) -> Vec<String> {
    let mut in_deps = false;
    let mut out = Vec::new();
    for l in toml.lines().map(str::trim) {
        if l.starts_with('[') {
            in_deps = l == "[dependencies]";
            continue;
        }
        let name = l.split(['=', '.', ' ']).next().unwrap_or("");
        if in_deps && CLI_CRATES.contains(&name) {
            out.push(name.to_string());
        }
    }
    out
}

/// `(line, what)` for each line of Rust code (comments skipped) that prints, exits, writes a
/// file or has a string naming a flag (`"--name`, or ` --name` inside a string).
fn cli_lines(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for (i, l) in text.lines().enumerate() {
        let code = l.trim_start();
        if code.starts_with("//") {
            continue;
        }
        if let Some(c) = CLI_CALLS.iter().find(|c| code.contains(*c)) {
            out.push((i + 1, format!("`{c}`")));
        }
        // Inside string literals: the text between the first and the last quote.
        if let (Some(a), Some(b)) = (code.find('"'), code.rfind('"')) {
            let lit = &code[a..=b];
            let flag = lit.match_indices("--").any(|(j, _)| {
                let before = lit[..j].chars().last();
                let after = lit[j + 2..].chars().next();
                matches!(before, Some('"' | ' ' | '`' | '(')) && after.is_some_and(|c| c.is_ascii_lowercase())
            });
            if flag {
                out.push((i + 1, "a string names a command-line flag".to_string()));
            }
        }
    }
    out
}

fn rel(root: &Path, p: &Path) -> String {
    p.strip_prefix(root).unwrap_or(p).display().to_string()
}

/// The rows of the "Tuned constants" table: `` | `NAME` | value | ... ``.
fn documented(doc: &str) -> Result<Vec<Documented>> {
    let mut rows: Vec<Documented> = Vec::new();
    let mut inside = false;
    for (i, line) in doc.lines().enumerate() {
        if line.starts_with("## ") {
            inside = line.trim() == SECTION;
            continue;
        }
        if !inside || !line.starts_with("| `") {
            continue;
        }
        let cells: Vec<&str> = line.trim_matches('|').split('|').map(str::trim).collect();
        let (Some(name), Some(text)) = (cells.first(), cells.get(1)) else { continue };
        let name = name.trim_matches('`').to_string();
        let Some((value, tolerance)) = parse_documented(text) else {
            bail!("{DOC}:{}: the value of `{name}` is `{text}`, expected a plain number", i + 1);
        };
        if rows.iter().any(|r| r.name == name) {
            bail!("{DOC}:{}: `{name}` is listed twice", i + 1);
        }
        rows.push(Documented { name, text: text.to_string(), value, tolerance, line: i + 1 });
    }
    Ok(rows)
}

/// A documented number and half a unit of its last printed digit.
fn parse_documented(text: &str) -> Option<(f64, f64)> {
    let t = text.replace(',', "");
    let value: f64 = t.parse().ok()?;
    let decimals = t.split_once('.').map_or(0, |(_, d)| d.len());
    Some((value, 0.5 * 10f64.powi(-(decimals as i32))))
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("listing {}", dir.display()))?
        .map(|e| e.map(|e| e.path()))
        .collect::<std::io::Result<_>>()?;
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out)?;
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
    Ok(())
}

/// Every `const NAME: T = EXPR;` (any visibility) in the sources, `EXPR` up to the `;`.
fn definitions(sources: &[(PathBuf, String)], name: &str) -> Vec<Defined> {
    let needle = format!("const {name}:");
    let mut out = Vec::new();
    for (file, text) in sources {
        for (i, line) in text.lines().enumerate() {
            let l = line.trim_start();
            let l = l.strip_prefix("pub(crate) ").or_else(|| l.strip_prefix("pub ")).unwrap_or(l);
            if !l.starts_with(&needle) {
                continue;
            }
            // The initializer may run onto the next lines.
            let rest: String = text.lines().skip(i).collect::<Vec<_>>().join(" ");
            let expr = rest.split_once('=').map(|(_, e)| e).and_then(|e| e.split_once(';')).map(|(e, _)| e.trim());
            if let Some(expr) = expr {
                out.push(Defined { file: file.clone(), line: i + 1, expr: expr.to_string() });
            }
        }
    }
    out
}

/// The value of a number, or of numbers and `std::f64::consts` names joined by `*` or `/`.
fn eval(expr: &str) -> Option<f64> {
    let mut value = None;
    let mut op = '*';
    let mut rest = expr.trim();
    loop {
        let end = rest.find(['*', '/']).unwrap_or(rest.len());
        let term = atom(rest[..end].trim())?;
        value = Some(match (value, op) {
            (None, _) => term,
            (Some(v), '*') => v * term,
            (Some(v), _) => v / term,
        });
        if end == rest.len() {
            return value;
        }
        op = rest.as_bytes()[end] as char;
        rest = &rest[end + 1..];
    }
}

fn atom(t: &str) -> Option<f64> {
    let t = t.trim_start_matches("std::f64::consts::").trim_start_matches("f64::consts::");
    let known = match t {
        "PI" => Some(std::f64::consts::PI),
        "TAU" => Some(std::f64::consts::TAU),
        "FRAC_PI_2" => Some(std::f64::consts::FRAC_PI_2),
        "FRAC_PI_3" => Some(std::f64::consts::FRAC_PI_3),
        "FRAC_PI_4" => Some(std::f64::consts::FRAC_PI_4),
        "FRAC_PI_6" => Some(std::f64::consts::FRAC_PI_6),
        _ => None,
    };
    if known.is_some() {
        return known;
    }
    let digits = t.replace('_', "");
    let digits = ["f64", "f32", "u32", "usize", "i32"].iter().fold(digits, |d, s| d.trim_end_matches(s).to_string());
    digits.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn expressions_and_documented_precision() {
        assert_eq!(eval("0.65"), Some(0.65));
        assert_eq!(eval("512"), Some(512.0));
        assert_eq!(eval("1_000.0_f64"), Some(1000.0));
        let v = eval("2.0 * std::f64::consts::FRAC_PI_3").unwrap();
        let (d, tol) = parse_documented("2.0944").unwrap();
        assert!((v - d).abs() <= tol);
        assert!(eval("foo(1)").is_none());
        let (d, tol) = parse_documented("0.65").unwrap();
        assert!((0.66f64 - d).abs() > tol, "0.66 is not 0.65");
    }

    #[test]
    fn rows_are_read_from_the_section_only() {
        let doc = "## Other\n| `A` | 1 | x |\n## Tuned constants\n| constant | value |\n|---|---|\n| `B` | 0.5 | y |\n";
        let rows = documented(doc).unwrap();
        assert_eq!(rows.len(), 1);
        assert_eq!((rows[0].name.as_str(), rows[0].value, rows[0].line), ("B", 0.5, 6));
    }
}

#[cfg(test)]
mod cli_awareness_tests {
    use super::*;

    #[test]
    fn flags_prints_and_cli_crates_are_found_and_comments_are_not() {
        let src = "// --sheet in a comment is fine\nlet a = 1;\nbail!(\"--char-mm {c}: too big\");\nprintln!(\"x\");\nlet s = \"a -- b\";\n";
        let found = cli_lines(src);
        assert_eq!(found.iter().map(|(l, _)| *l).collect::<Vec<_>>(), vec![3, 4], "{found:?}");
        let toml = "[dependencies]\nclap.workspace = true\nserde = \"1\"\n\n[dev-dependencies]\nanyhow = \"1\"\n";
        assert_eq!(cli_dependencies(toml), vec!["clap".to_string()]);
    }

    #[test]
    fn the_pipeline_and_safe_output_pass() {
        let root = crate::fixtures::root();
        for (dir, allowed) in LIBRARIES_NOT_CLI_AWARE {
            not_cli_aware(&root, dir, allowed).unwrap();
        }
        // safe-output's allowance is what lets it pass: without it its writes are found.
        let e = not_cli_aware(&root, "crates/safe-output", &[]).unwrap_err().to_string();
        assert!(e.contains("`fs::write`") && !e.contains("println") && !e.contains("flag"), "{e}");
    }

    #[test]
    fn runs_sweeps_and_programs_are_found_in_the_cli_and_comments_are_not() {
        let src = "// ForwardModel::default() in a comment is fine\nuse robot_io::sim::{SendMotion, execute_as_sent};\nlet s = model.sweep(&p, &run, e);\nlet (p, r) = build_program_chars(&t, None, &b, &f, &c)?;\nlet t = robot_io::time_program(&p, &k, &c)?;\nlet c = RobotConfig::default();\n";
        let found = pipeline_lines(src, false);
        assert_eq!(found.iter().map(|(l, _)| *l).collect::<Vec<_>>(), vec![2, 3, 4, 5], "{found:?}");
        assert!(found[0].1.contains("execute_as_sent") || found[0].1.contains("SendMotion"), "{found:?}");
        // The robot command may build and time a program, never run or sweep one.
        let found = pipeline_lines(src, true);
        assert_eq!(found.iter().map(|(l, _)| *l).collect::<Vec<_>>(), vec![2, 3], "{found:?}");
    }

    #[test]
    fn functions_over_the_limit_are_found_by_their_closing_brace() {
        let body = |n: usize| (0..n).map(|i| format!("        let x{i} = {i};\n")).collect::<String>();
        let src = format!(
            "fn short() {{\n{}}}\n\nimpl A {{\n    pub(crate) fn long(\n        a: u32,\n    ) -> u32 {{\n{}        a\n    }}\n\n    fn decl(&self);\n}}\n",
            body(3),
            body(10)
        );
        // `long`: its fn line, two of signature, its `{` line, 10 + 1 of body, the closing brace.
        assert_eq!(long_functions(&src, 12), vec![(8, "long".to_string(), 15)]);
        assert!(long_functions(&src, 15).is_empty());
    }

    #[test]
    fn the_cli_passes() {
        cli_not_pipeline(&crate::fixtures::root()).unwrap();
    }

    #[test]
    fn the_libraries_pass_and_a_long_function_is_named() {
        let root = crate::fixtures::root();
        assert!(library_functions_short(&root).unwrap() >= 10);
        // A library with one function over the limit, the CLI with one too (its own rule).
        let dir = std::env::temp_dir().join(format!("maobi-tidy-{}", std::process::id()));
        let long = format!("pub fn long() {{\n{}}}\n", "    let _ = 1;\n".repeat(LIBRARY_MAX_FN_LINES));
        for (krate, text) in [("lib-a", "pub fn short() {}\n".to_string()), ("lib-b", long.clone()), ("maobi", long)] {
            std::fs::create_dir_all(dir.join("crates").join(krate).join("src")).unwrap();
            std::fs::write(dir.join("crates").join(krate).join("src/lib.rs"), text).unwrap();
        }
        let e = library_functions_short(&dir).unwrap_err().to_string();
        let _ = std::fs::remove_dir_all(&dir);
        assert!(
            e.ends_with(&format!("\ncrates/lib-b/src/lib.rs:1: fn long is {} lines", LIBRARY_MAX_FN_LINES + 2)),
            "{e}"
        );
    }
}
