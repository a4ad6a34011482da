//! Registration marks: a few small inked rings at known paper positions in a sheet's margin,
//! written by the robot before the characters, so a photograph of the sheet can be mapped onto
//! the paper frame (`observe`, docs/closed-loop.md).
//!
//! Six marks: one near each corner of the sheet, a *key* mark beside the top-left one (it tells
//! which corner is which, so a photo taken upside down still maps the right way round) and one
//! in the middle of the bottom edge (a sixth point, so the fit has a residual). Each mark is a
//! horizontal bar made of two short strokes pressed lightly that end at the mark's centre from
//! opposite sides: the second is the first turned half a turn about the centre, so for any brush
//! that writes the same way in every direction, however wide or long its footprints or however
//! its hairs lag, the centre of the mark's ink is the mark's centre.

use brush_model::{BrushProfile, Extrapolation, ForwardModel, Press, Stroke, TrackPoint};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::sheet::Layout;

/// How far each of a mark's two strokes moves before it reaches the centre (it then runs on
/// past it by the footprint's root length), mm.
pub const MARK_TRAVEL_MM: f64 = 1.0;

/// Where in the profile's depth range a mark is pressed (0 = the shallowest, 1 = the deepest).
pub const MARK_DEPTH_FRACTION: f64 = 0.0;

/// Spacing of a mark's track points, mm.
pub const MARK_SPACING_MM: f64 = 0.25;

/// Free paper kept between a mark's ink and the sheet's edge or a character box, mm.
pub const MARK_CLEARANCE_MM: f64 = 1.0;

/// Free paper between two marks along an edge, mm.
pub const MARK_GAP_MM: f64 = 10.0;

/// The margin an automatic layout (no sheet) is widened to when marks are asked for, mm.
pub const MARK_MARGIN_MM: f64 = 12.0;

/// Which mark a [`Mark`] is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MarkRole {
    /// Near the top-left corner.
    TopLeft,
    /// Near the top-right corner.
    TopRight,
    /// Near the bottom-right corner.
    BottomRight,
    /// Near the bottom-left corner.
    BottomLeft,
    /// Beside the top-left mark, along the top edge: tells the corners apart.
    Key,
    /// In the middle of the bottom edge.
    BottomMiddle,
}

impl MarkRole {
    /// Where the mark is, in words (`"top-left"`, `"key (beside the top-left)"`, …).
    pub fn name(self) -> &'static str {
        match self {
            MarkRole::TopLeft => "top-left",
            MarkRole::TopRight => "top-right",
            MarkRole::BottomRight => "bottom-right",
            MarkRole::BottomLeft => "bottom-left",
            MarkRole::Key => "key (beside the top-left)",
            MarkRole::BottomMiddle => "bottom-middle",
        }
    }
}

/// One registration mark on the paper: a horizontal bar of ink centred on `centre_mm`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Mark {
    /// Which mark.
    pub role: MarkRole,
    /// The centre of its ink, paper mm.
    pub centre_mm: [f64; 2],
    /// Half its ink's length along paper x with the profile it was made for, mm.
    pub half_length_mm: f64,
    /// Half its ink's width along paper y with the profile it was made for, mm.
    pub half_width_mm: f64,
}

/// Why marks could not be placed.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum MarkError {
    /// The margin is too narrow for the marks.
    #[error(
        "a margin of {margin_mm:.1} mm leaves no room for the registration marks: they need at least {needed_mm:.1} mm with this brush"
    )]
    NoRoom {
        /// The layout's margin, mm.
        margin_mm: f64,
        /// The margin the marks need, mm.
        needed_mm: f64,
    },
    /// The sheet is too narrow for the marks along its top edge.
    #[error(
        "a sheet {width_mm:.0} mm wide has no room for the registration marks along its top edge (they need {needed_mm:.0} mm)"
    )]
    TooNarrow {
        /// The sheet's width, mm.
        width_mm: f64,
        /// The width the marks need, mm.
        needed_mm: f64,
    },
    /// The brush profile refused the mark's press.
    #[error("the brush cannot press a registration mark")]
    Profile(#[from] brush_model::ProfileError),
}

/// The press depth of a mark with `profile`, mm.
fn mark_h_mm(profile: &BrushProfile) -> f64 {
    let r = profile.ranges.h_mm;
    r.min + MARK_DEPTH_FRACTION * (r.max - r.min)
}

