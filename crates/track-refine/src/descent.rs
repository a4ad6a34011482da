//! The descent: Adam steps on the problem's gradient, directions re-derived every few steps,
//! every iterate projected into the ranges.

use std::time::Instant;

use crate::{Problem, RefineError, RefineOptions, Refined};

/// Runs the descent on `problem` (started at `t0`, for the wall time).
pub(crate) fn run(problem: Problem<'_>, opts: &RefineOptions, t0: Instant) -> Result<Refined, RefineError> {
    let mut theta = problem.initial();
    let steps = problem.steps();
    let mut adam = Adam::new(theta.len());
    let mut dirs = problem.directions(&theta);
    let mut curve = Vec::with_capacity(opts.iterations + 1);
    for it in 0..opts.iterations {
        if it > 0 && it % opts.rederive_every == 0 {
            dirs = problem.directions(&theta);
        }
        let (loss, mut grad) = problem.loss_grad(&theta, &dirs);
        if !loss.total.is_finite() {
            return Err(RefineError::NotFinite { iteration: it, value: loss.total });
        }
        problem.smooth_gradient(&mut grad, opts.gradient_sigma_mm);
        curve.push(loss);
        if it == 0 || (opts.floor_every > 0 && it % opts.floor_every == 0) {
            adam.set_floors(&grad, &problem.kinds(), opts.grad_floor);
        }
        adam.step(&mut theta, &grad, &steps);
        problem.project(&mut theta);
    }
    problem.project(&mut theta);
    let dirs = problem.directions(&theta);
    let last = problem.loss(&theta, &dirs);
    if !last.total.is_finite() {
        return Err(RefineError::NotFinite { iteration: opts.iterations, value: last.total });
    }
    curve.push(last);
    Ok(Refined {
        track: dirs.track,
        curve,
        variables: problem.len(),
        footprints: problem.pressed_count(),
        millis: t0.elapsed().as_secs_f64() * 1e3,
    })
}

/// Adam with per-variable step sizes (β₁ = 0.9, β₂ = 0.999) and a per-kind floor under the
/// gradient's scale: plain Adam moves every variable by about its step whatever the size of its
/// gradient, so the thousands of points deep inside a stroke (gradient near zero) would wander;
/// with the floor `ε` a variable whose gradient is well below `ε` moves in proportion to it.
struct Adam {
    m: Vec<f64>,
    v: Vec<f64>,
    floor: Vec<f64>,
    t: i32,
}

impl Adam {
    fn new(n: usize) -> Self {
        Self { m: vec![0.0; n], v: vec![0.0; n], floor: vec![1e-12; n], t: 0 }
    }

    /// Floors at `k` × the root mean square of each kind's first gradient.
    fn set_floors(&mut self, grad: &[f64], kinds: &[u8], k: f64) {
        for kind in 0..3u8 {
            let (mut s, mut n) = (0.0, 0usize);
            for (g, _) in grad.iter().zip(kinds).filter(|(_, c)| **c == kind) {
                s += g * g;
                n += 1;
            }
            let rms = if n > 0 { (s / n as f64).sqrt() } else { 0.0 };
            for (f, _) in self.floor.iter_mut().zip(kinds).filter(|(_, c)| **c == kind) {
                *f = (k * rms).max(1e-12);
            }
        }
    }

    fn step(&mut self, theta: &mut [f64], grad: &[f64], steps: &[f64]) {
        const B1: f64 = 0.9;
        const B2: f64 = 0.999;
        self.t += 1;
        let (c1, c2) = (1.0 - B1.powi(self.t), 1.0 - B2.powi(self.t));
        for i in 0..theta.len() {
            self.m[i] = B1 * self.m[i] + (1.0 - B1) * grad[i];
            self.v[i] = B2 * self.v[i] + (1.0 - B2) * grad[i] * grad[i];
            let (mh, vh) = (self.m[i] / c1, self.v[i] / c2);
            theta[i] -= steps[i] * mh / (vh.sqrt() + self.floor[i]);
        }
    }
}
