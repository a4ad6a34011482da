//! The runner trusts nothing the controller says (issue 26): a fake controller on loopback
//! (the SDK's framed protocol with its login, or the line-delimited form) that reports
//! impossible or far-away poses after a reconnect, motion the runner did not queue, an arm
//! moved between strokes, answers with the wrong ids, an endless answer, motion that never
//! finishes, robot names that do not belong in a method name; and scripts the script port would
//! split. Every case ends in a clear error in bounded time, after a lift from a commanded pose
//! where the brush may be down.

use std::io::{Read, Write};
use std::net::TcpListener;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use brush_model::{Stroke, Track, TrackPoint};
use robot_io::aubo::{AuboClient, Link, RunOptions, run_program, send_script};
use robot_io::wire::Transport;
use robot_io::wire::{self, FrameDecoder};
use robot_io::{Move, Pose, Program, RobotConfig, RobotError, build_program, tcp_iso};
use serde_json::{Value, json};

use crate::common::{paper, pen1};

// ---------------------------------------------------------------------------------------------
// The fake controller.

/// What the fake controller's arm does and what it was asked.
struct Ctl {
    /// The arm's TCP pose (moves execute at once).
    pose: [f64; 6],
    joints: [f64; 6],
    tcp_offset_m: f64,
    /// Moves executed: the method's last part and the target (pose or joints).
    moves: Vec<(String, [f64; 6])>,
    /// `getTcpPose` calls answered.
    tcp_reads: usize,
    /// Connections accepted.
    connections: usize,
    /// Moves executed on the current connection.
    moves_here: usize,
    /// Move requests seen (executed or not).
    move_requests: usize,
    /// Every method called, without the robot name, in order.
    calls: Vec<String>,
}

/// How the fake answers one request.
enum Reply {
    /// The default behaviour.
    Default,
    /// `result` with the request's id.
    Result(Value),
    /// These whole JSON-RPC messages, as they are.
    Raw(Vec<Value>),
    /// These whole messages, then the default answer.
    RawThenDefault(Vec<Value>),
    /// Close the connection without answering.
    Close,
}

/// Decides a request's answer: the state, the method without the robot, the params.
type Hook = Box<dyn FnMut(&mut Ctl, &str, &Value) -> Reply + Send>;

struct Fake {
    addr: String,
    ctl: Arc<Mutex<Ctl>>,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Drop for Fake {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

const ROBOT: &str = "rob1";
const HOME: [f64; 6] = robot_io::READY_JOINTS;

fn fk(q: &[f64; 6], offset_m: f64) -> [f64; 6] {
    Pose::from_iso(&robot_io::DhParams::AUBO_I5.forward(q, &tcp_iso(offset_m))).0
}

fn numbers(v: &Value) -> Option<[f64; 6]> {
    let v: Vec<f64> = serde_json::from_value(v.clone()).ok()?;
    v.try_into().ok()
}

/// A param by name (framed) or position (lines).
fn arg<'a>(params: &'a Value, name: &str, pos: usize) -> &'a Value {
    if params.is_object() { &params[name] } else { &params[pos] }
}

/// The default answer of the fake controller (an AUBO-i5 in robot-io's kinematics).
fn default_reply(c: &mut Ctl, method: &str, params: &Value) -> Option<Value> {
    Some(match method {
        "SystemInfo.getInterfaceVersionCode" => json!(24000),
        "getRobotNames" => json!([ROBOT]),
        "getAxisNames" => json!([]),
        "RobotConfig.setTcpOffset" => {
            c.tcp_offset_m = numbers(arg(params, "offset", 0))?[2];
            if c.moves.is_empty() {
                c.pose = fk(&c.joints, c.tcp_offset_m);
            }
            json!(0)
        }
        "MotionControl.setSpeedFraction" => json!(0),
        "MotionControl.moveLine" => {
            let p = numbers(arg(params, "pose", 0))?;
            c.pose = p;
            c.moves.push(("moveLine".into(), p));
            c.moves_here += 1;
            json!(0)
        }
        "MotionControl.moveJoint" => {
            let q = numbers(arg(params, "q", 0))?;
            c.joints = q;
            c.pose = fk(&q, c.tcp_offset_m);
            c.moves.push(("moveJoint".into(), q));
            c.moves_here += 1;
            json!(0)
        }
        "MotionControl.getExecId" => json!(-1),
        "RobotState.getTcpPose" => {
            c.tcp_reads += 1;
            json!(c.pose)
        }
        "RobotState.getJointPositions" => json!(c.joints),
        "RobotAlgorithm.inverseKinematics" => {
            let (qnear, pose) = (numbers(arg(params, "qnear", 0))?, numbers(arg(params, "pose", 1))?);
            match robot_io::DhParams::AUBO_I5.inverse(&Pose(pose), &tcp_iso(c.tcp_offset_m), Some(&qnear)) {
                Some(q) => json!([q, 0]),
                None => json!([[], -23]),
            }
        }
        "RobotAlgorithm.forwardKinematics" => json!([fk(&numbers(arg(params, "q", 0))?, c.tcp_offset_m), 0]),
        _ => return None,
    })
}

