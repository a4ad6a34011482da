//! The analytic soft footprint: the B-BSM teardrop with a soft edge, and its derivatives in
//! closed form.
//!
//! In the footprint's own frame (`u` along the axis from the root end towards the tip, `v`
//! across it, both mm) the outline's upper half is the cubic Bézier of docs/brush-model.md:
//! `x(t) = (4·lh − lt)·t(1−t)² + 3·lh·t²(1−t) + (lh + lt)·t³`, `y(t) = 4·lr·t(1−t)`. For a
//! point with `0 < u < L = lh + lt` the half-width there is `w = y(t*)` with `x(t*) = u` (a
//! safeguarded Newton solve; `x` is monotone whenever `4·lh ≥ lt`, true of both nominal brushes
//! at every press) and the signed measure is the *vertical* distance to the edge,
//! `d = w − |v|` (positive inside). Beyond the ends it is minus the distance to the end point
//! (`−|(u, v)|` behind the root, `−|(u − L, v)|` past the tip), so `d` is continuous
//! everywhere. Coverage is a smoothstep of `d` over `[−e, e]` (`e` the edge half-width, mm):
//! exactly 0 outside, exactly 1 inside, C¹ in between — compact support keeps the sums cheap.
//!
//! Derivatives: by the implicit function theorem on `x(t*) = u`,
//! `∂t*/∂u = 1/x'(t*)`, `∂t*/∂lh = −(∂x/∂lh)/x'(t*)`, `∂t*/∂lt = −(∂x/∂lt)/x'(t*)`, then
//! `∂w/∂t = 4·lr·(1 − 2t)`, `∂w/∂lr = 4t(1−t)`. Closed form costs a few multiplications per
//! pixel on top of the solve; forward-mode dual numbers would carry five tangents through
//! every Newton iteration for the same numbers, so closed form it is.

/// The three lengths of a footprint, mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Shape {
    /// Tip length (belly to tip), mm.
    pub(crate) lt: f64,
    /// Root length (root end to belly), mm.
    pub(crate) lh: f64,
    /// Belly half-width, mm.
    pub(crate) lr: f64,
}

/// The signed measure `d` at one point and its derivatives with respect to
/// `(u, v, lt, lh, lr)` (each mm per mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Measure {
    /// Signed vertical distance to the edge, mm (positive inside).
    pub(crate) d: f64,
    /// `∂d/∂(u, v, lt, lh, lr)`.
    pub(crate) grad: [f64; 5],
}

impl Shape {
    /// Footprint length `lh + lt`, mm.
    pub(crate) fn length(&self) -> f64 {
        self.lh + self.lt
    }

    /// `x(t)` of the upper curve, mm.
    pub(crate) fn x(&self, t: f64) -> f64 {
        let s = 1.0 - t;
        (4.0 * self.lh - self.lt) * t * s * s + 3.0 * self.lh * t * t * s + (self.lh + self.lt) * t * t * t
    }

    /// `x'(t)`, mm per unit t.
    pub(crate) fn dx(&self, t: f64) -> f64 {
        let s = 1.0 - t;
        let a1 = 4.0 * self.lh - self.lt;
        a1 * (s * s - 2.0 * t * s) + 3.0 * self.lh * (2.0 * t * s - t * t) + 3.0 * (self.lh + self.lt) * t * t
    }

    /// The curve parameter where `x(t) = u`, for `0 < u < L` (safeguarded Newton on `[0, 1]`).
    pub(crate) fn solve_t(&self, u: f64) -> f64 {
        self.solve_t_in(u, 0.0, 1.0, (u / self.length()).clamp(0.0, 1.0))
    }

    /// As [`Shape::solve_t`] with `t*` known to lie in `[lo, hi]`, starting from `t`.
    fn solve_t_in(&self, u: f64, mut lo: f64, mut hi: f64, mut t: f64) -> f64 {
        for _ in 0..30 {
            let f = self.x(t) - u;
            if f > 0.0 {
                hi = t;
            } else {
                lo = t;
            }
            let fp = self.dx(t);
            let mut next = if fp > 0.0 { t - f / fp } else { f64::NAN };
            if !(next > lo && next < hi) {
                next = 0.5 * (lo + hi);
            }
            // Newton converges quadratically: a step under 1e-7 leaves an error near 1e-14.
            if (next - t).abs() < 1e-7 {
                return next;
            }
            t = next;
        }
        t
    }

    /// The signed measure at `(u, v)` (footprint frame, mm), without derivatives.
    pub(crate) fn measure(&self, u: f64, v: f64) -> f64 {
        let l = self.length();
        if u <= 0.0 {
            -u.hypot(v)
        } else if u >= l {
            -(u - l).hypot(v)
        } else {
            let t = self.solve_t(u);
            4.0 * self.lr * t * (1.0 - t) - v.abs()
        }
    }

