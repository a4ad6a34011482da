//! The calibration sheet: a grid of single presses at chosen `(h, α, β)` spanning a brush
//! profile's calibrated range, with registration marks, so that one photo of the sheet gives
//! the footprint measurements a regression needs (the paper's §3.1 calibration, with the robot
//! pressing and a camera measuring; docs/closed-loop.md, "Calibration sheet").
//!
//! Each press is one stroke of three points at the press's tilt and lean: the brush touches
//! the paper lightly ([`PRESS_TOUCH_FRACTION`] of the shallowest calibrated press, too light
//! to leave a footprint) [`PRESS_SLIDE_MM`] ahead of the press point, slides back to it (an
//! upright brush's hairs now trail the way the footprint is to point) and presses straight down
//! to `h`. The footprint left is the one of the deepest state, rooted at the press point and
//! pointing along `β`, whatever the brush's tilt.

use bezier_raster::{Coverage, ModelKind};
use brush_model::{
    Brush, BrushProfile, Extrapolation, Footprint, ForwardModel, PointMm, Press, PressRanges, Range, Stroke, Track,
    TrackPoint,
};
use robot_io::{RobotConfig, build_program_chars};
use serde::{Deserialize, Serialize};
use thiserror::Error;
use trajectory::CharBox;

use crate::sheet::{Flow, Grid, Layout, Sheet, SheetTrack};
use crate::{Mark, MarkError, registration_marks};

/// Version of `layout.json` ([`CalibrationLayout`]).
pub const CALIBRATION_LAYOUT_VERSION: u32 = 1;

/// Depths per press grid: the h range's two ends and evenly spaced levels between.
pub const PRESS_H_LEVELS: usize = 4;
/// Tilts per press grid (α range's ends and between).
pub const PRESS_ALPHA_LEVELS: usize = 3;
/// Lean directions per press grid (β range's ends and between).
pub const PRESS_BETA_LEVELS: usize = 2;

/// How far ahead of the press point (along its direction) the brush touches down before
/// sliding back to it, mm.
pub const PRESS_SLIDE_MM: f64 = 1.0;

/// The slide's depth as a fraction of the profile's shallowest calibrated press (light enough
/// that the model leaves no footprint there).
pub const PRESS_TOUCH_FRACTION: f64 = 0.25;

/// Room in each cell for a brush this much larger than its profile says.
pub const CELL_GROWTH: f64 = 1.4;

/// Free paper between two cells, mm.
pub const CELL_GAP_MM: f64 = 4.0;

/// Why a calibration sheet could not be made.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum CalibrationSheetError {
    /// The presses do not fit on the sheet.
    #[error(
        "{presses} presses in cells of {cell_w_mm:.0}×{cell_h_mm:.0} mm need more room than the {sheet} sheet leaves inside a {margin_mm} mm margin ({cols} × {rows} cells fit)"
    )]
    NoRoom {
        /// Presses to place.
        presses: usize,
        /// Cell width, mm.
        cell_w_mm: f64,
        /// Cell height, mm.
        cell_h_mm: f64,
        /// The sheet's name.
        sheet: String,
        /// The margin, mm.
        margin_mm: f64,
        /// Cells that fit across.
        cols: usize,
        /// Cells that fit down.
        rows: usize,
    },
    /// The registration marks could not be placed.
    #[error("the registration marks do not fit")]
    Marks(#[from] MarkError),
    /// The profile refused a press of its own range.
    #[error("the brush profile cannot predict a press of its own range")]
    Profile(#[from] brush_model::ProfileError),
    /// The robot program of the sheet failed its check.
    #[error("the calibration sheet's robot program fails its check")]
    Program(#[from] robot_io::RobotError),
}

/// One press of the sheet.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CalibrationPress {
    /// Its number on the sheet, from 1, in writing order.
    pub number: usize,
    /// The press point: the footprint's root end, paper mm.
    pub root_mm: [f64; 2],
    /// Press depth, mm.
    pub h_mm: f64,
    /// Tilt, rad.
    pub alpha_rad: f64,
    /// Lean (and footprint) direction, rad from paper +x towards +y.
    pub beta_rad: f64,
    /// Its cell, the paper it alone inks: `[x0, y0, x1, y1]`, mm.
    pub cell_mm: [f64; 4],
    /// What the profile predicts for it.
    pub predicted: Footprint,
}

impl CalibrationPress {
    /// The press `(h, α, β)`.
    pub fn press(&self) -> Press {
        Press::new(self.h_mm, self.alpha_rad, self.beta_rad)
    }
}

/// `layout.json`: where each press of a calibration sheet is and how it was pressed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CalibrationLayout {
    /// Format version ([`CALIBRATION_LAYOUT_VERSION`]).
    pub version: u32,
    /// `"calibration-sheet"`.
    pub kind: String,
    /// The sheet.
    pub sheet: Sheet,
    /// The margin kept free on every side, mm.
    pub margin_mm: f64,
    /// The profile the sheet was made with (its name; its ranges are what the presses span).
    pub brush: String,
    /// That profile's brush (length and radius, mm): what a profile calibrated from the sheet
    /// records.
    pub brush_size: Brush,
    /// The ranges the presses span.
    pub ranges: PressRanges,
    /// The registration marks.
    pub marks: Vec<Mark>,
    /// The presses, in writing order.
    pub presses: Vec<CalibrationPress>,
}

