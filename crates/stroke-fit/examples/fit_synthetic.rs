//! Makes a synthetic photo of a pen1 footprint and fits it back.
//!
//! `cargo run -p stroke-fit --example fit_synthetic`

use brush_model::{BrushProfile, Extrapolation, PointMm, Press};
use stroke_fit::{Degradation, synthetic_photo};
use stroke_fit::{fit_footprint, mask_from_gray};

fn main() {
    let pen1 = BrushProfile::builtin("pen1").expect("built-in");
    let fp = pen1.predict(&Press::from_degrees(16.0, 6.0, 2.0), Extrapolation::Refuse).expect("in range");
    let (px, side) = (10.0, 320u32);
    let g = synthetic_photo(&fp, PointMm::new(5.0, 16.0), 0.1, px, side, side, &Degradation::default(), 1);
    let mask = mask_from_gray(g, side as usize, side as usize, "synthetic").expect("one stroke");
    let fit = fit_footprint(&mask, px);
    println!("truth: {fp:?}, root (5, 16) mm, β 0.1 rad");
    println!("fit:   {fit:?}");
}
