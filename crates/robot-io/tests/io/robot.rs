//! robot-io: frames, poses, kinematics, the safety envelope, exporters, and full runs against the
//! simulator on loopback (including a dropped connection mid-stroke).

// Poses written as a teach pendant shows them: rx = 3.14 rad (the tool flipped), not π.
#![allow(clippy::approx_constant, reason = "3.14 rad is a pendant-style rx, deliberately not π")]

use std::sync::atomic::AtomicBool;
use std::time::Duration;

use brush_model::{Track, TrackPoint};
use nalgebra::{Rotation3, Vector3};
use robot_io::aubo::{RunOptions, run_program};
use robot_io::sim::{Faults, Simulator};
use robot_io::{
    DhParams, PaperFile, PaperFrame, Pose, RobotConfig, RobotError, TouchPoint, TraceKind, aubo_lua, brush_pose,
    build_program, gcode, tcp_iso, urscript,
};

use crate::common::{paper, pen1, small_track};

/// The default settings with steps of up to 16 mm allowed within a stroke: [`small_track`]'s
/// points lie 10–15 mm apart, where a planned track's lie 0.15 mm apart.
fn sparse() -> RobotConfig {
    RobotConfig { limits: robot_io::Limits { max_step_mm: 16.0, ..Default::default() }, ..Default::default() }
}

/// [`sparse`] with every pressed move ending at rest on its point (no blend), so the trace
/// passes through each point exactly.
fn stops() -> RobotConfig {
    RobotConfig { blend_mm: 0.0, ..sparse() }
}

fn same_rotation(a: &Pose, b: &Pose) -> bool {
    a.to_iso().rotation.angle_to(&b.to_iso().rotation) < 1e-9
}

#[test]
fn level_paper_vertical_brush_is_pi_0_0() {
    let f = paper();
    let p = TrackPoint { x_mm: 30.0, y_mm: 40.0, h_mm: 12.0, alpha_rad: 0.0, beta_rad: 0.0 };
    let pose = brush_pose(&f, &p);
    let want = Pose([0.38, 0.11, 0.05 - 0.012, std::f64::consts::PI, 0.0, 0.0]);
    for k in 0..3 {
        assert!((pose.0[k] - want.0[k]).abs() < 1e-12, "{:?}", pose.0);
    }
    assert!(same_rotation(&pose, &want), "{:?}", pose.0);
    // β alone does not spin the tool when α = 0.
    let turned = brush_pose(&f, &TrackPoint { beta_rad: 1.0, ..p });
    assert!(same_rotation(&turned, &want));
    // The quaternion of Rx(π) is [0, 1, 0, 0] up to sign.
    let q = pose.quaternion();
    assert!((q[1].abs() - 1.0).abs() < 1e-12 && q[0].abs() < 1e-12);
}

#[test]
fn tilt_leans_the_tool_towards_the_footprint() {
    // Hand computation: on the level paper the tool z is base −z when upright; tilted by α
    // towards β = 0 (paper +x = base +x) it becomes (sin α, 0, −cos α).
    let f = paper();
    let a = 0.2f64;
    let pose = brush_pose(&f, &TrackPoint { x_mm: 0.0, y_mm: 0.0, h_mm: 0.0, alpha_rad: a, beta_rad: 0.0 });
    let z = pose.to_iso().rotation * Vector3::z();
    assert!((z - Vector3::new(a.sin(), 0.0, -a.cos())).norm() < 1e-12, "{z}");
    // β = 90° is paper +y, which is base −y on this sheet.
    let pose = brush_pose(
        &f,
        &TrackPoint { x_mm: 0.0, y_mm: 0.0, h_mm: 0.0, alpha_rad: a, beta_rad: std::f64::consts::FRAC_PI_2 },
    );
    let z = pose.to_iso().rotation * Vector3::z();
    assert!((z - Vector3::new(0.0, -a.sin(), -a.cos())).norm() < 1e-12, "{z}");
    // Euler convention: R = Rz(rz)·Ry(ry)·Rx(rx).
    let [_, _, _, rx, ry, rz] = pose.0;
    let r = Rotation3::from_axis_angle(&Vector3::z_axis(), rz)
        * Rotation3::from_axis_angle(&Vector3::y_axis(), ry)
        * Rotation3::from_axis_angle(&Vector3::x_axis(), rx);
    assert!((r.matrix() - pose.to_iso().rotation.to_rotation_matrix().matrix()).norm() < 1e-12);
}