/// A calibration sheet: its layout and its track (marks first, then one stroke per press).
#[derive(Clone, Debug)]
pub struct CalibrationSheet {
    /// Where each press is.
    pub layout: CalibrationLayout,
    /// The sheet track (`track.json`), checked as a robot program.
    pub track: SheetTrack,
}

/// `n` evenly spaced values over `r` (one when the range is a point).
fn levels(r: Range, n: usize) -> Vec<f64> {
    if n <= 1 || !(r.max - r.min > 1e-12) {
        return vec![r.min];
    }
    (0..n).map(|i| r.lerp(i as f64 / (n - 1) as f64)).collect()
}

/// The seed of the order presses are laid out in.
const ORDER_SEED: u64 = 28;

/// `0..n` shuffled (Fisher–Yates on a SplitMix64 stream from [`ORDER_SEED`]): the same order
/// every time, unrelated to the grid's rows and columns.
fn shuffled(n: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..n).collect();
    let mut rng = numerics::SplitMix64(ORDER_SEED);
    for i in (1..n).rev() {
        let j = (rng.next_u64() % (i as u64 + 1)) as usize;
        order.swap(i, j);
    }
    order
}

/// The three track points of a press (see the module doc).
pub fn press_stroke(p: &CalibrationPress, profile: &BrushProfile) -> Stroke {
    let touch = PRESS_TOUCH_FRACTION * profile.ranges.h_mm.min;
    let (s, c) = p.beta_rad.sin_cos();
    let at =
        |x: f64, y: f64, h: f64| TrackPoint { x_mm: x, y_mm: y, h_mm: h, alpha_rad: p.alpha_rad, beta_rad: p.beta_rad };
    let [x, y] = p.root_mm;
    Stroke {
        points: vec![at(x + PRESS_SLIDE_MM * c, y + PRESS_SLIDE_MM * s, touch), at(x, y, touch), at(x, y, p.h_mm)],
    }
}

