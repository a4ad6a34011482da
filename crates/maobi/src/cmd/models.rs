//! `maobi models`: every stroke model against the B-BSM footprint (the paper's Table 2), or
//! against real stroke photos.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use bezier_raster::{Coverage, DatasetSpec, ModelKind, Rasterizer, StrokeCanvas};
use brush_model::{Extrapolation, Press};
use rayon::prelude::*;
use serde::Serialize;
use stroke_metrics::{SsimWorkspace, Summary, csim};

use crate::common::{
    BrushArg, check_range, load_brush, load_image, print_json, print_model_table, progress, read_stroke_labels,
};

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

/// CSIM and SSIM summaries of one model.
#[derive(Serialize, Debug, Clone, Copy)]
pub struct ModelScores {
    /// Cosine similarity over the set.
    pub csim: Summary,
    /// Structural similarity over the set.
    pub ssim: Summary,
}

#[derive(Serialize)]
struct Report {
    reference: String,
    n: usize,
    brush: String,
    size: u32,
    models: BTreeMap<&'static str, ModelScores>,
}

/// One comparison target: the press and, for photos, the image.
struct Target {
    press: Press,
    photo: Option<Coverage>,
    px_per_mm: f64,
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
            let t = (0..args.n)
                .map(|i| Target { press: spec.press(i), photo: None, px_per_mm: spec.canvas.px_per_mm })
                .collect();
            (t, args.size, ModelKind::BASELINES.to_vec(), "bsm".to_string())
        }
        Some(dir) => {
            let (t, size) = load_reference(dir, &profile)?;
            (t, size, ModelKind::ALL.to_vec(), format!("photos:{}", dir.display()))
        }
    };
    let pb = progress(targets.len() as u64, "models");
    let ex = if args.reference.is_some() { Extrapolation::Allow } else { Extrapolation::Refuse };
    // Per target: (csim, ssim) for each model.
    let scores: Vec<Vec<(f64, f64)>> = targets
        .par_iter()
        .map_init(
            || (Rasterizer::new(), Coverage::new(size, size), Coverage::new(size, size), SsimWorkspace::new()),
            |(raster, truth, img, ws), t| -> Result<Vec<(f64, f64)>> {
                let fp = profile.predict(&t.press, ex)?;
                let canvas = StrokeCanvas::with_scale(size, t.px_per_mm);
                let anchor = canvas.anchor_mm(&fp, t.press.beta_rad);
                let truth: &Coverage = match &t.photo {
                    Some(p) => p,
                    None => {
                        raster.render(ModelKind::Bsm.model(), &fp, anchor, t.press.beta_rad, t.px_per_mm, truth);
                        truth
                    }
                };
                let mut out = Vec::with_capacity(models.len());
                for m in &models {
                    raster.render(m.model(), &fp, anchor, t.press.beta_rad, t.px_per_mm, img);
                    out.push((csim(truth.as_gray(), img.as_gray())?, ws.ssim(truth.as_gray(), img.as_gray())?));
                }
                pb.inc(1);
                Ok(out)
            },
        )
        .collect::<Result<_>>()?;
    pb.finish_and_clear();
    let mut table = BTreeMap::new();
    for (k, m) in models.iter().enumerate() {
        table.insert(
            m.name(),
            ModelScores {
                csim: Summary::of(scores.iter().map(|s| s[k].0)),
                ssim: Summary::of(scores.iter().map(|s| s[k].1)),
            },
        );
    }
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

fn load_reference(dir: &Path, profile: &brush_model::BrushProfile) -> Result<(Vec<Target>, u32)> {
    let mut targets = Vec::new();
    let mut size = None;
    for l in read_stroke_labels(&dir.join("labels.csv"))? {
        let file = dir.join(&l.file);
        let photo = load_image(&file)?;
        if photo.width() != photo.height() {
            bail!(
                "{}: expected a square image registered to the stroke canvas, got {}×{}",
                file.display(),
                photo.width(),
                photo.height()
            );
        }
        if *size.get_or_insert(photo.width()) != photo.width() {
            bail!("{}: all reference images must have the same size", file.display());
        }
        let px_per_mm = l.px_per_mm.unwrap_or_else(|| StrokeCanvas::for_profile(profile, photo.width()).px_per_mm);
        targets.push(Target { press: l.press, photo: Some(photo), px_per_mm });
    }
    Ok((targets, size.expect("at least one row")))
}