    /// The signed measure at `(u, v)` with its derivatives (the tests' reference for
    /// [`Shape::measure_grad_with`]).
    #[cfg(test)]
    pub(crate) fn measure_grad(&self, u: f64, v: f64) -> Measure {
        self.measure_grad_t(u, v, |u| self.solve_t(u))
    }

    /// As [`Shape::measure_grad`], the Newton solve for `t*` bracketed and started by this
    /// shape's width bounds (`bounds` from [`Shape::width_bounds`] of the same shape): the same
    /// value to rounding, in two or three iterations instead of five or six.
    pub(crate) fn measure_grad_with(&self, u: f64, v: f64, bounds: &WidthBounds) -> Measure {
        self.measure_grad_t(u, v, |u| {
            let x = u * bounds.inv_du;
            let k = (x as usize).min(bounds.lo.len() - 1);
            let (a, b) = (bounds.t[k], bounds.t[k + 1]);
            let f = (x - k as f64).clamp(0.0, 1.0);
            self.solve_t_in(u, a, b, a + f * (b - a))
        })
    }

    fn measure_grad_t(&self, u: f64, v: f64, solve: impl Fn(f64) -> f64) -> Measure {
        let l = self.length();
        if u <= 0.0 || u >= l {
            let du = if u <= 0.0 { u } else { u - l };
            let r = du.hypot(v);
            if r == 0.0 {
                return Measure { d: 0.0, grad: [0.0; 5] };
            }
            // d = −r; past the tip the end point moves with L = lh + lt.
            let (gu, gv) = (-du / r, -v / r);
            let gl = if u <= 0.0 { 0.0 } else { du / r };
            return Measure { d: -r, grad: [gu, gv, gl, gl, 0.0] };
        }
        let t = solve(u);
        let s = 1.0 - t;
        let xt = self.dx(t).max(1e-12 * l);
        let x_lh = 4.0 * t * s * s + 3.0 * t * t * s + t * t * t;
        let x_lt = -t * s * s + t * t * t;
        let w_t = 4.0 * self.lr * (1.0 - 2.0 * t);
        let d = 4.0 * self.lr * t * s - v.abs();
        let gv = if v > 0.0 {
            -1.0
        } else if v < 0.0 {
            1.0
        } else {
            0.0
        };
        Measure { d, grad: [w_t / xt, gv, -w_t * x_lt / xt, -w_t * x_lh / xt, 4.0 * t * s] }
    }
}

/// Bounds of a footprint's half-width over equal bins of `u ∈ (0, L)`, so that most pixels
/// can be classed as fully inside or fully outside the soft edge without solving for `t*`
/// (exactly: the half-width `4·lr·t(1 − t)` is unimodal in `t` and `t*(u)` is monotone, so its
/// extremes over a bin are at the bin's ends or, where `t = ½` falls in the bin, `lr`).
#[derive(Clone, Debug)]
pub(crate) struct WidthBounds {
    inv_du: f64,
    lo: Vec<f64>,
    hi: Vec<f64>,
    /// `t*` at the bins' ends (`bins + 1` values, 0 to 1).
    t: Vec<f64>,
}

impl WidthBounds {
    /// For `0 < u < L` and `|v|`: `Some(true)` when the coverage is surely 1 (`d ≥ e`),
    /// `Some(false)` when surely 0 (`d ≤ −e`), `None` when the pixel is in the soft edge.
    #[inline]
    pub(crate) fn classify(&self, u: f64, abs_v: f64, e: f64) -> Option<bool> {
        let k = ((u * self.inv_du) as usize).min(self.lo.len() - 1);
        if abs_v <= self.lo[k] - e {
            Some(true)
        } else if abs_v >= self.hi[k] + e {
            Some(false)
        } else {
            None
        }
    }
}

impl Shape {
    /// The half-width's bounds over `bins` equal bins of `(0, L)` (at least 1).
    pub(crate) fn width_bounds(&self, bins: usize) -> WidthBounds {
        let n = bins.max(1);
        let l = self.length();
        let t: Vec<f64> = (0..=n)
            .map(|k| match k {
                0 => 0.0,
                k if k == n => 1.0,
                k => self.solve_t(l * k as f64 / n as f64),
            })
            .collect();
        let w = |t: f64| 4.0 * self.lr * t * (1.0 - t);
        let (mut lo, mut hi) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for k in 0..n {
            let (a, b) = (t[k], t[k + 1]);
            lo.push(w(a).min(w(b)));
            hi.push(if a <= 0.5 && b >= 0.5 { self.lr } else { w(a).max(w(b)) });
        }
        WidthBounds { inv_du: n as f64 / l, lo, hi, t }
    }
}