/// Lays out a calibration sheet for `profile` on `sheet`: the full grid of
/// [`PRESS_H_LEVELS`] × [`PRESS_ALPHA_LEVELS`] × [`PRESS_BETA_LEVELS`] presses over the
/// profile's calibrated ranges, each in its own cell (room for a brush [`CELL_GROWTH`] times
/// larger than the profile says, [`CELL_GAP_MM`] between cells), the cells centred inside
/// `margin_mm` and filled row by row in a fixed shuffled order (so a press's place on the sheet,
/// and the light there in a photo, is unrelated to its depth or tilt), the registration marks
/// in the margin; the track's program is built and checked on a level sheet in front of the arm
/// with the default `robot.json`.
///
/// # Errors
/// [`CalibrationSheetError::NoRoom`] when the cells do not fit, [`CalibrationSheetError::Marks`]
/// when the marks do not, [`CalibrationSheetError::Profile`] and
/// [`CalibrationSheetError::Program`] when the profile or the program check refuses a press.
///
/// # Examples
/// ```
/// let pen1 = brush_model::BrushProfile::builtin("pen1")?;
/// let a4 = pipeline::parse_sheet("A4")?;
/// let cal = pipeline::calibration_sheet(&a4, 15.0, &pen1)?;
/// assert_eq!(cal.layout.presses.len(), 24);
/// assert_eq!(cal.track.strokes.len(), 12 + 24);
/// // The presses span the profile's depth range.
/// let h = |f: fn(f64, f64) -> f64| cal.layout.presses.iter().map(|p| p.h_mm).reduce(f).unwrap();
/// assert_eq!((h(f64::min), h(f64::max)), (11.0, 20.0));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn calibration_sheet(
    sheet: &Sheet,
    margin_mm: f64,
    profile: &BrushProfile,
) -> Result<CalibrationSheet, CalibrationSheetError> {
    let r = profile.ranges;
    let mut presses = Vec::new();
    for &b in &levels(r.beta_rad, PRESS_BETA_LEVELS) {
        for &a in &levels(r.alpha_rad, PRESS_ALPHA_LEVELS) {
            for &h in &levels(r.h_mm, PRESS_H_LEVELS) {
                presses.push(Press::new(h, a, b));
            }
        }
    }
    let n = presses.len();
    // The cell: the largest footprint at the most turned direction, grown.
    let mut len_max: f64 = 0.0;
    let mut width_max: f64 = 0.0;
    for c in r.corners() {
        let f = profile.predict(&c, Extrapolation::Refuse)?;
        len_max = len_max.max(f.length_mm());
        width_max = width_max.max(2.0 * f.lr_mm);
    }
    let along = CELL_GROWTH * len_max;
    let across = CELL_GROWTH * width_max;
    // The grown footprint's bounding box at each lean direction.
    let (mut cell_w, mut cell_h) = (0.0f64, 0.0f64);
    for b in levels(r.beta_rad, PRESS_BETA_LEVELS) {
        let (s, c) = (b.sin().abs(), b.cos().abs());
        cell_w = cell_w.max(along * c + across * s);
        cell_h = cell_h.max(along * s + across * c);
    }
    let (cell_w, cell_h) = (cell_w + CELL_GAP_MM, cell_h + CELL_GAP_MM);
    let (uw, uh) = (sheet.width_mm - 2.0 * margin_mm, sheet.height_mm - 2.0 * margin_mm);
    let cols = if uw > 0.0 { (uw / cell_w).floor() as usize } else { 0 };
    let rows = if uh > 0.0 { (uh / cell_h).floor() as usize } else { 0 };
    if cols == 0 || cols * rows < n {
        return Err(CalibrationSheetError::NoRoom {
            presses: n,
            cell_w_mm: cell_w,
            cell_h_mm: cell_h,
            sheet: sheet.name.clone(),
            margin_mm,
            cols,
            rows,
        });
    }
    let used_rows = n.div_ceil(cols);
    let (x0, y0) = (margin_mm + (uw - cols as f64 * cell_w) / 2.0, margin_mm + (uh - used_rows as f64 * cell_h) / 2.0);
    let order = shuffled(n);
    let mut placed = Vec::with_capacity(n);
    for pos in 0..n {
        let press = presses[order[pos]];
        let (col, row) = (pos % cols, pos / cols);
        let cell = [
            x0 + col as f64 * cell_w,
            y0 + row as f64 * cell_h,
            x0 + (col + 1) as f64 * cell_w,
            y0 + (row + 1) as f64 * cell_h,
        ];
        let centre = [(cell[0] + cell[2]) / 2.0, (cell[1] + cell[3]) / 2.0];
        let (s, c) = press.beta_rad.sin_cos();
        // The grown footprint's extent centred in the cell.
        let root_mm = [centre[0] - along / 2.0 * c, centre[1] - along / 2.0 * s];
        placed.push(CalibrationPress {
            number: pos + 1,
            root_mm,
            h_mm: press.h_mm,
            alpha_rad: press.alpha_rad,
            beta_rad: press.beta_rad,
            cell_mm: cell,
            predicted: profile.predict(&press, Extrapolation::Refuse)?,
        });
    }
    let strokes: Vec<Stroke> = placed.iter().map(|p| press_stroke(p, profile)).collect();
    // A layout whose "characters" are the presses' cells (square boxes from each cell's
    // top-left corner), for the sheet track and the marks.
    let boxes: Vec<CharBox> = placed
        .iter()
        .map(|p| CharBox { x0_mm: p.cell_mm[0], y0_mm: p.cell_mm[1], size_mm: cell_h.min(cell_w) })
        .collect();
    let layout = Layout {
        sheet: sheet.clone(),
        boxes: boxes.clone(),
        char_mm: cell_h.min(cell_w),
        per_line: cols,
        lines: used_rows,
        margin_mm,
    };
    let marks = registration_marks(&layout, profile)?;
    let labels: Vec<String> = placed.iter().map(|p| format!("P{:02}", p.number)).collect();
    let chars: Vec<(String, CharBox, &[Stroke])> =
        labels.iter().zip(&boxes).zip(&strokes).map(|((l, b), s)| (l.clone(), *b, std::slice::from_ref(s))).collect();
    let mut track = SheetTrack::new(&layout, Flow::Rows, Grid::None, &chars, profile).with_marks(&marks, profile);
    track.char = "calibration sheet".into();
    check_program(&track, profile)?;
    let layout = CalibrationLayout {
        version: CALIBRATION_LAYOUT_VERSION,
        kind: "calibration-sheet".into(),
        sheet: sheet.clone(),
        margin_mm,
        brush: profile.name.clone(),
        brush_size: profile.brush,
        ranges: r,
        marks,
        presses: placed,
    };
    Ok(CalibrationSheet { layout, track })
}

