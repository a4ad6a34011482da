//! `maobi models`: every stroke model against the B-BSM footprint (the paper's Table 2), or
//! against real stroke photos.

use std::collections::BTreeMap;
use std::path::PathBuf;

use anyhow::{Result, bail};
use bezier_raster::{DatasetSpec, ModelKind};
use brush_model::{Extrapolation, Press};
use pipeline::{ModelScores, ModelTarget, load_reference_photos, score_models};
use serde::Serialize;

use crate::common::{BrushArg, check_range, load_brush, print_json, print_model_table, progress};

/// Arguments of `maobi models`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Number of random presses over the calibrated range.
    #[arg(long, default_value_t = 500)]
    n: u64,
    /// Canvas side, px.
    #[arg(long, default_value_t = 128)]
    size: u32,
    #[command(flatten)]
    brush: BrushArg,
    /// Random seed for the presses.
    #[arg(long, default_value_t = 2024)]
    seed: u64,
    /// Compare against real stroke photos instead: a folder with `labels.csv`
    /// (`file,h_mm,alpha_deg,beta_deg`) and square images registered to the stroke canvas
    /// (footprint centred, scale from an optional `px_per_mm` column or the default canvas).
    #[arg(long)]
    reference: Option<PathBuf>,
    /// Print JSON instead of the table.
    #[arg(long)]
    json: bool,
    /// Also draw every model's footprint of one press side by side, with axes in mm, to this PNG
    /// (the press: the middle of the brush's calibrated h and α ranges, β = 0).
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
    /// Replace the --plot file if it exists (without it, an existing file is refused).
    #[arg(long)]
    force: bool,
}

#[derive(Serialize)]
struct Report {
    reference: String,
    n: usize,
    brush: String,
    size: u32,
    models: BTreeMap<&'static str, ModelScores>,
}

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    check_range("--n", args.n, 1, 1_000_000, "presses")?;
    check_range("--size", args.size, 8, 4096, "px")?;
    let profile = load_brush(&args.brush.brush)?;
    if let Some(plot) = &args.plot {
        if plot.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() != Some("png") {
            bail!("--plot {}: expected a .png file name", plot.display());
        }
        let r = &profile.ranges;
        let press = Press {
            h_mm: 0.5 * (r.h_mm.min + r.h_mm.max),
            alpha_rad: 0.5 * (r.alpha_rad.min + r.alpha_rad.max),
            beta_rad: 0.0,
        };
        crate::common::check_output_file("--plot", plot, args.force)?;
        crate::common::write_atomic(plot, &figures::models_png(&profile, &press)?)?;
        eprintln!("wrote {}: every stroke model's footprint of one press, axes in mm", plot.display());
    }
    let (targets, size, models, reference) = match &args.reference {
        None => {
            let spec = DatasetSpec::new(profile.clone(), args.size, args.seed);
            (ModelTarget::presses(&spec, args.n), args.size, ModelKind::BASELINES.to_vec(), "bsm".to_string())
        }
        Some(dir) => {
            let (t, size) = load_reference_photos(dir, &profile)?;
            (t, size, ModelKind::ALL.to_vec(), format!("photos:{}", dir.display()))
        }
    };
    let pb = progress(targets.len() as u64, "models");
    let ex = if args.reference.is_some() { Extrapolation::Allow } else { Extrapolation::Refuse };
    let table = score_models(&profile, &targets, size, &models, ex, &|| pb.inc(1))?;
    pb.finish_and_clear();
    let report = Report { reference, n: targets.len(), brush: profile.name.clone(), size, models: table };
    if args.json {
        print_json(&report)?;
    } else {
        crate::outln!(
            "{} presses of {} at {size}², each model against {} (%):",
            report.n,
            report.brush,
            report.reference
        )?;
        print_model_table(models.iter().map(|m| {
            let s = report.models[m.name()];
            (m.name(), s.csim, s.ssim)
        }))?;
    }
    Ok(())
}
