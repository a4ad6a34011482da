//! The sheet-photo path of `maobi calibrate --sheet-photo`: the footprints of a calibration
//! sheet (`maobi calibrate-sheet`) measured on one photo of it (docs/closed-loop.md,
//! "Calibration sheet"); the reading is the pipeline's ([`pipeline::read_calibration_sheet`]).

use std::path::Path;

use anyhow::{Context, Result, bail};
use brush_model::{Brush, Measurement};
use observe::{SheetPhoto, read_sheet_photo};
use pipeline::{CalibrationLayout, LeftOut};

use crate::common::progress;

/// The sheet photo measured: the marks found, every press's footprint fitted on the paper; the
/// presses that could not be measured, or whose fit is poor (IoU under `min_iou`), points the
/// wrong way or lies away from its press point, are listed and left out; fewer than three
/// quarters measured refuses the photo. Returns the measurements, `measurements.csv`'s text
/// (written by the caller once the fit is accepted) and the brush the sheet was made for.
pub fn measure(photo_path: &Path, cal: &Path, min_iou: f64) -> Result<(Vec<Measurement>, String, Brush)> {
    let path = if cal.is_dir() { cal.join("layout.json") } else { cal.to_path_buf() };
    let layout = CalibrationLayout::load(&path).context("--layout")?;
    let Some(marks) = layout.registration_marks() else {
        bail!("--layout: {} lacks registration marks (four corners and at least one more)", path.display());
    };
    let what = || format!("--sheet-photo {}", photo_path.display());
    let SheetPhoto { ink, registration: reg, .. } = read_sheet_photo(photo_path, &marks).with_context(what)?;
    let pb = progress(layout.presses.len() as u64, "measuring");
    let reading = pipeline::read_calibration_sheet(&layout, &ink, &reg, min_iou, &|| pb.inc(1));
    pb.finish_and_clear();
    let left_out: Vec<String> = reading
        .presses
        .iter()
        .filter_map(|p| {
            p.left_out.as_ref().map(|why| match why {
                LeftOut::PoorFit { iou, .. } => format!("{}: fit IoU {iou:.3} below --min-iou {min_iou}", p.label()),
                why => format!("{}: {why}", p.label()),
            })
        })
        .collect();
    let (rows, n) = (reading.used(), layout.presses.len());
    if !reading.enough() {
        bail!(
            "{}: only {} of the {n} presses of {} were found as single footprints (first: {}): a photo of another sheet?",
            what(),
            rows.len(),
            path.display(),
            left_out.first().map_or("", String::as_str)
        );
    }
    eprintln!(
        "marks: residual {:.2} mm RMS, {:.2} mm max; photo {:.1} px/mm, edges {:.2} mm",
        reg.residual_rms_mm, reg.residual_max_mm, reg.px_per_mm, reg.edge_mm
    );
    if !left_out.is_empty() {
        eprintln!("left out {} press(es): {}", left_out.len(), left_out.join("; "));
    }
    eprintln!("measured {} press(es), {} used", n, rows.len());
    Ok((rows, reading.csv(), layout.brush_size))
}
