//! `maobi train`: train the neural footprint generator.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use neural_gen::{Arch, Generator, GeneratorConfig, TrainOptions};

use crate::common::{
    BrushArg, FileSet, OutputLock, check_output_file, check_range, install_files, load_brush, step_progress,
};

/// Arguments of `maobi train`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    brush: BrushArg,
    /// Optimiser steps (2500 made the committed pen1 generator, crates/neural-gen/data/pen1.json).
    #[arg(long, default_value_t = 2500)]
    steps: usize,
    /// Batch size.
    #[arg(long, default_value_t = 64)]
    batch: usize,
    /// Peak learning rate (AdamW, weight decay 0; warm-up then cosine decay).
    #[arg(long, default_value_t = 2e-3)]
    lr: f64,
    /// Seed (weights and training presses).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Continue from this checkpoint's weights (optimiser state restarts).
    #[arg(long)]
    resume: Option<PathBuf>,
    /// Architecture: `default` (128²) or `tiny` (32², for tests).
    #[arg(long, default_value = "default", value_parser = ["default", "tiny"])]
    arch: String,
    /// Validate every N steps.
    #[arg(long, default_value_t = 100)]
    val_every: usize,
    /// Held-out presses for the final metrics.
    #[arg(long, default_value_t = 500)]
    eval_n: usize,
    /// Output weights (`.safetensors`); the config goes beside as `.json`, plus `loss.csv` and
    /// `loss.png`. All four are replaced only by a finished run; while it trains, the best
    /// weights so far are saved beside them as `NAME.checkpoint.safetensors` (and `.json`; give
    /// it to --resume after an interruption), removed once the run has finished.
    #[arg(short, long)]
    output: PathBuf,
    /// Replace a finished model at -o (its weights or config); without it an existing one is
    /// refused before any training.
    #[arg(long)]
    force: bool,
}

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    check_args(&args)?;
    let _lock = OutputLock::acquire("-o", &args.output)?;
    check_output_file("-o", &args.output, args.force)?;
    check_output_file("-o", &neural_gen::config_path(&args.output), args.force)
        .context("the config beside the weights")?;
    let checkpoint = neural_gen::checkpoint_path(&args.output);
    let profile = load_brush(&args.brush.brush)?;
    let mut g = start_generator(&args, profile)?;
    let a = &g.config.arch;
    eprintln!(
        "generator: {} parameters, {:.2} M multiply-adds per image, {}² output",
        a.parameter_count(),
        a.macs_per_image() as f64 / 1e6,
        g.config.size
    );
    // A bar on a terminal; without one (a log, CI) a line every 5 % of the steps.
    let progress = step_progress(args.steps as u64, "train");
    let opts = TrainOptions {
        steps: args.steps,
        batch: args.batch,
        lr: args.lr,
        seed: args.seed,
        val_every: args.val_every,
        patience: 8,
        checkpoint: Some(checkpoint.clone()),
    };
    let mut last_val = f64::NAN;
    let report = neural_gen::train(&mut g, &opts, |p| {
        if let Some(v) = p.val_mse {
            last_val = v;
        }
        let val = if last_val.is_nan() { "-".to_string() } else { format!("{last_val:.6}") };
        progress.step(p.step as u64, &format!("loss {:.6}  validation {val}", p.train_mse));
    })?;
    progress.finish_and_clear();
    let (csim, ssim) = neural_gen::evaluate(&g, args.eval_n)?;
    g.config.recipe = Some(report.recipe(&opts));
    g.config.metrics = Some(report.metrics(args.eval_n, &csim, &ssim));
    let dir = install_outputs(&g, &args.output, &report)?;
    for p in [checkpoint.clone(), neural_gen::config_path(&checkpoint)] {
        let _ = std::fs::remove_file(p);
    }
    crate::outln!(
        "{} steps in {:.1} s ({:.3} s/step, data {:.1}%){}; best validation MSE {:.6} at step {}; held-out (n = {}): SSIM mean {:.4} worst {:.4}, CSIM mean {:.4}",
        report.steps_run,
        report.wall_seconds,
        report.wall_seconds / report.steps_run as f64,
        100.0 * report.data_seconds / report.wall_seconds,
        if report.stopped_early { ", stopped early" } else { "" },
        report.best_val_mse,
        report.best_step,
        args.eval_n,
        ssim.mean,
        ssim.worst,
        csim.mean
    )?;
    crate::outln!(
        "wrote {} (config beside it: {}), {} and {}",
        args.output.display(),
        neural_gen::config_path(&args.output).display(),
        dir.join("loss.csv").display(),
        dir.join("loss.png").display()
    )?;
    Ok(())
}

/// Refuses flags out of range before any work.
fn check_args(args: &Args) -> Result<()> {
    check_range("--steps", args.steps, 1, 10_000_000, "steps")?;
    check_range("--batch", args.batch, 1, 256, "images")?;
    if !(args.lr.is_finite() && args.lr > 0.0 && args.lr <= 1.0) {
        bail!("--lr {}: expected a learning rate above 0 and at most 1", args.lr);
    }
    check_range("--val-every", args.val_every, 1, 10_000_000, "steps")?;
    check_range("--eval-n", args.eval_n, 1, 100_000, "presses")?;
    if args.output.extension().and_then(|e| e.to_str()) != Some("safetensors") {
        bail!("-o {}: expected a .safetensors file name", args.output.display());
    }
    Ok(())
}

/// The generator to train: the `--resume` checkpoint (trained for this brush) or a new one.
fn start_generator(args: &Args, profile: brush_model::BrushProfile) -> Result<Generator> {
    Ok(match &args.resume {
        Some(p) => {
            let g = Generator::load(p).with_context(|| format!("--resume {}", p.display()))?;
            if g.config.profile != profile && args.brush.brush != "pen1" {
                bail!(
                    "--resume {}: the checkpoint was trained for brush `{}`, not `{}`",
                    p.display(),
                    g.config.profile.name,
                    profile.name
                );
            }
            g
        }
        None => {
            let arch = if args.arch == "tiny" { Arch::tiny_32() } else { Arch::default_128() };
            Generator::new(GeneratorConfig::new(profile, arch), args.seed)?
        }
    })
}

/// Writes the weights, their config, `loss.csv` and `loss.png` beside one another, replaced
/// together ([`safe_output::FileSet`]: each first to a hidden temporary file
/// `.NAME.maobi-partial-PID` so that a failure, a full disk, changes none of the outputs; Ctrl-C
/// held off until the last rename). Returns the folder.
fn install_outputs(g: &Generator, output: &Path, report: &neural_gen::TrainReport) -> Result<PathBuf> {
    let dir =
        output.parent().filter(|d| !d.as_os_str().is_empty()).map(PathBuf::from).unwrap_or_else(|| PathBuf::from("."));
    let train: Vec<(f64, f64)> = report.history.iter().map(|p| (p.step as f64, p.train_mse)).collect();
    let val: Vec<(f64, f64)> = report.history.iter().filter_map(|p| p.val_mse.map(|v| (p.step as f64, v))).collect();
    let png = figures::loss_png(&[("train", train), ("validation", val)])?;
    let mut files = FileSet::new();
    g.save_into(&mut files, output)?;
    files.add(dir.join("loss.csv"), report.loss_csv().into_bytes());
    files.add(dir.join("loss.png"), png);
    install_files(files, "train-install")?;
    Ok(dir)
}
