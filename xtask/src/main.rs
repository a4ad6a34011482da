//! `cargo xtask`: project automation for maobi (see `cargo xtask help`).

// A binary's items are reachable only inside it: `pub` here means "used by other modules".
#![allow(unreachable_pub)]

use std::process::ExitCode;

mod bench;
mod figures;
mod fixtures;
mod gates;
mod io;
mod refine_gate;
mod skeleton_counts;
mod skeleton_train;
mod styles;
mod tidy;
mod train_fixture;
mod worlds;

const HELP: &str = "\
cargo xtask <task>

Tasks:
  help                 print this help
  fixtures [--check] [--hanzi-data DIR] [--only TEXT]
                       regenerate every generated file under fixtures/ (or, with --check,
                       verify the committed files are what the generators produce now)
  gates [--update]     similarity regression gates against fixtures/baselines/*.json
  train-fixture        train the committed pen1 generator (crates/neural-gen/data/; about 5 minutes)
  styles --font F [...] compare centre-line methods (skeleton, template) on a font's glyphs
                       and synthetic scans of them (`cargo xtask styles --help`)
  skeleton-counts [--hanzi-data DIR] [--set FILE] [...]
                       skeleton stroke counts against the medians on a character set
                       (`cargo xtask skeleton-counts --help`)
  skeleton-train --hanzi-data DIR
                       train the skeleton's junction and corner models
                       (crates/trajectory/data/skeleton-models.json; `cargo xtask skeleton-train --help`)
  tidy                 check that the tuned constants in docs/trajectory.md (section Tuned constants)
                       have the values the code gives them
  bench [--quick]      run the criterion benchmarks and the dataset throughput; print one table
                       (also target/bench-summary.md)
  worlds --chars TEXT|--set FILE [...]
                       the executed figure under worlds that disagree with the model (hairs
                       that need a press, another trail, a mismatched brush; `cargo xtask
                       worlds --help`)
";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        None | Some("help") | Some("--help") | Some("-h") => {
            print!("{HELP}");
            Ok(())
        }
        Some("fixtures") => fixtures::run(&args[1..]),
        Some("gates") => gates::run(&args[1..]),
        Some("bench") => bench::run(&args[1..]),
        Some("skeleton-counts") => skeleton_counts::run(&args[1..]),
        Some("skeleton-train") => skeleton_train::run(&args[1..]),
        Some("styles") => styles::run(&args[1..]),
        Some("tidy") => tidy::run(&args[1..]),
        Some("train-fixture") => train_fixture::run(&args[1..]),
        Some("worlds") => worlds::run(&args[1..]),
        Some(other) => Err(anyhow::anyhow!("unknown task `{other}`\n\n{HELP}")),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}
