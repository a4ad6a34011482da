//! Nelder–Mead minimisation (Nelder & Mead 1965) with the standard coefficients: reflection 1,
//! expansion 2, contraction ½, shrink ½.

/// How the outside contraction point (between the centroid `c` and the reflected point `r`,
/// taken when the reflection beat only the worst vertex `w`) is computed. The two are equal in
/// exact arithmetic and can differ in the last bit; both exist so that results computed with
/// either stay bit-identical.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum OutsideContraction {
    /// `c − ½(w − c)`: along the line from the worst vertex, as the reflection itself.
    #[default]
    FromWorst,
    /// `c + ½(r − c)`: halfway from the centroid to the reflected point.
    FromReflected,
}

/// Settings of [`nelder_mead`] over `N` parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NelderMead<const N: usize> {
    /// The start simplex: the start point and, for each parameter `k`, the start point moved by
    /// `step[k]` along `k` (in the parameter's own units).
    pub step: [f64; N],
    /// The most iterations (each sorts the simplex and replaces or shrinks it once).
    pub max_iters: usize,
    /// Stop early once the best and worst values of the simplex differ by less than this;
    /// `None` always runs [`NelderMead::max_iters`] iterations.
    pub min_spread: Option<f64>,
    /// See [`OutsideContraction`].
    pub outside: OutsideContraction,
}

impl<const N: usize> NelderMead<N> {
    /// `max_iters` iterations from a simplex of `step`, no early stop,
    /// [`OutsideContraction::FromWorst`].
    pub fn new(step: [f64; N], max_iters: usize) -> Self {
        Self { step, max_iters, min_spread: None, outside: OutsideContraction::FromWorst }
    }
}

