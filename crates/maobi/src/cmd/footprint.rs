//! `maobi footprint`: the footprint a press leaves.

use anyhow::Result;
use brush_model::Extrapolation;

use crate::common::{PressArgs, load_brush, print_json};

/// Arguments of `maobi footprint`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    press: PressArgs,
    /// Brush: pen1, pen2 or a profile JSON file.
    #[arg(long, default_value = "pen1")]
    brush: String,
    /// Predict even outside the profile's calibrated range.
    #[arg(long)]
    extrapolate: bool,
    /// Print `{"lt_mm","lh_mm","lr_mm"}` as JSON.
    #[arg(long)]
    json: bool,
}

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    let profile = load_brush(&args.brush)?;
    let press = args.press.press(&profile)?;
    let extrapolation = if args.extrapolate { Extrapolation::Allow } else { Extrapolation::Refuse };
    let fp = crate::common::predict_or_hint(&profile, &press, extrapolation, "give --extrapolate to use it anyway")?;
    if args.json {
        print_json(&fp)?;
    } else {
        crate::outln!(
            "{} ({}): h = {} mm, α = {}°, β = {}°\n  tip length  lt = {:.3} mm\n  root length lh = {:.3} mm\n  belly half-width lr = {:.3} mm (width {:.3} mm)\n  length lh + lt = {:.3} mm, area = {:.2} mm²",
            profile.name,
            match profile.source {
                brush_model::Source::Nominal => "nominal",
                brush_model::Source::Calibrated => "calibrated",
            },
            args.press.h_mm,
            args.press.alpha_deg,
            args.press.beta_deg,
            fp.lt_mm,
            fp.lh_mm,
            fp.lr_mm,
            2.0 * fp.lr_mm,
            fp.length_mm(),
            fp.area_mm2()
        )?;
    }
    Ok(())
}
