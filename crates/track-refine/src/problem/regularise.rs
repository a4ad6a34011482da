//! The regularisers (smoothness, spacing, range barriers; see [`super::Problem`]) and the
//! smoothing of the gradient along the track.

use super::Problem;

impl Problem<'_> {
    /// Smooths a gradient along each stroke (a Sobolev-type preconditioner): the position
    /// part over each stroke's position groups and the depth part over each run of consecutive
    /// pressed points, with a Gaussian of `sigma_mm` along the track (in points of the input's
    /// median spacing). Every update is then a smooth displacement field, so the directions the
    /// forward model derives from the motion change smoothly between re-derivations; `sigma_mm`
    /// = 0 leaves the gradient as it is.
    pub fn smooth_gradient(&self, grad: &mut [f64], sigma_mm: f64) {
        if !(sigma_mm > 0.0) {
            return;
        }
        let mut gaps: Vec<f64> = Vec::new();
        for r in &self.vars.stroke_groups {
            for j in r.start..r.end.saturating_sub(1) {
                gaps.push(
                    (self.vars.q0[j + 1][0] - self.vars.q0[j][0]).hypot(self.vars.q0[j + 1][1] - self.vars.q0[j][1]),
                );
            }
        }
        if gaps.is_empty() {
            return;
        }
        gaps.sort_by(f64::total_cmp);
        let spacing = gaps[gaps.len() / 2].max(1e-6);
        let sigma = sigma_mm / spacing;
        let radius = (3.0 * sigma).ceil() as usize;
        let kernel: Vec<f64> = (0..=radius).map(|k| (-0.5 * (k as f64 / sigma).powi(2)).exp()).collect();
        let blur = |v: &mut [f64], stride: usize, ranges: &[std::ops::Range<usize>]| {
            for r in ranges {
                for c in 0..stride {
                    let src: Vec<f64> = (r.start..r.end).map(|j| v[stride * j + c]).collect();
                    let n = src.len();
                    for (i, j) in (r.start..r.end).enumerate() {
                        let (lo, hi) = (i.saturating_sub(radius), (i + radius).min(n - 1));
                        let (mut acc, mut wsum) = (0.0, 0.0);
                        for (k, s) in src.iter().enumerate().take(hi + 1).skip(lo) {
                            let w = kernel[k.abs_diff(i)];
                            acc += w * s;
                            wsum += w;
                        }
                        v[stride * j + c] = acc / wsum;
                    }
                }
            }
        };
        let (ho, ao) = (self.vars.h_off(), self.vars.a_off());
        blur(&mut grad[..ho], 2, &self.vars.stroke_groups);
        // Runs of consecutive pressed points.
        let runs = self.vars.pressed_runs();
        blur(&mut grad[ho..ao], 1, &runs);
    }

    pub(super) fn smoothness(&self, theta: &[f64], grad: &mut [f64], want_grad: bool) -> f64 {
        let w = self.opts.smooth_weight / self.vars.q0.len().max(1) as f64;
        let mut sum = 0.0;
        // Positions: second differences of the displacement over each stroke's groups.
        for r in &self.vars.stroke_groups {
            for j in r.start + 1..r.end.saturating_sub(1) {
                for c in 0..2 {
                    let d = |g: usize| theta[2 * g + c] - self.vars.q0[g][c];
                    let dd = d(j - 1) - 2.0 * d(j) + d(j + 1);
                    sum += w * dd * dd;
                    if want_grad {
                        grad[2 * (j - 1) + c] += 2.0 * w * dd;
                        grad[2 * j + c] -= 4.0 * w * dd;
                        grad[2 * (j + 1) + c] += 2.0 * w * dd;
                    }
                }
            }
        }
        // Depths: over runs of consecutive pressed points of a stroke.
        let ho = self.vars.h_off();
        for k in 1..self.vars.pressed.len().saturating_sub(1) {
            let (a, b, c) = (self.vars.pressed[k - 1], self.vars.pressed[k], self.vars.pressed[k + 1]);
            if a.0 != b.0 || b.0 != c.0 || a.1 + 1 != b.1 || b.1 + 1 != c.1 {
                continue;
            }
            let d = |i: usize| theta[ho + i] - self.vars.h0[i];
            let dd = d(k - 1) - 2.0 * d(k) + d(k + 1);
            sum += w * dd * dd;
            if want_grad {
                grad[ho + k - 1] += 2.0 * w * dd;
                grad[ho + k] -= 4.0 * w * dd;
                grad[ho + k + 1] += 2.0 * w * dd;
            }
        }
        sum
    }

    pub(super) fn spacing(&self, theta: &[f64], grad: &mut [f64], want_grad: bool) -> f64 {
        let w = self.opts.spacing_weight / self.vars.q0.len().max(1) as f64;
        let mut sum = 0.0;
        for r in &self.vars.stroke_groups {
            for j in r.start..r.end.saturating_sub(1) {
                let d0 =
                    (self.vars.q0[j + 1][0] - self.vars.q0[j][0]).hypot(self.vars.q0[j + 1][1] - self.vars.q0[j][1]);
                let (dx, dy) = (theta[2 * j + 2] - theta[2 * j], theta[2 * j + 3] - theta[2 * j + 1]);
                let d = dx.hypot(dy);
                let r = d - d0;
                sum += w * r * r;
                if want_grad && d > 0.0 {
                    let (gx, gy) = (2.0 * w * r * dx / d, 2.0 * w * r * dy / d);
                    grad[2 * j + 2] += gx;
                    grad[2 * j + 3] += gy;
                    grad[2 * j] -= gx;
                    grad[2 * j + 1] -= gy;
                }
            }
        }
        sum
    }

    pub(super) fn barrier(&self, theta: &[f64], grad: &mut [f64], want_grad: bool) -> f64 {
        let w = self.opts.barrier_weight;
        let mut sum = 0.0;
        let r = self.profile.ranges.h_mm;
        let mut one = |i: usize, lo: f64, hi: f64| {
            let m = 0.02 * (hi - lo).max(1e-9);
            let v = theta[i];
            let (below, above) = ((lo - v).max(0.0), (v - hi).max(0.0));
            sum += w * (below * below + above * above) / (m * m);
            if want_grad {
                grad[i] += w * 2.0 * (above - below) / (m * m);
            }
        };
        let (ho, ao) = (self.vars.h_off(), self.vars.a_off());
        for i in ho..ao {
            one(i, r.min, r.max);
        }
        for i in ao..theta.len() {
            one(i, self.vars.alpha_range.0, self.vars.alpha_range.1);
        }
        sum
    }
}
