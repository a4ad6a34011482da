//! Stage 1 of [`super::register`]: the global affine fit of the template's ink onto the
//! target's, from the moments start, by Nelder–Mead on the symmetric overlap of the two inks
//! blurred by a Gaussian (coarse, then fine).

use kurbo::{Affine, Point};
use numerics::{Edge, NelderMead, Normalise, OutsideContraction, gaussian_blur, nelder_mead};

use super::TemplateOptions;
use crate::glyph::{EM, Glyph};
use crate::{TrajectoryError, distance, raster};

/// The global affine fit of [`register_template`](super::register_template) (stage 1): its coefficients and the blurred-ink
/// overlap before and after.
pub(super) struct GlobalFit {
    /// Template em frame → target em frame, kurbo's affine coefficients.
    pub(super) coeffs: [f64; 6],
    /// Overlap (0..1) of the moments start.
    pub(super) overlap_start: f64,
    /// Overlap (0..1) of the fit.
    pub(super) overlap_fit: f64,
}

/// Stage 1 of [`register_template`](super::register_template): the affine map of the template's ink onto the target's, from the
/// moments start, Nelder–Mead on the overlap of the blurred inks at two blur widths.
pub(super) fn global_fit(
    template: &Glyph,
    target: &Glyph,
    opts: &TemplateOptions,
) -> Result<GlobalFit, TrajectoryError> {
    let fit_n = opts.fit_px.max(32) as usize;
    let t_cov = raster::render_glyph(template, fit_n as u32);
    let g_cov = raster::render_glyph(target, fit_n as u32);
    let t_ink = raster::ink_points(t_cov.data(), fit_n, 2500).ok_or(TrajectoryError::Empty(template.ch))?;
    let g_ink = raster::ink_points(g_cov.data(), fit_n, 2500).ok_or(TrajectoryError::Empty(target.ch))?;
    let start = moment_start(t_cov.data(), g_cov.data(), fit_n);
    let mut q = start.as_coeffs();
    let mut overlap_start = None;
    let mut overlap_fit = 0.0;
    for sigma_px in [4.0, 1.5] {
        let tb = gaussian_blur(t_cov.data(), fit_n, fit_n, sigma_px, Edge::Zero, Normalise::Sum);
        let gb = gaussian_blur(g_cov.data(), fit_n, fit_n, sigma_px, Edge::Zero, Normalise::Sum);
        let score = |c: &[f64; 6]| overlap(Affine::new(*c), &t_ink, &g_ink, &tb, &gb, fit_n);
        overlap_start.get_or_insert_with(|| score(&q));
        let steps = [0.05, 0.05, 0.05, 0.05, 12.0, 12.0];
        let nm = NelderMead { outside: OutsideContraction::FromReflected, ..NelderMead::new(steps, 160) };
        let (best, val) = nelder_mead(|c| -score(c), q, &nm);
        q = best;
        overlap_fit = -val;
    }
    Ok(GlobalFit { coeffs: q, overlap_start: overlap_start.unwrap_or(0.0), overlap_fit })
}

/// The start of the global fit: template ink centroid onto the target's, per-axis spread matched.
fn moment_start(t: &[f32], g: &[f32], n: usize) -> Affine {
    let (ct, st) = raster::moments(t, n);
    let (cg, sg) = raster::moments(g, n);
    let sx = (sg.x / st.x.max(1e-9)).clamp(0.3, 3.0);
    let sy = (sg.y / st.y.max(1e-9)).clamp(0.3, 3.0);
    Affine::new([sx, 0.0, 0.0, sy, cg.x - sx * ct.x, cg.y - sy * ct.y])
}

/// Symmetric blurred overlap of template and target under `a` (template → target).
fn overlap(a: Affine, t_ink: &[Point], g_ink: &[Point], tb: &[f32], gb: &[f32], n: usize) -> f64 {
    let det = a.determinant();
    if !(0.05..20.0).contains(&det) {
        return 0.0;
    }
    let inv = a.inverse();
    let s = n as f64 / EM;
    let fwd = t_ink.iter().map(|&p| {
        let q = a * p;
        distance::sample(gb, n, n, q.x * s, q.y * s)
    });
    let back = g_ink.iter().map(|&p| {
        let q = inv * p;
        distance::sample(tb, n, n, q.x * s, q.y * s)
    });
    0.5 * (fwd.sum::<f64>() / t_ink.len() as f64 + back.sum::<f64>() / g_ink.len() as f64)
}
