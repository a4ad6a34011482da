//! The simulator's path buffer (issue 27), as the SDK names it: a timed stroke's joint
//! waypoints allocated, appended, evaluated against joint limits and moved on their timing;
//! invalid use refused (moving before a valid evaluation, an unknown name, NaN, a joint step
//! beyond the rate at the interval, a jump from where the arm is); the buffers' count and size
//! capped. Loopback only; every wait is bounded.

use std::time::Duration;

use robot_io::aubo::{AuboClient, Link};
use robot_io::sim::{Listen, MAX_BUFFER_WAYPOINTS, MAX_PATH_BUFFERS, MAX_TOTAL_WAYPOINTS, SimOptions, Simulator};
use robot_io::wire::Transport;
use robot_io::{HOME_JOINTS, RobotError, TraceKind};
use serde_json::{Value, json};

const T: Duration = Duration::from_secs(3);
const MC: &str = "rob1.MotionControl.";

fn framed(sim: &Simulator) -> AuboClient {
    AuboClient::open(&sim.addr.to_string(), &Link::default(), T).unwrap().0
}

fn call(c: &mut AuboClient, m: &str, params: Value) -> Value {
    c.call(&format!("{MC}{m}"), params).unwrap()
}

/// Waypoints from the home joints, joint 1 turning `rate` rad/s for `n` intervals of `dt`.
fn ramp(n: usize, rate: f64, dt: f64) -> Vec<[f64; 6]> {
    (0..n)
        .map(|k| {
            let mut q = HOME_JOINTS;
            // Smooth start and stop (a cosine ramp of the angle).
            let f = k as f64 / (n - 1) as f64;
            q[0] += rate * dt * (n - 1) as f64 * (0.5 - 0.5 * (std::f64::consts::PI * f).cos()) * 0.5;
            q
        })
        .collect()
}

fn alloc(c: &mut AuboClient, name: &str, size: usize) -> Value {
    call(c, "pathBufferAlloc", json!({"name": name, "type": 2, "size": size}))
}