/// Builds the sheet's robot program on a level sheet in front of the arm with the default
/// `robot.json`, as `robot check` would: every press and move within the envelope.
fn check_program(track: &SheetTrack, profile: &BrushProfile) -> Result<(), robot_io::RobotError> {
    let [w, h] = track.sheet_mm;
    let frame = robot_io::level_frame_in_front([w / 2.0, h / 2.0], [0.0, 0.0, w, h]);
    let t = Track { strokes: track.strokes.clone() };
    build_program_chars(&t, Some(&track.stroke_chars), profile, &frame, &RobotConfig::default())?;
    Ok(())
}

/// The sheet's planned ink (every stroke through the forward model, marks included) at
/// `px_per_mm`, the whole sheet, each press's cell outlined in light grey.
pub fn calibration_sheet_image(cal: &CalibrationSheet, profile: &BrushProfile, px_per_mm: f64) -> Coverage {
    let model = ForwardModel::default();
    let mut stamps = Vec::new();
    for s in &cal.track.strokes {
        for st in model.sweep(profile, &s.points, Extrapolation::Refuse).stamps {
            if let Ok(fp) = profile.predict_oriented(&st.press(), Extrapolation::Refuse) {
                stamps.push(bezier_raster::Stamp { footprint: fp, anchor: st.anchor(), beta_rad: st.beta_rad });
            }
        }
    }
    let [w, h] = cal.track.sheet_mm;
    let (wp, hp) = ((w * px_per_mm).ceil() as u32, (h * px_per_mm).ceil() as u32);
    let mut img =
        bezier_raster::render_stamps(&stamps, ModelKind::Bsm.model(), PointMm::new(0.0, 0.0), px_per_mm, wp, hp);
    // Each press's cell outlined faintly.
    let (wu, hu) = (wp as usize, hp as usize);
    let px = |v: f64, n: usize| ((v * px_per_mm) as usize).min(n - 1);
    let data = img.data_mut();
    for p in &cal.layout.presses {
        let [x0, y0, x1, y1] = p.cell_mm;
        let (i0, i1, j0, j1) = (px(x0, wu), px(x1, wu), px(y0, hu), px(y1, hu));
        for i in i0..=i1 {
            for j in [j0, j1] {
                data[j * wu + i] = data[j * wu + i].max(CELL_OUTLINE);
            }
        }
        for j in j0..=j1 {
            for i in [i0, i1] {
                data[j * wu + i] = data[j * wu + i].max(CELL_OUTLINE);
            }
        }
    }
    img
}