/// Coverage of a signed measure `d` with an edge half-width `e` (mm): a smoothstep from 0 at
/// `d = −e` to 1 at `d = e`. Returns the coverage and `∂c/∂d`.
pub(crate) fn edge(d: f64, e: f64) -> (f64, f64) {
    let s = (d + e) / (2.0 * e);
    if s <= 0.0 {
        (0.0, 0.0)
    } else if s >= 1.0 {
        (1.0, 0.0)
    } else {
        (s * s * (3.0 - 2.0 * s), 6.0 * s * (1.0 - s) / (2.0 * e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SH: Shape = Shape { lt: 13.5, lh: 5.25, lr: 3.0 };

    #[test]
    fn the_half_width_matches_the_bezier() {
        // At t = ½ the curve is at the belly: x = lh, half-width lr.
        assert!((SH.x(0.5) - SH.lh).abs() < 1e-12);
        assert!((SH.measure(SH.lh, 0.0) - SH.lr).abs() < 1e-9);
        assert!((SH.measure(SH.lh, SH.lr)).abs() < 1e-9);
        for u in [0.3, 2.0, 7.0, 15.0, 18.5] {
            let t = SH.solve_t(u);
            assert!((SH.x(t) - u).abs() < 1e-9, "u {u}");
        }
    }

    #[test]
    fn the_measure_is_continuous_at_the_ends() {
        for v in [-1.0, 0.0, 0.5] {
            assert!((SH.measure(1e-9, v) - SH.measure(-1e-9, v)).abs() < 1e-6);
            let l = SH.length();
            assert!((SH.measure(l - 1e-9, v) - SH.measure(l + 1e-9, v)).abs() < 1e-6);
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let pts = [(-0.7, 0.4), (0.8, 0.9), (4.0, -2.5), (9.0, 1.7), (17.0, 0.3), (19.5, -0.6)];
        for &(u, v) in &pts {
            let m = SH.measure_grad(u, v);
            let eps = 1e-6;
            let f = |du: f64, dv: f64, dt: f64, dh: f64, dr: f64| {
                Shape { lt: SH.lt + dt, lh: SH.lh + dh, lr: SH.lr + dr }.measure(u + du, v + dv)
            };
            let fd = [
                (f(eps, 0.0, 0.0, 0.0, 0.0) - f(-eps, 0.0, 0.0, 0.0, 0.0)) / (2.0 * eps),
                (f(0.0, eps, 0.0, 0.0, 0.0) - f(0.0, -eps, 0.0, 0.0, 0.0)) / (2.0 * eps),
                (f(0.0, 0.0, eps, 0.0, 0.0) - f(0.0, 0.0, -eps, 0.0, 0.0)) / (2.0 * eps),
                (f(0.0, 0.0, 0.0, eps, 0.0) - f(0.0, 0.0, 0.0, -eps, 0.0)) / (2.0 * eps),
                (f(0.0, 0.0, 0.0, 0.0, eps) - f(0.0, 0.0, 0.0, 0.0, -eps)) / (2.0 * eps),
            ];
            assert!((m.d - f(0.0, 0.0, 0.0, 0.0, 0.0)).abs() < 1e-12);
            for (k, (g, d)) in m.grad.iter().zip(&fd).enumerate() {
                assert!((g - d).abs() < 1e-5, "({u}, {v}) ∂{k}: {g} vs {d}");
            }
        }
    }

    #[test]
    fn the_bracketed_solve_agrees_with_the_plain_one() {
        let b = SH.width_bounds(32);
        for i in 1..500 {
            let u = SH.length() * i as f64 / 500.0;
            for v in [-2.0, 0.3, 2.9] {
                let (p, q) = (SH.measure_grad(u, v), SH.measure_grad_with(u, v, &b));
                assert!((p.d - q.d).abs() < 1e-9, "u {u}: {} vs {}", p.d, q.d);
                for (x, y) in p.grad.iter().zip(&q.grad) {
                    assert!((x - y).abs() < 1e-7, "u {u}: {x} vs {y}");
                }
            }
        }
    }

    #[test]
    fn width_bounds_class_pixels_as_the_measure_does() {
        let e = 0.3;
        let b = SH.width_bounds(32);
        let (mut classed, mut n) = (0, 0);
        for i in 1..400 {
            let u = SH.length() * i as f64 / 400.0;
            for j in 0..80 {
                let v = -4.0 + 8.0 * j as f64 / 79.0;
                let (c, _) = edge(SH.measure(u, v), e);
                n += 1;
                match b.classify(u, v.abs(), e) {
                    Some(true) => assert_eq!(c, 1.0, "({u}, {v})"),
                    Some(false) => assert_eq!(c, 0.0, "({u}, {v})"),
                    None => continue,
                }
                classed += 1;
            }
        }
        assert!(classed * 2 > n, "{classed} of {n} classed");
    }

    #[test]
    fn the_edge_is_a_c1_ramp() {
        assert_eq!(edge(-1.0, 0.5), (0.0, 0.0));
        assert_eq!(edge(1.0, 0.5), (1.0, 0.0));
        let (c, dc) = edge(0.0, 0.5);
        assert!((c - 0.5).abs() < 1e-12 && (dc - 1.5).abs() < 1e-12);
    }
}
