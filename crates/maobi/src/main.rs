//! `maobi`: the command line of the maobi robotic-calligraphy toolkit.
//!
//! Each subcommand is a thin layer over one library crate; see `docs/ARCHITECTURE.md`.
//! Every error is printed as one line and exits with status 2.

// A binary's items are reachable only inside it: `pub` here means "used by other modules".
#![allow(unreachable_pub)]

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod cmd;
mod common;
mod generator;

// Training and rendering create and drop large buffers all the time; glibc hands allocations
// above its mmap threshold back to the OS on every free, so each new tensor pays a page fault
// per 4 KiB. mimalloc keeps and reuses them (generator training step: see docs/neural-gen.md).
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Robotic Chinese calligraphy: brush models, footprints, tracks and robots.
#[derive(Parser, Debug)]
#[command(name = "maobi", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Fit a brush profile from footprint measurements (CSV) or from stroke photos.
    Calibrate(cmd::calibrate::Args),
    /// A calibration sheet: a robot program pressing a grid of single footprints over a brush's range, with marks.
    CalibrateSheet(cmd::calibrate_sheet::Args),
    /// Fit a B-BSM footprint to one stroke photo.
    FitStroke(cmd::fit_stroke::Args),
    /// Predict the footprint a press leaves.
    Footprint(cmd::footprint::Args),
    /// Render one footprint (PNG or SVG).
    Stroke(cmd::stroke::Args),
    /// Compare two images: CSIM, SSIM, IoU, MSE, PSNR.
    Compare(cmd::compare::Args),
    /// Write a dataset of random footprints (PNGs + labels.csv).
    Dataset(cmd::dataset::Args),
    /// Write characters: brush track, render, reference and scores.
    Write(cmd::write::Args),
    /// A photo of a written sheet → each character's ink, its scores and what the brush did differently.
    Observe(cmd::observe::Args),
    /// One self-contained HTML page that plays a track over its sheet (brush, footprints, plots, check, dips).
    Preview(cmd::preview::Args),
    /// Run the write pipeline over many characters and report mean scores.
    Evaluate(cmd::evaluate::Args),
    /// Robot arms: check, export, send, simulate.
    #[command(subcommand)]
    Robot(cmd::robot::RobotCmd),
    /// The generator against the analytic B-BSM and the baselines (the paper's Table 3).
    EvalGenerator(cmd::eval_generator::Args),
    /// Train the neural footprint generator.
    Train(cmd::train::Args),
    /// Score every stroke model against the B-BSM footprint (the paper's Table 2).
    Models(cmd::models::Args),
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => {
            // --help and --version.
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
        Err(e) if e.kind() == clap::error::ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            // `maobi` or `maobi robot` alone: the help as --help prints it, still a failure.
            let _ = e.print();
            return ExitCode::from(2);
        }
        Err(e) => {
            eprintln!("{}", one_line(&e.render().to_string()));
            return ExitCode::from(2);
        }
    };
    // `println!` in a command not yet moved to `outln!` panics when stdout's reader has gone
    // away (`maobi … | head`): end quietly then too, as `outln!` does.
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let msg = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if msg.starts_with("failed printing to stdout") && msg.contains("Broken pipe") {
            std::process::exit(0);
        }
        default_hook(info);
    }));
    // `robot` installs its own Ctrl-C handling (the brush is lifted first).
    if !matches!(cli.command, Command::Robot(_)) {
        if let Err(e) = common::install_interrupt_handler() {
            eprintln!("error: {e:#}");
            return ExitCode::from(2);
        }
    }
    let result = match cli.command {
        Command::Calibrate(a) => cmd::calibrate::run(a),
        Command::CalibrateSheet(a) => cmd::calibrate_sheet::run(a),
        Command::Footprint(a) => cmd::footprint::run(a),
        Command::FitStroke(a) => cmd::fit_stroke::run(a),
        Command::Stroke(a) => cmd::stroke::run(a),
        Command::Compare(a) => cmd::compare::run(a),
        Command::Dataset(a) => cmd::dataset::run(a),
        Command::Models(a) => cmd::models::run(a),
        Command::Write(a) => cmd::write::run(a),
        Command::Evaluate(a) => cmd::evaluate::run(a),
        Command::Preview(a) => cmd::preview::run(a),
        Command::Observe(a) => cmd::observe::run(a),
        Command::Train(a) => cmd::train::run(a),
        Command::EvalGenerator(a) => cmd::eval_generator::run(a),
        Command::Robot(c) => cmd::robot::run(c),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // The reader of stdout went away (`maobi … | head`): nothing left to say to anyone.
        Err(e) if common::is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

/// Folds clap's multi-line usage error into one line, dropping the usage and help hints; a
/// tip (a similar subcommand or flag, how to pass a value) follows in parentheses.
fn one_line(msg: &str) -> String {
    let mut out = String::new();
    let mut tips = Vec::new();
    for l in msg.lines().map(str::trim) {
        if l.is_empty() || l.starts_with("Usage:") || l.starts_with("For more information") {
            continue;
        }
        if l.starts_with("tip:") {
            tips.push(l);
        } else {
            if !out.is_empty() {
                out.push(' ');
            }
            out.push_str(l);
        }
    }
    if !tips.is_empty() {
        out.push_str(&format!(" ({})", tips.join("; ")));
    }
    out
}