#[test]
fn kabsch_recovers_a_tilted_sheet_and_refuses_bad_ones() {
    let truth = nalgebra::Isometry3::new(Vector3::new(0.3, -0.1, 0.12), Vector3::new(0.05, -0.03, 2.0));
    let touch = |u: f64, v: f64| {
        let q = truth * nalgebra::Point3::new(u / 1000.0, v / 1000.0, 0.0);
        TouchPoint { paper_mm: [u, v], robot_m: [q.x, q.y, q.z] }
    };
    let file = PaperFile {
        touch_points: vec![touch(0.0, 0.0), touch(200.0, 0.0), touch(0.0, 150.0), touch(180.0, 140.0)],
        size_mm: Some([210.0, 297.0]),
        max_residual_mm: None,
    };
    let f = PaperFrame::fit(&file).unwrap();
    assert!(f.residual_mm < 1e-9);
    assert!((f.iso.translation.vector - truth.translation.vector).norm() < 1e-12);
    assert!(f.iso.rotation.angle_to(&truth.rotation) < 1e-12);
    let back = f.to_paper([truth.translation.vector.x, truth.translation.vector.y, truth.translation.vector.z]);
    assert!(back.iter().all(|v| v.abs() < 1e-9));
    let collinear = PaperFile {
        touch_points: vec![touch(0.0, 0.0), touch(100.0, 0.0), touch(200.0, 0.0)],
        size_mm: None,
        max_residual_mm: None,
    };
    assert!(PaperFrame::fit(&collinear).unwrap_err().to_string().contains("collinear"));
    let mut noisy = file.clone();
    noisy.touch_points[3].robot_m[2] += 0.01;
    assert!(PaperFrame::fit(&noisy).unwrap_err().to_string().contains("residual"));
    let two = PaperFile { touch_points: file.touch_points[..2].to_vec(), size_mm: None, max_residual_mm: None };
    assert!(PaperFrame::fit(&two).unwrap_err().to_string().contains("at least 3"));
}

#[test]
fn inverse_kinematics_round_trips() {
    let tcp = tcp_iso(0.048);
    for q in [
        [0.1, -0.4, 1.5, 0.2, 1.4, 0.3],
        [-0.8, 0.2, 1.9, -0.3, 1.6, -1.0],
        [0.5, -0.2618, 1.7453, 0.4363, 1.5708, 0.2],
    ] {
        let pose = Pose::from_iso(&DhParams::AUBO_I5.forward(&q, &tcp));
        let sol = DhParams::AUBO_I5.inverse(&pose, &tcp, None).expect("reachable");
        let back = Pose::from_iso(&DhParams::AUBO_I5.forward(&sol, &tcp));
        for k in 0..3 {
            assert!((back.0[k] - pose.0[k]).abs() < 2e-5);
        }
        assert!(same_rotation_loose(&back, &pose));
    }
    // Two metres away is out of reach.
    assert!(DhParams::AUBO_I5.inverse(&Pose([2.0, 0.0, 0.2, std::f64::consts::PI, 0.0, 0.0]), &tcp, None).is_none());
}

