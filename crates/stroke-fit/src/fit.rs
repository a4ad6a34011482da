//! Fitting a B-BSM footprint to a stroke's ink mask.
//!
//! Start: image moments give the centroid and the principal axis; ink pixels projected on the
//! axis give the length and, binned, the half-width profile, whose widest bin is the belly. Both
//! ends are tried as the root (which end is the tip is decided by which fits better, not
//! assumed). Refinement: Nelder–Mead over `(anchor x, anchor y, β, ln lt, ln lh, ln lr)`
//! maximising the soft IoU `Σ min(c, m) / Σ max(c, m)` between the rendered footprint's coverage
//! `c` and the ink mask `m`, on a crop around the ink.

use bezier_raster::{Bsm, Coverage, Rasterizer};
use brush_model::{Footprint, PointMm, wrap_angle_rad};
use numerics::{NelderMead, nelder_mead};
use serde::Serialize;

use crate::photo::InkMask;

/// A fitted footprint, in mm on the photo (x right, y down from its top-left corner).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct StrokeFit {
    /// Tip length, mm.
    pub lt_mm: f64,
    /// Root length, mm.
    pub lh_mm: f64,
    /// Belly half-width, mm.
    pub lr_mm: f64,
    /// Root end (footprint origin P0), mm.
    pub anchor_mm: [f64; 2],
    /// Direction root → tip, radians from +x towards +y.
    pub beta_rad: f64,
    /// IoU of the fitted outline (thresholded at 0.5) with the ink.
    pub iou: f64,
}

impl StrokeFit {
    /// The footprint.
    pub fn footprint(&self) -> Footprint {
        Footprint { lt_mm: self.lt_mm, lh_mm: self.lh_mm, lr_mm: self.lr_mm }
    }
}

struct Problem<'a> {
    mask: &'a InkMask,
    x0: usize,
    y0: usize,
    w: usize,
    h: usize,
    raster: Rasterizer,
    img: Coverage,
}

impl Problem<'_> {
    /// Parameters: anchor (px, full image), β, ln lt, ln lh, ln lr (px).
    fn render(&mut self, p: &[f64; 6]) {
        let fp = Footprint { lt_mm: p[3].exp(), lh_mm: p[4].exp(), lr_mm: p[5].exp() };
        let anchor = PointMm::new(p[0] - self.x0 as f64, p[1] - self.y0 as f64);
        self.raster.render(&Bsm, &fp, anchor, p[2], 1.0, &mut self.img);
    }

    fn soft_iou(&mut self, p: &[f64; 6]) -> f64 {
        if p.iter().any(|v| !v.is_finite()) || p[3] > 9.0 || p[4] > 9.0 || p[5] > 9.0 {
            return 0.0;
        }
        self.render(p);
        let (mut inter, mut union) = (0.0f64, 0.0f64);
        let d = self.img.data();
        for y in 0..self.h {
            let row = &self.mask.ink[(self.y0 + y) * self.mask.width + self.x0..][..self.w];
            for (x, &m) in row.iter().enumerate() {
                let c = d[y * self.w + x] as f64;
                if m {
                    inter += c;
                    union += 1.0;
                } else {
                    union += c;
                }
            }
        }
        if union > 0.0 { inter / union } else { 0.0 }
    }

    fn hard_iou(&mut self, p: &[f64; 6]) -> f64 {
        self.render(p);
        let (mut i, mut u) = (0usize, 0usize);
        let d = self.img.data();
        for y in 0..self.h {
            for x in 0..self.w {
                let m = self.mask.ink[(self.y0 + y) * self.mask.width + self.x0 + x];
                let c = d[y * self.w + x] >= 0.5;
                i += (m && c) as usize;
                u += (m || c) as usize;
            }
        }
        if u > 0 { i as f64 / u as f64 } else { 0.0 }
    }
}

/// Bins along the principal axis for finding the belly (the widest place).
const BINS: usize = 48;

/// The moments start, px: the ink's centroid, its principal axis, its extent along that axis
/// (measured from the centroid), and the belly's place and half-width.
struct MomentStart {
    cx: f64,
    cy: f64,
    /// Unit vector along the principal axis.
    ux: f64,
    uy: f64,
    tmin: f64,
    tmax: f64,
    t_belly: f64,
    half: f64,
}

impl MomentStart {
    fn from_points(pts: &[(f64, f64)]) -> Self {
        let n = pts.len() as f64;
        let (cx, cy) = (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
        let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
        for &(x, y) in pts {
            sxx += (x - cx) * (x - cx);
            syy += (y - cy) * (y - cy);
            sxy += (x - cx) * (y - cy);
        }
        let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
        let (ux, uy) = (theta.cos(), theta.sin());
        let proj: Vec<(f64, f64)> =
            pts.iter().map(|&(x, y)| ((x - cx) * ux + (y - cy) * uy, -(x - cx) * uy + (y - cy) * ux)).collect();
        let tmin = proj.iter().map(|p| p.0).fold(f64::INFINITY, f64::min) - 0.5;
        let tmax = proj.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max) + 0.5;
        let mut lo = [f64::INFINITY; BINS];
        let mut hi = [f64::NEG_INFINITY; BINS];
        for &(t, s) in &proj {
            let b = (((t - tmin) / (tmax - tmin)) * BINS as f64).floor().clamp(0.0, (BINS - 1) as f64) as usize;
            lo[b] = lo[b].min(s);
            hi[b] = hi[b].max(s);
        }
        let (belly_bin, half) = (0..BINS)
            .filter(|&b| hi[b] >= lo[b])
            .map(|b| (b, 0.5 * (hi[b] - lo[b] + 1.0)))
            .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
        let t_belly = tmin + (belly_bin as f64 + 0.5) / BINS as f64 * (tmax - tmin);
        Self { cx, cy, ux, uy, tmin, tmax, t_belly, half }
    }

