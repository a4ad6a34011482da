//! Training on footprints rendered on the fly by bezier-raster.

use std::path::{Path, PathBuf};
use std::time::Instant;

use bezier_raster::{Bsm, Coverage, DatasetSpec, Rasterizer, StrokeCanvas};
use brush_model::Press;
#[cfg(any(test, feature = "bench"))]
use candle_core::Tensor;
#[cfg(any(test, feature = "bench"))]
use candle_nn::{Optimizer, ParamsAdamW};

#[cfg(any(test, feature = "bench"))]
use crate::adam::FusedAdamW;
use crate::direct::DirectTrainer;
use rayon::prelude::*;
use serde::Serialize;

use crate::model::Generator;
use crate::{ConfigError, Metrics, NeuralGenError, Recipe};
use stroke_metrics::Summary;

#[cfg(any(test, feature = "bench"))]
fn cerr(e: candle_core::Error) -> NeuralGenError {
    NeuralGenError::Candle(e)
}

/// Training options.
#[derive(Clone, Debug)]
pub struct TrainOptions {
    /// Optimiser steps.
    pub steps: usize,
    /// Batch size.
    pub batch: usize,
    /// Peak learning rate.
    pub lr: f64,
    /// Seed of the training presses.
    pub seed: u64,
    /// Validate every this many steps.
    pub val_every: usize,
    /// Stop after this many validations without a 0.1 % improvement.
    pub patience: usize,
    /// Save the best weights here as training goes (and its config beside).
    pub checkpoint: Option<PathBuf>,
}

impl Default for TrainOptions {
    fn default() -> Self {
        Self { steps: 3000, batch: 64, lr: 2e-3, seed: 1, val_every: 100, patience: 8, checkpoint: None }
    }
}

/// One logged step.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct TrainPoint {
    /// Step (1-based).
    pub step: usize,
    /// Training MSE of this step's batch.
    pub train_mse: f64,
    /// Validation MSE, on validation steps.
    pub val_mse: Option<f64>,
    /// Learning rate used.
    pub lr: f64,
}

/// What training did.
#[derive(Clone, Debug, Serialize)]
pub struct TrainReport {
    /// Every step.
    pub history: Vec<TrainPoint>,
    /// Best validation MSE.
    pub best_val_mse: f64,
    /// Step of the best validation.
    pub best_step: usize,
    /// Steps run.
    pub steps_run: usize,
    /// Whether early stopping ended the run.
    pub stopped_early: bool,
    /// Wall time, s.
    pub wall_seconds: f64,
    /// Time spent rendering training data, s.
    pub data_seconds: f64,
}

/// The learning-rate schedule [`train`] follows, as a [`Recipe`] records it.
pub const SCHEDULE: &str = "linear warm-up over 5% of the steps, cosine decay to 5%";

impl TrainReport {
    /// The recipe of this run of [`train`] with `opts` (the steps actually run, the MSE loss,
    /// [`SCHEDULE`], the wall time and rayon's thread count), for [`GeneratorConfig::recipe`](crate::GeneratorConfig).
    pub fn recipe(&self, opts: &TrainOptions) -> Recipe {
        Recipe {
            steps: self.steps_run,
            batch: opts.batch,
            lr: opts.lr,
            seed: opts.seed,
            loss: "mse".into(),
            schedule: SCHEDULE.into(),
            wall_seconds: self.wall_seconds,
            threads: rayon::current_num_threads(),
        }
    }

    /// The held-out metrics of the trained generator: [`crate::evaluate`]'s CSIM and SSIM over
    /// `n` presses, with this run's best validation MSE.
    pub fn metrics(&self, n: usize, csim: &Summary, ssim: &Summary) -> Metrics {
        Metrics { n, ssim_mean: ssim.mean, ssim_worst: ssim.worst, csim_mean: csim.mean, val_mse: self.best_val_mse }
    }

