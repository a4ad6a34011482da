//! The sheet-photo path of `maobi calibrate --sheet-photo`: the footprints of a calibration
//! sheet (`maobi calibrate-sheet`) measured on one photo of it (docs/closed-loop.md,
//! "Calibration sheet").

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use brush_model::{Brush, Footprint, Measurement};
use observe::{Photo, ink_map, measure_footprint, register};
use pipeline::CalibrationLayout;
use rayon::prelude::*;

use crate::common::progress;

/// How far (degrees) a measured footprint may point from its press's direction.
const MAX_DIRECTION_DEG: f64 = 20.0;

/// How far (mm) a measured footprint's root may lie from its press point.
const MAX_ROOT_MM: f64 = 5.0;

/// Below this share of the presses measured the photo is refused as not of the sheet.
const MIN_MEASURED_SHARE: f64 = 0.75;

/// Reads `CAL/layout.json` (or the file itself).
fn load_layout(cal: &Path) -> Result<(PathBuf, CalibrationLayout)> {
    let path = if cal.is_dir() { cal.join("layout.json") } else { cal.to_path_buf() };
    let text = std::fs::read_to_string(&path).with_context(|| format!("--layout: cannot read {}", path.display()))?;
    let layout: CalibrationLayout = serde_json::from_str(&text).with_context(|| {
        format!(
            "--layout: {} is not a calibration sheet's layout.json (written by `maobi calibrate-sheet`)",
            path.display()
        )
    })?;
    if layout.kind != "calibration-sheet" || layout.version != pipeline::CALIBRATION_LAYOUT_VERSION {
        bail!(
            "--layout: {} is a `{}` layout of version {}; expected a calibration-sheet layout of version {}",
            path.display(),
            layout.kind,
            layout.version,
            pipeline::CALIBRATION_LAYOUT_VERSION
        );
    }
    if layout.presses.is_empty() {
        bail!("--layout: {} lists no presses", path.display());
    }
    check_layout(&path, &layout)?;
    Ok((path, layout))
}

/// The largest press cell a calibration layout read back may hold, mm a side (each is measured
/// at up to 10 px per mm: 2,500 px).
const MAX_CELL_MM: f64 = 250.0;

/// The most presses a calibration layout read back may list.
const MAX_PRESSES: usize = 10_000;

/// Checks what a calibration layout read back may hold before anything is sized from it: the
/// sheet, the number of presses and marks, every press's cell (finite, on the sheet, at most
/// [`MAX_CELL_MM`] a side) and its press values.
fn check_layout(path: &Path, l: &CalibrationLayout) -> Result<()> {
    let bad =
        |field: String, what: String| -> Result<()> { bail!("--layout: {}: field `{field}`: {what}", path.display()) };
    let (w, h) = (l.sheet.width_mm, l.sheet.height_mm);
    if !([w, h].iter().all(|v| v.is_finite() && (10.0..=pipeline::MAX_SHEET_MM).contains(v))) {
        return bad("sheet".into(), format!("{w}×{h} mm: expected sides of 10..={} mm", pipeline::MAX_SHEET_MM));
    }
    if l.presses.len() > MAX_PRESSES {
        return bad("presses".into(), format!("{} presses: expected at most {MAX_PRESSES}", l.presses.len()));
    }
    if l.marks.len() > 6 {
        return bad("marks".into(), format!("{} marks: a sheet has at most 6", l.marks.len()));
    }
    for (i, m) in l.marks.iter().enumerate() {
        let [x, y] = m.centre_mm;
        let sizes = [m.half_length_mm, m.half_width_mm];
        let on = x.is_finite() && y.is_finite() && (0.0..=w).contains(&x) && (0.0..=h).contains(&y);
        if !(on && sizes.iter().all(|v| v.is_finite() && *v > 0.0 && *v <= MAX_CELL_MM)) {
            return bad(format!("marks[{i}]"), "expected a mark on the sheet, its half sizes 0..=250 mm".into());
        }
    }
    for (i, p) in l.presses.iter().enumerate() {
        let [x0, y0, x1, y1] = p.cell_mm;
        let on = [x0, y0, x1, y1].iter().all(|v| v.is_finite()) && x0 >= 0.0 && y0 >= 0.0 && x1 <= w && y1 <= h;
        if !(on && x1 > x0 && y1 > y0 && x1 - x0 <= MAX_CELL_MM && y1 - y0 <= MAX_CELL_MM) {
            return bad(
                format!("presses[{i}].cell_mm"),
                format!(
                    "[{x0}, {y0}, {x1}, {y1}] mm: expected a cell on the {w}×{h} mm sheet, at most {MAX_CELL_MM} mm a side"
                ),
            );
        }
        let values = [p.h_mm, p.alpha_rad, p.beta_rad, p.root_mm[0], p.root_mm[1]];
        if !values.iter().all(|v| v.is_finite()) {
            return bad(format!("presses[{i}]"), "expected finite h_mm, alpha_rad, beta_rad and root_mm".into());
        }
    }
    Ok(())
}

