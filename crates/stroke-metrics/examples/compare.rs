//! Scores two synthetic discs against each other.
//!
//! `cargo run -p stroke-metrics --example compare`

use stroke_metrics::{GrayRef, Summary, compare};

fn disc(n: usize, cx: f32, r: f32) -> Vec<f32> {
    (0..n * n)
        .map(|i| {
            let (x, y) = ((i % n) as f32 + 0.5, (i / n) as f32 + 0.5);
            (r - ((x - cx).powi(2) + (y - n as f32 / 2.0).powi(2)).sqrt() + 0.5).clamp(0.0, 1.0)
        })
        .collect()
}

fn main() {
    let n = 64;
    let reference = disc(n, 32.0, 12.0);
    let mut ssims = Vec::new();
    for shift in 0..5 {
        let moved = disc(n, 32.0 + shift as f32, 12.0);
        let s = compare(GrayRef::new(&reference, n, n).unwrap(), GrayRef::new(&moved, n, n).unwrap()).unwrap();
        println!("shift {shift} px: {s:?}");
        ssims.push(s.ssim);
    }
    println!("SSIM over the set: {:?}", Summary::of(ssims));
}