    /// The loss curve as CSV: `step,train_mse,val_mse,lr`, one row per step, `val_mse` empty
    /// where the step was not validated.
    ///
    /// # Examples
    /// ```
    /// use neural_gen::{TrainPoint, TrainReport};
    /// let point = |step, val_mse| TrainPoint { step, train_mse: 0.5, val_mse, lr: 0.001 };
    /// let report = TrainReport {
    ///     history: vec![point(1, None), point(2, Some(0.25))],
    ///     best_val_mse: 0.25, best_step: 2, steps_run: 2, stopped_early: false, wall_seconds: 1.0, data_seconds: 0.1,
    /// };
    /// assert_eq!(report.loss_csv(), "step,train_mse,val_mse,lr\n1,0.5,,0.001\n2,0.5,0.25,0.001\n");
    /// ```
    pub fn loss_csv(&self) -> String {
        let mut csv = String::from("step,train_mse,val_mse,lr\n");
        for p in &self.history {
            let val = p.val_mse.map_or(String::new(), |v| v.to_string());
            csv.push_str(&format!("{},{},{val},{}\n", p.step, p.train_mse, p.lr));
        }
        csv
    }
}

/// Where [`train`]'s checkpoints of a run that will save to `output` go (set
/// [`TrainOptions::checkpoint`] to it): `NAME.checkpoint.safetensors` beside it (its config at
/// [`config_path`](crate::config_path) of that).
///
/// # Examples
/// ```
/// use std::path::Path;
/// assert_eq!(neural_gen::checkpoint_path(Path::new("out/pen2.safetensors")), Path::new("out/pen2.checkpoint.safetensors"));
/// ```
pub fn checkpoint_path(output: &Path) -> PathBuf {
    let stem = output.file_stem().map_or("generator".into(), |s| s.to_string_lossy().into_owned());
    output.with_file_name(format!("{stem}.checkpoint.safetensors"))
}

/// The fixed validation grid: h at 6 levels, α at 4, β at 2 (48 presses), inside the ranges.
pub(crate) fn validation_presses(g: &Generator) -> Vec<Press> {
    let r = &g.config.ranges;
    let mut v = Vec::new();
    for i in 0..6 {
        for j in 0..4 {
            for k in 0..2 {
                v.push(Press::new(
                    r.h_mm.lerp((i as f64 + 0.5) / 6.0),
                    r.alpha_rad.lerp((j as f64 + 0.5) / 4.0),
                    r.beta_rad.lerp((k as f64 + 0.5) / 2.0),
                ));
            }
        }
    }
    v
}

/// Renders the analytic B-BSM targets of presses in the generator's canvas convention, in
/// parallel: `B × S²` values, image after image.
///
/// # Errors
/// [`NeuralGenError`] if the profile refuses a press.
pub(crate) fn targets(g: &Generator, presses: &[Press]) -> Result<Vec<f32>, NeuralGenError> {
    let s = g.config.size as usize;
    let mut out = vec![0f32; presses.len() * s * s];
    targets_into(g, presses, &mut out)?;
    Ok(out)
}

/// As [`targets`], into `out` (`B × S²` values, every one overwritten).
fn targets_into(g: &Generator, presses: &[Press], out: &mut [f32]) -> Result<(), NeuralGenError> {
    let s = g.config.size;
    let ss = (s * s) as usize;
    debug_assert_eq!(out.len(), presses.len() * ss);
    let canvas = StrokeCanvas::with_scale(s, g.config.px_per_mm);
    let profile = &g.config.profile;
    out.par_chunks_mut(ss).zip(presses.par_iter()).try_for_each_init(
        || (Rasterizer::new(), Coverage::new(s, s)),
        |(r, img), (dst, p)| -> Result<(), NeuralGenError> {
            let fp = profile.predict(p, brush_model::Extrapolation::Allow).map_err(|e| NeuralGenError::Config {
                source_name: "profile".into(),
                problem: ConfigError::Profile(e),
            })?;
            r.render(&Bsm, &fp, canvas.anchor_mm(&fp, p.beta_rad), p.beta_rad, canvas.px_per_mm, img);
            dst.copy_from_slice(img.data());
            Ok(())
        },
    )
}

/// One batch of training data: normalised inputs (`[B, 3]`) and targets (`B × S²`), rendered
/// into reused buffers.
struct Batch {
    presses: Vec<Press>,
    x: Vec<f32>,
    y: Vec<f32>,
}

