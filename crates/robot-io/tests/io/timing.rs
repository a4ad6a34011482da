//! Timed strokes (issue 27): the time law keeps the speed, acceleration and jerk limits, slows
//! at sharp turns and steep presses, and refuses what exceeds a limit, naming the stroke.

use robot_io::brush_model::{BrushProfile, Stroke, Track, TrackPoint};
use robot_io::{
    DhParams, Program, RobotConfig, RobotError, TimedStroke, build_program, level_frame_in_front, time_program,
};

fn pt(x: f64, y: f64, h: f64) -> TrackPoint {
    TrackPoint { x_mm: x, y_mm: y, h_mm: h, alpha_rad: 0.0, beta_rad: 0.0 }
}

fn program(points: Vec<TrackPoint>, cfg: &RobotConfig) -> Program {
    let profile = BrushProfile::builtin("pen1").unwrap();
    let frame = level_frame_in_front([60.0, 60.0], [0.0, 0.0, 210.0, 297.0]);
    build_program(&Track { strokes: vec![Stroke { points }] }, &profile, &frame, cfg).unwrap().0
}

fn timed(points: Vec<TrackPoint>, cfg: &RobotConfig) -> TimedStroke {
    time_program(&program(points, cfg), &DhParams::AUBO_I5, cfg).unwrap().strokes.remove(0)
}

/// The TCP speed between consecutive waypoints, m/s.
fn speeds(t: &TimedStroke) -> Vec<f64> {
    t.poses
        .windows(2)
        .map(|w| {
            let (a, b) = (w[0].position(), w[1].position());
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt() / t.interval_s
        })
        .collect()
}

#[test]
fn a_straight_stroke_runs_at_the_write_speed_within_every_limit() {
    let cfg = RobotConfig::default();
    let t = timed((0..=60).map(|i| pt(30.0 + f64::from(i), 60.0, 3.0)).collect(), &cfg);
    // 60 mm: at most 20 mm/s, reached in the middle, ramps at both ends.
    assert!(t.duration_s > 3.0 && t.duration_s < 4.0, "{t:?}");
    assert!(t.peak_speed_m_s <= 0.02 + 1e-9 && t.peak_speed_m_s > 0.0199, "{t:?}");
    assert!(t.peak_acc_m_s2 <= cfg.write_acc_m_s2 * 1.01, "{t:?}");
    assert!(t.peak_joint_acc_rad_s2 <= cfg.joint_acc_rad_s2, "{t:?}");
    assert!(t.peak_joint_jerk_rad_s3 <= cfg.limits.max_joint_jerk_rad_s3, "{t:?}");
    assert!(t.reference_s <= t.duration_s && t.reference_s > 3.0, "{t:?}");
    // Starts and ends at rest, at the stroke's ends, one waypoint per interval.
    let v = speeds(&t);
    assert!(v[0] < 1e-3 && *v.last().unwrap() < 1e-3, "{:?} {:?}", &v[..3], &v[v.len() - 3..]);
    assert_eq!(t.joints.len(), t.poses.len());
    assert!((t.duration_s - (t.joints.len() - 1) as f64 * t.interval_s).abs() < 1e-9);
    // Our forward kinematics of the waypoints lie on the path.
    assert!(t.path_error_m < 1e-6 && t.path_error_rad < 1e-6, "{t:?}");
    // One branch: no joint moves more than its speed allows in one interval.
    for w in t.joints.windows(2) {
        assert!((0..6).all(|j| (w[1][j] - w[0][j]).abs() <= cfg.joint_speed_rad_s * t.interval_s + 1e-12));
    }
}

#[test]
fn the_brush_slows_at_a_sharp_turn_and_on_a_steep_press() {
    let cfg = RobotConfig::default();
    // An L: 30 mm right, then 30 mm down; points 0.5 mm apart.
    let mut l: Vec<TrackPoint> = (0..=60).map(|i| pt(30.0 + 0.5 * f64::from(i), 60.0, 3.0)).collect();
    l.extend((1..=60).map(|i| pt(60.0, 60.0 + 0.5 * f64::from(i), 3.0)));
    let t = timed(l, &cfg);
    let v = speeds(&t);
    // The waypoint nearest the corner.
    let corner = t
        .poses
        .iter()
        .enumerate()
        .min_by(|a, b| {
            let d = |p: &robot_io::Pose| {
                let q = p.position();
                let c = t.poses[0].position();
                // The corner is 30 mm along x from the start in the base frame's plane.
                ((q[0] - c[0]).abs() - 0.03).abs() + ((q[1] - c[1]).abs() - 0.03).abs()
            };
            d(a.1).total_cmp(&d(b.1))
        })
        .unwrap()
        .0;
    let at_corner = v[corner.min(v.len() - 1)];
    assert!(at_corner < 0.25 * cfg.write_speed_m_s, "{at_corner} m/s at the corner");
    assert!(v.iter().copied().fold(0.0, f64::max) > 0.0199);
    assert!(t.peak_acc_m_s2 <= cfg.write_acc_m_s2 * 1.01, "{t:?}");
    // A press 5 mm deeper over 2 mm of paper: the depth rate stays within 20 mm/s.
    let mut p: Vec<TrackPoint> =
        (0..=20).map(|i| pt(30.0 + 0.1 * f64::from(i), 60.0, 1.0 + 0.25 * f64::from(i))).collect();
    p.extend((1..=20).map(|i| pt(32.0 + f64::from(i), 60.0, 6.0)));
    let t = timed(p, &cfg);
    assert!(t.peak_depth_rate_mm_s <= cfg.timing.max_depth_rate_mm_s * 1.001, "{t:?}");
    assert!(t.peak_depth_rate_mm_s > 0.5 * cfg.timing.max_depth_rate_mm_s, "{t:?}");
}

