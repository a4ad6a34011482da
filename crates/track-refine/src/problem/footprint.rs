//! Footprint preparation: the footprints at an iterate (position, press, direction through the
//! aim coupling, the analytic lengths and their derivatives, the pixel box), and the chain rule
//! that takes the image term's per-footprint partials back to the variables.

use super::{Directions, Problem};
use crate::Target;
use crate::image::Fp;
use crate::soft::Shape;

impl Problem<'_> {
    /// The footprints at an iterate with the given directions.
    pub(super) fn footprints(&self, theta: &[f64], dirs: &Directions) -> Vec<Fp> {
        let (ho, ao) = (self.vars.h_off(), self.vars.a_off());
        let m = &self.profile.model;
        let t = self.target;
        let e = self.edge_mm;
        self.vars
            .pressed
            .iter()
            .enumerate()
            .map(|(k, &(s, i))| {
                let slot = self.vars.slots[s][i];
                let p = self.vars.strokes[s][i];
                let x = theta[2 * slot.group];
                let y = theta[2 * slot.group + 1];
                let h = theta[ho + k];
                let alpha = self.vars.group_alpha[slot.group].map_or(p.alpha_rad, |a| theta[ao + a]);
                let beta = match dirs.aim[k] {
                    Some(aim) => {
                        let (ax, ay) = self.aim_point(theta, aim, dirs.slide[k], h, alpha);
                        (ay - y).atan2(ax - x)
                    }
                    None => dirs.beta_rad[k],
                };
                let wrapped = (beta + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
                let bs = self.profile.ranges.beta_rad.clamp(wrapped);
                let terms = [&m.lt_mm, &m.lh_mm, &m.lr_mm];
                let [lt, lh, lr] = terms.map(|t| t.eval(h, alpha, bs).max(1e-6));
                let dh = terms.map(|t| t.h_mm.unwrap_or(0.0));
                let da = terms.map(|t| t.alpha_rad.unwrap_or(0.0));
                let shape = Shape { lt, lh, lr };
                let [i0, i1, j0, j1] = pixel_box(t, e, (x, y), beta, &shape);
                Fp { x, y, h, alpha, beta, shape, dh, da, db: [0.0; 3], i0, i1, j0, j1 }
            })
            .collect()
    }

    /// Adds the footprints' partials to the variables' gradient (through the aim coupling of
    /// each direction).
    pub(super) fn scatter(&self, theta: &[f64], dirs: &Directions, fps: &[Fp], per_fp: &[[f64; 5]], grad: &mut [f64]) {
        let (ho, ao) = (self.vars.h_off(), self.vars.a_off());
        for (k, &(si, pi)) in self.vars.pressed.iter().enumerate() {
            let slot = self.vars.slots[si][pi];
            let g = per_fp[k];
            grad[2 * slot.group] += g[0];
            grad[2 * slot.group + 1] += g[1];
            grad[ho + k] += g[2];
            if let Some(a) = self.vars.group_alpha[slot.group] {
                grad[ao + a] += g[3];
            }
            if let Some((ga, gb, fr)) = dirs.aim[k] {
                // β = atan2(aim − p): ∂β/∂aim = (−r_y, r_x)/|r|², ∂β/∂p = −∂β/∂aim.
                let fp = &fps[k];
                let [kx, ky, _] = dirs.slide[k];
                let (ax, ay) = self.aim_point(theta, (ga, gb, fr), dirs.slide[k], fp.h, fp.alpha);
                let (rx, ry) = (ax - fp.x, ay - fp.y);
                let r2 = rx * rx + ry * ry;
                if r2 > 0.0 {
                    let (bx, by) = (-ry / r2 * g[4], rx / r2 * g[4]);
                    if kx != 0.0 || ky != 0.0 {
                        // The aim slides with the reach: ∂aim/∂(h, α) = k·∂reach/∂(h, α).
                        let [rh, ra] = self.reach_grad();
                        let ga_k = bx * kx + by * ky;
                        grad[self.vars.h_off() + k] += ga_k * rh;
                        if let Some(a) = self.vars.group_alpha[slot.group] {
                            grad[self.vars.a_off() + a] += ga_k * ra;
                        }
                    }
                    grad[2 * slot.group] -= bx;
                    grad[2 * slot.group + 1] -= by;
                    grad[2 * ga] += (1.0 - fr) * bx;
                    grad[2 * ga + 1] += (1.0 - fr) * by;
                    grad[2 * gb] += fr * bx;
                    grad[2 * gb + 1] += fr * by;
                }
            }
        }
    }
}

/// The inclusive pixel box `[i0, i1, j0, j1]` on `t` (clipped to it; empty when `i0 > i1`) of
/// a footprint's band `u ∈ [−e, L + e]`, `|v| ≤ lr + e` (`e` the edge half-width, mm), the
/// footprint at `(x, y)` mm pointing along `beta` rad.
fn pixel_box(t: &Target, e: f64, at: (f64, f64), beta: f64, shape: &Shape) -> [i64; 4] {
    pixel_box_on(t.origin_mm, t.mm_per_px, (t.width, t.height), e, at, beta, shape)
}

/// [`pixel_box`] on a raster of `size` px whose top-left corner is `origin` mm, `mm_per_px`.
pub(crate) fn pixel_box_on(
    origin: brush_model::PointMm,
    mm_per_px: f64,
    size: (u32, u32),
    e: f64,
    (x, y): (f64, f64),
    beta: f64,
    shape: &Shape,
) -> [i64; 4] {
    let (sb, cb) = beta.sin_cos();
    // Local box u ∈ [−e, L + e], |v| ≤ lr + e, rotated onto the paper.
    let (ul, uh, vh) = (-e, shape.length() + e, shape.lr + e);
    let (mut xmin, mut xmax, mut ymin, mut ymax) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for (u, v) in [(ul, -vh), (ul, vh), (uh, -vh), (uh, vh)] {
        let (px, py) = (x + u * cb - v * sb, y + u * sb + v * cb);
        xmin = xmin.min(px);
        xmax = xmax.max(px);
        ymin = ymin.min(py);
        ymax = ymax.max(py);
    }
    let col = |v: f64, up: bool| {
        let f = (v - origin.x_mm) / mm_per_px - 0.5;
        if up { f.floor() as i64 } else { f.ceil() as i64 }
    };
    let row = |v: f64, up: bool| {
        let f = (v - origin.y_mm) / mm_per_px - 0.5;
        if up { f.floor() as i64 } else { f.ceil() as i64 }
    };
    let (w, hgt) = (size.0 as i64, size.1 as i64);
    [col(xmin, false).max(0), col(xmax, true).min(w - 1), row(ymin, false).max(0), row(ymax, true).min(hgt - 1)]
}
