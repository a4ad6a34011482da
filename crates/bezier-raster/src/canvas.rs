//! The single-footprint canvas convention used by `maobi stroke`, the dataset and the neural
//! generator.

use brush_model::{BrushProfile, Footprint, PointMm};
use serde::{Deserialize, Serialize};

/// A square canvas for one footprint: `size × size` px at `px_per_mm`.
///
/// The default scale ([`StrokeCanvas::for_profile`]) makes the largest footprint of the brush's
/// calibrated range fit at any rotation with a 5 % margin: `px_per_mm = 0.95·size / D`, where `D`
/// is the largest diagonal of a footprint's own-frame bounding box over the range corners
/// ([`BrushProfile::max_extent_mm`]). Each footprint is then placed so that the centre of its
/// rotated bounding box falls on the canvas centre ([`StrokeCanvas::anchor_mm`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StrokeCanvas {
    /// Side length, px.
    pub size: u32,
    /// Scale, px per mm.
    pub px_per_mm: f64,
}

impl StrokeCanvas {
    /// The default canvas for a profile (see the type's docs).
    pub fn for_profile(profile: &BrushProfile, size: u32) -> Self {
        let d = profile.max_extent_mm().max(1e-6);
        Self { size, px_per_mm: 0.95 * size as f64 / d }
    }

    /// A canvas with an explicit scale.
    pub fn with_scale(size: u32, px_per_mm: f64) -> Self {
        Self { size, px_per_mm }
    }

    /// Side length, mm.
    pub fn size_mm(&self) -> f64 {
        self.size as f64 / self.px_per_mm
    }

    /// The anchor (mm from the canvas's top-left corner) that centres this footprint's rotated
    /// outline on the canvas.
    pub fn anchor_mm(&self, fp: &Footprint, beta_rad: f64) -> PointMm {
        let c = fp.placed_bounds(PointMm::default(), beta_rad).centre();
        let half = 0.5 * self.size_mm();
        PointMm::new(half - c.x_mm, half - c.y_mm)
    }

    /// The same anchor in pixel coordinates (x right, y down; pixel centres at `i + 0.5`).
    pub fn anchor_px(&self, fp: &Footprint, beta_rad: f64) -> [f64; 2] {
        let a = self.anchor_mm(fp, beta_rad);
        [a.x_mm * self.px_per_mm, a.y_mm * self.px_per_mm]
    }
}
