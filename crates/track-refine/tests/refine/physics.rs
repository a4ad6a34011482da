//! A refined character track keeps the physics: depths and tilts inside the profile's ranges,
//! unpressed states unpressed, strokes and points as built, every direction what the forward
//! model derives, and the robot check (default robot.json) passes.

use brush_model::{BrushProfile, Extrapolation, ForwardModel, PointMm};
use robot_io::{PaperFrame, RobotConfig, build_program};
use track_refine::{RefineOptions, Target, refine};
use trajectory::{CharBox, Method, Sizing, TrackOptions, build_track, centre_lines, embedded_glyph, render_glyph};

fn check(ch: char, alpha_deg: f64) {
    let pen1 = BrushProfile::builtin("pen1").unwrap();
    let g = embedded_glyph(ch).unwrap();
    let paths = centre_lines(&g, Method::Medians, 256).unwrap();
    let alpha = alpha_deg.to_radians();
    let char_box = CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm: trajectory::auto_char_mm(&paths, &pen1, alpha) };
    let topts =
        TrackOptions { char_box, spacing_mm: trajectory::DEFAULT_SPACING_MM, alpha_rad: alpha, sizing: Sizing::Brush };
    let built = build_track(&paths, &pen1, &topts).unwrap().track;
    let px = 96;
    let target =
        Target::new(px, px, render_glyph(&g, px).data().to_vec(), PointMm::new(0.0, 0.0), char_box.size_mm / px as f64)
            .unwrap();
    let opts = RefineOptions { iterations: 8, ..RefineOptions::default() };
    let out = refine(&built, &pen1, &target, &opts).unwrap();
    let t = &out.track;
    assert_eq!(t.strokes.len(), built.strokes.len());
    let (hr, ar) = (pen1.ranges.h_mm, pen1.ranges.alpha_rad);
    let mut moved = 0.0f64;
    for (s, b) in t.strokes.iter().zip(&built.strokes) {
        assert_eq!(s.points.len(), b.points.len());
        for (p, q) in s.points.iter().zip(&b.points) {
            if q.h_mm >= hr.min {
                assert!(hr.contains(p.h_mm), "{ch}: h {} outside {:?}", p.h_mm, hr);
            } else {
                assert_eq!(p.h_mm, q.h_mm, "{ch}: an unpressed state keeps its depth");
            }
            assert!(ar.contains(p.alpha_rad), "{ch}: α {} outside {:?}", p.alpha_rad, ar);
            moved = moved.max((p.x_mm - q.x_mm).hypot(p.y_mm - q.y_mm));
        }
        // Directions are the forward model's (upright rule, as build_track derives them).
        let dragged = ForwardModel { tilt_threshold_rad: f64::INFINITY, ..ForwardModel::default() };
        let again = dragged.with_directions(&pen1, &s.points, Extrapolation::Refuse);
        for (i, (p, q)) in s.points.iter().zip(&again).enumerate() {
            let eased = i > 0 && p.h_mm <= 0.0 && s.points[i - 1].h_mm > 0.0;
            if !eased {
                assert!(brush_model::wrap_angle_rad(p.beta_rad - q.beta_rad).abs() < 1e-9, "{ch}: point {i}");
            }
        }
    }
    assert!(moved > 0.0, "{ch}: refinement moved nothing");
    let mut frame =
        PaperFrame::level([0.45 - char_box.size_mm / 2000.0, 0.05 + char_box.size_mm / 2000.0, 0.05], [0.0, 0.0]);
    frame.bounds_mm = [-char_box.size_mm, -char_box.size_mm, 2.0 * char_box.size_mm, 2.0 * char_box.size_mm];
    build_program(t, &pen1, &frame, &RobotConfig::default()).unwrap_or_else(|e| panic!("{ch} α {alpha_deg}°: {e}"));
}

#[test]
fn a_refined_track_stays_in_range_and_passes_the_robot_check() {
    check('永', 0.0);
}

#[test]
fn a_refined_tilted_track_stays_in_range_and_passes_the_robot_check() {
    check('永', 5.0);
}