/// The kinematics are the AUBO controller's own (modified DH with its `a`, `alpha`, `d`, `theta`
/// arrays): the i5's nominal arrays put the flange where the controller does, and a waypoint
/// saved by a real controller (joints, TCP offset, pose, that arm's calibrated arrays) is
/// reproduced within 1.5 mm. maobi's earlier table put the first of these 0.9 m away.
#[test]
fn the_kinematics_are_the_controllers() {
    use robot_io::DhParams;
    let flange = DhParams::AUBO_I5.forward(&[0.0, -0.2618, 1.7453, 0.4363, 1.5708, 0.0], &tcp_iso(0.0));
    let want = Vector3::new(0.549, -0.121, 0.263);
    assert!((flange.translation.vector - want).norm() < 1e-3, "{:?}", flange.translation.vector);
    // The saved waypoint: that controller's arrays (same theta), TCP offset 0.1 m along y.
    let real = DhParams {
        a_m: [0.0, 5.8e-5, 0.36851, 0.31634, 4.53e-5, 3.166e-4],
        alpha_rad: [0.0, -1.56995, 3.13975, 3.14489, -1.57019, 1.56620],
        d_m: [0.122, 0.12161, -1.145e-4, 1.145e-4, 0.10210, 0.094],
        theta_rad: DhParams::AUBO_I5.theta_rad,
    };
    let tcp = nalgebra::Isometry3::translation(0.0, 0.1, 0.0);
    let q = [-0.17556, 0.13348, -0.76781, 0.73389, -1.55988, -0.60547];
    let saved = Pose([-0.49913, -0.09370, 0.57777, -3.09482, -0.04559, -1.14230]);
    let got = Pose::from_iso(&real.forward(&q, &tcp));
    let miss_m = (got.to_iso().translation.vector - saved.to_iso().translation.vector).norm();
    assert!(miss_m < 1.6e-3, "{got:?} is {:.2} mm from the saved pose", miss_m * 1e3);
    let turn = got.to_iso().rotation.angle_to(&saved.to_iso().rotation);
    assert!(turn < 0.01, "{got:?} turns {turn} rad from the saved pose");
    // The inverse in the same convention finds joints that reproduce the saved pose.
    let back = real.inverse(&saved, &tcp, Some(&q)).expect("the saved pose is reachable");
    let again = real.forward(&back, &tcp);
    assert!((again.translation.vector - saved.to_iso().translation.vector).norm() < 2e-5);
    assert!(real.validate().is_ok());
    let bad = DhParams { d_m: [0.122, f64::INFINITY, 0.0, 0.0, 0.1, 0.1], ..real };
    assert!(bad.validate().unwrap_err().to_string().contains("d[1]"));
}

fn same_rotation_loose(a: &Pose, b: &Pose) -> bool {
    a.to_iso().rotation.angle_to(&b.to_iso().rotation) < 2e-4
}

#[test]
fn the_safety_envelope_refuses_before_anything_moves() {
    let (f, cfg) = (paper(), sparse());
    let (prog, report) = build_program(&small_track(), &pen1(), &f, &cfg).unwrap();
    assert_eq!(report.strokes, 2);
    assert_eq!(prog.strokes[0].press.len(), 3);
    assert!(report.estimated_seconds > 0.0);
    let refuse = |t: Track, cfg: &RobotConfig, f: &PaperFrame, needle: &str| {
        let e = build_program(&t, &pen1(), f, cfg).unwrap_err();
        assert!(matches!(e, RobotError::Unsafe { .. }), "{e}");
        assert!(e.to_string().contains(needle), "{e}");
    };
    let mut deep = small_track();
    deep.strokes[1].points[2].h_mm = 25.0;
    refuse(deep, &cfg, &f, "stroke 2, point 3: press h = 25.000 mm is deeper");
    let mut off = small_track();
    off.strokes[0].points[1].x_mm = 250.0;
    refuse(off, &cfg, &f, "outside the paper");
    let far = PaperFrame::level([1.5, 0.0, 0.05], [200.0, 200.0]);
    refuse(small_track(), &cfg, &far, "not reachable");
    let fast = RobotConfig { write_speed_m_s: 0.5, ..sparse() };
    refuse(small_track(), &fast, &f, "write_speed_m_s = 0.5 exceeds the limit 0.25");
    refuse(Track::default(), &cfg, &f, "no points");
}

