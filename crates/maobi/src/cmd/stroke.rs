//! `maobi stroke`: render one footprint to PNG or SVG.

use std::path::PathBuf;

use anyhow::{Result, bail};
use bezier_raster::{ModelKind, StrokeCanvas};
use brush_model::Extrapolation;
use serde_json::json;

use crate::common::{
    BrushArg, MAX_PX_PER_MM, MIN_PX_PER_MM, PressArgs, StrokeRendererArgs, check_output_file, check_range, load_brush,
    parse_model, print_json, write_atomic,
};

/// Arguments of `maobi stroke`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    press: PressArgs,
    #[command(flatten)]
    brush: BrushArg,
    /// Stroke model that draws the footprint (`--renderer analytic`).
    #[arg(long, default_value = "bsm", value_parser = parse_model())]
    model: ModelKind,
    /// Canvas side, px.
    #[arg(long, default_value_t = 128)]
    size: u32,
    /// Scale, px per mm (default: the brush's largest footprint fits the canvas).
    #[arg(long, allow_negative_numbers = true)]
    px_per_mm: Option<f64>,
    /// Predict even outside the profile's calibrated range.
    #[arg(long)]
    extrapolate: bool,
    /// Output file: `.png` (black ink on white) or `.svg`.
    #[arg(short, long)]
    output: PathBuf,
    /// Replace the output file if it exists (without it, an existing file is refused).
    #[arg(long)]
    force: bool,
    /// Print the footprint, scale and anchor as JSON.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    renderer: StrokeRendererArgs,
}

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    if args.renderer.neural() {
        return run_neural(&args);
    }
    let profile = load_brush(&args.brush.brush)?;
    if !(8..=8192).contains(&args.size) {
        bail!("--size {}: expected a canvas side between 8 and 8192 px", args.size);
    }
    let canvas = match args.px_per_mm {
        Some(s) => {
            StrokeCanvas::with_scale(args.size, check_range("--px-per-mm", s, MIN_PX_PER_MM, MAX_PX_PER_MM, "px/mm")?)
        }
        None => StrokeCanvas::for_profile(&profile, args.size),
    };
    let press = args.press.press(&profile)?;
    let ex = if args.extrapolate { Extrapolation::Allow } else { Extrapolation::Refuse };
    let fp = crate::common::predict_or_hint(&profile, &press, ex, "give --extrapolate to use it anyway")?;
    let ext = args.output.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let bytes = match ext.as_deref() {
        Some("png") => canvas.draw(args.model.model(), &fp, press.beta_rad).encode_png()?,
        Some("svg") => canvas.svg(args.model.model(), &fp, press.beta_rad).into_bytes(),
        _ => bail!("-o {}: expected a .png or .svg file name", args.output.display()),
    };
    check_output_file("-o", &args.output, args.force)?;
    write_atomic(&args.output, &bytes)?;
    if args.json {
        print_json(&json!({
            "footprint": fp,
            "px_per_mm": canvas.px_per_mm,
            "anchor_px": canvas.anchor_px(&fp, press.beta_rad),
            "beta_rad": press.beta_rad,
            "size": args.size,
            "model": args.model.name(),
        }))?;
    }
    let what = if ext.as_deref() == Some("svg") {
        format!("{:.1} mm square SVG", canvas.size_mm())
    } else {
        format!("{0}×{0} px PNG at {1:.3} px/mm", args.size, canvas.px_per_mm)
    };
    wrote(&args, &format!("{} footprint, {what}", args.model.name()))
}

fn run_neural(args: &Args) -> Result<()> {
    let g = args.renderer.generator()?;
    if args.output.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() != Some("png") {
        bail!("-o {}: the neural renderer writes PNG only", args.output.display());
    }
    if args.size != 128 && args.size != g.config.size {
        bail!("--size {}: the generator draws {}² images", args.size, g.config.size);
    }
    if args.px_per_mm.is_some() {
        bail!("--px-per-mm: the generator's scale is fixed ({:.4} px/mm)", g.config.px_per_mm);
    }
    let press = args.press.press(&g.config.profile)?;
    // The generator only knows its training range.
    let fp = crate::common::predict_or_hint(
        &g.config.profile,
        &press,
        Extrapolation::Refuse,
        "the generator knows only its training range: --extrapolate works with --renderer analytic",
    )?;
    let img = g.render(&[press])?.remove(0);
    check_output_file("-o", &args.output, args.force)?;
    write_atomic(&args.output, &img.encode_png()?)?;
    if args.json {
        let canvas = StrokeCanvas::with_scale(g.config.size, g.config.px_per_mm);
        print_json(&json!({
            "footprint": fp,
            "px_per_mm": g.config.px_per_mm,
            "anchor_px": canvas.anchor_px(&fp, press.beta_rad),
            "beta_rad": press.beta_rad,
            "size": g.config.size,
            "model": "b-bsmg",
        }))?;
    }
    wrote(args, &format!("generator footprint, {0}×{0} px PNG at {1:.3} px/mm", g.config.size, g.config.px_per_mm))
}

/// Says what was written where: on stdout, or on stderr when stdout carries `--json`.
fn wrote(args: &Args, what: &str) -> Result<()> {
    let line = format!("wrote {}: {what}", args.output.display());
    if args.json {
        eprintln!("{line}");
        Ok(())
    } else {
        crate::outln!("{line}")
    }
}
