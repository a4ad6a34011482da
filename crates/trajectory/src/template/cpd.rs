//! Coherent point drift (Myronenko & Song 2010, the non-rigid form), stage 2 of
//! [`super::register`]: a Gaussian displacement field moving the template's skeleton points onto
//! the target's.
//!
//! Frame: the em frame, normalised by [`EM`] inside the fit (σ² values below are in those
//! normalised units); displacements come out in em units. Deterministic: fixed iteration count,
//! no randomness.

use kurbo::{Point, Vec2};
use nalgebra::DMatrix;

use super::TemplateOptions;
use crate::glyph::EM;

/// The smallest CPD σ², normalised (σ = 12 em units): correspondences stay soft over about a
/// stroke's width, so points do not snap onto single skeleton pixels of the wrong stroke.
const SIGMA_FLOOR2: f64 = (12.0 / EM) * (12.0 / EM);

/// Ridge on the CPD's weights, relative to the mean diagonal of the data term.
const CPD_RIDGE: f64 = 1e-2;

/// Side of the squares the CPD's kernel centres are thinned to, em units.
const CENTRE_CELL_EM: f64 = 40.0;

/// The CPD's starting σ, em units (about two stroke widths).
const SIGMA_START_EM: f64 = 40.0;

/// A fitted coherent-point-drift displacement field (coordinates normalised by the em).
pub(super) struct Cpd {
    /// The kernel centres (the template points before the fit), normalised.
    centres: Vec<Point>,
    /// Per centre, the displacement weight, normalised.
    weights: Vec<Vec2>,
    /// 2β², normalised.
    two_beta2: f64,
}

impl Cpd {
    /// Non-rigid CPD of `y` (template points, moved) onto `x` (target points), em units.
    pub(super) fn fit(y_em: &[Point], x_em: &[Point], opts: &TemplateOptions) -> Self {
        let y: Vec<Point> = y_em.iter().map(|p| Point::new(p.x / EM, p.y / EM)).collect();
        let x: Vec<Point> = x_em.iter().map(|p| Point::new(p.x / EM, p.y / EM)).collect();
        let (m, n) = (y.len(), x.len());
        let beta = opts.cpd_beta_em / EM;
        let two_beta2 = 2.0 * beta * beta;
        // Kernel centres: the template points thinned to one per CENTRE_CELL_EM square. A kernel
        // at every point (plain CPD) is so ill-conditioned at this width that the field swings
        // wildly between the points, and it must hold off them (stroke outlines are carried too).
        let cell = CENTRE_CELL_EM / EM;
        let mut seen = std::collections::HashSet::new();
        let centres: Vec<Point> = y
            .iter()
            .copied()
            .filter(|p| seen.insert(((p.x / cell).floor() as i64, (p.y / cell).floor() as i64)))
            .collect();
        let k = centres.len();
        let kern = |a: Point, b: Point| (-(a - b).hypot2() / two_beta2).exp();
        let gyc = DMatrix::from_fn(m, k, |i, j| kern(y[i], centres[j]));
        let gcc = DMatrix::from_fn(k, k, |i, j| kern(centres[i], centres[j]));
        let mut t = y.clone();
        // The global fit has done the coarse work: start at σ = SIGMA_START_EM rather than at
        // the spread of all pairs, which first shrinks the template towards its centroid.
        let mut sigma2 = (SIGMA_START_EM / EM).powi(2);
        let w = opts.cpd_outlier.clamp(0.0, 0.99);
        let mut wmat = DMatrix::<f64>::zeros(k, 2);
        let mut e = vec![0.0; m];
        for _ in 0..opts.cpd_iters {
            let c = 2.0 * std::f64::consts::PI * sigma2 * w / (1.0 - w) * m as f64 / n as f64;
            let mut p1 = vec![0.0; m];
            let mut px = vec![Vec2::ZERO; m];
            let (mut np, mut sx2) = (0.0, 0.0);
            for xn in &x {
                let mut den = c;
                for (k, tm) in t.iter().enumerate() {
                    e[k] = (-(*xn - *tm).hypot2() / (2.0 * sigma2)).exp();
                    den += e[k];
                }
                let mut pt1 = 0.0;
                for k in 0..m {
                    let p = e[k] / den;
                    p1[k] += p;
                    px[k] += xn.to_vec2() * p;
                    pt1 += p;
                }
                np += pt1;
                sx2 += pt1 * xn.to_vec2().hypot2();
            }
            if np < 1e-9 {
                break;
            }
            // (Gycᵀ·diag(P1)·Gyc + λσ²·Gcc)·W = Gycᵀ·(P·X − diag(P1)·Y)
            let dg = DMatrix::from_fn(m, k, |i, j| p1[i] * gyc[(i, j)]);
            let mut a = gyc.transpose() * &dg;
            // A ridge on the weights themselves: the Gaussian kernel matrix alone leaves directions
            // of huge, cancelling weights that fit the points and swing wildly off them.
            let ridge = CPD_RIDGE * (0..k).map(|i| a[(i, i)]).sum::<f64>() / k as f64;
            a += &gcc * (opts.cpd_lambda * sigma2);
            for i in 0..k {
                a[(i, i)] += ridge;
            }
            let r = DMatrix::from_fn(m, 2, |i, j| {
                let v = px[i] - y[i].to_vec2() * p1[i];
                if j == 0 { v.x } else { v.y }
            });
            match a.lu().solve(&(gyc.transpose() * r)) {
                Some(sol) => wmat = sol,
                None => break,
            }
            let gw = &gyc * &wmat;
            for k in 0..m {
                t[k] = y[k] + Vec2::new(gw[(k, 0)], gw[(k, 1)]);
            }
            let mut cross = 0.0;
            let mut tt = 0.0;
            for k in 0..m {
                cross += px[k].dot(t[k].to_vec2());
                tt += p1[k] * t[k].to_vec2().hypot2();
            }
            sigma2 = ((sx2 - 2.0 * cross + tt) / (2.0 * np)).max(SIGMA_FLOOR2);
        }
        let weights = (0..k).map(|i| Vec2::new(wmat[(i, 0)], wmat[(i, 1)])).collect();
        Self { centres, weights, two_beta2 }
    }

    /// The displacement at an em-frame point, em units.
    pub(super) fn displacement(&self, p: Point) -> Vec2 {
        let q = Point::new(p.x / EM, p.y / EM);
        let mut d = Vec2::ZERO;
        for (c, w) in self.centres.iter().zip(&self.weights) {
            d += *w * (-(q - *c).hypot2() / self.two_beta2).exp();
        }
        d * EM
    }
}