/// Minimises `f` from `start`; returns the best point found and its value. Deterministic: `f`
/// is called in a fixed order (the start, the other vertices in parameter order, then as the
/// iterations need), ties are kept in their order (stable sort, NaN sorts by
/// [`f64::total_cmp`]). `f` may keep state (`FnMut`), e.g. a reused image buffer.
///
/// # Examples
/// ```
/// use numerics::{NelderMead, nelder_mead};
/// // Rosenbrock's valley, minimum 0 at (1, 1).
/// let f = |p: &[f64; 2]| (1.0 - p[0]).powi(2) + 100.0 * (p[1] - p[0] * p[0]).powi(2);
/// let opts = NelderMead { min_spread: Some(1e-14), ..NelderMead::new([0.5, 0.5], 2000) };
/// let (p, v) = nelder_mead(f, [-1.2, 1.0], &opts);
/// assert!((p[0] - 1.0).abs() < 1e-3 && (p[1] - 1.0).abs() < 1e-3 && v < 1e-6, "{p:?} {v}");
/// ```
pub fn nelder_mead<const N: usize>(
    mut f: impl FnMut(&[f64; N]) -> f64,
    start: [f64; N],
    opts: &NelderMead<N>,
) -> ([f64; N], f64) {
    let mut pts: Vec<([f64; N], f64)> = Vec::with_capacity(N + 1);
    pts.push((start, f(&start)));
    for k in 0..N {
        let mut p = start;
        p[k] += opts.step[k];
        let v = f(&p);
        pts.push((p, v));
    }
    if N == 0 {
        return pts[0];
    }
    for _ in 0..opts.max_iters {
        pts.sort_by(|a, b| a.1.total_cmp(&b.1));
        if opts.min_spread.is_some_and(|s| (pts[N].1 - pts[0].1).abs() < s) {
            break;
        }
        let mut c = [0.0; N];
        for (p, _) in &pts[..N] {
            for k in 0..N {
                c[k] += p[k] / N as f64;
            }
        }
        let (worst, f_worst) = pts[N];
        let lerp = |a: &[f64; N], b: &[f64; N], t: f64| {
            let mut q = [0.0; N];
            for k in 0..N {
                q[k] = a[k] + t * (b[k] - a[k]);
            }
            q
        };
        let r = lerp(&c, &worst, -1.0);
        let fr = f(&r);
        if fr < pts[0].1 {
            let e = lerp(&c, &worst, -2.0);
            let fe = f(&e);
            pts[N] = if fe < fr { (e, fe) } else { (r, fr) };
        } else if fr < pts[N - 1].1 {
            pts[N] = (r, fr);
        } else {
            let q = if fr < f_worst {
                match opts.outside {
                    OutsideContraction::FromWorst => lerp(&c, &worst, -0.5),
                    OutsideContraction::FromReflected => lerp(&c, &r, 0.5),
                }
            } else {
                lerp(&c, &worst, 0.5)
            };
            let fc = f(&q);
            if fc < f_worst.min(fr) {
                pts[N] = (q, fc);
            } else {
                let best = pts[0].0;
                for p in pts.iter_mut().skip(1) {
                    p.0 = lerp(&best, &p.0, 0.5);
                    p.1 = f(&p.0);
                }
            }
        }
    }
    pts.sort_by(|a, b| a.1.total_cmp(&b.1));
    pts[0]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_a_quadratic_minimum_in_six_dimensions() {
        let centre = [1.0, -2.0, 0.5, 3.0, -0.25, 4.0];
        let f =
            |x: &[f64; 6]| x.iter().zip(centre).enumerate().map(|(k, (a, b))| (k + 1) as f64 * (a - b).powi(2)).sum();
        for outside in [OutsideContraction::FromWorst, OutsideContraction::FromReflected] {
            let opts = NelderMead { outside, ..NelderMead::new([1.0; 6], 3000) };
            let (x, v) = nelder_mead(f, [0.0; 6], &opts);
            assert!(x.iter().zip(centre).all(|(a, b)| (a - b).abs() < 1e-3) && v < 1e-6, "{outside:?}: {x:?} {v}");
        }
    }

    #[test]
    fn the_early_stop_calls_f_less_and_max_iters_bounds_the_calls() {
        let count = |opts: &NelderMead<2>| {
            let mut n = 0;
            let (_, v) = nelder_mead(
                |x: &[f64; 2]| {
                    n += 1;
                    x[0] * x[0] + x[1] * x[1]
                },
                [2.0, 1.0],
                opts,
            );
            (n, v)
        };
        let (all, v_all) = count(&NelderMead::new([0.5, 0.5], 500));
        let (early, v_early) = count(&NelderMead { min_spread: Some(1e-6), ..NelderMead::new([0.5, 0.5], 500) });
        assert!(early < all, "{early} {all}");
        assert!(v_early < 1e-5 && v_all <= v_early, "{v_early} {v_all}");
        // Each iteration calls f at most N + 2 times (reflection, contraction, shrink of N).
        let (few, _) = count(&NelderMead::new([0.5, 0.5], 3));
        assert!(few <= 3 + 3 * 4, "{few}");
    }

    #[test]
    fn zero_iterations_return_the_best_start_vertex() {
        let (x, v) = nelder_mead(|x: &[f64; 2]| x[0] + x[1], [1.0, 1.0], &NelderMead::new([-0.5, 0.25], 0));
        assert_eq!((x, v), ([0.5, 1.0], 1.5));
    }

    #[test]
    fn nan_values_never_win() {
        // NaN outside the unit disc: the search stays inside and finds the minimum at (0.3, 0).
        let f =
            |x: &[f64; 2]| if x[0] * x[0] + x[1] * x[1] > 1.0 { f64::NAN } else { (x[0] - 0.3).powi(2) + x[1] * x[1] };
        let (x, v) = nelder_mead(f, [0.0, 0.0], &NelderMead::new([0.8, 0.8], 400));
        assert!(v.is_finite() && (x[0] - 0.3).abs() < 1e-4 && x[1].abs() < 1e-4, "{x:?} {v}");
    }
}
