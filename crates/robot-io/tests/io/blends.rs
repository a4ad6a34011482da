//! Blended `moveLine`s on the simulator: the corner rounded inside the blend radius without
//! stopping, on the time law; blends a controller refuses (more than half a neighbouring move,
//! a zero-length move that blends) refused with −5; the runner's move-per-point mode refusing a
//! program with such blends before it connects, and running a compacted one blended.

use std::sync::atomic::AtomicBool;
use std::time::Duration;

use brush_model::{Stroke, Track, TrackPoint};
use robot_io::aubo::{AuboClient, Link, RunOptions, run_program};
use robot_io::sim::{Faults, Simulator};
use robot_io::{
    Move, Pose, RobotConfig, RobotError, TRACE_STEP_M, TraceEntry, TraceKind, build_program, compact_program,
};
use serde_json::json;

use crate::common::{paper, pen1};

const MOVE_LINE: &str = "rob1.MotionControl.moveLine";
const T: Duration = Duration::from_secs(3);

fn line(c: &mut AuboClient, pose: [f64; 6], blend_m: f64) -> i64 {
    match c.call_status(MOVE_LINE, json!({"pose": pose, "a": 0.3, "v": 0.02, "blend_radius": blend_m, "duration": 0.0}))
    {
        Ok(status) => status,
        Err(RobotError::Controller { code, .. }) => code,
        Err(e) => panic!("{e}"),
    }
}

fn at(x: f64, y: f64) -> [f64; 6] {
    [x, y, 0.1, std::f64::consts::PI, 0.0, 0.0]
}

fn speed(w: &[TraceEntry]) -> f64 {
    let (a, b) = (w[0].pose.position(), w[1].pose.position());
    (0..3).map(|i| (b[i] - a[i]).powi(2)).sum::<f64>().sqrt() / (w[1].t_s - w[0].t_s)
}

#[test]
fn the_simulator_rounds_a_blended_corner_without_stopping() {
    let sim = Simulator::start("127.0.0.1:0", Faults::default()).unwrap();
    let mut c = AuboClient::open(&sim.addr.to_string(), &Link::default(), T).unwrap().0;
    assert_eq!(line(&mut c, at(0.40, 0.0), 0.0), 0);
    let before = sim.trace().len();
    // 10 mm along x, a right angle, 10 mm along y; the corner blended by 2 mm.
    assert_eq!(line(&mut c, at(0.41, 0.0), 0.002), 0);
    assert_eq!(line(&mut c, at(0.41, 0.01), 0.0), 0);
    assert_eq!(c.tcp_pose("rob1").unwrap(), Pose(at(0.41, 0.01)));
    let trace: Vec<TraceEntry> = sim.trace()[before..].to_vec();
    assert!(trace.iter().all(|e| e.kind == TraceKind::Line));
    // The corner is cut: the path passes the parabola's apex, r·√2/4 = 0.71 mm from the corner,
    // and never leaves the commanded lines outside the 2 mm around it.
    let corner = |e: &TraceEntry| (e.pose.0[0] - 0.41).hypot(e.pose.0[1]);
    let (k, closest) = trace.iter().enumerate().min_by(|a, b| corner(a.1).total_cmp(&corner(b.1))).unwrap();
    assert!((corner(closest) - 0.002 * 2f64.sqrt() / 4.0).abs() < 2e-5, "{} mm", corner(closest) * 1e3);
    for e in &trace {
        let (x, y) = (e.pose.0[0], e.pose.0[1]);
        assert!(
            if x < 0.408 {
                y.abs() < 1e-9
            } else if y > 0.002 {
                (x - 0.41).abs() < 1e-9
            } else {
                true
            },
            "{x} {y}"
        );
    }
    // It does not stop at the corner: √(a·ρ) with ρ = 1 mm at the apex, 17 mm/s.
    assert!(speed(&trace[k..k + 2]) > 0.015, "{} m/s at the corner", speed(&trace[k..k + 2]));
    // The time law: never faster than commanded, samples at most 0.2 mm apart, starting and
    // ending at rest.
    assert!(
        trace
            .windows(2)
            .all(|w| speed(w) <= 0.02 * (1.0 + 1e-6) && speed(w) * (w[1].t_s - w[0].t_s) <= TRACE_STEP_M + 1e-12)
    );
    assert!(speed(&trace[..2]) < 0.005 && speed(&trace[trace.len() - 2..]) < 0.005);
}

#[test]
fn blends_a_controller_would_refuse_are_refused() {
    let sim = Simulator::start("127.0.0.1:0", Faults::default()).unwrap();
    let mut c = AuboClient::open(&sim.addr.to_string(), &Link::default(), T).unwrap().0;
    assert_eq!(line(&mut c, at(0.40, 0.0), 0.0), 0);
    // More than half its own 3 mm move.
    assert_eq!(line(&mut c, at(0.403, 0.0), 0.002), -5);
    // Half of it: accepted (it waits for the next move).
    assert_eq!(line(&mut c, at(0.403, 0.0), 0.0015), 0);
    // A next move of 2 mm: the 1.5 mm blend before it would be more than half of it.
    assert_eq!(line(&mut c, at(0.403, 0.002), 0.0), -5);
    // A zero-length move cannot take the blend either.
    assert_eq!(line(&mut c, at(0.403, 0.0), 0.0), -5);
    assert_eq!(line(&mut c, at(0.403, 0.003), 0.0), 0);
    assert_eq!(c.tcp_pose("rob1").unwrap(), Pose(at(0.403, 0.003)));
    // Nothing of the refused moves was executed: the path stays on x = 0.40–0.403, y = 0–0.003.
    assert!(sim.trace().iter().rev().take(50).all(|e| e.pose.0[1] >= -1e-9 && e.pose.0[0] <= 0.403 + 1e-9));
}

