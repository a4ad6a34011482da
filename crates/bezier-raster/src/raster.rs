//! Filling outlines into coverage images with tiny-skia.

use brush_model::{Footprint, PointMm};
use kurbo::{BezPath, PathEl, Shape};
use tiny_skia::{FillRule, Mask, PathBuilder, Transform};

use crate::coverage::Coverage;
use crate::models::StrokeModel;

/// A reusable rasteriser: keeps its scratch mask and path builder between calls so that
/// rendering many footprints allocates nothing after warm-up. Not `Sync`; use one per thread.
pub struct Rasterizer {
    mask: Option<Mask>,
}

impl Default for Rasterizer {
    fn default() -> Self {
        Self::new()
    }
}

/// Converts a path in mm to a tiny-skia path in pixels, offset by `(ox, oy)` px.
fn to_skia(path_mm: &BezPath, px_per_mm: f64, ox: f64, oy: f64) -> Option<tiny_skia::Path> {
    let mut b = PathBuilder::new();
    let t = |p: kurbo::Point| ((p.x * px_per_mm - ox) as f32, (p.y * px_per_mm - oy) as f32);
    for el in path_mm.elements() {
        match *el {
            PathEl::MoveTo(p) => {
                let (x, y) = t(p);
                b.move_to(x, y)
            }
            PathEl::LineTo(p) => {
                let (x, y) = t(p);
                b.line_to(x, y)
            }
            PathEl::QuadTo(p1, p2) => {
                let ((x1, y1), (x2, y2)) = (t(p1), t(p2));
                b.quad_to(x1, y1, x2, y2)
            }
            PathEl::CurveTo(p1, p2, p3) => {
                let ((x1, y1), (x2, y2), (x3, y3)) = (t(p1), t(p2), t(p3));
                b.cubic_to(x1, y1, x2, y2, x3, y3)
            }
            PathEl::ClosePath => b.close(),
        }
    }
    b.finish()
}

/// The pixel box `[x0, y0, width, height]` that [`Rasterizer::stamp`] draws `path_mm` into on a
/// `w × h` image (its bounding box widened by a pixel, clipped), `None` when empty.
pub(crate) fn stamp_box(path_mm: &BezPath, px_per_mm: f64, w: u32, h: u32) -> Option<[u32; 4]> {
    let bb = path_mm.bounding_box();
    let (w, h) = (i64::from(w), i64::from(h));
    let x0 = ((bb.x0 * px_per_mm).floor() as i64 - 1).clamp(0, w);
    let y0 = ((bb.y0 * px_per_mm).floor() as i64 - 1).clamp(0, h);
    let x1 = ((bb.x1 * px_per_mm).ceil() as i64 + 1).clamp(0, w);
    let y1 = ((bb.y1 * px_per_mm).ceil() as i64 + 1).clamp(0, h);
    if x1 <= x0 || y1 <= y0 || !bb.is_finite() {
        return None;
    }
    Some([x0 as u32, y0 as u32, (x1 - x0) as u32, (y1 - y0) as u32])
}

impl Rasterizer {
    /// A rasteriser with no scratch space yet.
    pub fn new() -> Self {
        Self { mask: None }
    }

    /// The size of the scratch mask so far (`(0, 0)` before the first stamp): tiny-skia's
    /// anti-aliasing at a footprint's edge can depend on it, so a rasteriser that is to draw
    /// what another would draw after some stamps starts from the same size
    /// ([`Rasterizer::grow_to`]).
    pub(crate) fn mask_size(&self) -> (u32, u32) {
        self.mask.as_ref().map_or((0, 0), |m| (m.width(), m.height()))
    }

    /// Grows the scratch mask to at least `w × h`, as stamps of those sizes would have.
    pub(crate) fn grow_to(&mut self, w: u32, h: u32) {
        if w > 0 && h > 0 {
            self.scratch(w, h);
        }
    }

    /// A scratch mask at least `w × h`, with its top-left `w × h` block cleared.
    fn scratch(&mut self, w: u32, h: u32) -> &mut Mask {
        let fits = self.mask.as_ref().is_some_and(|m| m.width() >= w && m.height() >= h);
        if !fits {
            let (mw, mh) = match &self.mask {
                Some(m) => (m.width().max(w), m.height().max(h)),
                None => (w, h),
            };
            self.mask = Some(Mask::new(mw, mh).expect("non-zero mask size"));
        }
        let m = self.mask.as_mut().expect("mask exists");
        let stride = m.width() as usize;
        if w as usize == stride {
            m.data_mut()[..stride * h as usize].fill(0);
        } else {
            for row in m.data_mut().chunks_mut(stride).take(h as usize) {
                row[..w as usize].fill(0);
            }
        }
        m
    }

    /// Fills `path_mm` (paper mm, nonzero rule) into `out`, replacing its content. Paper mm map
    /// to pixels by `px_per_mm` with the paper origin at the image's top-left corner.
    pub fn fill(&mut self, path_mm: &BezPath, px_per_mm: f64, out: &mut Coverage) {
        out.clear();
        self.stamp(path_mm, px_per_mm, out);
    }

    /// Fills `path_mm` into `out` by per-pixel max (a stamp): only the path's bounding box is
    /// touched, so stamping many small footprints into a large image stays cheap.
    pub fn stamp(&mut self, path_mm: &BezPath, px_per_mm: f64, out: &mut Coverage) {
        let Some([x0, y0, bw, bh]) = stamp_box(path_mm, px_per_mm, out.width(), out.height()) else { return };
        let Some(path) = to_skia(path_mm, px_per_mm, x0 as f64, y0 as f64) else { return };
        let mask = self.scratch(bw, bh);
        mask.fill_path(&path, FillRule::Winding, true, Transform::identity());
        let stride = mask.width() as usize;
        let ow = out.width() as usize;
        let src = mask.data();
        let dst = out.data_mut();
        for r in 0..bh as usize {
            let s = &src[r * stride..r * stride + bw as usize];
            let d0 = (y0 as usize + r) * ow + x0 as usize;
            let d = &mut dst[d0..d0 + bw as usize];
            // Coverage `sv / 255` (a select, not a table: the loop vectorises), kept where larger.
            for (dv, &sv) in d.iter_mut().zip(s) {
                let v = f32::from(sv) / 255.0;
                *dv = if v > *dv { v } else { *dv };
            }
        }
    }

    /// Renders one footprint with `model` at `anchor` (mm) and `beta_rad` into `out`, replacing
    /// its content.
    pub fn render(
        &mut self,
        model: &dyn StrokeModel,
        fp: &Footprint,
        anchor: PointMm,
        beta_rad: f64,
        px_per_mm: f64,
        out: &mut Coverage,
    ) {
        self.fill(&model.outline(fp, anchor, beta_rad), px_per_mm, out);
    }
}
