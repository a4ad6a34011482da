//! `maobi`: the command line of the maobi robotic-calligraphy toolkit.
//!
//! Each subcommand is a thin layer over one library crate; see `docs/ARCHITECTURE.md`.
//! Every error is printed as one line and exits with status 2.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod cmd;
mod common;

/// Robotic Chinese calligraphy: brush models, footprints, tracks and robots.
#[derive(Parser, Debug)]
#[command(name = "maobi", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Fit a brush profile from footprint measurements (CSV).
    Calibrate(cmd::calibrate::Args),
    /// Predict the footprint a press leaves.
    Footprint(cmd::footprint::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Calibrate(a) => cmd::calibrate::run(a),
        Command::Footprint(a) => cmd::footprint::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}