#[test]
fn a_stroke_beyond_a_limit_is_refused_naming_the_stroke_and_the_limit() {
    let cfg = RobotConfig::default();
    let points: Vec<TrackPoint> = (0..=40).map(|i| pt(30.0 + f64::from(i), 60.0, 3.0)).collect();
    let prog = program(points, &cfg);
    let mut tight = cfg.clone();
    tight.limits.max_joint_jerk_rad_s3 = 1e-3;
    let e = time_program(&prog, &DhParams::AUBO_I5, &tight).unwrap_err();
    assert!(matches!(e, RobotError::Unsafe { stroke: Some(0), .. }), "{e}");
    assert!(e.to_string().contains("limits.max_joint_jerk_rad_s3"), "{e}");
    let mut near = cfg.clone();
    near.limits.min_singular_value = 0.9;
    let e = time_program(&prog, &DhParams::AUBO_I5, &near).unwrap_err();
    assert!(e.to_string().contains("limits.min_singular_value") && e.to_string().contains("singularity"), "{e}");
    // Another arm (a longer upper arm): the same program times on its own joints, and our
    // forward kinematics of them reproduce the path.
    let mut other = DhParams::AUBO_I5;
    other.a_m[2] += 0.02;
    let t = time_program(&prog, &other, &cfg).unwrap();
    let nominal = time_program(&prog, &DhParams::AUBO_I5, &cfg).unwrap();
    assert!(t.strokes[0].path_error_m < 1e-6);
    assert!((t.strokes[0].joints[0][1] - nominal.strokes[0].joints[0][1]).abs() > 1e-3);
}

#[test]
fn a_compacted_stroke_keeps_its_path_with_valid_blends_and_no_zero_length_move() {
    use robot_io::{COMPACT_TOLERANCE_M, check_blends, compact_program};
    let cfg = RobotConfig::default();
    // A quarter circle of radius 20 mm, points 0.15 mm apart, a repeated point, a deepening press.
    let mut pts: Vec<TrackPoint> = (0..=209)
        .map(|i| {
            let a = f64::from(i) * 0.15 / 20.0;
            pt(40.0 + 20.0 * a.cos(), 60.0 + 20.0 * a.sin(), 2.0 + 0.01 * f64::from(i))
        })
        .collect();
    pts.insert(50, pts[50]);
    let prog = program(pts, &cfg);
    let compact = compact_program(&prog, &cfg);
    check_blends(&compact).unwrap();
    let (before, after) = (prog.strokes[0].press.len(), compact.strokes[0].press.len());
    assert!(after * 5 <= before, "{after} moves of {before}");
    // Every original pressed point lies within the tolerance of the compacted polyline.
    let line: Vec<[f64; 3]> = robot_io::pressed_path(&compact.strokes[0]).iter().map(|p| p.position()).collect();
    for p in robot_io::pressed_path(&prog.strokes[0]) {
        let q = nalgebra::Vector3::from(p.position());
        let d = line
            .windows(2)
            .map(|w| {
                let (a, b) = (nalgebra::Vector3::from(w[0]), nalgebra::Vector3::from(w[1]));
                let f = ((q - a).dot(&(b - a)) / (b - a).norm_squared()).clamp(0.0, 1.0);
                (a + (b - a) * f - q).norm()
            })
            .fold(f64::INFINITY, f64::min);
        assert!(d <= COMPACT_TOLERANCE_M + 1e-12, "{d}");
    }
    // The blend of the uncompacted program (0.5 mm over 0.15 mm moves) is what it refuses.
    let e = check_blends(&prog).unwrap_err();
    assert!(e.to_string().contains("more than half the shorter of its moves"), "{e}");
}

#[test]
fn the_brush_stops_exactly_where_the_path_turns_back() {
    let cfg = RobotConfig::default();
    // Out 10 mm and back along the same line, pressing 2 mm deeper at the far end.
    let mut pts: Vec<TrackPoint> =
        (0..=50).map(|i| pt(40.0 + 0.2 * f64::from(i), 60.0, 3.0 + 0.04 * f64::from(i))).collect();
    pts.extend((1..=50).map(|i| pt(50.0 - 0.2 * f64::from(i), 60.0, 5.0 - 0.04 * f64::from(i))));
    let prog = program(pts, &cfg);
    let far = robot_io::pressed_path(&prog.strokes[0])[50].position();
    let t = time_program(&prog, &DhParams::AUBO_I5, &cfg).unwrap().strokes.remove(0);
    // A waypoint at the turning point itself (the deepest press is reached, not cut short).
    let closest = t
        .poses
        .iter()
        .map(|p| (0..3).map(|k| (p.position()[k] - far[k]).powi(2)).sum::<f64>().sqrt())
        .fold(f64::INFINITY, f64::min);
    assert!(closest < 1e-12, "{closest}");
}