#[test]
fn exports_follow_the_documented_forms() {
    let (prog, _) = build_program(&small_track(), &pen1(), &paper(), &sparse()).unwrap();
    let lua = aubo_lua(&prog, "test").unwrap();
    assert!(lua.contains("\nreturn function(api)\n  local _ENV = require('aubo').sched.select_robot(1)\n"));
    assert!(lua.ends_with("\nend\n"));
    assert!(lua.contains("\n  setTcpOffset({0, 0, 0.048000, 0, 0, 0})\n  setSpeedFraction(1.000000)\n"));
    assert_eq!(lua.matches("moveLine(").count() + lua.matches("moveJoint(").count(), prog.move_count());
    let timing = robot_io::time_program(&prog, &robot_io::DhParams::AUBO_I5, &sparse()).unwrap();
    let ur = urscript(&prog, &timing, &sparse(), "test").unwrap();
    assert!(ur.starts_with("# maobi") && ur.contains("\ndef maobi_program():\n") && ur.ends_with("\nend\n"));
    assert!(ur.contains("  write_output_integer_register(24, 0)\n") && ur.contains("t=0, r="));
    let movel = ur.lines().find(|l| l.trim_start().starts_with("movel(")).unwrap();
    let inside = movel.trim().trim_start_matches("movel(p[").split(']').next().unwrap();
    assert_eq!(inside.split(", ").count(), 6, "{movel}");
    assert!(movel.contains("a=") && movel.contains("v=") && movel.contains("r="));
    // The level paper's upright brush is Rx(π): rotation vector (π, 0, 0) up to sign.
    let times = robot_io::point_times(&prog, &timing).unwrap();
    let (g, warnings) = gcode(&small_track(), &times, &sparse(), "test").unwrap();
    assert!(g.contains("G21") && g.contains("G90") && g.trim_end().ends_with("M2"));
    assert!(g.contains("G1 X40.000000 Y-60.000000 Z-15.000000 F1200.000000"), "{g}");
    // Y toward the user: the paper's y as it is.
    let toward = RobotConfig { plotter: robot_io::PlotterConfig { y_axis: robot_io::YAxis::Toward }, ..sparse() };
    let (g, _) = gcode(&small_track(), &times, &toward, "test").unwrap();
    assert!(g.contains("G1 X40.000000 Y60.000000 Z-15.000000 F1200.000000"), "{g}");
    assert!(warnings.iter().any(|w| w.contains("α")) && warnings.iter().any(|w| w.contains("β")));
}

fn run(sim: &Simulator, prog: &robot_io::Program) -> Result<robot_io::aubo::RunReport, RobotError> {
    let stop = AtomicBool::new(false);
    let opts = RunOptions {
        timeout: Duration::from_millis(500),
        max_reconnects: 3,
        backoff: Duration::from_millis(10),
        ..RunOptions::new(&stop)
    };
    run_program(&sim.addr.to_string(), prog, None, &opts, |_| {})
}

#[test]
fn a_full_run_on_the_simulator_follows_the_track() {
    let (prog, _) = build_program(&small_track(), &pen1(), &paper(), &stops()).unwrap();
    let sim = Simulator::start("127.0.0.1:0", Faults { queue_full_every: Some(4), ..Faults::default() }).unwrap();
    let report = run(&sim, &prog).unwrap();
    assert_eq!(report.strokes_completed, vec![0, 1]);
    assert_eq!(report.reconnects, 0);
    let trace = sim.trace();
    assert_eq!(trace[0].kind, TraceKind::Joint);
    // Every pressed pose of the program was reached, in order, and the motion between was
    // executed continuously: samples at most 0.2 mm (and 5 ms) apart, in time order.
    let f = paper();
    let targets: Vec<[f64; 3]> =
        small_track().strokes.iter().flat_map(|s| s.points.iter().map(|p| [p.x_mm, p.y_mm, p.h_mm])).collect();
    assert_eq!(targets.len(), 8);
    let mut next = 0;
    for t in trace.iter().filter(|t| t.kind == TraceKind::Line) {
        let p = f.to_paper(t.pose.position());
        if next < targets.len() && (0..3).all(|k| (p[k] - targets[next][k]).abs() < 1e-6) {
            next += 1;
        }
    }
    assert_eq!(next, 8, "all pressed targets reached in order");
    for w in trace.windows(2).filter(|w| w[1].kind == TraceKind::Line) {
        let (a, b) = (w[0].pose.position(), w[1].pose.position());
        let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
        assert!(d <= robot_io::TRACE_STEP_M + 1e-9, "a jump of {} mm", d * 1e3);
        assert!(w[1].t_s >= w[0].t_s && w[1].t_s - w[0].t_s <= robot_io::TRACE_STEP_S + 1e-9);
    }
}