/// The grey level of a cell's outline in [`calibration_sheet_image`] (ink = 1).
const CELL_OUTLINE: f32 = 0.25;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parse_sheet;

    #[test]
    fn presses_span_the_range_in_their_own_cells_and_leave_one_footprint_each() {
        let pen1 = BrushProfile::builtin("pen1").unwrap();
        let cal = calibration_sheet(&parse_sheet("A4").unwrap(), 15.0, &pen1).unwrap();
        let p = &cal.layout.presses;
        assert_eq!(p.len(), PRESS_H_LEVELS * PRESS_ALPHA_LEVELS * PRESS_BETA_LEVELS);
        // Every combination once.
        let mut keys: Vec<(i64, i64, i64)> =
            p.iter().map(|q| ((q.h_mm * 1e6) as i64, (q.alpha_rad * 1e9) as i64, (q.beta_rad * 1e9) as i64)).collect();
        keys.sort_unstable();
        keys.dedup();
        assert_eq!(keys.len(), p.len());
        // Cells inside the margin, apart, and each holding its grown footprint.
        for (i, a) in p.iter().enumerate() {
            let c = a.cell_mm;
            assert!(c[0] >= 15.0 && c[1] >= 15.0 && c[2] <= 195.0 && c[3] <= 282.0, "{a:?}");
            for b in &p[i + 1..] {
                let d = b.cell_mm;
                assert!(c[2] <= d[0] + 1e-9 || d[2] <= c[0] + 1e-9 || c[3] <= d[1] + 1e-9 || d[3] <= c[1] + 1e-9);
            }
            let (s, co) = a.beta_rad.sin_cos();
            let tip = CELL_GROWTH * a.predicted.length_mm();
            let end = [a.root_mm[0] + tip * co, a.root_mm[1] + tip * s];
            for q in [a.root_mm, end] {
                assert!(q[0] > c[0] && q[0] < c[2] && q[1] > c[1] && q[1] < c[3], "{a:?}");
            }
        }
        // The order is shuffled: no column holds one depth only.
        let cols: Vec<f64> = {
            let mut x: Vec<f64> = p.iter().map(|q| q.cell_mm[0]).collect();
            x.sort_by(f64::total_cmp);
            x.dedup();
            x
        };
        for x in cols {
            let mut hs: Vec<f64> = p.iter().filter(|q| q.cell_mm[0] == x).map(|q| q.h_mm).collect();
            hs.dedup();
            assert!(hs.len() > 1, "column at x = {x} mm presses one depth only");
        }
        // The forward model leaves each press's own footprint, at its root, along β.
        let model = ForwardModel::default();
        for (a, s) in p.iter().zip(&cal.track.strokes[cal.track.mark_strokes..]) {
            let sweep = model.sweep(&pen1, &s.points, Extrapolation::Refuse);
            let last = sweep.stamps.last().unwrap();
            assert!((last.x_mm - a.root_mm[0]).abs() < 1e-9 && (last.y_mm - a.root_mm[1]).abs() < 1e-9);
            assert!((last.h_mm - a.h_mm).abs() < 1e-9);
            assert!(sweep.stamps.iter().all(|st| (st.beta_rad - a.beta_rad).abs() < 1e-9), "{a:?}");
            assert!(sweep.stamps.iter().all(|st| st.x_mm == a.root_mm[0] && st.y_mm == a.root_mm[1]));
        }
        // A sheet too small is refused, naming the room needed.
        let e = calibration_sheet(&parse_sheet("A6").unwrap(), 15.0, &pen1).unwrap_err();
        assert!(matches!(e, CalibrationSheetError::NoRoom { presses: 24, .. }), "{e}");
    }
}
