//! `maobi fit-stroke`: fit a B-BSM footprint to one stroke photo.

use std::path::PathBuf;

use anyhow::{Context, Result};
use bezier_raster::{Bsm, StrokeModel};
use serde_json::json;
use stroke_fit::StrokeFit;

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
        write_atomic(out, &overlay(&mask, &fit, scale).with_context(|| format!("drawing {}", out.display()))?)?;
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

/// The photo in grey with the fitted outline in red (the paper's Fig. 8).
pub fn overlay(mask: &stroke_fit::InkMask, fit: &StrokeFit, scale: f64) -> Result<Vec<u8>> {
    let (w, h) = (mask.width as u32, mask.height as u32);
    let path =
        Bsm.outline(&fit.footprint(), brush_model::PointMm::new(fit.anchor_mm[0], fit.anchor_mm[1]), fit.beta_rad);
    let mut img = image::RgbImage::from_fn(w, h, |x, y| {
        let g = (mask.gray[(y * w + x) as usize].clamp(0.0, 1.0) * 255.0) as u8;
        image::Rgb([g, g, g])
    });
    // Sample the outline densely and draw 2-px red dots. Flattened to a quarter pixel, so the
    // number of points follows the outline's length in pixels, not in mm (a tiny --px-per-mm
    // made millions of points); each segment's dots are capped by the image's perimeter.
    let flat = {
        let mut pts = Vec::new();
        kurbo::flatten(path.iter(), 0.25 / scale, |el| match el {
            kurbo::PathEl::MoveTo(p) | kurbo::PathEl::LineTo(p) => pts.push(p),
            _ => {}
        });
        pts
    };
    for win in flat.windows(2) {
        let (a, b) = (win[0], win[1]);
        let steps = ((a.distance(b) * scale) * 2.0).ceil().clamp(1.0, 4.0 * (w + h) as f64) as usize;
        for i in 0..=steps {
            let p = a.lerp(b, i as f64 / steps as f64);
            let (cx, cy) = ((p.x * scale) as i64, (p.y * scale) as i64);
            for dy in 0..2 {
                for dx in 0..2 {
                    let (x, y) = (cx + dx, cy + dy);
                    if x >= 0 && y >= 0 && (x as u32) < w && (y as u32) < h {
                        img.put_pixel(x as u32, y as u32, image::Rgb([230, 20, 20]));
                    }
                }
            }
        }
    }
    let mut out = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)?;
    Ok(out)
}
