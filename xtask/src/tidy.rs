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
//! exit, write files nor name a command-line flag.

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
    pipeline_not_cli_aware(&root)?;
    println!("tidy: {PIPELINE_DIR} knows no command line");
    Ok(())
}

const PIPELINE_DIR: &str = "crates/pipeline";

/// Crates the pipeline must not depend on: command-line parsing, terminal progress, plotting,
/// the binary's allocator and signal handling, and `anyhow` (its errors are typed).
const CLI_CRATES: &[&str] = &["clap", "indicatif", "plotters", "mimalloc", "ctrlc", "anyhow"];

/// What the pipeline's sources must not do: print, exit, write files.
const CLI_CALLS: &[&str] =
    &["println!", "eprintln!", "print!(", "eprint!(", "process::exit", "fs::write", "File::create"];

/// Fails naming every place where crates/pipeline depends on a CLI crate, prints, exits, writes
/// a file or names a flag.
fn pipeline_not_cli_aware(root: &Path) -> Result<()> {
    let manifest = root.join(PIPELINE_DIR).join("Cargo.toml");
    let toml = std::fs::read_to_string(&manifest).with_context(|| format!("reading {}", manifest.display()))?;
    let mut problems = cli_dependencies(&toml)
        .into_iter()
        .map(|d| format!("{PIPELINE_DIR}/Cargo.toml: depends on `{d}`"))
        .collect::<Vec<_>>();
    let mut files = Vec::new();
    rust_files(&root.join(PIPELINE_DIR).join("src"), &mut files)?;
    for f in files {
        let text = std::fs::read_to_string(&f).with_context(|| format!("reading {}", f.display()))?;
        for (line, what) in cli_lines(&text) {
            problems.push(format!("{}:{line}: {what}", rel(root, &f)));
        }
    }
    if !problems.is_empty() {
        bail!("the pipeline is CLI-aware (docs/ARCHITECTURE.md, invariants):\n{}", problems.join("\n"));
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
    fn the_pipeline_crate_passes() {
        pipeline_not_cli_aware(&crate::fixtures::root()).unwrap();
    }
}