impl Batch {
    fn new() -> Self {
        Batch { presses: Vec::new(), x: Vec::new(), y: Vec::new() }
    }

    /// The batch of `step`: presses `step·B .. (step + 1)·B` of `spec`'s stream.
    fn fill(&mut self, g: &Generator, spec: &DatasetSpec, step: usize, batch: usize) -> Result<(), NeuralGenError> {
        self.presses.clear();
        self.presses.extend((0..batch).map(|i| spec.press((step * batch + i) as u64)));
        self.x.clear();
        self.x.extend(self.presses.iter().flat_map(|p| g.config.normalise(p)));
        let ss = (g.config.size * g.config.size) as usize;
        self.y.resize(batch * ss, 0.0);
        targets_into(g, &self.presses, &mut self.y)
    }
}

/// One optimiser step of the network alone through candle's graph (forward, MSE, backward,
/// fused AdamW with weight decay 0): what [`train()`] ran before the direct kernels
/// (`DirectTrainer`), kept as their reference in tests and benchmarks; public for the
/// benchmarks.
#[cfg(any(test, feature = "bench"))]
pub struct NetworkStep {
    opt: FusedAdamW,
}

#[cfg(any(test, feature = "bench"))]
impl NetworkStep {
    /// The optimiser over `g`'s weights at learning rate `lr`.
    ///
    /// # Errors
    /// [`NeuralGenError::Candle`].
    pub fn new(g: &Generator, lr: f64) -> Result<Self, NeuralGenError> {
        let opt = FusedAdamW::new(g.varmap.all_vars(), ParamsAdamW { lr, weight_decay: 0.0, ..Default::default() })
            .map_err(cerr)?;
        Ok(Self { opt })
    }

    /// One step on inputs `x` `[B, 3]` against targets `y` `[B, 1, S, S]` at learning rate
    /// `lr`; returns the MSE before the step.
    ///
    /// # Errors
    /// [`NeuralGenError::Candle`] (shapes).
    pub fn step(&mut self, g: &mut Generator, x: &Tensor, y: &Tensor, lr: f64) -> Result<f64, NeuralGenError> {
        self.opt.set_learning_rate(lr);
        let out = g.forward_autograd(x)?;
        let loss = (out - y).and_then(|d| d.sqr()).and_then(|d| d.mean_all()).map_err(cerr)?;
        self.opt.backward_step(&loss).map_err(cerr)?;
        g.weights_changed();
        Ok(loss.to_scalar::<f32>().map_err(cerr)? as f64)
    }
}

fn lr_at(step: usize, total: usize, peak: f64) -> f64 {
    let warm = (total / 20).max(1);
    if step < warm {
        return peak * (step + 1) as f64 / warm as f64;
    }
    let t = (step - warm) as f64 / (total - warm).max(1) as f64;
    peak * (0.05 + 0.95 * 0.5 * (1.0 + (std::f64::consts::PI * t).cos()))
}