#[test]
fn a_dropped_connection_mid_stroke_is_resumed_without_rewriting() {
    let (prog, _) = build_program(&small_track(), &pen1(), &paper(), &stops()).unwrap();
    // Moves: 1 joint, stroke 1 = 2 approach + 3 press + 1 lift (moves 2–7); stroke 2 travels
    // (8), descends onto its first point (9), presses (10, 11, ...): the drop hits move 11, in
    // the middle of stroke 2.
    let sim = Simulator::start("127.0.0.1:0", Faults { drop_after_moves: Some(11), ..Faults::default() }).unwrap();
    let report = run(&sim, &prog).unwrap();
    assert_eq!(report.strokes_completed, vec![0, 1]);
    assert_eq!((report.reconnects, report.strokes_resumed), (1, 1));
    let trace = sim.trace();
    let f = paper();
    // Stroke 1's first pressed point was written exactly once; stroke 2's first point twice
    // (before the drop and on resumption), with a lift in between.
    let count_at = |x: f64, y: f64| {
        trace
            .iter()
            .filter(|t| {
                let p = f.to_paper(t.pose.position());
                (p[0] - x).abs() < 1e-6 && (p[1] - y).abs() < 1e-6 && (p[2] - 15.0).abs() < 1e-6
            })
            .count()
    };
    assert_eq!(count_at(40.0, 60.0), 1);
    assert_eq!(count_at(70.0, 62.0), 1);
    assert_eq!(count_at(55.0, 40.0), 2);
    assert_eq!(count_at(55.0, 55.0), 2);
    assert_eq!(count_at(55.0, 70.0), 1);
    assert_eq!(count_at(55.5, 85.0), 1);
    let i_resume = trace
        .iter()
        .rposition(|t| {
            let p = f.to_paper(t.pose.position());
            (p[0] - 55.0).abs() < 1e-6 && (p[1] - 40.0).abs() < 1e-6 && (p[2] - 15.0).abs() < 1e-6
        })
        .unwrap();
    // Between the interrupted press and resuming, the brush went up to the safe height.
    let i_cut = trace
        .iter()
        .position(|t| {
            let p = f.to_paper(t.pose.position());
            (p[0] - 55.0).abs() < 1e-6 && (p[1] - 55.0).abs() < 1e-6 && (p[2] - 15.0).abs() < 1e-6
        })
        .unwrap();
    assert!(i_cut < i_resume);
    assert!(trace[i_cut..i_resume].iter().any(|t| f.to_paper(t.pose.position())[2] < -10.0));
}

