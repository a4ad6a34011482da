//! The generator against the analytic B-BSM (the paper's Table 3).

use bezier_raster::{Bsm, Coverage, DatasetSpec, Rasterizer, StrokeCanvas};
use brush_model::Press;
use rayon::prelude::*;
use stroke_metrics::{GrayRef, SsimWorkspace, Summary};

use crate::NeuralGenError;
use crate::model::Generator;

/// Held-out presses: drawn with a seed training never uses.
pub const HELD_OUT_SEED: u64 = 0x4845_4c44_4f55_54;

/// CSIM and SSIM summaries of the generator against the analytic footprints over `n` held-out
/// presses (rendered in batches of 64).
///
/// # Errors
/// [`NeuralGenError`] from inference.
pub fn evaluate(g: &Generator, n: usize) -> Result<(Summary, Summary), NeuralGenError> {
    let s = g.config.size;
    let spec = DatasetSpec {
        profile: g.config.profile.clone(),
        canvas: StrokeCanvas::with_scale(s, g.config.px_per_mm),
        seed: HELD_OUT_SEED,
    };
    let presses: Vec<Press> = (0..n as u64).map(|i| spec.press(i)).collect();
    let mut gen_imgs = Vec::with_capacity(n);
    for chunk in presses.chunks(64) {
        gen_imgs.extend(g.render(chunk)?);
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