impl Fake {
    /// A fake controller on 127.0.0.1 serving one connection at a time (framed with login, or
    /// lines, told apart by the first byte) for at most 30 s.
    fn start(mut hook: impl FnMut(&mut Ctl, &str, &Value) -> Reply + Send + 'static) -> Fake {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        listener.set_nonblocking(true).unwrap();
        let addr = listener.local_addr().unwrap().to_string();
        let ctl = Arc::new(Mutex::new(Ctl {
            pose: fk(&HOME, 0.0),
            joints: HOME,
            tcp_offset_m: 0.0,
            moves: Vec::new(),
            tcp_reads: 0,
            connections: 0,
            moves_here: 0,
            move_requests: 0,
            calls: Vec::new(),
        }));
        let stop = Arc::new(AtomicBool::new(false));
        let (c2, s2) = (ctl.clone(), stop.clone());
        let thread = std::thread::spawn(move || {
            let end = Instant::now() + Duration::from_secs(30);
            let hook: &mut Hook = &mut (Box::new(move |c: &mut Ctl, m: &str, p: &Value| hook(c, m, p)) as Hook);
            while !s2.load(Ordering::SeqCst) && Instant::now() < end {
                match listener.accept() {
                    Ok((s, _)) => {
                        {
                            let mut c = c2.lock().unwrap();
                            c.connections += 1;
                            c.moves_here = 0;
                        }
                        serve(s, &c2, hook, &s2, end);
                    }
                    Err(_) => std::thread::sleep(Duration::from_millis(2)),
                }
            }
        });
        Fake { addr, ctl, stop, thread: Some(thread) }
    }

    fn moves(&self) -> Vec<(String, [f64; 6])> {
        self.ctl.lock().unwrap().moves.clone()
    }
}