    /// The Nelder–Mead start `[x, y, β, ln lt, ln lh, ln lr]` (px) and its steps, with the
    /// root at the low end of the axis (`root_at_min`) or the high end.
    fn simplex(&self, root_at_min: bool) -> ([f64; 6], [f64; 6]) {
        let len = self.tmax - self.tmin;
        let (t_root, dir) = if root_at_min { (self.tmin, 1.0) } else { (self.tmax, -1.0) };
        let lh = ((self.t_belly - t_root) * dir).clamp(0.05 * len, 0.95 * len);
        let lt = (len - lh).max(0.05 * len);
        let start = [
            self.cx + t_root * self.ux,
            self.cy + t_root * self.uy,
            (dir * self.uy).atan2(dir * self.ux),
            lt.ln(),
            lh.ln(),
            self.half.max(0.5).ln(),
        ];
        let step = [0.05 * len, 0.05 * len, 0.05, 0.1, 0.2, 0.1];
        (start, step)
    }
}

/// The crop `(x0, y0, x1, y1)`, px (end exclusive): the ink's bounding box with a margin of a
/// quarter of its size (at least 4 px), within the image.
fn crop_box(pts: &[(f64, f64)], w: usize, h: usize) -> (usize, usize, usize, usize) {
    let (mut bx0, mut by0, mut bx1, mut by1) = (w, h, 0, 0);
    for &(x, y) in pts {
        bx0 = bx0.min(x as usize);
        by0 = by0.min(y as usize);
        bx1 = bx1.max(x as usize);
        by1 = by1.max(y as usize);
    }
    let m = ((bx1 - bx0).max(by1 - by0) / 4).max(4);
    let (x0, y0) = (bx0.saturating_sub(m), by0.saturating_sub(m));
    (x0, y0, (bx1 + m + 1).min(w), (by1 + m + 1).min(h))
}

/// Fits the footprint to the mask; lengths are returned in mm using `px_per_mm`.
///
/// # Examples
/// ```
/// use stroke_fit::brush_model::{BrushProfile, Extrapolation, PointMm, Press};
/// use stroke_fit::{Degradation, synthetic_photo};
/// use stroke_fit::{fit_footprint, mask_from_gray};
/// // A synthetic photo of a known press, 8 px/mm, blurred, noisy and JPEG-compressed.
/// let pen1 = BrushProfile::builtin("pen1").unwrap();
/// let fp = pen1.predict(&Press::from_degrees(15.0, 5.0, 0.0), Extrapolation::Refuse).unwrap();
/// let (px_per_mm, size_px) = (8.0, 160);
/// let gray = synthetic_photo(&fp, PointMm::new(3.0, 10.0), 0.0, px_per_mm, size_px, size_px, &Degradation::default(), 1);
/// let mask = mask_from_gray(gray, size_px as usize, size_px as usize, "synthetic").unwrap();
/// let fit = fit_footprint(&mask, px_per_mm);
/// let rel = |a: f64, b: f64| (a - b).abs() / b;
/// assert!(rel(fit.lt_mm, fp.lt_mm) < 0.05 && rel(fit.lh_mm, fp.lh_mm) < 0.05 && rel(fit.lr_mm, fp.lr_mm) < 0.05);
/// assert!(fit.beta_rad.abs() < 0.02 && fit.iou > 0.9);
/// ```
pub fn fit_footprint(mask: &InkMask, px_per_mm: f64) -> StrokeFit {
    let (w, h) = (mask.width, mask.height);
    let pts: Vec<(f64, f64)> =
        (0..w * h).filter(|&i| mask.ink[i]).map(|i| ((i % w) as f64 + 0.5, (i / w) as f64 + 0.5)).collect();
    let moments = MomentStart::from_points(&pts);
    let (x0, y0, x1, y1) = crop_box(&pts, w, h);
    let mut prob = Problem {
        mask,
        x0,
        y0,
        w: x1 - x0,
        h: y1 - y0,
        raster: Rasterizer::new(),
        img: Coverage::new((x1 - x0) as u32, (y1 - y0) as u32),
    };
    let mut best: Option<([f64; 6], f64)> = None;
    for root_at_min in [true, false] {
        let (start, step) = moments.simplex(root_at_min);
        let mut f = |p: &[f64; 6]| 1.0 - prob.soft_iou(p);
        let (mut p, mut v) =
            nelder_mead(&mut f, start, &NelderMead { min_spread: Some(1e-9), ..NelderMead::new(step, 400) });
        // Restart once from the optimum with smaller steps (Nelder–Mead can stall).
        let small = step.map(|s| s * 0.2);
        let (p2, v2) = nelder_mead(&mut f, p, &NelderMead { min_spread: Some(1e-9), ..NelderMead::new(small, 300) });
        if v2 < v {
            (p, v) = (p2, v2);
        }
        if best.is_none_or(|b| v < b.1) {
            best = Some((p, v));
        }
    }
    let (p, _) = best.expect("two candidates");
    let iou = prob.hard_iou(&p);
    StrokeFit {
        lt_mm: p[3].exp() / px_per_mm,
        lh_mm: p[4].exp() / px_per_mm,
        lr_mm: p[5].exp() / px_per_mm,
        anchor_mm: [p[0] / px_per_mm, p[1] / px_per_mm],
        beta_rad: wrap_angle_rad(p[2]),
        iou,
    }
}
