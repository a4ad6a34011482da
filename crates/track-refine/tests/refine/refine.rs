//! Refinement on synthetic targets: gradients against finite differences, one step lowers the
//! loss, a refined track stays in the ranges and passes the robot check.

use crate::common::{bar_target, line_track, pen1};
use brush_model::{PointMm, Track};
use track_refine::{Problem, RefineOptions, Target, refine};

#[test]
fn gradients_match_finite_differences() {
    let profile = pen1();
    let target = bar_target(64);
    for alpha in [0.0, 5f64.to_radians()] {
        let track = line_track(12.0, alpha, 267);
        // No coupling; the aims found by the reach only; with the farthest-sample aims of the
        // stroke's start; and with the aims sliding as the reach changes with the depth.
        for (coupling, far, reach) in
            [(false, false, false), (true, false, false), (true, true, false), (true, true, true)]
        {
            let opts = RefineOptions {
                smooth_weight: 5.0,
                spacing_weight: 5.0,
                aim_coupling: coupling,
                aim_far: far,
                aim_reach: reach,
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
    let track = line_track(11.5, 0.0, 267);
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
    let out = refine(&line_track(11.5, 0.0, 267), &profile, &target, &RefineOptions::default()).unwrap();
    let (first, last) = (out.curve[0], out.curve[out.curve.len() - 1]);
    assert!(last.image < 0.9 * first.image, "{first:?} → {last:?}");
}

#[test]
fn refinement_is_deterministic() {
    let profile = pen1();
    let target = bar_target(64);
    let opts = RefineOptions { iterations: 5, ..RefineOptions::default() };
    let a = refine(&line_track(12.0, 0.0, 267), &profile, &target, &opts).unwrap();
    let b = refine(&line_track(12.0, 0.0, 267), &profile, &target, &opts).unwrap();
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
    let e =
        refine(&line_track(12.0, 0.0, 267), &profile, &target, &RefineOptions { edge_px: 0.0, ..Default::default() })
            .unwrap_err();
    assert!(e.to_string().contains("edge_px") && e.to_string().contains("expected"), "{e}");
    let e = Target::new(4, 4, vec![0.0; 15], PointMm::new(0.0, 0.0), 1.0).unwrap_err();
    assert!(e.to_string().contains("expected width × height"), "{e}");
    let e = Target::new(2, 2, vec![0.0, 2.0, 0.0, 0.0], PointMm::new(0.0, 0.0), 1.0).unwrap_err();
    assert!(e.to_string().contains("[0, 1]"), "{e}");
    let blank = Target::new(8, 8, vec![0.0; 64], PointMm::new(0.0, 0.0), 8.0).unwrap();
    let e = refine(&line_track(12.0, 0.0, 267), &profile, &blank, &RefineOptions::default()).unwrap_err();
    assert!(e.to_string().contains("no ink"), "{e}");
}

/// With `aim_far`, the footprints of a stroke's start (before the brush has moved the drag
/// rule's reach since touch-down) aim at the farthest sample, as the forward model does, and
/// each aim reproduces the direction the model derived; without it their angles are held.
#[test]
fn the_first_footprints_of_a_stroke_aim_at_the_farthest_sample() {
    let profile = pen1();
    let target = bar_target(64);
    let track = line_track(12.0, 0.0, 267);
    let count = |far: bool| {
        let opts = RefineOptions { aim_far: far, ..RefineOptions::default() };
        let p = Problem::new(&track, &profile, &target, &opts).unwrap();
        let theta = p.initial();
        let dirs = p.directions(&theta);
        let hmin = profile.ranges.h_mm.min;
        let pressed: Vec<_> =
            dirs.track.strokes.iter().flat_map(|s| s.points.iter()).filter(|q| q.h_mm >= hmin).collect();
        assert_eq!(pressed.len(), dirs.aim.len());
        for (k, (q, aim)) in pressed.iter().zip(&dirs.aim).enumerate() {
            if let Some((ga, gb, f)) = *aim {
                let ax = (1.0 - f) * theta[2 * ga] + f * theta[2 * gb];
                let ay = (1.0 - f) * theta[2 * ga + 1] + f * theta[2 * gb + 1];
                let beta = (ay - q.y_mm).atan2(ax - q.x_mm);
                assert!(
                    (beta - dirs.beta_rad[k]).abs() < 1e-9,
                    "footprint {k}: aim gives {beta}, model {}",
                    dirs.beta_rad[k]
                );
            }
        }
        // Index of the first footprint with an aim.
        (dirs.aim.iter().filter(|a| a.is_some()).count(), dirs.aim.iter().position(Option::is_some))
    };
    let (held, first_held) = count(false);
    let (far, first_far) = count(true);
    // The reach is half a 15–18 mm footprint: the first ~7 mm of the 40 mm stroke (about 45 points).
    assert!(far >= held + 30, "{far} aims with aim_far, {held} without");
    assert!(first_far.unwrap() < 3 && first_held.unwrap() > 30, "{first_far:?} {first_held:?}");
}

/// The footprints' directions follow the hairs of the profile the track is refined for (its
/// `hairs.trail_reach`, as the closed loop fits it), not a reach carried beside it.
#[test]
fn directions_follow_the_profiles_trail_reach() {
    let target = bar_target(64);
    // A quarter circle of radius 20 mm, upright, pressed 12 mm.
    let pts = (0..=60)
        .map(|i| {
            let a = std::f64::consts::FRAC_PI_2 * f64::from(i) / 60.0;
            brush_model::TrackPoint {
                x_mm: 10.0 + 20.0 * a.sin(),
                y_mm: 40.0 - 20.0 * a.cos(),
                h_mm: 12.0,
                alpha_rad: 0.0,
                beta_rad: 0.0,
            }
        })
        .collect();
    let track = Track { strokes: vec![brush_model::Stroke { points: pts }] };
    let betas = |trail_reach: f64| {
        let mut profile = pen1();
        profile.hairs.trail_reach = trail_reach;
        let opts = RefineOptions::default();
        let p = Problem::new(&track, &profile, &target, &opts).unwrap();
        let got = p.directions(&p.initial()).beta_rad;
        let model =
            brush_model::ForwardModel { tilt_threshold_rad: f64::INFINITY, ..brush_model::ForwardModel::default() };
        let want = model.with_directions(&profile, &track.strokes[0].points, brush_model::Extrapolation::Refuse);
        for (g, w) in got.iter().zip(&want) {
            assert!(brush_model::wrap_angle_rad(g - w.beta_rad).abs() < 1e-12, "{trail_reach}: {g} vs {}", w.beta_rad);
        }
        got
    };
    let (own, short) = (betas(brush_model::TRAIL_REACH), betas(0.3));
    assert!(
        own.iter().zip(&short).any(|(a, b)| (a - b).abs() > 1e-3),
        "the reach turns the footprints round the curve"
    );
    // The options carry no reach of their own: one written by an older build is refused by name.
    let old = r#"{"iterations": 20, "trail_reach": 0.3}"#;
    let e = serde_json::from_str::<RefineOptions>(old).unwrap_err();
    assert!(e.to_string().contains("trail_reach"), "{e}");
}
