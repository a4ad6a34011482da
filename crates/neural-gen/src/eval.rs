//! The generator against the analytic B-BSM (the paper's Table 3).

use bezier_raster::{Bsm, Coverage, DatasetSpec, Rasterizer, StrokeCanvas};
use brush_model::Press;
use rayon::prelude::*;
use stroke_metrics::{GrayRef, SsimWorkspace, Summary};

use crate::model::Generator;
use crate::{ConfigError, GeneratorConfig, NeuralGenError};

/// Held-out presses: drawn with a seed training never uses.
pub const HELD_OUT_SEED: u64 = 0x0048_454c_444f_5554;

/// The held-out presses and canvas [`evaluate`] scores a generator with `config` on: its
/// profile, its canvas (`size`, `px_per_mm`), [`HELD_OUT_SEED`]. Press `i` is `spec.press(i)`,
/// so other models can be scored on the same presses (`maobi eval-generator`).
///
/// # Examples
/// ```
/// use neural_gen::{Arch, GeneratorConfig, held_out_spec};
/// let profile = neural_gen::brush_model::BrushProfile::builtin("pen1").unwrap();
/// let config = GeneratorConfig::new(profile, Arch::tiny_32());
/// let spec = held_out_spec(&config);
/// assert_eq!((spec.canvas.size, spec.seed), (config.size, neural_gen::HELD_OUT_SEED));
/// ```
pub fn held_out_spec(config: &GeneratorConfig) -> DatasetSpec {
    DatasetSpec {
        profile: config.profile.clone(),
        canvas: StrokeCanvas::with_scale(config.size, config.px_per_mm),
        seed: HELD_OUT_SEED,
    }
}

/// CSIM and SSIM summaries of the generator against the analytic footprints over `n` held-out
/// presses ([`held_out_spec`]; rendered in batches of 64).
///
/// # Errors
/// [`NeuralGenError::Config`] for `n = 0` (metrics of nothing); [`NeuralGenError`] from
/// inference, or when the generator's output is not finite.
pub fn evaluate(g: &Generator, n: usize) -> Result<(Summary, Summary), NeuralGenError> {
    if n == 0 {
        return Err(NeuralGenError::Config { source_name: "evaluation".into(), problem: ConfigError::NoPresses });
    }
    let s = g.config.size;
    let spec = held_out_spec(&g.config);
    let presses: Vec<Press> = (0..n as u64).map(|i| spec.press(i)).collect();
    let mut gen_imgs = Vec::with_capacity(n);
    for chunk in presses.chunks(64) {
        gen_imgs.extend(g.render(chunk)?);
    }
    if let Some(i) = gen_imgs.iter().position(|img| img.data().iter().any(|v| !v.is_finite())) {
        return Err(NeuralGenError::Shape(format!(
            "the generator's image of held-out press {i} is not finite (NaN or infinite pixels)"
        )));
    }
    let scores: Vec<(f64, f64)> = presses
        .par_iter()
        .zip(gen_imgs.par_iter())
        .map_init(
            || (Rasterizer::new(), Coverage::new(s, s), SsimWorkspace::new()),
            |(r, truth, ws), (p, img)| {
                let fp = g.config.profile.predict(p, brush_model::Extrapolation::Allow).expect("in range");
                r.render(&Bsm, &fp, spec.canvas.anchor_mm(&fp, p.beta_rad), p.beta_rad, spec.canvas.px_per_mm, truth);
                let (a, b) = (
                    GrayRef::new(truth.data(), s as usize, s as usize).expect("sized"),
                    GrayRef::new(img.data(), s as usize, s as usize).expect("sized"),
                );
                (stroke_metrics::csim(a, b).expect("same size"), ws.ssim(a, b).expect("same size"))
            },
        )
        .collect();
    Ok((Summary::of(scores.iter().map(|x| x.0)), Summary::of(scores.iter().map(|x| x.1))))
}
