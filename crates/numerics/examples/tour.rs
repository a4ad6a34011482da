//! A tour of the crate: a Nelder–Mead fit, a blurred point, a few SplitMix64 draws.
//!
//! `cargo run -p numerics --example tour`

use numerics::{Edge, NelderMead, Normalise, SplitMix64, gaussian_blur, nelder_mead};

fn main() {
    // A line through noisy points: slope and intercept by Nelder–Mead on the squared error.
    let mut rng = SplitMix64(1);
    let pts: Vec<(f64, f64)> = (0..20).map(|i| (i as f64, 0.5 * i as f64 - 2.0 + 0.1 * rng.normal())).collect();
    let sse = |p: &[f64; 2]| pts.iter().map(|&(x, y)| (p[0] * x + p[1] - y).powi(2)).sum::<f64>();
    let opts = NelderMead { min_spread: Some(1e-12), ..NelderMead::new([0.1, 0.5], 500) };
    let (p, v) = nelder_mead(sse, [0.0, 0.0], &opts);
    println!("line: slope {:.3}, intercept {:.3} (true 0.5, −2), squared error {v:.4}", p[0], p[1]);

    // One ink pixel blurred with σ = 1 px: the middle row of the result.
    let mut img = vec![0.0f32; 7 * 7];
    img[3 * 7 + 3] = 1.0;
    let out = gaussian_blur(&img, 7, 7, 1.0, Edge::Zero, Normalise::Sum);
    let row: Vec<String> = out[3 * 7..4 * 7].iter().map(|v| format!("{v:.3}")).collect();
    println!("blurred point, middle row: {}", row.join(" "));

    // Draws from one seed.
    let mut r = SplitMix64(42);
    println!("SplitMix64(42): {:#018x} {:.4} {:.4} {:+.4}", r.next_u64(), r.next_f64(), r.uniform(), r.normal());
}