/// The registration marks of a layout: six horizontal bars in its top and bottom margins,
/// their centres `margin / 2` in from the top or bottom edge, the corner ones' ends `margin / 2`
/// in from the sides, the key mark [`MARK_GAP_MM`] beside the top-left one ([`MarkRole`] says
/// where each sits).
///
/// # Errors
/// [`MarkError::NoRoom`] when the margin cannot hold a mark's ink clear of the edge and of the
/// character boxes ([`MARK_CLEARANCE_MM`] each side), [`MarkError::TooNarrow`] when the top edge
/// cannot hold three marks; [`MarkError::Profile`] when the profile refuses the mark's press.
///
/// # Examples
/// ```
/// let pen1 = brush_model::BrushProfile::builtin("pen1")?;
/// let a4 = pipeline::parse_sheet("A4")?;
/// let layout = pipeline::layout_on_sheet(&a4, 4, pipeline::Flow::Columns, None, 20.0, None)?;
/// let marks = pipeline::registration_marks(&layout, &pen1)?;
/// assert_eq!(marks.len(), 6);
/// assert_eq!(marks[0].centre_mm[1], 10.0);
/// assert!(marks[0].centre_mm[0] - marks[0].half_length_mm >= 10.0);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn registration_marks(layout: &Layout, profile: &BrushProfile) -> Result<Vec<Mark>, MarkError> {
    let fp = profile.predict(&Press::new(mark_h_mm(profile), 0.0, 0.0), Extrapolation::Refuse)?;
    let half_length_mm = fp.lt_mm + fp.lh_mm + MARK_TRAVEL_MM;
    let half_width_mm = fp.lr_mm;
    let m = layout.margin_mm;
    let needed_mm = 2.0 * (half_width_mm + MARK_CLEARANCE_MM);
    if !(m >= needed_mm) {
        return Err(MarkError::NoRoom { margin_mm: m, needed_mm });
    }
    let (w, h) = (layout.sheet.width_mm, layout.sheet.height_mm);
    // Between marks along an edge: room for the search window of each (MARK_GAP_MM).
    let step = 2.0 * half_length_mm + MARK_GAP_MM;
    let needed_w = m + 3.0 * step - MARK_GAP_MM;
    if w < needed_w {
        return Err(MarkError::TooNarrow { width_mm: w, needed_mm: needed_w });
    }
    // As far in from the sides as from the top and bottom edges: a photo's paper edge is soft.
    let (x_left, x_right) = (m / 2.0 + half_length_mm, w - m / 2.0 - half_length_mm);
    let (y_top, y_bottom) = (m / 2.0, h - m / 2.0);
    let at = |role, x, y| Mark { role, centre_mm: [x, y], half_length_mm, half_width_mm };
    Ok(vec![
        at(MarkRole::TopLeft, x_left, y_top),
        at(MarkRole::TopRight, x_right, y_top),
        at(MarkRole::BottomRight, x_right, y_bottom),
        at(MarkRole::BottomLeft, x_left, y_bottom),
        at(MarkRole::Key, x_left + step, y_top),
        at(MarkRole::BottomMiddle, w / 2.0, y_bottom),
    ])
}

/// The strokes that write `marks`, two per mark: each presses at the shallowest depth of the
/// profile ([`MARK_DEPTH_FRACTION`]), starts [`MARK_TRAVEL_MM`] from the mark's centre and runs
/// through it and on by the footprint's root length, the first from the left, the second from
/// the right, upright, with each footprint's direction
/// as the forward model gives it.
pub fn mark_strokes(marks: &[Mark], profile: &BrushProfile) -> Vec<Stroke> {
    let h = mark_h_mm(profile);
    let model = ForwardModel::default();
    // Each stroke runs on past the centre by the footprint's root length, so the two
    // footprints' bellies meet at the centre and the mark is one blob of ink.
    let past = profile.predict(&Press::new(h, 0.0, 0.0), Extrapolation::Refuse).map_or(0.0, |f| f.lh_mm);
    let travel = MARK_TRAVEL_MM + past;
    let n = (travel / MARK_SPACING_MM).ceil().max(2.0) as usize;
    let mut out = Vec::with_capacity(2 * marks.len());
    for m in marks {
        for side in [-1.0, 1.0] {
            let points: Vec<TrackPoint> = (0..=n)
                .map(|k| TrackPoint {
                    x_mm: m.centre_mm[0] + side * (MARK_TRAVEL_MM - travel * k as f64 / n as f64),
                    y_mm: m.centre_mm[1],
                    h_mm: h,
                    alpha_rad: 0.0,
                    beta_rad: 0.0,
                })
                .collect();
            out.push(Stroke { points: model.with_directions(profile, &points, Extrapolation::Refuse) });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sheet::{Flow, layout_on_sheet, parse_sheet};

    #[test]
    fn marks_sit_in_the_margin_clear_of_boxes_and_edges() {
        let pen1 = BrushProfile::builtin("pen1").unwrap();
        let a4 = parse_sheet("A4").unwrap();
        let l = layout_on_sheet(&a4, 6, Flow::Columns, None, 20.0, None).unwrap();
        let marks = registration_marks(&l, &pen1).unwrap();
        assert_eq!(marks.len(), 6);
        for m in &marks {
            let [x, y] = m.centre_mm;
            let (hl, hw) = (m.half_length_mm, m.half_width_mm);
            assert!(x - hl > 0.0 && y - hw > 0.0 && x + hl < 210.0 && y + hw < 297.0, "{m:?}");
            for b in &l.boxes {
                let apart = x + hl < b.x0_mm
                    || x - hl > b.x0_mm + b.size_mm
                    || y + hw < b.y0_mm
                    || y - hw > b.y0_mm + b.size_mm;
                assert!(apart, "{m:?} touches {b:?}");
            }
        }
        let strokes = mark_strokes(&marks, &pen1);
        assert_eq!(strokes.len(), 12);
        for (pair, m) in strokes.chunks(2).zip(&marks) {
            // The second stroke is the first turned half a turn about the centre.
            for (a, b) in pair[0].points.iter().zip(&pair[1].points) {
                assert!((a.x_mm + b.x_mm - 2.0 * m.centre_mm[0]).abs() < 1e-9);
                assert!((a.y_mm - m.centre_mm[1]).abs() < 1e-12 && (b.y_mm - m.centre_mm[1]).abs() < 1e-12);
                assert!(a.is_pressed() && b.is_pressed());
            }
        }
        // A margin too narrow is refused with the margin needed.
        let tight = layout_on_sheet(&a4, 6, Flow::Columns, None, 5.0, None).unwrap();
        let e = registration_marks(&tight, &pen1).unwrap_err();
        assert!(matches!(e, MarkError::NoRoom { needed_mm, .. } if needed_mm > 5.0), "{e}");
    }
}
