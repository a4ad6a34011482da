//! `maobi fit-stroke`: fit a B-BSM footprint to one stroke photo.

use std::path::PathBuf;

use anyhow::{Context, Result};
use serde_json::json;

use crate::common::{check_output_file, fit_photo, print_json, write_atomic};

/// Arguments of `maobi fit-stroke`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The photo (PNG or JPEG, colour or grey; dark ink on light paper).
    photo: PathBuf,
    /// Scale, px per mm (default: the image's resolution metadata).
    #[arg(long)]
    px_per_mm: Option<f64>,
    /// Write the photo with the fitted outline drawn on it.
    #[arg(long)]
    overlay: Option<PathBuf>,
    /// Print `{"lt_mm","lh_mm","lr_mm","anchor_mm","beta_rad","iou"}` as JSON.
    #[arg(long)]
    json: bool,
    /// Replace the --overlay file if it exists (without it, an existing file is refused).
    #[arg(long)]
    force: bool,
}

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    let (fit, mask, scale) = fit_photo(&args.photo, args.px_per_mm, "--px-per-mm")?;
    if let Some(out) = &args.overlay {
        check_output_file("--overlay", out, args.force)?;
        write_atomic(
            out,
            &stroke_fit::fit_overlay(&mask, &fit, scale).with_context(|| format!("drawing {}", out.display()))?,
        )?;
    }
    if args.json {
        print_json(
            &json!({"lt_mm": fit.lt_mm, "lh_mm": fit.lh_mm, "lr_mm": fit.lr_mm, "anchor_mm": fit.anchor_mm, "beta_rad": fit.beta_rad, "iou": fit.iou}),
        )?;
    } else {
        crate::outln!(
            "lt = {:.3} mm, lh = {:.3} mm, lr = {:.3} mm, root at ({:.2}, {:.2}) mm, β = {:.2}°, IoU {:.4} (scale {scale} px/mm)",
            fit.lt_mm,
            fit.lh_mm,
            fit.lr_mm,
            fit.anchor_mm[0],
            fit.anchor_mm[1],
            fit.beta_rad.to_degrees(),
            fit.iou
        )?;
    }
    if let Some(out) = &args.overlay {
        let line = format!("overlay written to {}", out.display());
        if args.json { eprintln!("{line}") } else { crate::outln!("{line}")? }
    }
    Ok(())
}