/// Trains `g` with AdamW (weight decay 0) on MSE against analytic footprints drawn uniformly
/// from the profile's ranges, a warm-up then cosine learning-rate schedule, validation on a fixed
/// grid, early stopping, and checkpoints of the best weights. Deterministic for a seed at a given
/// thread count. `on_step` sees every step (for a progress bar).
///
/// # Errors
/// [`NeuralGenError`] from candle or from saving checkpoints.
pub fn train(
    g: &mut Generator,
    opts: &TrainOptions,
    mut on_step: impl FnMut(&TrainPoint),
) -> Result<TrainReport, NeuralGenError> {
    if opts.steps == 0 || opts.batch == 0 || opts.val_every == 0 || !(opts.lr.is_finite() && opts.lr > 0.0) {
        return Err(NeuralGenError::Config {
            source_name: "training options".into(),
            problem: ConfigError::TrainOptions {
                steps: opts.steps,
                batch: opts.batch,
                val_every: opts.val_every,
                lr: opts.lr,
            },
        });
    }
    let t0 = Instant::now();
    g.weights_changed();
    let spec = DatasetSpec {
        profile: g.config.profile.clone(),
        canvas: StrokeCanvas::with_scale(g.config.size, g.config.px_per_mm),
        seed: opts.seed,
    };
    let val_p = validation_presses(g);
    let cfg = g.config.clone();
    let normalised = |ps: &[Press]| -> Vec<f32> { ps.iter().flat_map(|p| cfg.normalise(p)).collect() };
    let (val_x, val_y) = (normalised(&val_p), targets(g, &val_p)?);
    let mut net = DirectTrainer::new(g)?;
    let mut history = Vec::with_capacity(opts.steps);
    let (mut best, mut best_step, mut since) = (f64::INFINITY, 0, 0);
    let mut best_weights: Option<Vec<Vec<f32>>> = None;
    let mut data_seconds = 0.0;
    let mut stopped_early = false;
    // The next batch's targets render while the network trains on this one (two buffers,
    // swapped each step); every batch is the same whichever thread renders it.
    let (mut cur, mut next) = (Batch::new(), Batch::new());
    let td = Instant::now();
    cur.fill(g, &spec, 0, opts.batch)?;
    data_seconds += td.elapsed().as_secs_f64();
    for step in 0..opts.steps {
        let lr = lr_at(step, opts.steps, opts.lr);
        let more = step + 1 < opts.steps;
        let gr = &*g;
        let (trained, rendered) = rayon::join(
            || net.step(&cur.x, &cur.y, lr),
            || -> Result<f64, NeuralGenError> {
                let td = Instant::now();
                if more {
                    next.fill(gr, &spec, step + 1, opts.batch)?;
                }
                Ok(td.elapsed().as_secs_f64())
            },
        );
        let train_mse = trained?;
        data_seconds += rendered?;
        std::mem::swap(&mut cur, &mut next);
        let mut point = TrainPoint { step: step + 1, train_mse, val_mse: None, lr };
        if (step + 1) % opts.val_every == 0 || step + 1 == opts.steps {
            let imgs = net.images(&val_x)?;
            let v = imgs.iter().zip(&val_y).map(|(a, b)| ((a - b) as f64).powi(2)).sum::<f64>() / val_y.len() as f64;
            point.val_mse = Some(v);
            if v < best * 0.999 {
                best = v;
                best_step = step + 1;
                since = 0;
                best_weights = Some(net.snapshot());
                if let Some(p) = &opts.checkpoint {
                    net.write_back(g)?;
                    g.save(p)?;
                }
            } else {
                since += 1;
            }
        }
        on_step(&point);
        history.push(point);
        if since >= opts.patience {
            stopped_early = true;
            break;
        }
    }
    if let Some(w) = best_weights {
        net.restore(w);
    }
    net.write_back(g)?;
    Ok(TrainReport {
        steps_run: history.len(),
        history,
        best_val_mse: best,
        best_step,
        stopped_early,
        wall_seconds: t0.elapsed().as_secs_f64(),
        data_seconds,
    })
}

#[cfg(test)]
mod record_tests {
    use super::*;

    #[test]
    fn the_recipe_and_metrics_record_the_run_as_it_went() {
        let point = |step, val_mse| TrainPoint { step, train_mse: 0.5, val_mse, lr: 0.002 };
        let report = TrainReport {
            history: vec![point(1, None), point(2, Some(0.125))],
            best_val_mse: 0.125,
            best_step: 2,
            steps_run: 2,
            stopped_early: true,
            wall_seconds: 3.5,
            data_seconds: 0.5,
        };
        let opts = TrainOptions { steps: 10, batch: 8, lr: 0.002, seed: 9, ..TrainOptions::default() };
        let r = report.recipe(&opts);
        assert_eq!((r.steps, r.batch, r.lr, r.seed), (2, 8, 0.002, 9), "the steps run, not asked");
        assert_eq!((r.loss.as_str(), r.schedule.as_str(), r.wall_seconds), ("mse", SCHEDULE, 3.5));
        let csim = Summary { count: 40, best: 0.99, worst: 0.9, mean: 0.95 };
        let ssim = Summary { count: 40, best: 0.98, worst: 0.8, mean: 0.9 };
        let m = report.metrics(40, &csim, &ssim);
        assert_eq!((m.n, m.ssim_mean, m.ssim_worst, m.csim_mean, m.val_mse), (40, 0.9, 0.8, 0.95, 0.125));
    }
}