#[test]
fn a_buffer_runs_on_its_timing_and_invalid_use_is_refused() {
    let sim = Simulator::start_with(
        &[Listen { bind: "127.0.0.1:0".into(), transports: vec![Transport::Framed] }],
        SimOptions::default(),
    )
    .unwrap();
    let mut c = framed(&sim);
    let (dt, lim_v, lim_a) = (0.01, [0.5; 6], [2.0; 6]);
    let w = ramp(200, 0.3, dt);
    assert_eq!(alloc(&mut c, "s1", w.len()), 0);
    // Before an evaluation: not valid, and not moved.
    assert_eq!(call(&mut c, "movePathBuffer", json!({"name": "s1"})), -5);
    for chunk in w.chunks(64) {
        assert_eq!(call(&mut c, "pathBufferAppend", json!({"name": "s1", "waypoints": chunk})), 0);
    }
    assert_eq!(call(&mut c, "pathBufferValid", json!({"name": "s1"})), false);
    // A joint speed limit the waypoints exceed at this interval: refused, still not valid.
    let slow = [0.01; 6];
    assert_eq!(call(&mut c, "pathBufferEval", json!({"name": "s1", "a": lim_a, "v": slow, "t": dt})), -5);
    assert_eq!(call(&mut c, "pathBufferValid", json!({"name": "s1"})), false);
    assert_eq!(call(&mut c, "pathBufferEval", json!({"name": "s1", "a": lim_a, "v": lim_v, "t": dt})), 0);
    assert_eq!(call(&mut c, "pathBufferValid", json!({"name": "s1"})), true);
    assert_eq!(call(&mut c, "pathBufferList", Value::Null), json!(["s1"]));
    // Unknown names.
    assert_eq!(call(&mut c, "pathBufferValid", json!({"name": "nope"})), false);
    assert_eq!(call(&mut c, "movePathBuffer", json!({"name": "nope"})), -5);
    let t0 = sim.trace().last().map_or(0.0, |t| t.t_s);
    assert_eq!(call(&mut c, "movePathBuffer", json!({"name": "s1"})), 0);
    // Executed on its timing: samples every dt / 2, the arm at the last waypoint.
    let trace: Vec<_> = sim.trace().into_iter().filter(|t| t.kind == TraceKind::PathBuffer).collect();
    assert_eq!(trace.len(), 2 * w.len() - 1);
    assert!((trace.last().unwrap().t_s - t0 - dt * (w.len() - 1) as f64).abs() < 1e-9);
    assert!(trace.windows(2).all(|p| (p[1].t_s - p[0].t_s - dt / 2.0).abs() < 1e-9));
    let q = c.joint_positions("rob1").unwrap();
    assert!(q.iter().zip(w.last().unwrap()).all(|(a, b)| (a - b).abs() < 1e-12), "{q:?}");
    // Moving it again: its first waypoint is far from the arm now, refused.
    assert_eq!(call(&mut c, "movePathBuffer", json!({"name": "s1"})), -5);
    assert_eq!(call(&mut c, "pathBufferFree", json!({"name": "s1"})), 0);
    assert_eq!(call(&mut c, "pathBufferFree", json!({"name": "s1"})), -5);
    // NaN and out-of-range joints, more waypoints than allocated, other types, bad names.
    assert_eq!(alloc(&mut c, "s2", 3), 0);
    let nan = c
        .call(&format!("{MC}pathBufferAppend"), json!({"name": "s2", "waypoints": [[0.0, 0.0, 0.0, 0.0, 0.0, "NaN"]]}));
    assert_eq!(nan.unwrap(), -5);
    assert_eq!(call(&mut c, "pathBufferAppend", json!({"name": "s2", "waypoints": [[9.0, 0, 0, 0, 0, 0]]})), -5);
    assert_eq!(call(&mut c, "pathBufferAppend", json!({"name": "s2", "waypoints": vec![HOME_JOINTS; 4]})), -5);
    assert_eq!(call(&mut c, "pathBufferAppend", json!({"name": "s2", "waypoints": vec![HOME_JOINTS; 3]})), 0);
    assert_eq!(call(&mut c, "pathBufferAlloc", json!({"name": "s3", "type": 1, "size": 10})), -5);
    assert_eq!(alloc(&mut c, "", 10), -5);
    assert_eq!(alloc(&mut c, &"x".repeat(65), 10), -5);
    assert_eq!(call(&mut c, "pathBufferEval", json!({"name": "s2", "a": lim_a, "v": lim_v, "t": f64::MAX})), -5);
    let neg = [-1.0; 6];
    assert_eq!(call(&mut c, "pathBufferEval", json!({"name": "s2", "a": lim_a, "v": neg, "t": dt})), -5);
    // A step beyond the rate at the interval, between two waypoints otherwise at rest.
    let mut jump = vec![HOME_JOINTS; 4];
    jump[2][3] += 0.1;
    jump[3][3] += 0.1;
    assert_eq!(alloc(&mut c, "s4", 4), 0);
    assert_eq!(call(&mut c, "pathBufferAppend", json!({"name": "s4", "waypoints": jump})), 0);
    let big_a = [20.0; 6];
    assert_eq!(call(&mut c, "pathBufferEval", json!({"name": "s4", "a": big_a, "v": lim_v, "t": dt})), -5);
    assert_eq!(call(&mut c, "pathBufferValid", json!({"name": "s4"})), false);
    // The caps: sizes, the count of buffers and the waypoints of all of them together.
    assert_eq!(alloc(&mut c, "big", MAX_BUFFER_WAYPOINTS + 1), -5);
    let mut held = 2; // s2 and s4
    while held < MAX_PATH_BUFFERS {
        assert_eq!(alloc(&mut c, &format!("b{held}"), 10), 0);
        held += 1;
    }
    assert_eq!(alloc(&mut c, "one_more", 10), -5);
    for k in 2..MAX_PATH_BUFFERS {
        assert_eq!(call(&mut c, "pathBufferFree", json!({"name": format!("b{k}")})), 0);
    }
    let mut k = 0;
    let mut total = 7;
    while total + MAX_BUFFER_WAYPOINTS <= MAX_TOTAL_WAYPOINTS {
        assert_eq!(alloc(&mut c, &format!("w{k}"), MAX_BUFFER_WAYPOINTS), 0);
        total += MAX_BUFFER_WAYPOINTS;
        k += 1;
    }
    assert_eq!(alloc(&mut c, "over", MAX_BUFFER_WAYPOINTS), -5);
    // Motion belongs to one session: a second client's movePathBuffer is refused.
    let mut other = AuboClient::open(&sim.addr.to_string(), &Link::default(), T).unwrap().0;
    let e = other.call(&format!("{MC}movePathBuffer"), json!({"name": "s2"})).unwrap_err();
    assert!(matches!(e, RobotError::Rpc { code: -32001, .. }), "{e}");
}

