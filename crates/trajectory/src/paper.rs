//! Placement on paper: the [`CharBox`] that maps the em frame (1024 units, y down) onto paper
//! millimetres (origin top-left, x right, y down), and [`auto_char_mm`], its default size for a
//! brush.
//!
//! Invariant: the map is a uniform scale plus a shift (no rotation, no flip), so em half-widths
//! become mm half-widths by [`CharBox::mm_per_em`] alone.

use brush_model::{BrushProfile, PointMm};
use kurbo::Point;
use serde::{Deserialize, Serialize};

use crate::glyph::EM;
use crate::path::StrokePath;

/// Where a character sits on the paper: the em box maps onto the square
/// `[x0, x0 + size] × [y0, y0 + size]` mm. Em point `(x', y')` (y down) is at
/// `(x0 + x'/1024·size, y0 + y'/1024·size)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CharBox {
    /// Left edge, mm.
    pub x0_mm: f64,
    /// Top edge, mm.
    pub y0_mm: f64,
    /// Side, mm.
    pub size_mm: f64,
}

impl CharBox {
    /// Millimetres per em unit.
    pub fn mm_per_em(&self) -> f64 {
        self.size_mm / EM
    }
    /// An em-frame point on the paper.
    pub fn to_paper(&self, p: Point) -> PointMm {
        PointMm::new(self.x0_mm + p.x * self.mm_per_em(), self.y0_mm + p.y * self.mm_per_em())
    }
    /// A paper point in the em frame.
    pub fn to_em(&self, p: PointMm) -> Point {
        Point::new((p.x_mm - self.x0_mm) / self.mm_per_em(), (p.y_mm - self.y0_mm) / self.mm_per_em())
    }
}

/// The char box side (mm) [`auto_char_mm`] falls back to when the paths have no width or the
/// profile gives no belly width: a middle size for the built-in brushes, not tuned
/// (docs/trajectory.md, Tuned constants).
const FALLBACK_CHAR_MM: f64 = 60.0;

/// The lower percentile of the glyphs' half-widths [`auto_char_mm`] matches to the brush's
/// range (with [`CHAR_BOX_HIGH_PERCENTILE`]). Chosen on the tuning set (docs/trajectory.md,
/// Tuned constants).
const CHAR_BOX_LOW_PERCENTILE: f64 = 0.2;
/// The upper percentile ([`CHAR_BOX_LOW_PERCENTILE`]).
const CHAR_BOX_HIGH_PERCENTILE: f64 = 0.8;

/// The default char box size for a set of centre lines: the em scale that maps the glyphs'
/// typical half-widths (20th to 80th percentile over all points) onto the brush's belly
/// half-width range at tilt `alpha_rad`, matching their geometric middles. Returns mm.
///
/// # Examples
/// ```
/// use trajectory::brush_model::BrushProfile;
/// use trajectory::{Method, auto_char_mm, centre_lines, embedded_glyph};
/// let paths = centre_lines(&embedded_glyph('永').unwrap(), Method::Medians, 256).unwrap();
/// let pen1 = BrushProfile::builtin("pen1").unwrap();
/// let size_mm = auto_char_mm(&paths, &pen1, 0.0);
/// // A box in which pen1's widths match the glyph's strokes: about 12–17 cm for common characters.
/// assert!((100.0..200.0).contains(&size_mm));
/// ```
pub fn auto_char_mm(paths: &[StrokePath], profile: &BrushProfile, alpha_rad: f64) -> f64 {
    let mut w: Vec<f64> = paths.iter().flat_map(|p| p.half_widths.iter().copied()).filter(|v| *v > 0.0).collect();
    w.sort_by(f64::total_cmp);
    let beta = profile.ranges.beta_rad.min;
    let lr = |h: f64| profile.model.lr_mm.eval(h, alpha_rad, beta);
    let (lo, hi) = (lr(profile.ranges.h_mm.min), lr(profile.ranges.h_mm.max));
    if w.is_empty() || lo <= 0.0 || hi <= 0.0 {
        return FALLBACK_CHAR_MM;
    }
    let q = |f: f64| w[((w.len() - 1) as f64 * f).round() as usize];
    let (w20, w80) = (q(CHAR_BOX_LOW_PERCENTILE), q(CHAR_BOX_HIGH_PERCENTILE));
    let k = ((lo * hi) / (w20 * w80)).sqrt();
    k * EM
}