#[test]
fn the_simulator_validates_requests() {
    let sim = Simulator::start("127.0.0.1:0", Faults::default()).unwrap();
    let mut c = robot_io::aubo::AuboClient::connect(&sim.addr.to_string(), Duration::from_millis(500)).unwrap();
    assert_eq!(c.robot_names().unwrap(), vec!["rob1".to_string()]);
    let e = c.call("rob9.MotionControl.getExecId", serde_json::json!([])).unwrap_err();
    assert!(matches!(e, RobotError::Rpc { code: -32601, .. }), "{e}");
    let bad = c
        .call_status("rob1.MotionControl.moveLine", serde_json::json!([[0.4, 0.1, 0.1, 3.14, 0.0], 0.5, 0.1, 0.0, 0.0]))
        .unwrap_err();
    assert!(matches!(bad, RobotError::Controller { code: -5, .. }), "{bad}");
    let far = c
        .call_status(
            "rob1.MotionControl.moveLine",
            serde_json::json!([[3.0, 0.0, 0.1, 3.14, 0.0, 0.0], 0.5, 0.1, 0.0, 0.0]),
        )
        .unwrap_err();
    assert!(matches!(far, RobotError::Controller { code: -10, .. }), "{far}");
    let fast = c
        .call_status(
            "rob1.MotionControl.moveLine",
            serde_json::json!([[0.4, 0.1, 0.1, 3.14, 0.0, 0.0], 0.5, 9.0, 0.0, 0.0]),
        )
        .unwrap_err();
    assert!(matches!(fast, RobotError::Controller { code: -5, .. }));
    assert_eq!(c.exec_id("rob1").unwrap(), -1);
    // A slow controller times out.
    let slow = Simulator::start("127.0.0.1:0", Faults { delay_ms: Some(300), ..Faults::default() }).unwrap();
    let mut c = robot_io::aubo::AuboClient::connect(&slow.addr.to_string(), Duration::from_millis(100)).unwrap();
    assert!(matches!(c.robot_names(), Err(RobotError::Timeout(_))));
}

/// The first move reaches the pose above the first stroke on a controller whose kinematics are
/// not maobi's nominal table (a real i5's calibrated arrays): the controller solves it. With
/// joints from maobi's earlier nominal table, a controller in this convention put the brush
/// 741 mm from that pose.
#[test]
fn the_first_move_lands_above_the_first_stroke_on_a_controller_with_its_own_kinematics() {
    use robot_io::DhParams;
    use robot_io::Move;
    use robot_io::sim::{Listen, SimOptions};
    use robot_io::wire::Transport;
    let real = DhParams {
        a_m: [0.0, 5.8e-5, 0.36851, 0.31634, 4.53e-5, 3.166e-4],
        alpha_rad: [0.0, -1.56995, 3.13975, 3.14489, -1.57019, 1.56620],
        d_m: [0.122, 0.12161, -1.145e-4, 1.145e-4, 0.10210, 0.094],
        theta_rad: DhParams::AUBO_I5.theta_rad,
    };
    let (prog, _) = build_program(&small_track(), &pen1(), &paper(), &stops()).unwrap();
    let Move::JointPose { pose: above, .. } = prog.start else { panic!("the start is {:?}", prog.start) };
    let sim = Simulator::start_with(
        &[Listen { bind: "127.0.0.1:0".into(), transports: vec![Transport::Framed] }],
        SimOptions { kinematics: real, ..SimOptions::default() },
    )
    .unwrap();
    let stop = AtomicBool::new(false);
    let opts = RunOptions { timeout: Duration::from_millis(500), ..RunOptions::new(&stop) };
    let report = run_program(&sim.addr.to_string(), &prog, None, &opts, |_| {}).unwrap();
    assert_eq!(report.strokes_completed, vec![0, 1]);
    // The joint move's last sample is the pose asked for, in the controller's own model.
    let trace = sim.trace();
    let end_of_start = trace.iter().take_while(|t| t.kind == TraceKind::Joint).last().unwrap();
    let miss_m = (end_of_start.pose.to_iso().translation.vector - above.to_iso().translation.vector).norm();
    assert!(miss_m < 2e-5, "the first move ends {:.3} mm from the pose above the first stroke", miss_m * 1e3);
}