/// The sheet photo measured: the marks found, every press's footprint fitted on the paper; the
/// presses that could not be measured, or whose fit is poor (IoU under `min_iou`), points the
/// wrong way or lies away from its press point, are listed and left out; fewer than three
/// quarters measured refuses the photo. Returns the measurements, `measurements.csv`'s text
/// (written by the caller once the fit is accepted) and the brush the sheet was made for.
pub fn measure(photo_path: &Path, cal: &Path, min_iou: f64) -> Result<(Vec<Measurement>, String, Brush)> {
    let (path, layout) = load_layout(cal)?;
    let marks = match pipeline::known_marks(&layout.marks) {
        Some(marks) if layout.marks.len() >= 5 => marks,
        _ => bail!("--layout: {} lacks registration marks (four corners and at least one more)", path.display()),
    };
    let what = || format!("--sheet-photo {}", photo_path.display());
    let img = bezier_raster::decode_image(photo_path).with_context(what)?;
    let photo = Photo::from_image(&img).with_context(what)?;
    let ink = ink_map(&photo).with_context(what)?;
    let reg = register(&ink, &marks).with_context(what)?;
    let pb = progress(layout.presses.len() as u64, "measuring");
    let results: Vec<_> = layout
        .presses
        .par_iter()
        .map(|p| {
            let r = measure_footprint(&ink, &reg, p.cell_mm);
            pb.inc(1);
            r
        })
        .collect();
    pb.finish_and_clear();
    let mut csv = format!("press,{},iou,used\n", brush_model::MEASUREMENT_COLUMNS);
    let mut rows = Vec::new();
    let mut left_out = Vec::new();
    for (p, r) in layout.presses.iter().zip(results) {
        let label = format!("P{:02}", p.number);
        let m = match r {
            Ok(m) => m,
            Err(e) => {
                left_out.push(format!("{label}: {e}"));
                continue;
            }
        };
        let turn = brush_model::wrap_angle_rad(m.beta_rad - p.beta_rad).abs().to_degrees();
        let off = (m.root_mm[0] - p.root_mm[0]).hypot(m.root_mm[1] - p.root_mm[1]);
        let why = if m.iou < min_iou {
            Some(format!("fit IoU {:.3} below --min-iou {min_iou}", m.iou))
        } else if turn > MAX_DIRECTION_DEG {
            Some(format!("points {turn:.0}° away from the press's direction"))
        } else if off > MAX_ROOT_MM {
            Some(format!("its root end lies {off:.1} mm from the press point"))
        } else {
            None
        };
        let measured =
            Measurement { press: p.press(), footprint: Footprint { lt_mm: m.lt_mm, lh_mm: m.lh_mm, lr_mm: m.lr_mm } };
        let fields = brush_model::measurement_fields(&measured, Some(4));
        csv.push_str(&format!("{label},{fields},{:.4},{}\n", m.iou, why.is_none()));
        match why {
            Some(w) => left_out.push(format!("{label}: {w}")),
            None => rows.push(measured),
        }
    }
    let n = layout.presses.len();
    if (rows.len() as f64) < MIN_MEASURED_SHARE * n as f64 {
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
    Ok((rows, csv, layout.brush_size))
}
