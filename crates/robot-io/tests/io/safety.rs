//! The safety envelope and the runner's fault behaviour (issue #18): a mirrored paper frame,
//! unbounded tilt and wrist motion, settings the controller rejects, lifting the brush on any
//! error or Ctrl-C, and a flaky link behind a proxy that drops every N-th request.

use std::io::{Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use brush_model::{Stroke, Track, TrackPoint};
use robot_io::aubo::{AuboClient, Link, RunOptions, run_program};
use robot_io::sim::{Faults, Simulator};
use robot_io::wire::Transport;
use robot_io::{
    Approach, CONTROLLER_MAX_ACC, CONTROLLER_MAX_BLEND_M, CONTROLLER_MAX_SPEED, CONTROLLER_MAX_SPEED_FRACTION,
    CONTROLLER_MAX_TCP_OFFSET_M, DipStation, Move, PaperFile, PaperFrame, Program, RobotConfig, RobotError, TraceEntry,
    build_program,
};

use crate::common::{paper, pen1};

fn pt(x: f64, y: f64, h: f64, alpha: f64, beta: f64) -> TrackPoint {
    TrackPoint { x_mm: x, y_mm: y, h_mm: h, alpha_rad: alpha, beta_rad: beta }
}

/// Horizontal strokes of `n` points 0.5 mm apart, pressed at 12 mm, one per 10 mm row.
/// The defaults, each pressed move ending at rest on its point (no blend): the rows' points lie
/// 0.5 mm apart, closer than twice the default blend, which a blending controller refuses.
fn stops() -> RobotConfig {
    RobotConfig { blend_mm: 0.0, ..RobotConfig::default() }
}

fn rows(strokes: usize, n: usize) -> Track {
    Track {
        strokes: (0..strokes)
            .map(|k| Stroke {
                points: (0..n).map(|i| pt(40.0 + 0.5 * i as f64, 40.0 + 10.0 * k as f64, 12.0, 0.05, 0.0)).collect(),
            })
            .collect(),
    }
}

fn refused(track: &Track, frame: &PaperFrame, cfg: &RobotConfig, needles: &[&str]) {
    let e = build_program(track, &pen1(), frame, cfg).unwrap_err();
    assert!(matches!(e, RobotError::Unsafe { .. }), "{e}");
    for n in needles {
        assert!(e.to_string().contains(n), "`{e}` lacks `{n}`");
    }
}

fn fixture_paper() -> PaperFile {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/robot/paper.json");
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn a_mirrored_or_upside_down_paper_frame_is_refused() {
    let file = fixture_paper();
    let frame = PaperFrame::fit(&file).unwrap();
    let cfg = RobotConfig::default();
    build_program(&rows(1, 5), &pen1(), &frame, &cfg).unwrap();
    // Negate every robot y: the fit is exact (a rotation by 180° about base x), but the
    // into-paper normal now points up, and the brush would come from below.
    let mut mirrored = file.clone();
    for t in &mut mirrored.touch_points {
        t.robot_m[1] = -t.robot_m[1];
    }
    let frame_m = PaperFrame::fit(&mirrored).unwrap();
    assert!(frame_m.residual_mm < 1e-9);
    refused(&rows(1, 5), &frame_m, &cfg, &["mirrored", "180.0°", "approach.max_angle_rad"]);
    // A sheet tilted 45° about base x still faces the brush; 70° does not.
    for (deg, ok) in [(45.0f64, true), (70.0, false)] {
        let mut tilted = file.clone();
        let (c, s) = (deg.to_radians().cos(), deg.to_radians().sin());
        for t in &mut tilted.touch_points {
            let v = t.paper_mm[1] / 1000.0; // distance along paper y (base −y when level)
            t.robot_m = [t.robot_m[0], 0.25 - v * c, 0.05 + v * s];
        }
        let f = PaperFrame::fit(&tilted).unwrap();
        let r = build_program(&rows(1, 5), &pen1(), &f, &cfg);
        assert_eq!(r.is_ok(), ok, "{deg}°: {:?}", r.err().map(|e| e.to_string()));
    }
    // The approach side is configuration: a robot that writes on a ceiling says so.
    let from_below = RobotConfig {
        approach: Approach { into_paper_base: [0.0, 0.0, 1.0], ..Approach::default() },
        ..RobotConfig::default()
    };
    refused(&rows(1, 5), &frame, &from_below, &["180.0°"]);
}

#[test]
fn tilt_is_bounded_by_the_limit_and_the_profile() {
    let (f, cfg) = (paper(), RobotConfig::default());
    let with_alpha = |a: f64| {
        let mut t = rows(2, 8);
        t.strokes[1].points[3].alpha_rad = a;
        t
    };
    refused(&with_alpha(3.0), &f, &cfg, &["stroke 2, point 4", "α = 3.0000 rad", "max_tilt_rad = 0.5236"]);
    // 15°: under the 30° limit but beyond pen1's calibrated 10° + 2°.
    refused(
        &with_alpha(15f64.to_radians()),
        &f,
        &cfg,
        &["stroke 2, point 4", "calibrated range", "alpha_tolerance_rad"],
    );
    refused(&with_alpha(-0.1), &f, &cfg, &["calibrated range"]);
    // 11° is inside the tolerance; a sudden jump there from 2.9° turns the tool 0.28 rad/mm,
    // refused under a stricter turn limit.
    let mut held = rows(2, 8);
    for p in &mut held.strokes[1].points {
        p.alpha_rad = 11f64.to_radians();
    }
    build_program(&held, &pen1(), &f, &cfg).unwrap();
    build_program(&with_alpha(11f64.to_radians()), &pen1(), &f, &cfg).unwrap();
    let no_jumps = RobotConfig {
        limits: robot_io::Limits { max_turn_rad_per_mm: 0.2, ..Default::default() },
        ..RobotConfig::default()
    };
    refused(&with_alpha(11f64.to_radians()), &f, &no_jumps, &["point 4", "max_turn_rad_per_mm = 0.2"]);
    let strict =
        RobotConfig { limits: robot_io::Limits { max_tilt_rad: 0.02, ..Default::default() }, ..RobotConfig::default() };
    refused(&held, &f, &strict, &["max_tilt_rad = 0.0200"]);
}

#[test]
fn orientation_and_depth_change_are_bounded_while_pressed_only() {
    let (f, cfg) = (paper(), RobotConfig::default());
    let a = 0.17; // pen1's largest calibrated tilt, about 10°
    // β reverses between two pressed points 0.15 mm apart: a 0.34 rad turn, 2.3 rad/mm.
    let flip = |h: f64, dx: f64| Track {
        strokes: vec![Stroke {
            points: vec![
                pt(50.0, 50.0, 12.0, a, 0.0),
                pt(52.0, 50.0, h, a, 0.0),
                pt(52.0 + dx, 50.0, h, a, std::f64::consts::PI),
                pt(55.0, 50.0, 12.0, a, std::f64::consts::PI),
            ],
        }],
    };
    refused(&flip(12.0, 0.15), &f, &cfg, &["point 3", "rad/mm", "max_turn_rad_per_mm"]);
    // Turning in place while pressed twists the hairs in the paper: refused.
    refused(&flip(12.0, 0.0), &f, &cfg, &["point 3", "in place while pressed"]);
    // At the surface (h = 0) the same turn in place is allowed: no per-mm limit, and a move
    // without travel has no rate at the write speed.
    let (_, report) = build_program(&flip(0.0, 0.0), &pen1(), &f, &cfg).unwrap();
    assert!(report.max_turn_rad_per_mm < 1e-9, "{report:?}");
    // ... but turning while sliding 0.15 mm along the surface is a 46 rad/s wrist at 20 mm/s.
    refused(&flip(0.0, 0.15), &f, &cfg, &["point 3", "rad/s", "max_wrist_rate_rad_s = 20"]);
    // The wrist rate scales with the write speed: 0.2 rad over 2 mm is 2 rad/s at 20 mm/s but
    // 25 rad/s at 0.25 m/s.
    let slow_turn = Track {
        strokes: vec![Stroke {
            points: vec![pt(50.0, 50.0, 12.0, 0.1, 0.0), pt(52.0, 50.0, 12.0, 0.1, std::f64::consts::PI)],
        }],
    };
    build_program(&slow_turn, &pen1(), &f, &cfg).unwrap();
    let fast = RobotConfig { write_speed_m_s: 0.25, ..RobotConfig::default() };
    refused(&slow_turn, &f, &fast, &["point 2", "at 0.25 m/s", "max_wrist_rate_rad_s"]);
    // Depth: 5 → 15 mm within 0.15 mm of travel while pressed is a plunge; the same change
    // straight down in place, or via the surface and back, is normal.
    let plunge = |dx: f64, mid: f64| Track {
        strokes: vec![Stroke {
            points: vec![
                pt(50.0, 50.0, 5.0, 0.0, 0.0),
                pt(50.0 + dx, 50.0, mid, 0.0, 0.0),
                pt(50.0 + dx, 50.0, 15.0, 0.0, 0.0),
                pt(55.0, 50.0, 15.0, 0.0, 0.0),
            ],
        }],
    };
    refused(&plunge(0.15, 15.0), &f, &cfg, &["point 2", "mm/mm", "max_depth_change_per_mm = 40"]);
    build_program(&plunge(0.0, 15.0), &pen1(), &f, &cfg).unwrap();
    build_program(&plunge(0.0, 0.0), &pen1(), &f, &cfg).unwrap();
}

#[test]
fn every_setting_is_checked_against_the_controller_and_the_limits() {
    let (f, t) = (paper(), rows(1, 5));
    let cases: Vec<(&str, RobotConfig, &str)> = vec![
        ("blend 1e6", RobotConfig { blend_mm: 1e6, ..Default::default() }, "blend_mm = 1000000 exceeds the limit 2"),
        ("negative blend", RobotConfig { blend_mm: -1.0, ..Default::default() }, "blend_mm must be ≥ 0"),
        (
            "acc beyond controller",
            RobotConfig { write_acc_m_s2: 25.0, ..Default::default() },
            "write_acc_m_s2 = 25 is beyond what the controller accepts (at most 20",
        ),
        ("speed beyond controller", RobotConfig { travel_speed_m_s: 4.0, ..Default::default() }, "at most 3.2 m/s"),
        ("speed fraction", RobotConfig { speed_fraction: 1.5, ..Default::default() }, "speed_fraction"),
        ("zero speed fraction", RobotConfig { speed_fraction: 0.0, ..Default::default() }, "speed_fraction"),
        ("NaN speed", RobotConfig { write_speed_m_s: f64::NAN, ..Default::default() }, "write_speed_m_s"),
        ("low lift", RobotConfig { lift_mm: 1.0, ..Default::default() }, "min_lift_mm"),
        (
            "joint acc over its limit",
            RobotConfig { joint_acc_rad_s2: 5.0, ..Default::default() },
            "joint_acc_rad_s2 = 5 exceeds the limit 3",
        ),
        (
            "limit beyond controller",
            RobotConfig {
                limits: robot_io::Limits { max_blend_mm: 200.0, ..Default::default() },
                ..Default::default()
            },
            "limits.max_blend_mm = 200 is beyond what the controller accepts",
        ),
        (
            "zero approach direction",
            RobotConfig {
                approach: Approach { into_paper_base: [0.0; 3], ..Default::default() },
                ..Default::default()
            },
            "approach.into_paper_base",
        ),
        (
            "approach angle past 90°",
            RobotConfig { approach: Approach { max_angle_rad: 2.0, ..Default::default() }, ..Default::default() },
            "approach.max_angle_rad",
        ),
        ("empty robot name", RobotConfig { robot_name: Some(" ".into()), ..Default::default() }, "robot_name"),
        (
            "robot name with a method in it",
            RobotConfig { robot_name: Some("rob1.MotionControl.moveLine".into()), ..Default::default() },
            "robot_name \"rob1.MotionControl.moveLine\" must be 1 to 64 letters",
        ),
        // Physical minimums: values that print as 0.000000 in a program, or unit mistakes.
        (
            "write speed 1e-9",
            RobotConfig { write_speed_m_s: 1e-9, ..Default::default() },
            "write_speed_m_s = 1e-9 is below",
        ),
        (
            "speed fraction 1e-300",
            RobotConfig { speed_fraction: 1e-300, ..Default::default() },
            "speed_fraction = 1e-300 is below",
        ),
        ("travel acc 1e-5", RobotConfig { travel_acc_m_s2: 1e-5, ..Default::default() }, "travel_acc_m_s2"),
        ("joint speed 1e-4", RobotConfig { joint_speed_rad_s: 1e-4, ..Default::default() }, "joint_speed_rad_s"),
        ("lift 5 m", RobotConfig { lift_mm: 5000.0, ..Default::default() }, "lift_mm = 5000 is beyond"),
        (
            "step limit 1 m",
            RobotConfig {
                limits: robot_io::Limits { max_step_mm: 1000.0, ..Default::default() },
                ..Default::default()
            },
            "limits.max_step_mm = 1000 is beyond",
        ),
        (
            "wrist rate 1e9",
            RobotConfig {
                limits: robot_io::Limits { max_wrist_rate_rad_s: 1e9, ..Default::default() },
                ..Default::default()
            },
            "limits.max_wrist_rate_rad_s",
        ),
    ];
    for (what, cfg, needle) in cases {
        let e = build_program(&t, &pen1(), &f, &cfg).unwrap_err().to_string();
        assert!(e.contains(needle), "{what}: `{e}` lacks `{needle}`");
        assert!(e.contains("robot.json"), "{what}: {e}");
    }
    // A brush too long for the controller's tool offset.
    let mut long = pen1();
    long.brush.length_mm = 600.0;
    let e = build_program(&t, &long, &f, &RobotConfig::default()).unwrap_err().to_string();
    assert!(e.contains("tool offset"), "{e}");
}

/// Two points of one stroke far apart, a track in metres, and a paper file whose tolerance or
/// units let a wrong frame through are refused, each naming what is wrong.
#[test]
fn jumps_units_and_tolerances_are_bounded() {
    let (f, cfg) = (paper(), RobotConfig::default());
    // Two pressed points 100 mm apart in one stroke.
    let jump = Track {
        strokes: vec![Stroke { points: vec![pt(40.0, 40.0, 12.0, 0.05, 0.0), pt(140.0, 40.0, 12.0, 0.05, 0.0)] }],
    };
    refused(&jump, &f, &cfg, &["stroke 1, point 2", "100.000 mm", "limits.max_step_mm = 5"]);
    // A step at the limit passes, just beyond it is refused.
    let step = |d: f64| Track {
        strokes: vec![Stroke { points: vec![pt(40.0, 40.0, 12.0, 0.05, 0.0), pt(40.0 + d, 40.0, 12.0, 0.05, 0.0)] }],
    };
    build_program(&step(4.9), &pen1(), &f, &cfg).unwrap();
    refused(&step(5.2), &f, &cfg, &["max_step_mm"]);
    // The same rows written in metres: 0.0225 mm wide, pressed 0.012 mm.
    let mut metres = rows(2, 5);
    for p in metres.strokes.iter_mut().flat_map(|s| s.points.iter_mut()) {
        (p.x_mm, p.y_mm, p.h_mm) = (p.x_mm / 1000.0, p.y_mm / 1000.0, p.h_mm / 1000.0);
    }
    refused(&metres, &f, &cfg, &["spans only", "millimetres"]);
    // Right size, but pressed 0.02 mm deep at most: not a brush's press.
    let mut shallow = rows(2, 20);
    for p in shallow.strokes.iter_mut().flat_map(|s| s.points.iter_mut()) {
        p.h_mm = 0.02;
    }
    refused(&shallow, &f, &cfg, &["deepest press is 0.0200 mm", "2.750 mm"]);
    // paper.json: a tolerance of 1e9 mm, robot points in millimetres, paper points in metres.
    let file = fixture_paper();
    let fit_err = |f: &PaperFile| PaperFrame::fit(f).unwrap_err().to_string();
    let loose = PaperFile { max_residual_mm: Some(1e9), ..file.clone() };
    assert!(fit_err(&loose).contains("max_residual_mm = 1000000000 must be in (0, 5]"), "{}", fit_err(&loose));
    let mut robot_mm = file.clone();
    for t in &mut robot_mm.touch_points {
        t.robot_m = t.robot_m.map(|v| v * 1000.0);
    }
    assert!(fit_err(&robot_mm).contains("robot_m is in metres"), "{}", fit_err(&robot_mm));
    let mut paper_m = file.clone();
    for t in &mut paper_m.touch_points {
        t.paper_mm = t.paper_mm.map(|v| v / 1000.0);
    }
    assert!(fit_err(&paper_m).contains("paper_mm is in millimetres"), "{}", fit_err(&paper_m));
    let huge = PaperFile { size_mm: Some([1e9, 300.0]), ..file };
    assert!(fit_err(&huge).contains("size_mm"), "{}", fit_err(&huge));
}

#[test]
fn the_controller_ranges_are_the_simulators() {
    let sim = Simulator::start("127.0.0.1:0", Faults::default()).unwrap();
    let mut c = AuboClient::connect(&sim.addr.to_string(), Duration::from_millis(500)).unwrap();
    let pose = [0.4, 0.1, 0.1, std::f64::consts::PI, 0.0, 0.0];
    let line = |c: &mut AuboClient, a: f64, v: f64, blend: f64| {
        c.call_status("rob1.MotionControl.moveLine", serde_json::json!([pose, a, v, blend, 0.0]))
    };
    assert!(line(&mut c, CONTROLLER_MAX_ACC, CONTROLLER_MAX_SPEED, CONTROLLER_MAX_BLEND_M).is_ok());
    for (a, v, b) in [
        (CONTROLLER_MAX_ACC * 1.001, 0.1, 0.0),
        (0.5, CONTROLLER_MAX_SPEED * 1.001, 0.0),
        (0.5, 0.1, CONTROLLER_MAX_BLEND_M * 1.001),
        (0.0, 0.1, 0.0),
        (0.5, 0.0, 0.0),
    ] {
        let e = line(&mut c, a, v, b).unwrap_err();
        assert!(matches!(e, RobotError::Controller { code: -5, .. }), "a {a} v {v} blend {b}: {e}");
    }
    let frac =
        |c: &mut AuboClient, f: f64| c.call_status("rob1.MotionControl.setSpeedFraction", serde_json::json!([f]));
    assert!(frac(&mut c, CONTROLLER_MAX_SPEED_FRACTION).is_ok());
    assert!(frac(&mut c, CONTROLLER_MAX_SPEED_FRACTION * 1.001).is_err());
    let tcp = |c: &mut AuboClient, z: f64| {
        c.call_status("rob1.RobotConfig.setTcpOffset", serde_json::json!([[0, 0, z, 0, 0, 0]]))
    };
    assert!(tcp(&mut c, CONTROLLER_MAX_TCP_OFFSET_M * 0.999).is_ok());
    assert!(tcp(&mut c, CONTROLLER_MAX_TCP_OFFSET_M).is_err());
}

#[test]
fn no_commanded_pose_goes_below_the_paper() {
    let f = paper();
    // A dip station whose ink lies over the sheet, below the paper's surface: refused.
    let over_sheet = RobotConfig {
        dip: Some(DipStation {
            pose: [0.40, 0.10, 0.06, std::f64::consts::PI, 0.0, 0.0],
            depth_mm: 30.0,
            every_strokes: 1,
        }),
        ..RobotConfig::default()
    };
    refused(&rows(1, 5), &f, &over_sheet, &["stroke 1", "dip station (in the ink)", "below the paper surface"]);
    // Beside the sheet (paper x < 0) the ink pot may be lower than the paper.
    let beside = RobotConfig {
        dip: Some(DipStation { pose: [0.30, 0.10, 0.06, std::f64::consts::PI, 0.0, 0.0], ..over_sheet.dip.unwrap() }),
        ..RobotConfig::default()
    };
    build_program(&rows(1, 5), &pen1(), &f, &beside).unwrap();
    // The pose above the ink must be above the paper's plane (travel reaches it in a line).
    let low = RobotConfig {
        dip: Some(DipStation { pose: [0.30, 0.10, 0.04, std::f64::consts::PI, 0.0, 0.0], ..over_sheet.dip.unwrap() }),
        ..RobotConfig::default()
    };
    refused(&rows(1, 5), &f, &low, &["dip station (above the ink)", "below the paper surface"]);
    // Every line move of a checked program: pressed no deeper than the track, the rest above.
    let (prog, _) = build_program(&rows(2, 6), &pen1(), &f, &RobotConfig::default()).unwrap();
    for st in &prog.strokes {
        for m in st.approach.iter().take(1).chain(std::iter::once(&st.lift)) {
            let Move::Line { pose, .. } = m else { panic!("line") };
            assert!((prog.depth_mm(pose.position()) + 20.0).abs() < 1e-9);
        }
        for m in &st.press {
            let Move::Line { pose, .. } = m else { panic!("line") };
            assert!((prog.depth_mm(pose.position()) - 12.0).abs() < 1e-9);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The runner: errors, Ctrl-C and a flaky link.

/// A loopback TCP proxy in front of the simulator: forwards requests (one JSON value and a
/// newline each, as the client writes them) and answers, closes a connection instead of
/// forwarding its `drop_every`-th request, and sets `trigger.1` when the `trigger.0`-th request
/// of the whole run passes. Every loop ends when `stop` is set or after 60 s.
struct Proxy {
    addr: SocketAddr,
    stop: Arc<AtomicBool>,
    drops: Arc<AtomicUsize>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Proxy {
    fn start(upstream: SocketAddr, drop_every: Option<usize>, trigger: Option<(usize, Arc<AtomicBool>)>) -> Proxy {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        listener.set_nonblocking(true).unwrap();
        let addr = listener.local_addr().unwrap();
        let stop = Arc::new(AtomicBool::new(false));
        let drops = Arc::new(AtomicUsize::new(0));
        let total = Arc::new(AtomicUsize::new(0));
        let (st, dr) = (stop.clone(), drops.clone());
        let thread = std::thread::spawn(move || {
            let end = Instant::now() + Duration::from_secs(60);
            while !st.load(Ordering::SeqCst) && Instant::now() < end {
                match listener.accept() {
                    Ok((client, _)) => {
                        let Ok(server) = TcpStream::connect(upstream) else { continue };
                        let (st, dr, total, trigger) = (st.clone(), dr.clone(), total.clone(), trigger.clone());
                        std::thread::spawn(move || relay(client, server, drop_every, trigger, total, dr, st, end));
                    }
                    Err(_) => std::thread::sleep(Duration::from_millis(2)),
                }
            }
        });
        Proxy { addr, stop, drops, thread: Some(thread) }
    }
}

impl Drop for Proxy {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn relay(
    mut client: TcpStream,
    mut server: TcpStream,
    drop_every: Option<usize>,
    trigger: Option<(usize, Arc<AtomicBool>)>,
    total: Arc<AtomicUsize>,
    drops: Arc<AtomicUsize>,
    stop: Arc<AtomicBool>,
    end: Instant,
) {
    let tick = Some(Duration::from_millis(10));
    client.set_read_timeout(tick).unwrap();
    server.set_read_timeout(tick).unwrap();
    let (mut c2, mut s2) = (client.try_clone().unwrap(), server.try_clone().unwrap());
    let (stop2, done) = (stop.clone(), Arc::new(AtomicBool::new(false)));
    let done2 = done.clone();
    // Answers: server → client.
    let back = std::thread::spawn(move || {
        let mut buf = [0u8; 4096];
        while !stop2.load(Ordering::SeqCst) && !done2.load(Ordering::SeqCst) && Instant::now() < end {
            match s2.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => {
                    if c2.write_all(&buf[..n]).is_err() {
                        break;
                    }
                }
                Err(e) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {}
                Err(_) => break,
            }
        }
        done2.store(true, Ordering::SeqCst);
    });
    // Requests: client → server, counted by their newline.
    let (mut request, mut seen) = (Vec::new(), 0usize);
    let mut buf = [0u8; 4096];
    'outer: while !stop.load(Ordering::SeqCst) && !done.load(Ordering::SeqCst) && Instant::now() < end {
        match client.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => {
                for &b in &buf[..n] {
                    request.push(b);
                    if b != b'\n' {
                        continue;
                    }
                    seen += 1;
                    if drop_every.is_some_and(|k| seen % k == 0) {
                        drops.fetch_add(1, Ordering::SeqCst);
                        break 'outer;
                    }
                    let t = total.fetch_add(1, Ordering::SeqCst) + 1;
                    if let Some((k, flag)) = &trigger {
                        if t == *k {
                            flag.store(true, Ordering::SeqCst);
                        }
                    }
                    if server.write_all(&request).is_err() {
                        break 'outer;
                    }
                    request.clear();
                }
            }
            Err(e) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {}
            Err(_) => break,
        }
    }
    done.store(true, Ordering::SeqCst);
    let _ = client.shutdown(Shutdown::Both);
    let _ = server.shutdown(Shutdown::Both);
    let _ = back.join();
}

fn opts(stop: &AtomicBool) -> RunOptions<'_> {
    RunOptions {
        // The proxy counts requests by their newline: the line-delimited transport.
        link: Link::new(Transport::Lines),
        timeout: Duration::from_millis(500),
        backoff: Duration::from_millis(5),
        max_backoff: Duration::from_millis(80),
        ..RunOptions::new(stop)
    }
}

/// How far the last executed pose lies above the paper, mm.
fn last_height_mm(trace: &[TraceEntry], f: &PaperFrame) -> f64 {
    -f.to_paper(trace.last().expect("moves executed").pose.position())[2]
}

/// How many of a stroke's pressed points the executed path reached.
fn points_reached(trace: &[TraceEntry], f: &PaperFrame, stroke: &Stroke) -> usize {
    stroke
        .points
        .iter()
        .filter(|p| {
            let want = robot_io::brush_pose(f, p).position();
            trace.iter().any(|t| t.pose.position().iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-9))
        })
        .count()
}

fn stopped(e: RobotError) -> (RobotError, usize, bool, String) {
    match e {
        RobotError::RunStopped { cause, completed, lifted, lift, .. } => (*cause, completed, lifted, lift),
        other => panic!("expected RunStopped, got {other}"),
    }
}

#[test]
fn a_controller_error_mid_stroke_lifts_the_brush_and_says_so() {
    let f = paper();
    let track = rows(2, 8);
    let (mut prog, _) = build_program(&track, &pen1(), &f, &stops()).unwrap();
    // Tamper after the check: the controller refuses the 4th pressed move of stroke 2 (−5: a
    // speed beyond its range).
    let Move::Line { v, .. } = &mut prog.strokes[1].press[3] else { panic!("line") };
    *v = 10.0;
    let sim = Simulator::start("127.0.0.1:0", Faults::default()).unwrap();
    let stop = AtomicBool::new(false);
    let e = run_program(&sim.addr.to_string(), &prog, None, &opts(&stop), |_| {}).unwrap_err();
    let msg = chain(&e);
    let (cause, completed, lifted, lift) = stopped(e);
    assert!(matches!(cause, RobotError::Controller { code: -5, .. }), "{msg}");
    assert_eq!(completed, 1);
    assert!(lifted, "{msg}");
    assert!(msg.contains("controller error code -5") && msg.contains("after 1 of 2 strokes"), "{msg}");
    assert!(lift.contains("lifted from 12.0 mm below the paper"), "{lift}");
    let trace = sim.trace();
    assert!((last_height_mm(&trace, &f) - 20.0).abs() < 1e-6, "{}", last_height_mm(&trace, &f));
    // The brush was pressed when the error came: stroke 2's first four points were written.
    assert_eq!(points_reached(&trace, &f, &track.strokes[0]), 8);
    assert_eq!(points_reached(&trace, &f, &track.strokes[1]), 4);
}

#[test]
fn ctrl_c_mid_stroke_stops_lifts_and_is_an_error() {
    let f = paper();
    let track = rows(2, 30);
    let (prog, _) = build_program(&track, &pen1(), &f, &stops()).unwrap();
    let sim = Simulator::start("127.0.0.1:0", Faults::default()).unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    // Requests: names, tool, speed, start move, exec id (5); stroke 1 is 2 + 29 + 1 moves and an
    // exec id (38); the 55th request is in the middle of stroke 2's pressed moves.
    let proxy = Proxy::start(sim.addr, None, Some((55, stop.clone())));
    let e = run_program(&proxy.addr.to_string(), &prog, None, &opts(&stop), |_| {}).unwrap_err();
    let msg = chain(&e);
    assert!(msg.starts_with("stopped after 1 of 2 strokes") && msg.ends_with("interrupted (Ctrl-C)"), "{msg}");
    let (cause, completed, lifted, _) = stopped(e);
    assert!(matches!(cause, RobotError::Interrupted) && completed == 1 && lifted, "{msg}");
    let trace = sim.trace();
    assert!((last_height_mm(&trace, &f) - 20.0).abs() < 1e-6);
    assert_eq!(points_reached(&trace, &f, &track.strokes[0]), 30);
    let cut = points_reached(&trace, &f, &track.strokes[1]);
    assert!(cut > 0 && cut < 30, "stroke 2 was cut short: {cut} of 30 points");
    // Stopping between strokes: no retreat needed, still an error.
    let sim = Simulator::start("127.0.0.1:0", Faults::default()).unwrap();
    let stop = AtomicBool::new(false);
    let e = run_program(&sim.addr.to_string(), &prog, None, &opts(&stop), |_| stop.store(true, Ordering::SeqCst))
        .unwrap_err();
    let (cause, completed, lifted, lift) = stopped(e);
    assert!(matches!(cause, RobotError::Interrupted) && completed == 1 && lifted);
    assert!(lift.contains("at the safe height"), "{lift}");
}

#[test]
fn a_controller_that_stays_away_ends_in_gave_up_with_the_connection_error_as_cause() {
    let f = paper();
    let (prog, _) = build_program(&rows(2, 30), &pen1(), &f, &stops()).unwrap();
    let sim = Simulator::start("127.0.0.1:0", Faults::default()).unwrap();
    // One connection only, dropped after 20 requests (mid stroke 1); then nothing listens.
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap();
    let upstream = sim.addr;
    let proxy = std::thread::spawn(move || {
        let (client, _) = listener.accept().unwrap();
        drop(listener);
        let server = TcpStream::connect(upstream).unwrap();
        let end = Instant::now() + Duration::from_secs(30);
        let (total, drops, stop) =
            (Arc::new(AtomicUsize::new(0)), Arc::new(AtomicUsize::new(0)), Arc::new(AtomicBool::new(false)));
        relay(client, server, Some(20), None, total, drops, stop, end);
    });
    let stop = AtomicBool::new(false);
    let e = run_program(&addr.to_string(), &prog, None, &opts(&stop), |_| {}).unwrap_err();
    let msg = chain(&e);
    let (cause, completed, lifted, _) = stopped(e);
    let RobotError::GaveUp { reconnect_attempts, last, .. } = cause else { panic!("{msg}") };
    assert_eq!(reconnect_attempts, 5, "{msg}");
    assert!(matches!(*last, RobotError::Io { .. }), "{msg}");
    assert!(msg.contains("then 5 connection attempt(s) failed; last fault: connection: "), "{msg}");
    assert_eq!(completed, 0);
    assert!(!lifted, "{msg}");
    proxy.join().unwrap();
}

#[test]
fn a_flaky_link_either_finishes_or_gives_up_in_bounded_time_with_the_brush_lifted() {
    let f = paper();
    // Short strokes (about 20 requests each): every 50th request dropped, the run finishes;
    // each drop restarts at most the stroke it hit.
    let (prog, _) = build_program(&rows(6, 12), &pen1(), &f, &stops()).unwrap();
    let sim = Simulator::start("127.0.0.1:0", Faults::default()).unwrap();
    let proxy = Proxy::start(sim.addr, Some(50), None);
    let stop = AtomicBool::new(false);
    let t0 = Instant::now();
    let r = run_program(&proxy.addr.to_string(), &prog, None, &opts(&stop), |_| {}).unwrap();
    assert_eq!(r.strokes_completed, (0..6).collect::<Vec<_>>());
    assert!(r.reconnects >= 1 && r.reconnects == proxy.drops.load(Ordering::SeqCst), "{r:?}");
    assert!(t0.elapsed() < Duration::from_secs(20));
    assert!((last_height_mm(&sim.trace(), &f) - 20.0).abs() < 1e-6);
    drop(proxy);
    // A stroke that needs more than 50 requests can never finish: the runner gives up after
    // 3 tries of it (not for ever), lifts the brush and says why.
    let (prog, _) = build_program(&rows(3, 70), &pen1(), &f, &stops()).unwrap();
    let sim = Simulator::start("127.0.0.1:0", Faults::default()).unwrap();
    let proxy = Proxy::start(sim.addr, Some(50), None);
    let t0 = Instant::now();
    let e = run_program(&proxy.addr.to_string(), &prog, None, &opts(&stop), |_| {}).unwrap_err();
    let took = t0.elapsed();
    let msg = chain(&e);
    assert!(took < Duration::from_secs(20), "{took:?}");
    assert!(msg.contains("gave up on the flaky link at stroke 1: 4 fault(s) on this stroke (at most 3)"), "{msg}");
    let (cause, completed, lifted, _) = stopped(e);
    assert!(matches!(cause, RobotError::GaveUp { .. }) && completed == 0 && lifted, "{msg}");
    let trace = sim.trace();
    assert!((last_height_mm(&trace, &f) - 20.0).abs() < 1e-6, "{}", last_height_mm(&trace, &f));
    // The total budget bounds a link that fails on every stroke.
    let many = RunOptions { max_retries_per_stroke: 100, max_retries_total: 5, ..opts(&stop) };
    let sim = Simulator::start("127.0.0.1:0", Faults::default()).unwrap();
    let proxy = Proxy::start(sim.addr, Some(50), None);
    let e = run_program(&proxy.addr.to_string(), &prog, None, &many, |_| {}).unwrap_err();
    assert!(chain(&e).contains("6 in the run (at most 5)"), "{}", chain(&e));
    assert!((last_height_mm(&sim.trace(), &f) - 20.0).abs() < 1e-6);
    // Nothing listening: the first connection fails as it is, nothing moved, nothing to lift.
    let dead = TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap();
    let e = run_program(&dead.to_string(), &prog, None, &opts(&stop), |_| {}).unwrap_err();
    assert!(matches!(e, RobotError::Io { .. }), "{e}");
}

#[test]
fn program_helpers_measure_depth_along_the_paper_normal() {
    let f = paper();
    let (prog, _): (Program, _) = build_program(&rows(1, 10), &pen1(), &f, &stops()).unwrap();
    let p = robot_io::brush_pose(&f, &pt(10.0, 20.0, 7.0, 0.1, 0.3));
    assert!((prog.depth_mm(p.position()) - 7.0).abs() < 1e-9);
    let up = prog.lifted_out(&p, 0.02);
    assert!((prog.depth_mm(up.position()) + 20.0).abs() < 1e-9);
    let q = f.to_paper(up.position());
    assert!((q[0] - 10.0).abs() < 1e-9 && (q[1] - 20.0).abs() < 1e-9);
    assert_eq!(&up.0[3..], &p.0[3..]);
}

#[test]
fn the_robot_json_fixture_spells_out_the_defaults() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/robot/robot.json");
    let mut c = RobotConfig::load(&path).unwrap();
    let d = RobotConfig::default();
    // Angles written in decimal may differ from the constants in the last bit.
    for (a, b) in [
        (&mut c.approach.max_angle_rad, d.approach.max_angle_rad),
        (&mut c.limits.max_tilt_rad, d.limits.max_tilt_rad),
        (&mut c.limits.alpha_tolerance_rad, d.limits.alpha_tolerance_rad),
    ] {
        assert!((*a - b).abs() < 1e-12, "{a} vs {b}");
        *a = b;
    }
    assert_eq!(c, d);
    // Unknown fields are refused, naming them.
    let dir = tempfile_dir();
    let bad = dir.join("robot.json");
    std::fs::write(&bad, r#"{"limits": {"max_tilt_deg": 5}}"#).unwrap();
    let e = chain(&RobotConfig::load(&bad).unwrap_err());
    assert!(e.contains("robot.json") && e.contains("max_tilt_deg"), "{e}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// A file larger than any paper, robot or track file maobi writes is refused without reading
/// it whole (a sparse 65 MiB file: its size is all it costs).
#[test]
fn oversized_robot_files_are_refused_by_size() {
    // Its own folder: another test removes `tempfile_dir()` when it ends.
    let dir = std::env::temp_dir().join(format!("robot-io-huge-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("huge.json");
    let f = std::fs::File::create(&path).unwrap();
    f.set_len(robot_io::MAX_FILE_BYTES + 1024).unwrap();
    drop(f);
    for e in [
        RobotConfig::load(&path).unwrap_err(),
        PaperFrame::load(&path).unwrap_err(),
        robot_io::TrackFile::load(&path).unwrap_err(),
    ] {
        let m = e.to_string();
        assert!(m.contains("huge.json") && m.contains("larger than 64 MiB"), "{m}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

fn tempfile_dir() -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("robot-io-safety-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The error and its causes, joined as `anyhow` prints them with `{:#}`.
fn chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        s += &format!(": {c}");
        cause = c.source();
    }
    s
}
