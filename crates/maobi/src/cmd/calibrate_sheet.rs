//! `maobi calibrate-sheet`: a robot program that presses a grid of single footprints over a
//! brush's calibrated range, with registration marks (docs/closed-loop.md, "Calibration
//! sheet"); `maobi calibrate --sheet-photo` measures them (`cmd/calibrate/sheet_photo.rs`).

use std::path::PathBuf;

use anyhow::{Context, Result};
use pipeline::{calibration_sheet, calibration_sheet_image, parse_sheet};

use crate::common::{OutputLock, Stage, check_output_folder, check_range, load_brush, recover_leftovers, write_atomic};

/// Scale of `layout.png`, px per mm.
const LAYOUT_PX_PER_MM: f64 = 4.0;

/// Arguments of `maobi calibrate-sheet`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The brush to calibrate (its profile's ranges are what the presses span): pen1, pen2 or a
    /// profile JSON.
    #[arg(long, default_value = "pen1")]
    brush: String,
    /// The paper: A0–A6, B3–B5 (A4L for landscape), WxH in mm, or a paper.json.
    #[arg(long, default_value = "A4")]
    sheet: String,
    /// Margin kept free on every side (the registration marks sit in it), mm.
    #[arg(long, default_value_t = 15.0, allow_negative_numbers = true)]
    margin_mm: f64,
    /// Output folder: track.json (the robot program's track, marks first), layout.json (each
    /// press's paper position, h, α, β) and layout.png (the planned ink, cells outlined).
    #[arg(short, long, visible_alias = "out", value_name = "CAL")]
    output: PathBuf,
    /// Replace an existing output folder that maobi wrote.
    #[arg(long)]
    force: bool,
}

/// Runs `maobi calibrate-sheet`.
pub fn run(args: Args) -> Result<()> {
    check_range("--margin-mm", args.margin_mm, 0.0, 500.0, "mm")?;
    let profile = load_brush(&args.brush)?;
    let sheet = parse_sheet(&args.sheet).with_context(|| format!("--sheet {}", args.sheet))?;
    let cal = calibration_sheet(&sheet, args.margin_mm, &profile)
        .with_context(|| format!("--sheet {} --margin-mm {} --brush {}", args.sheet, args.margin_mm, args.brush))?;
    let img = calibration_sheet_image(&cal, &profile, LAYOUT_PX_PER_MM);
    let _lock = OutputLock::acquire("--output", &args.output)?;
    recover_leftovers(&args.output)?;
    check_output_folder("--output", &args.output, args.force)?;
    let stage = Stage::new(&args.output)?;
    write_atomic(&stage.path().join("track.json"), serde_json::to_string_pretty(&cal.track)?.as_bytes())?;
    write_atomic(&stage.path().join("layout.json"), serde_json::to_string_pretty(&cal.layout)?.as_bytes())?;
    write_atomic(&stage.path().join("layout.png"), &img.encode_png()?)?;
    stage.install("--output", &args.output, args.force)?;
    let r = &cal.layout.ranges;
    crate::outln!(
        "{} presses of {} (h {}–{} mm, α {:.1}–{:.1}°, β {:.1}–{:.1}°) on the {} sheet with {} registration marks; outputs in {}",
        cal.layout.presses.len(),
        profile.name,
        r.h_mm.min,
        r.h_mm.max,
        r.alpha_rad.min.to_degrees(),
        r.alpha_rad.max.to_degrees(),
        r.beta_rad.min.to_degrees(),
        r.beta_rad.max.to_degrees(),
        sheet.name,
        cal.layout.marks.len(),
        args.output.display()
    )?;
    crate::outln!(
        "next: `maobi robot send {} --paper paper.json --host …` (or `robot export` it), photograph the sheet, then `maobi calibrate --sheet-photo PHOTO --layout {} -o brush.json`",
        args.output.join("track.json").display(),
        args.output.display()
    )?;
    Ok(())
}