/// The char box a render places the character by: recorded, with a positive size, else refused
/// naming the file and the field. Reading the track does not check it (a track without one, or
/// with a bad one, still checks, exports and sends).
#[test]
fn a_track_file_gives_its_char_box_only_when_recorded_with_a_positive_size() {
    use robot_io::TrackFile;
    let tf = TrackFile {
        char: Some("一".into()),
        char_box_mm: Some([20.0, 30.0, 80.0]),
        sheet_mm: None,
        brush: pen1(),
        strokes: small_track().strokes,
        stroke_chars: None,
    };
    let mut v = serde_json::to_value(&tf).unwrap();
    let read = |v: &serde_json::Value| TrackFile::from_json(&v.to_string(), "t.json").unwrap();
    let path = std::path::Path::new("t.json");
    assert_eq!(read(&v).char_box(path).unwrap(), [20.0, 30.0, 80.0]);
    for size in [0.0, -30.0] {
        v["char_box_mm"][2] = serde_json::json!(size);
        let e = read(&v).char_box(path).unwrap_err();
        assert!(matches!(e, RobotError::Config { .. }), "{e:?}");
        assert_eq!(e.to_string(), "t.json: field `char_box_mm` must be [x0, y0, size] with size > 0");
    }
    let nan = TrackFile { char_box_mm: Some([f64::NAN, 0.0, 10.0]), ..tf.clone() };
    assert!(nan.char_box(path).unwrap_err().to_string().ends_with("with size > 0"));
    v.as_object_mut().unwrap().remove("char_box_mm");
    let e = read(&v).char_box(path).unwrap_err();
    assert_eq!(e.to_string(), "t.json: field `char_box_mm` must be [x0, y0, size]");
}

#[test]
fn a_track_file_places_checks_and_times_its_program() {
    use robot_io::{IN_FRONT_M, TrackFile, time_program};
    let track = small_track();
    let tf = |sheet_mm, char_box_mm| TrackFile {
        char: None,
        char_box_mm,
        sheet_mm,
        brush: pen1(),
        strokes: track.strokes.clone(),
        stroke_chars: None,
    };
    // A plotter's level sheet: the whole sheet, else the char box and one box size around it,
    // else the strokes' extent (x 40..70, y 40..85 mm) and 10 mm; its middle in front of the arm.
    for (t, bounds) in [
        (tf(Some([210.0, 297.0]), Some([20.0, 30.0, 80.0])), [0.0, 0.0, 210.0, 297.0]),
        (tf(None, Some([20.0, 30.0, 80.0])), [-60.0, -50.0, 180.0, 190.0]),
        (tf(None, None), [30.0, 30.0, 80.0, 95.0]),
        (TrackFile { strokes: Vec::new(), ..tf(None, None) }, [0.0, 0.0, 1.0, 1.0]),
    ] {
        let f = t.level_frame();
        assert_eq!(f.bounds_mm, bounds);
        let [x, y, depth] = f.to_paper(IN_FRONT_M);
        let mid = [(bounds[0] + bounds[2]) / 2.0, (bounds[1] + bounds[3]) / 2.0];
        assert!((x - mid[0]).abs() < 1e-9 && (y - mid[1]).abs() < 1e-9 && depth.abs() < 1e-9, "{bounds:?}");
    }
    assert_eq!(tf(None, None).title(), "track");
    assert_eq!(TrackFile { char: Some("永".into()), ..tf(None, None) }.title(), "永");
    // The check: the program built and checked on the frame, timed on the nominal AUBO-i5; as
    // JSON the report's fields with the timing beside them.
    let cfg = sparse();
    let check = tf(None, None).check(&paper(), &cfg).unwrap();
    let (program, report) = build_program(&track, &pen1(), &paper(), &cfg).unwrap();
    assert_eq!(tf(None, None).build_program(&paper(), &cfg).unwrap(), (program.clone(), report.clone()));
    let timing = time_program(&program, &DhParams::AUBO_I5, &cfg).unwrap();
    assert_eq!((&check.report, &check.timing), (&report, &timing));
    let mut want = serde_json::to_value(&report).unwrap();
    want["timing"] = serde_json::to_value(&timing).unwrap();
    assert_eq!(serde_json::to_value(&check).unwrap(), want);
    // A frame the track does not fit is refused as the program's check refuses it.
    let small = PaperFrame::level([0.35, 0.15, 0.05], [50.0, 50.0]);
    assert!(matches!(tf(None, None).check(&small, &cfg), Err(RobotError::Unsafe { .. })));
}