/// One stroke with a right-angle corner, points `step_mm` apart, pressed 12 mm.
fn corner_track(step_mm: f64) -> Track {
    let n = (20.0 / step_mm).round() as usize;
    let pt = |x: f64, y: f64| TrackPoint { x_mm: x, y_mm: y, h_mm: 12.0, alpha_rad: 0.0, beta_rad: 0.0 };
    let mut points: Vec<TrackPoint> = (0..=n).map(|i| pt(40.0 + step_mm * i as f64, 60.0)).collect();
    points.extend((1..=n).map(|i| pt(60.0, 60.0 + step_mm * i as f64)));
    Track { strokes: vec![Stroke { points }] }
}

#[test]
fn the_runner_sends_only_valid_blends_and_the_compacted_program_runs_blended() {
    let cfg = RobotConfig { blend_mm: 2.0, ..RobotConfig::default() };
    let (dense, _) = build_program(&corner_track(0.5), &pen1(), &paper(), &cfg).unwrap();
    let stop = AtomicBool::new(false);
    let opts = RunOptions { timeout: Duration::from_millis(2000), ..RunOptions::new(&stop) };
    // 2 mm blends on 0.5 mm moves: refused before connecting (nothing listens there).
    let e = run_program("127.0.0.1:9", &dense, None, &opts, |_| {}).unwrap_err();
    assert!(matches!(e, RobotError::Unsafe { .. }) && e.to_string().contains("more than half"), "{e}");
    // Compacted: one move per side, the corner blended by 2 mm.
    let compact = compact_program(&dense, &cfg);
    assert_eq!(compact.strokes[0].press.len(), 2);
    assert!(matches!(compact.strokes[0].press[0], Move::Line { blend_m, .. } if (blend_m - 0.002).abs() < 1e-12));
    let sim = Simulator::start("127.0.0.1:0", Faults::default()).unwrap();
    let r = run_program(&sim.addr.to_string(), &compact, None, &opts, |_| {}).unwrap();
    assert_eq!(r.strokes_completed, vec![0]);
    let f = paper();
    let pressed: Vec<[f64; 3]> =
        sim.trace().iter().map(|e| f.to_paper(e.pose.position())).filter(|p| p[2] > 11.999).collect();
    // The pressed path cuts the corner at (60, 60) by the parabola (0.71 mm) and otherwise
    // follows the track.
    let d = pressed.iter().map(|p| (p[0] - 60.0).hypot(p[1] - 60.0)).fold(f64::INFINITY, f64::min);
    assert!((d - 2.0 * 2f64.sqrt() / 4.0).abs() < 0.02, "{d} mm from the corner");
    assert!(
        pressed
            .iter()
            .all(|p| (p[1] - 60.0).abs() < 1e-6 || (p[0] - 60.0).abs() < 1e-6 || (p[0] > 58.0 && p[1] < 62.0))
    );
}

#[test]
fn the_compacted_program_stops_where_the_path_turns_back() {
    // Out 20 mm, back 10 mm at 150° from the way out, then on, turning 60°: the reversal's tip
    // gets no blend (a blend would round it off), the 60° turn keeps its 2 mm.
    let cfg = RobotConfig { blend_mm: 2.0, ..RobotConfig::default() };
    let pt = |x: f64, y: f64| TrackPoint { x_mm: x, y_mm: y, h_mm: 12.0, alpha_rad: 0.0, beta_rad: 0.0 };
    let back = 150f64.to_radians();
    let (bx, by) = (60.0 + 10.0 * back.cos(), 60.0 + 10.0 * back.sin());
    let mut points: Vec<TrackPoint> = (0..=40).map(|i| pt(40.0 + 0.5 * f64::from(i), 60.0)).collect();
    points.extend((1..=20).map(|i| pt(60.0 + 0.5 * f64::from(i) * back.cos(), 60.0 + 0.5 * f64::from(i) * back.sin())));
    let on = back + 60f64.to_radians();
    let (ux, uy) = (on.cos(), on.sin());
    points.extend((1..=20).map(|i| pt(bx + 0.5 * f64::from(i) * ux, by + 0.5 * f64::from(i) * uy)));
    let track = Track { strokes: vec![Stroke { points }] };
    let (dense, _) = build_program(&track, &pen1(), &paper(), &cfg).unwrap();
    let compact = compact_program(&dense, &cfg);
    let blends: Vec<f64> = compact.strokes[0]
        .press
        .iter()
        .map(|m| match *m {
            Move::Line { blend_m, .. } => blend_m,
            _ => panic!("a pressed move that is not a line"),
        })
        .collect();
    assert_eq!(blends.len(), 3, "{blends:?}");
    assert_eq!(blends[0], 0.0, "the reversal blends: {blends:?}");
    assert!((blends[1] - 0.002).abs() < 1e-12, "the 60° turn: {blends:?}");
    assert_eq!(blends[2], 0.0);
}