/// A two-stroke track, points 0.2 mm apart, with the built-in pen1 brush.
fn two_strokes() -> robot_io::brush_model::Track {
    use robot_io::brush_model::{Stroke, Track, TrackPoint};
    let pt = |x: f64, y: f64| TrackPoint { x_mm: x, y_mm: y, h_mm: 3.0, alpha_rad: 0.0, beta_rad: 0.0 };
    Track {
        strokes: vec![
            Stroke { points: (0..=150).map(|i| pt(40.0 + 0.2 * f64::from(i), 50.0)).collect() },
            Stroke { points: (0..=150).map(|i| pt(55.0, 40.0 + 0.2 * f64::from(i))).collect() },
        ],
    }
}

fn distance_to_polyline(p: [f64; 3], line: &[[f64; 3]]) -> f64 {
    let v = |a: [f64; 3]| nalgebra::Vector3::from(a);
    line.windows(2)
        .map(|w| {
            let (a, b, p) = (v(w[0]), v(w[1]), v(p));
            let ab = b - a;
            let f = if ab.norm_squared() > 0.0 { ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0) } else { 0.0 };
            (a + ab * f - p).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn send_writes_each_stroke_as_one_path_buffer_on_the_controllers_own_kinematics() {
    use robot_io::DhParams;
    use robot_io::{RobotConfig, build_program};
    use std::sync::atomic::AtomicBool;
    let profile = robot_io::brush_model::BrushProfile::builtin("pen1").unwrap();
    let frame = robot_io::level_frame_in_front([55.0, 55.0], [0.0, 0.0, 210.0, 297.0]);
    let cfg = RobotConfig::default();
    let (program, _) = build_program(&two_strokes(), &profile, &frame, &cfg).unwrap();
    // A controller whose arm is not the nominal one (its upper arm 20 mm longer): the runner
    // must time on the parameters it reports, or the brush would leave the path.
    let mut arm = DhParams::AUBO_I5;
    arm.a_m[2] += 0.02;
    let nominal = robot_io::time_program(&program, &DhParams::AUBO_I5, &cfg).unwrap();
    let q = nominal.strokes[0].joints[0];
    let off = (arm.forward(&q, &program.tcp()).translation.vector
        - DhParams::AUBO_I5.forward(&q, &program.tcp()).translation.vector)
        .norm();
    assert!(off > 0.005, "the two arms differ by {off} m");
    let options = SimOptions { kinematics: arm, ..SimOptions::default() };
    let sim =
        Simulator::start_with(&[Listen { bind: "127.0.0.1:0".into(), transports: vec![Transport::Framed] }], options)
            .unwrap();
    let stop = AtomicBool::new(false);
    let opts = robot_io::aubo::RunOptions { path_buffer: Some(cfg.clone()), ..robot_io::aubo::RunOptions::new(&stop) };
    let report = robot_io::aubo::run_program(&sim.addr.to_string(), &program, None, &opts, |_| {}).unwrap();
    assert_eq!(report.strokes_completed, vec![0, 1]);
    assert_eq!(report.path_buffers, 2);
    // It reported a compensation (its arm minus the nominal one), checked against its own
    // forward kinematics; the parameters were the controller's.
    assert!(report.compensation_checked && !report.nominal_kinematics);
    // A few calls per stroke, not one per point (302 points).
    assert!(report.calls < 60, "{} calls", report.calls);
    // Every executed path-buffer sample lies on its stroke's commanded path.
    let trace = sim.trace();
    let path_samples: Vec<_> = trace.iter().filter(|t| t.kind == TraceKind::PathBuffer).collect();
    assert!(path_samples.len() > 200, "{}", path_samples.len());
    let lines: Vec<Vec<[f64; 3]>> =
        program.strokes.iter().map(|st| robot_io::pressed_path(st).iter().map(|p| p.position()).collect()).collect();
    for t in &path_samples {
        let d = lines.iter().map(|l| distance_to_polyline(t.pose.position(), l)).fold(f64::INFINITY, f64::min);
        assert!(d < 1e-4, "a sample {:.4} mm off the path", d * 1e3);
    }
    // Our nominal arm's waypoints on that controller would have written elsewhere.
    let wrong = arm.forward(&nominal.strokes[0].joints[10], &program.tcp()).translation.vector;
    let d = lines.iter().map(|l| distance_to_polyline([wrong.x, wrong.y, wrong.z], l)).fold(f64::INFINITY, f64::min);
    assert!(d > 1e-3, "{d}");
}

#[test]
fn nominal_kinematics_are_refused_unless_accepted_and_still_checked_by_the_controller() {
    use robot_io::DhParams;
    use robot_io::{RobotConfig, build_program};
    use std::sync::atomic::AtomicBool;
    let profile = robot_io::brush_model::BrushProfile::builtin("pen1").unwrap();
    let frame = robot_io::level_frame_in_front([55.0, 55.0], [0.0, 0.0, 210.0, 297.0]);
    let cfg = RobotConfig::default();
    let (program, _) = build_program(&two_strokes(), &profile, &frame, &cfg).unwrap();
    let start = |options: SimOptions| {
        Simulator::start_with(&[Listen { bind: "127.0.0.1:0".into(), transports: vec![Transport::Framed] }], options)
            .unwrap()
    };
    let stop = AtomicBool::new(false);
    let opts = |nominal: bool, accept: bool| robot_io::aubo::RunOptions {
        path_buffer: Some(cfg.clone()),
        nominal_kinematics: nominal,
        accept_nominal_kinematics: accept,
        ..robot_io::aubo::RunOptions::new(&stop)
    };
    let moved = |sim: &Simulator| sim.trace().iter().any(|t| t.kind != TraceKind::Joint);
    // A controller that does not report its parameters: refused before a stroke is written
    // (only the start move, which the controller solves itself, ran).
    let without = SimOptions { kinematics_param: false, ..SimOptions::default() };
    let sim = start(without.clone());
    let e =
        robot_io::aubo::run_program(&sim.addr.to_string(), &program, None, &opts(false, false), |_| {}).unwrap_err();
    assert!(matches!(&e, RobotError::NominalKinematics { reason } if reason.contains("getKinematicsParam")), "{e}");
    assert!(!moved(&sim));
    // Accepted: written, on the nominal parameters (which this arm has), checked by its own
    // forward kinematics.
    let sim = start(without);
    let r = robot_io::aubo::run_program(&sim.addr.to_string(), &program, None, &opts(false, true), |_| {}).unwrap();
    assert_eq!((r.strokes_completed.len(), r.nominal_kinematics, r.compensation_checked), (2, true, false));
    // Nominal asked for: refused unless accepted, even where the controller reports its own.
    let sim = start(SimOptions::default());
    let e = robot_io::aubo::run_program(&sim.addr.to_string(), &program, None, &opts(true, false), |_| {}).unwrap_err();
    assert!(matches!(&e, RobotError::NominalKinematics { reason } if reason.contains("asked for")), "{e}");
    // Accepted on an arm that is not the nominal one: its forward kinematics disagree, and
    // nothing is written.
    let mut arm = DhParams::AUBO_I5;
    arm.a_m[2] += 0.02;
    let sim = start(SimOptions { kinematics: arm, ..SimOptions::default() });
    let e = robot_io::aubo::run_program(&sim.addr.to_string(), &program, None, &opts(true, true), |_| {}).unwrap_err();
    assert!(e.to_string().contains("the controller's forward kinematics put the TCP"), "{e}");
    assert!(!moved(&sim));
}
