//! The single-footprint canvas convention used by `maobi stroke`, the dataset and the neural
//! generator.

use brush_model::{BrushProfile, Footprint, PointMm};

use crate::{Coverage, Rasterizer, StrokeModel, svg_document};
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

    /// The footprint `fp` turned by `beta_rad`, drawn by `model` centred on this canvas
    /// ([`StrokeCanvas::anchor_mm`]): `size × size` coverage (1 = ink).
    ///
    /// # Examples
    /// ```
    /// use bezier_raster::{Bsm, StrokeCanvas};
    /// use bezier_raster::brush_model::Footprint;
    /// let fp = Footprint { lt_mm: 8.0, lh_mm: 2.0, lr_mm: 1.5 };
    /// let img = StrokeCanvas::with_scale(64, 4.0).draw(&Bsm, &fp, 0.3);
    /// assert_eq!((img.width(), img.height()), (64, 64));
    /// assert!(img.ink() > 50.0, "about π·lr·(lt + lh)/2 mm² at 16 px/mm²");
    /// ```
    pub fn draw(&self, model: &dyn StrokeModel, fp: &Footprint, beta_rad: f64) -> Coverage {
        let mut img = Coverage::new(self.size, self.size);
        Rasterizer::new().render(model, fp, self.anchor_mm(fp, beta_rad), beta_rad, self.px_per_mm, &mut img);
        img
    }

    /// The same footprint's outline as an SVG document of the canvas, [`StrokeCanvas::size_mm`]
    /// square in mm ([`svg_document`]).
    pub fn svg(&self, model: &dyn StrokeModel, fp: &Footprint, beta_rad: f64) -> String {
        let path = model.outline(fp, self.anchor_mm(fp, beta_rad), beta_rad);
        svg_document(&path, self.size_mm(), self.size_mm())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Bsm;

    #[test]
    fn a_drawn_footprint_is_centred_and_its_svg_is_the_same_outline() {
        let fp = Footprint { lt_mm: 9.0, lh_mm: 3.0, lr_mm: 2.0 };
        let canvas = StrokeCanvas::with_scale(96, 5.0);
        let img = canvas.draw(&Bsm, &fp, 1.0);
        // The ink's bounding box is centred on the canvas to within a pixel.
        let (mut x0, mut y0, mut x1, mut y1) = (u32::MAX, u32::MAX, 0, 0);
        for y in 0..96 {
            for x in 0..96 {
                if img.get(x, y) > 0.5 {
                    (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
                }
            }
        }
        let centre = |a: u32, b: u32| 0.5 * (a + b + 1) as f64;
        assert!((centre(x0, x1) - 48.0).abs() <= 1.0 && (centre(y0, y1) - 48.0).abs() <= 1.0, "{x0}..{x1}, {y0}..{y1}");
        let svg = canvas.svg(&Bsm, &fp, 1.0);
        assert!(svg.contains("width=\"19.2mm\""), "{svg}");
        let path = Bsm.outline(&fp, canvas.anchor_mm(&fp, 1.0), 1.0).to_svg();
        assert!(svg.contains(&path));
    }
}
