//! SSIM with separable Gaussian filtering over the valid region only.
//!
//! scikit-image filters the whole image (with reflected borders) and then discards a 5 px band
//! around the edge before averaging. Every value kept depends only on pixels inside the image, so
//! we filter just the kept region and never touch the border handling: the result is the same to
//! rounding. Filtering and statistics are in `f64`, as scikit-image does.

use crate::{GrayRef, MetricsError, same_size};

/// Radius of the Gaussian window: `int(3.5·σ + 0.5)` = 5 for σ = 1.5 (scikit-image's truncate
/// of 3.5), so the window is 11×11 and 5 px are cropped from each border.
pub const SSIM_RADIUS: usize = 5;
const WIN: usize = 2 * SSIM_RADIUS + 1;
const SIGMA: f64 = 1.5;
const C1: f64 = 0.01 * 0.01;
const C2: f64 = 0.03 * 0.03;

fn gaussian_weights() -> [f64; WIN] {
    let mut w = [0.0; WIN];
    for (i, wi) in w.iter_mut().enumerate() {
        let x = i as f64 - SSIM_RADIUS as f64;
        *wi = (-0.5 * x * x / (SIGMA * SIGMA)).exp();
    }
    let s: f64 = w.iter().sum();
    w.map(|v| v / s)
}

/// Reusable buffers for SSIM, so repeated calls allocate nothing.
#[derive(Debug, Default, Clone)]
pub struct SsimWorkspace {
    /// Vertically filtered rows: x, y, x², y², xy (each `width` long).
    cols: [Vec<f64>; 5],
    /// Horizontally filtered results (each `width − 10` long).
    out: [Vec<f64>; 5],
}

impl SsimWorkspace {
    /// An empty workspace; buffers grow on first use.
    pub fn new() -> Self {
        Self::default()
    }

    /// Mean SSIM of `a` and `b` (see the crate docs for the exact definition).
    ///
    /// # Errors
    /// [`MetricsError::SizeMismatch`]; [`MetricsError::TooSmall`] below 11×11.
    pub fn ssim(&mut self, a: GrayRef<'_>, b: GrayRef<'_>) -> Result<f64, MetricsError> {
        same_size(a, b)?;
        let (w, h) = (a.width(), a.height());
        if w < WIN || h < WIN {
            return Err(MetricsError::TooSmall(w, h));
        }
        let g = gaussian_weights();
        let ow = w - 2 * SSIM_RADIUS;
        let oh = h - 2 * SSIM_RADIUS;
        for v in self.cols.iter_mut() {
            v.resize(w, 0.0);
        }
        for v in self.out.iter_mut() {
            v.resize(ow, 0.0);
        }
        let mut total = 0.0f64;
        for r in 0..oh {
            // Vertical pass: rows r..r+11 of the image into one filtered row.
            let [cx, cy, cxx, cyy, cxy] = &mut self.cols;
            cx.fill(0.0);
            cy.fill(0.0);
            cxx.fill(0.0);
            cyy.fill(0.0);
            cxy.fill(0.0);
            for (k, &wk) in g.iter().enumerate() {
                let (ra, rb) = (a.row(r + k), b.row(r + k));
                for c in 0..w {
                    let (x, y) = (ra[c] as f64, rb[c] as f64);
                    cx[c] += wk * x;
                    cy[c] += wk * y;
                    cxx[c] += wk * (x * x);
                    cyy[c] += wk * (y * y);
                    cxy[c] += wk * (x * y);
                }
            }
            // Horizontal pass over the kept columns.
            for (o, c) in self.out.iter_mut().zip(self.cols.iter()) {
                o.fill(0.0);
                for (k, &wk) in g.iter().enumerate() {
                    let src = &c[k..k + ow];
                    for (d, s) in o.iter_mut().zip(src) {
                        *d += wk * s;
                    }
                }
            }
            let [ux, uy, uxx, uyy, uxy] = &self.out;
            let mut row_sum = 0.0;
            for i in 0..ow {
                let (mx, my) = (ux[i], uy[i]);
                let vx = uxx[i] - mx * mx;
                let vy = uyy[i] - my * my;
                let vxy = uxy[i] - mx * my;
                let num = (2.0 * mx * my + C1) * (2.0 * vxy + C2);
                let den = (mx * mx + my * my + C1) * (vx + vy + C2);
                row_sum += num / den;
            }
            total += row_sum;
        }
        Ok(total / (ow * oh) as f64)
    }
}

/// Mean SSIM of `a` and `b`, allocating a fresh [`SsimWorkspace`]; see the crate docs.
///
/// # Examples
/// ```
/// use stroke_metrics::{GrayRef, ssim};
/// // A 32 × 32 bar, and the same bar moved by 2 px.
/// let bar = |x0: usize| -> Vec<f32> { (0..32 * 32).map(|i| if (x0..x0 + 6).contains(&(i % 32)) { 1.0 } else { 0.0 }).collect() };
/// let (a, b) = (bar(10), bar(12));
/// let (a, b) = (GrayRef::new(&a, 32, 32).unwrap(), GrayRef::new(&b, 32, 32).unwrap());
/// assert!((ssim(a, a).unwrap() - 1.0).abs() < 1e-12);
/// let s = ssim(a, b).unwrap();
/// assert!(s > 0.0 && s < 1.0);
/// // The window is 11 × 11: smaller images are refused.
/// let tiny = [0.0f32; 100];
/// assert!(ssim(GrayRef::new(&tiny, 10, 10).unwrap(), GrayRef::new(&tiny, 10, 10).unwrap()).is_err());
/// ```
///
/// # Errors
/// [`MetricsError::SizeMismatch`]; [`MetricsError::TooSmall`] below 11×11.
pub fn ssim(a: GrayRef<'_>, b: GrayRef<'_>) -> Result<f64, MetricsError> {
    SsimWorkspace::new().ssim(a, b)
}
