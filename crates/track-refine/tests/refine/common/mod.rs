//! Synthetic inputs shared by the refinement tests.

#![allow(dead_code)]

use brush_model::{BrushProfile, PointMm, Stroke, Track, TrackPoint};
use track_refine::Target;

/// The built-in pen1 profile.
pub fn pen1() -> BrushProfile {
    BrushProfile::builtin("pen1").unwrap()
}

/// A gently bent stroke along +x at y ≈ 30 mm from x = 10 to 50 mm in `n` steps, its depth
/// rising from `h` to `h + 2` mm, at tilt `alpha`, with a glide state at its start like the
/// track builder's turn-over.
pub fn line_track(h: f64, alpha: f64, n: usize) -> Track {
    let mut points = vec![TrackPoint { x_mm: 10.0, y_mm: 30.0, h_mm: 0.01, alpha_rad: alpha, beta_rad: 0.0 }];
    for i in 0..=n {
        let x = 10.0 + 40.0 * i as f64 / n as f64;
        // A gentle bend so that directions vary.
        let y = 30.0 + 2.0 * ((x - 10.0) / 40.0 * std::f64::consts::PI).sin();
        points.push(TrackPoint {
            x_mm: x,
            y_mm: y,
            h_mm: h + 2.0 * (i as f64 / n as f64),
            alpha_rad: alpha,
            beta_rad: 0.0,
        });
    }
    Track { strokes: vec![Stroke { points }] }
}

/// A horizontal bar from x = 8 to 48 mm, y = 26 to 36 mm on a `px²` raster of a 64 mm box.
pub fn bar_target(px: u32) -> Target {
    let mm = 64.0 / px as f64;
    let mut ink = vec![0f32; (px * px) as usize];
    for j in 0..px {
        for i in 0..px {
            let (x, y) = ((i as f64 + 0.5) * mm, (j as f64 + 0.5) * mm);
            if (8.0..48.0).contains(&x) && (26.0..36.0).contains(&y) {
                ink[(j * px + i) as usize] = 1.0;
            }
        }
    }
    Target::new(px, px, ink, PointMm::new(0.0, 0.0), mm).unwrap()
}