/// Serves one connection until it closes, the hook closes it, or `stop`.
fn serve(mut s: std::net::TcpStream, ctl: &Mutex<Ctl>, hook: &mut Hook, stop: &AtomicBool, end: Instant) {
    s.set_nodelay(true).unwrap();
    s.set_read_timeout(Some(Duration::from_millis(20))).unwrap();
    let mut framed: Option<bool> = None;
    let mut frames = FrameDecoder::default();
    let mut lines = Vec::new();
    let mut buf = vec![0u8; 64 * 1024];
    while !stop.load(Ordering::SeqCst) && Instant::now() < end {
        let n = match s.read(&mut buf) {
            Ok(0) => return,
            Ok(n) => n,
            Err(e) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => continue,
            Err(_) => return,
        };
        let is_framed = *framed.get_or_insert(buf[0] == b'S');
        let mut requests = Vec::new();
        if is_framed {
            frames.push(&buf[..n]);
            while let Ok(Some(p)) = frames.next_frame() {
                if p.starts_with(b"__login__") {
                    let ok = wire::parse_login(&p).is_some_and(|l| l.digest == wire::login_digest("123456"));
                    let _ = s.write_all(&wire::encode_frame(&wire::login_reply(ok)).unwrap());
                    continue;
                }
                requests.push(serde_json::from_slice::<Value>(&p).unwrap());
            }
        } else {
            lines.extend_from_slice(&buf[..n]);
            while let Some(i) = lines.iter().position(|&b| b == b'\n') {
                let line: Vec<u8> = lines.drain(..=i).collect();
                requests.push(serde_json::from_slice::<Value>(&line).unwrap());
            }
        }
        for req in requests {
            let full = req["method"].as_str().unwrap_or("").to_string();
            let method = full.strip_prefix(&format!("{ROBOT}.")).unwrap_or(&full).to_string();
            let params = req.get("params").cloned().unwrap_or(Value::Null);
            let answers = {
                let mut c = ctl.lock().unwrap();
                if method.starts_with("MotionControl.move") {
                    c.move_requests += 1;
                }
                c.calls.push(method.clone());
                let default = |c: &mut Ctl| match default_reply(c, &method, &params) {
                    Some(r) => json!({"jsonrpc": "2.0", "id": req["id"], "result": r}),
                    None => json!({"jsonrpc": "2.0", "id": req["id"],
                        "error": {"code": -32601, "message": format!("no method {full}")}}),
                };
                match hook(&mut c, &method, &params) {
                    Reply::Default => vec![default(&mut c)],
                    Reply::Result(r) => vec![json!({"jsonrpc": "2.0", "id": req["id"], "result": r})],
                    Reply::Raw(v) => v,
                    Reply::RawThenDefault(mut v) => {
                        v.push(default(&mut c));
                        v
                    }
                    Reply::Close => return,
                }
            };
            for a in answers {
                let bytes = serde_json::to_vec(&a).unwrap();
                let out =
                    if is_framed { wire::encode_frame(&bytes).unwrap() } else { [bytes, b"\n".to_vec()].concat() };
                if s.write_all(&out).is_err() {
                    return;
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Programs and options.

/// Horizontal strokes of `n` points 1 mm apart, pressed at 12 mm, one per 10 mm row.
fn rows(strokes: usize, n: usize) -> Track {
    Track {
        strokes: (0..strokes)
            .map(|k| Stroke {
                points: (0..n)
                    .map(|i| TrackPoint {
                        x_mm: 40.0 + i as f64,
                        y_mm: 40.0 + 10.0 * k as f64,
                        h_mm: 12.0,
                        alpha_rad: 0.05,
                        beta_rad: 0.0,
                    })
                    .collect(),
            })
            .collect(),
    }
}

fn program(strokes: usize, n: usize) -> Program {
    build_program(&rows(strokes, n), &pen1(), &paper(), &RobotConfig::default()).unwrap().0
}

fn opts(stop: &AtomicBool, transport: Transport) -> RunOptions<'_> {
    RunOptions {
        link: Link::new(transport),
        timeout: Duration::from_millis(500),
        backoff: Duration::from_millis(5),
        max_backoff: Duration::from_millis(40),
        min_wait: Duration::from_millis(200),
        max_wait_per_stroke: Duration::from_millis(500),
        ..RunOptions::new(stop)
    }
}

/// The targets of a program's moves in the order they run (joint moves: `None`).
fn targets(p: &Program) -> Vec<Option<Pose>> {
    std::iter::once(&p.start)
        .chain(p.strokes.iter().flat_map(|s| s.moves()))
        .map(|m| match m {
            Move::Line { pose, .. } => Some(*pose),
            _ => None,
        })
        .collect()
}

fn stopped(e: RobotError) -> (RobotError, usize, bool, String) {
    match e {
        RobotError::RunStopped { cause, completed, lifted, lift, .. } => (*cause, completed, lifted, lift),
        other => panic!("expected RunStopped, got {}", chain(&other)),
    }
}

/// The error and its causes, as `anyhow` prints them with `{:#}`.
fn chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        s += &format!(": {c}");
        cause = c.source();
    }
    s
}

fn dist_mm(a: &[f64], b: &[f64]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt() * 1e3
}

// ---------------------------------------------------------------------------------------------
// 1. A reported pose is checked.

#[test]
fn a_pose_reported_after_a_reconnect_off_the_commanded_path_stops_the_run_after_a_lift_from_the_commanded_pose() {
    let prog = program(2, 8);
    let all = targets(&prog);
    // Moves: the start, stroke 1 (2 approach + 7 press + 1 lift), stroke 2: travel (12),
    // descent (13), pressed (14, 15, …): the link drops when move 16 arrives (not executed).
    let drop_at = 16;
    let commanded = all[drop_at - 1].unwrap();
    let at_drop = all[drop_at - 2].unwrap(); // where the arm is: move 15 was the last executed
    let f = paper();
    let shifted = |d: [f64; 6]| -> [f64; 6] { std::array::from_fn(|k| at_drop.0[k] + d[k]) };
    // (case, the pose reported after reconnecting, what the error must say; None: trusted)
    let cases: Vec<(&str, [f64; 6], Option<&str>)> = vec![
        ("on the path", at_drop.0, None),
        ("4 mm below the path", shifted([0.0, 0.0, -0.004, 0.0, 0.0, 0.0]), None),
        (
            "1e300",
            [1e300, -1e300, 1e300, 1e300, -1e300, 1e300],
            Some("1e300 m from the robot base: outside the workspace (at most 1.2 m)"),
        ),
        ("1.5 m from the base", [1.5, 0.0, 0.1, std::f64::consts::PI, 0.0, 0.0], Some("outside the workspace")),
        (
            "300 mm beside the program",
            shifted([0.3, 0.0, 0.0, 0.0, 0.0, 0.0]),
            Some("outside the box of this program's poses"),
        ),
        (
            "80 mm away",
            shifted([0.0, -0.08, 0.0, 0.0, 0.0, 0.0]),
            Some("80.0 mm from the nearest point of the commanded path"),
        ),
        (
            "6 mm below the path",
            shifted([0.0, 0.0, -0.006, 0.0, 0.0, 0.0]),
            Some("6.0 mm from the nearest point of the commanded path"),
        ),
        ("turned 0.3 rad", shifted([0.0, 0.0, 0.0, 0.3, 0.0, 0.0]), Some("orientation")),
    ];
    for (case, reported, needle) in cases {
        let fake = Fake::start(move |c, m, _| {
            if m.starts_with("MotionControl.move") && c.move_requests == drop_at && c.connections == 1 {
                return Reply::Close;
            }
            // After the reconnect, until a move arrives, the controller reports `reported`.
            if m == "RobotState.getTcpPose" && c.connections > 1 && c.moves_here == 0 {
                c.tcp_reads += 1;
                return Reply::Result(json!(reported));
            }
            Reply::Default
        });
        let stop = AtomicBool::new(false);
        let t0 = Instant::now();
        let r = run_program(&fake.addr, &prog, None, &opts(&stop, Transport::Framed), |_| {});
        assert!(t0.elapsed() < Duration::from_secs(10), "{case}: {:?}", t0.elapsed());
        let moves = fake.moves();
        let Some(needle) = needle else {
            let report = r.unwrap_or_else(|e| panic!("{case}: {}", chain(&e)));
            assert_eq!((report.strokes_completed.clone(), report.strokes_resumed), (vec![0, 1], 1), "{case}");
            continue;
        };
        let e = r.unwrap_err();
        let msg = chain(&e);
        let (cause, completed, lifted, lift) = stopped(e);
        assert!(matches!(cause, RobotError::UnexpectedState(_)), "{case}: {msg}");
        assert!(msg.contains(needle), "{case}: {msg}");
        assert!(msg.contains("getTcpPose reported") && msg.contains("after reconnecting on stroke 2"), "{case}: {msg}");
        assert_eq!(completed, 1, "{case}");
        // One move after the reconnect: straight out of the paper above the last commanded pose.
        let (kind, lift_target) = moves.last().unwrap().clone();
        assert_eq!(moves.len(), drop_at, "{case}: {moves:?}");
        assert_eq!(kind, "moveLine");
        let want = prog.lifted_out(&commanded, 0.02);
        assert!(dist_mm(&lift_target, &want.0) < 1e-6, "{case}: {lift_target:?} vs {want:?}");
        let (a, b) = (f.to_paper(commanded.position()), f.to_paper(Pose(lift_target).position()));
        assert!((a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9 && (b[2] + 20.0).abs() < 1e-9, "{case}");
        assert!(lifted && lift.contains("from the last commanded pose"), "{case}: {lift}");
    }
}

#[test]
fn a_pose_off_the_commanded_one_after_a_stroke_is_a_fault_not_believed() {
    // The controller executes stroke 1 but reports its end 80 mm off (a drifted or lying
    // controller): the run stops; the last commanded pose is at the safe height, so nothing
    // more is sent.
    let prog = program(2, 6);
    let stroke1 = 1 + prog.strokes[0].moves().count();
    let fake = Fake::start(move |c, m, _| {
        if m == "RobotState.getTcpPose" && c.moves.len() == stroke1 {
            c.tcp_reads += 1;
            let mut p = c.pose;
            p[1] += 0.08;
            return Reply::Result(json!(p));
        }
        Reply::Default
    });
    let stop = AtomicBool::new(false);
    let e = run_program(&fake.addr, &prog, None, &opts(&stop, Transport::Framed), |_| {}).unwrap_err();
    let msg = chain(&e);
    let (cause, completed, lifted, lift) = stopped(e);
    assert!(matches!(cause, RobotError::UnexpectedState(_)), "{msg}");
    assert!(
        msg.contains("after stroke 1: getTcpPose reported") && msg.contains("80.0 mm from the commanded pose"),
        "{msg}"
    );
    assert_eq!(completed, 0, "stroke 1 is not complete until the arm is seen at its end");
    assert_eq!(fake.moves().len(), stroke1, "nothing sent after the stroke");
    assert!(!lifted && lift.contains("at the safe height, so nothing was sent"), "{lift}");
}

// ---------------------------------------------------------------------------------------------
// 2. Motion the runner did not command.

#[test]
fn motion_or_a_pose_before_the_run_that_the_runner_did_not_command_is_refused_before_anything_moves() {
    let prog = program(1, 4);
    // (case, answer to getExecId, answer to getTcpPose, what the error says)
    let cases: [(&str, i64, Option<[f64; 6]>, &str); 3] = [
        (
            "another client moving",
            7,
            None,
            "before the run: getExecId reported motion 7 though this run has nothing queued (is another client driving the arm?)",
        ),
        ("a pose of 1e300", -1, Some([1e300; 6]), "before the run: getTcpPose reported [1e300"),
        (
            "a pose 3 m away",
            -1,
            Some([3.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
            "3.000 m from the robot base: outside the workspace",
        ),
    ];
    for (case, exec, pose, needle) in cases {
        let fake = Fake::start(move |c, m, _| match (m, pose) {
            ("MotionControl.getExecId", _) => Reply::Result(json!(exec)),
            ("RobotState.getTcpPose", Some(p)) => {
                c.tcp_reads += 1;
                Reply::Result(json!(p))
            }
            _ => Reply::Default,
        });
        let stop = AtomicBool::new(false);
        let e = run_program(&fake.addr, &prog, None, &opts(&stop, Transport::Framed), |_| {}).unwrap_err();
        // Nothing moved: the error as it is, not a stopped run, and no move sent.
        assert!(matches!(&e, RobotError::UnexpectedState(m) if m.contains(needle)), "{case}: {}", chain(&e));
        assert!(fake.moves().is_empty(), "{case}");
    }
}

#[test]
fn an_arm_moved_by_someone_else_between_strokes_stops_the_run() {
    let prog = program(2, 6);
    let stroke1 = 1 + prog.strokes[0].moves().count();
    // getTcpPose: before the run (1), after the start (2), before stroke 1 (3), after it (4);
    // then another client moves the arm 30 mm along x, or keeps it moving.
    // (case, what the error says, what the retreat says)
    let cases = [
        ("moved 30 mm", "before stroke 2: getTcpPose reported", "nothing was sent"),
        ("moving", "before stroke 2: getExecId reported motion 12", "could not lift the brush"),
    ];
    for (case, needle, lift_needle) in cases {
        let moving = case == "moving";
        let fake = Fake::start(move |c, m, _| {
            if c.tcp_reads >= 4 {
                if moving && m == "MotionControl.getExecId" {
                    return Reply::Result(json!(12));
                }
                if !moving && m == "RobotState.getTcpPose" {
                    c.tcp_reads += 1;
                    let mut p = c.pose;
                    p[0] += 0.03;
                    return Reply::Result(json!(p));
                }
            }
            Reply::Default
        });
        let stop = AtomicBool::new(false);
        let t0 = Instant::now();
        let e = run_program(&fake.addr, &prog, None, &opts(&stop, Transport::Framed), |_| {}).unwrap_err();
        assert!(t0.elapsed() < Duration::from_secs(5), "{case}: {:?}", t0.elapsed());
        let msg = chain(&e);
        let (cause, completed, lifted, lift) = stopped(e);
        assert!(matches!(cause, RobotError::UnexpectedState(_)), "{case}: {msg}");
        assert!(msg.contains(needle), "{case}: {msg}");
        if !moving {
            assert!(msg.contains("30.0 mm from the commanded pose"), "{case}: {msg}");
        }
        assert_eq!(completed, 1, "{case}");
        assert_eq!(fake.moves().len(), stroke1, "{case}: no move after stroke 1");
        assert!(!lifted && lift.contains(lift_needle), "{case}: {lift}");
    }
}

// ---------------------------------------------------------------------------------------------
// 3. Ids, and answers without end.

#[test]
fn answers_with_ids_that_do_not_match_are_named_not_a_timeout() {
    const T: Duration = Duration::from_millis(400);
    for transport in [Transport::Framed, Transport::Lines] {
        // (case, wrong answers per request, then the right one?, error expected, quick?)
        let cases = [
            ("one wrong answer per call", 1, false, Some("answered id"), false),
            ("three wrong answers", 3, false, Some("3 answers on this connection with ids that did not match"), true),
            ("one stray answer, then the right one", 1, true, None, true),
        ];
        for (case, wrong, then_right, needle, quick) in cases {
            let mut first = true;
            let fake = Fake::start(move |c, m, p| {
                let mut out = Vec::new();
                let result = default_reply(c, m, p).unwrap_or(Value::Null);
                for k in 0..wrong {
                    let id = if transport == Transport::Lines { json!(1000 + k) } else { json!(format!("wrong-{k}")) };
                    out.push(json!({"jsonrpc": "2.0", "id": id, "result": result}));
                }
                if then_right {
                    // One stray answer before the first call's own, then plain answers.
                    let stray = std::mem::replace(&mut first, false);
                    return if stray { Reply::RawThenDefault(out) } else { Reply::Default };
                }
                Reply::Raw(out)
            });
            let t0 = Instant::now();
            let r = AuboClient::open(&fake.addr, &Link::new(transport), T);
            let took = t0.elapsed();
            match needle {
                None => {
                    let (_, names) = r.unwrap_or_else(|e| panic!("{transport} {case}: {}", chain(&e)));
                    assert_eq!(names, vec![ROBOT.to_string()]);
                }
                Some(needle) => {
                    let e = r.err().unwrap_or_else(|| panic!("{transport} {case}: no error"));
                    let msg = chain(&e);
                    assert!(matches!(e, RobotError::Protocol(_)), "{transport} {case}: {msg}");
                    assert!(msg.contains(needle) && msg.contains("expected"), "{transport} {case}: {msg}");
                    assert!(!msg.contains("timeout"), "{transport} {case}: {msg}");
                }
            }
            assert!(took < if quick { T / 2 } else { T * 2 }, "{transport} {case}: {took:?}");
        }
    }
}

#[test]
fn an_answer_without_end_is_refused_at_the_byte_limit() {
    // A line-delimited controller that answers with an unterminated string of 9 MiB.
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let peer = std::thread::spawn(move || {
        let (mut s, _) = listener.accept().unwrap();
        let mut req = [0u8; 256];
        let _ = s.read(&mut req);
        let _ = s.write_all(b"{\"jsonrpc\":\"2.0\",\"id\":1,\"result\":\"");
        let chunk = vec![b'a'; 1 << 20];
        for _ in 0..9 {
            if s.write_all(&chunk).is_err() {
                break;
            }
        }
    });
    let mut c = AuboClient::connect(&addr, Duration::from_secs(5)).unwrap();
    let t0 = Instant::now();
    let e = c.robot_names().unwrap_err();
    assert!(matches!(&e, RobotError::Framing(m) if m.contains("longer than 8388608 bytes")), "{e}");
    assert!(t0.elapsed() < Duration::from_secs(5));
    drop(c);
    peer.join().unwrap();
}

// ---------------------------------------------------------------------------------------------
// 4. Motion that never finishes.

#[test]
fn a_controller_that_never_reports_idle_stops_the_run_in_bounded_time_saying_how_long_it_waited() {
    // Fast moves, so that the limits derived from them are short.
    let cfg = RobotConfig {
        write_speed_m_s: 0.2,
        write_acc_m_s2: 2.0,
        travel_speed_m_s: 0.25,
        travel_acc_m_s2: 2.0,
        ..RobotConfig::default()
    };
    let prog = build_program(&rows(2, 3), &pen1(), &paper(), &cfg).unwrap().0;
    let fake = Fake::start(|c, m, _| {
        if m == "MotionControl.getExecId" && c.moves.len() > 1 {
            return Reply::Result(json!(3));
        }
        Reply::Default
    });
    let stop = AtomicBool::new(false);
    let o = opts(&stop, Transport::Framed);
    let t0 = Instant::now();
    let e = run_program(&fake.addr, &prog, None, &o, |_| {}).unwrap_err();
    let took = t0.elapsed();
    let msg = chain(&e);
    let (cause, completed, lifted, lift) = stopped(e);
    let RobotError::UnexpectedState(why) = cause else { panic!("{msg}") };
    assert!(why.starts_with("stroke 1: rob1: motion did not finish: waited"), "{why}");
    assert!(
        why.contains("getExecId still 3") && why.contains("s of motion was queued (limit: 2 × the expected time"),
        "{why}"
    );
    assert_eq!(completed, 0);
    // The retreat waits too (bounded), and says it could not lift.
    assert!(!lifted && lift.contains("could not lift the brush") && lift.contains("did not finish"), "{lift}");
    // The stroke's expected time: path / speed + speed / acceleration per move, from the start
    // pose (above its first point); its limit: 2 × that, at least 0.2 s, at most 0.5 s unless
    // the moves need more (then 1.5 × that).
    let Move::JointPose { pose: mut at, .. } = prog.start else { panic!("the start is a joint move to a pose") };
    let mut expected_s = 0.0;
    for m in prog.strokes[0].moves() {
        let Move::Line { pose, v, a, .. } = *m else { panic!("line") };
        expected_s += dist_mm(&at.0, &pose.0) / 1e3 / v + v / a;
        at = pose;
    }
    let limit_s = (2.0 * expected_s).min(0.5f64.max(1.5 * expected_s)).max(0.2);
    assert!(why.contains(&format!("(limit {limit_s:.1} s)")), "{why}: limit {limit_s:.2} s");
    assert!(why.contains(&format!("; {expected_s:.1} s of motion was queued")), "{why}: {expected_s:.2} s");
    // The stroke's wait and the retreat's, each bounded by the limit (and a poll): seconds.
    assert!(took >= Duration::from_secs_f64(limit_s), "{took:?}");
    assert!(took < Duration::from_secs_f64(2.0 * limit_s + 2.0), "{took:?} for a limit of {limit_s:.2} s");
}

// ---------------------------------------------------------------------------------------------
// 7. The first move: the controller solves the start pose.

#[test]
fn the_start_pose_is_solved_by_the_controller_and_refused_before_anything_moves_when_it_cannot() {
    let prog = program(1, 4);
    let Move::JointPose { pose: start, .. } = prog.start else { panic!("the start is a joint move to a pose") };
    // (case, the fake's answer to a method, what the refusal says; None: the run finishes)
    type Answer = fn(&str, &Ctl, &Value) -> Option<Value>;
    let cases: [(&str, Answer, Option<&str>); 6] = [
        ("solved", |_, _, _| None, None),
        (
            "no solution",
            |m, _, _| (m == "RobotAlgorithm.inverseKinematics").then(|| json!([[], -23])),
            Some("controller error code -23"),
        ),
        (
            "joints beyond the limits",
            |m, _, _| (m == "RobotAlgorithm.inverseKinematics").then(|| json!([[4.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0])),
            Some("beyond the joint limits"),
        ),
        (
            "its own FK 1 mm away",
            |m, c, p| {
                (m == "RobotAlgorithm.forwardKinematics").then(|| {
                    let mut x = fk(&numbers(arg(p, "q", 0)).unwrap(), c.tcp_offset_m);
                    x[0] += 0.001;
                    json!([x, 0])
                })
            },
            Some("1.000 mm"),
        ),
        (
            "a bare list",
            |m, _, _| (m == "RobotAlgorithm.inverseKinematics").then(|| json!([0.0, 0.1, 0.2, 0.3, 0.4, 0.5])),
            Some("expected [[six numbers], status]"),
        ),
        (
            "joints of 1e300",
            |m, _, _| (m == "RobotState.getJointPositions").then(|| json!([1e300f64; 6].to_vec())),
            Some("getJointPositions reported"),
        ),
    ];
    for (case, answer, needle) in cases {
        let fake = Fake::start(move |c, m, p| match answer(m, c, p) {
            Some(r) => Reply::Result(r),
            None => Reply::Default,
        });
        let stop = AtomicBool::new(false);
        let r = run_program(&fake.addr, &prog, None, &opts(&stop, Transport::Framed), |_| {});
        let ctl = fake.ctl.lock().unwrap();
        match needle {
            None => {
                r.unwrap_or_else(|e| panic!("{case}: {}", chain(&e)));
                // Joints read, solved from them, the solution checked, then moved to.
                let first: Vec<&str> = ctl
                    .calls
                    .iter()
                    .map(String::as_str)
                    .skip_while(|m| !m.starts_with("RobotState.getJointPositions"))
                    .take(4)
                    .collect();
                assert_eq!(
                    first,
                    [
                        "RobotState.getJointPositions",
                        "RobotAlgorithm.inverseKinematics",
                        "RobotAlgorithm.forwardKinematics",
                        "MotionControl.moveJoint"
                    ],
                    "{case}"
                );
                let (kind, q) = &ctl.moves[0];
                assert_eq!(kind, "moveJoint");
                assert!(dist_mm(&fk(q, prog.tcp_offset_m), &start.0) < 0.01, "{case}: the joints reach the start pose");
            }
            Some(needle) => {
                let e = r.unwrap_err();
                let msg = chain(&e);
                assert!(matches!(e, RobotError::Unsafe { .. }), "{case}: {msg}");
                assert!(
                    msg.contains("no joints for the start pose")
                        && msg.contains("nothing was moved")
                        && msg.contains(needle),
                    "{case}: {msg}"
                );
                assert!(ctl.moves.is_empty() && ctl.move_requests == 0, "{case}");
            }
        }
    }
}

#[test]
fn an_arm_that_does_not_arrive_at_the_start_pose_stops_the_run_before_the_first_stroke() {
    // The controller's FK confirms its IK, but the arm ends 741 mm away (kinematics that do not
    // describe the arm): the check after the start move stops the run; the start pose is at the
    // safe height, so nothing more is sent.
    let prog = program(1, 4);
    let fake = Fake::start(|c, m, p| {
        if m == "MotionControl.moveJoint" {
            let q = numbers(arg(p, "q", 0)).unwrap();
            let mut x = fk(&q, c.tcp_offset_m);
            x[0] -= 0.741;
            c.pose = x;
            c.moves.push(("moveJoint".into(), q));
            return Reply::Result(json!(0));
        }
        Reply::Default
    });
    let stop = AtomicBool::new(false);
    let e = run_program(&fake.addr, &prog, None, &opts(&stop, Transport::Framed), |_| {}).unwrap_err();
    let msg = chain(&e);
    let (cause, completed, lifted, lift) = stopped(e);
    assert!(matches!(cause, RobotError::UnexpectedState(_)), "{msg}");
    assert!(
        msg.contains("after the move to the start pose: getTcpPose reported")
            && msg.contains("741.0 mm from the commanded pose"),
        "{msg}"
    );
    assert_eq!((completed, fake.moves().len()), (0, 1), "{msg}");
    assert!(!lifted && lift.contains("nothing was sent"), "{lift}");
}

// ---------------------------------------------------------------------------------------------
// 5 and 6. Text that goes onto a wire.

#[test]
fn a_script_the_script_port_would_split_is_refused_before_connecting() {
    // Nothing listens at `dead`: a refused script fails before connecting, a good one at the
    // connection.
    let dead = TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().to_string();
    let cases = [
        ("return function(api)\r\n\r\nend", Some("\"\\r\\n\\r\\n\"")),
        ("-- 十\r\n\r\nG1 Z-40\nreturn function(api) end", Some("at byte 6 (line 1)")),
        ("return function(api)\n\0end", Some("a NUL byte at byte 21 (line 2)")),
        ("return function(api)\r\nend\r\n", None),
    ];
    for (script, needle) in cases {
        let e = send_script(&dead, script, Duration::from_millis(300)).unwrap_err();
        match needle {
            Some(n) => {
                assert!(matches!(&e, RobotError::Unsafe { reason, .. } if reason.contains(n)), "{script:?}: {e}");
                assert!(e.to_string().contains("nothing was sent"), "{e}");
            }
            None => assert!(matches!(e, RobotError::Io { .. }), "{script:?}: {e}"),
        }
    }
}

#[test]
fn robot_names_that_are_not_plain_identifiers_are_refused_naming_them() {
    let long_ok = "r".repeat(64);
    let too_long = "r".repeat(65);
    let cases: Vec<(String, bool)> = vec![
        ("rob_1".into(), true),
        (long_ok, true),
        (too_long, false),
        ("".into(), false),
        ("rob1.MotionControl.moveLine".into(), false),
        ("rob 1".into(), false),
        ("rob1\n".into(), false),
        ("ロボ".into(), false),
    ];
    for (name, ok) in cases {
        let n2 = name.clone();
        let fake =
            Fake::start(move |_, m, _| if m == "getRobotNames" { Reply::Result(json!([n2])) } else { Reply::Default });
        let r = AuboClient::open(&fake.addr, &Link::default(), Duration::from_millis(500));
        match (r, ok) {
            (Ok((_, names)), true) => assert_eq!(names, vec![name]),
            (Err(e), false) => {
                let shown = format!("{:?}", name.chars().take(80).collect::<String>());
                assert!(
                    matches!(&e, RobotError::Protocol(m) if m.contains("getRobotNames: robot name") && m.contains(&shown)),
                    "{name:?}: {e}"
                );
            }
            (r, _) => panic!("{name:?}: {:?}", r.map(|x| x.1).map_err(|e| e.to_string())),
        }
    }
    // A name given by the caller goes through the same check before any request.
    let fake = Fake::start(|_, _, _| Reply::Default);
    let (mut c, _) = AuboClient::open(&fake.addr, &Link::default(), Duration::from_millis(500)).unwrap();
    let e = c.tcp_pose("rob1.RobotState.getTcpPose\",\"x").unwrap_err();
    assert!(e.to_string().contains("is not a plain identifier"), "{e}");
}
