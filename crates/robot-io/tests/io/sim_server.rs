//! The simulator as a server a hostile client cannot hurt (issue 26): one session owns motion,
//! slow moves and tiny speed fractions are refused or bounded, requests are parsed under a byte
//! limit, connections are bounded in number and idle time, the unauthenticated transports are
//! served only when asked, a full trace disk does not stop it, and odd settings and HTTP
//! lengths are refused. Loopback only; every wait is bounded.

use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::Duration;

use proptest::prelude::*;
use robot_io::aubo::{AuboClient, Link};
use robot_io::sim::{Faults, Listen, MAX_REQUEST_BYTES, SimOptions, Simulator, serve_bytes};
use robot_io::wire::Transport;
use robot_io::{MAX_SAMPLES_PER_MOVE, RobotError, line_motion};
use serde_json::{Value, json};

const T: Duration = Duration::from_secs(3);
const MOVE_LINE: &str = "rob1.MotionControl.moveLine";
const HOME_POSE_NEAR: [f64; 6] = [0.4, 0.1, 0.1, std::f64::consts::PI, 0.0, 0.0];

fn start(transports: &[Transport], options: SimOptions) -> Simulator {
    Simulator::start_with(&[Listen { bind: "127.0.0.1:0".into(), transports: transports.to_vec() }], options).unwrap()
}

/// A logged-in framed client.
fn framed(sim: &Simulator) -> AuboClient {
    AuboClient::open(&sim.addr.to_string(), &Link::default(), T).unwrap().0
}

fn line_to(c: &mut AuboClient, pose: [f64; 6], v: f64) -> Result<i64, RobotError> {
    c.call_status(MOVE_LINE, json!({"pose": pose, "a": 0.5, "v": v, "blend_radius": 0.0, "duration": 0.0}))
}

fn moved(p: [f64; 6], dx: f64) -> [f64; 6] {
    let mut q = p;
    q[0] += dx;
    q
}

/// Reads until the peer closes (true) or 5 s pass (false); returns what it sent too.
fn read_to_close(s: &mut TcpStream) -> (bool, Vec<u8>) {
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    let mut all = Vec::new();
    let mut buf = [0u8; 4096];
    loop {
        match s.read(&mut buf) {
            Ok(0) => return (true, all),
            Ok(n) => all.extend_from_slice(&buf[..n]),
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionReset => return (true, all),
            Err(_) => return (false, all),
        }
    }
}

#[test]
fn a_second_session_cannot_move_while_the_first_owns_motion() {
    let options = SimOptions { owner_wait: Duration::from_millis(100), ..SimOptions::default() };
    let sim = start(&[Transport::Framed], options);
    let mut a = framed(&sim);
    let mut b = framed(&sim);
    let p1 = moved(HOME_POSE_NEAR, 0.0);
    let p2 = moved(HOME_POSE_NEAR, 0.02);
    assert_eq!(line_to(&mut a, p1, 0.1).unwrap(), 0);
    let start = a.tcp_pose("rob1").unwrap();
    let after_a1 = sim.trace().len();
    // B reads freely, but its motion commands are refused, naming why.
    assert_eq!(b.tcp_pose("rob1").unwrap(), start);
    assert!(b.is_steady("rob1").unwrap());
    for (what, r) in [
        ("moveLine", line_to(&mut b, moved(p1, -0.05), 0.1)),
        ("setSpeedFraction", b.set_speed_fraction("rob1", 0.5)),
        ("setTcpOffset", b.set_tcp_offset("rob1", [0.0, 0.0, 0.1, 0.0, 0.0, 0.0])),
    ] {
        let e = r.unwrap_err();
        assert!(
            matches!(&e, RobotError::Rpc { code: -32001, message, .. } if message.contains("owned by another session")),
            "{what}: {e}"
        );
    }
    assert_eq!(sim.trace().len(), after_a1, "nothing of B's executed");
    // A goes on: the trace is A's two moves, one after the other, nothing between.
    assert_eq!(line_to(&mut a, p2, 0.1).unwrap(), 0);
    let trace = sim.trace();
    let t0 = trace[after_a1 - 1].t_s;
    let want = robot_io::sim::ramped_line_motion(&robot_io::Pose(p1), &robot_io::Pose(p2), 0.1, 0.5, t0);
    assert_eq!(&trace[after_a1..], &want[..]);
    // On a trapezoidal time law: 20 mm at 0.1 m/s with 0.5 m/s² ramps takes 0.2 + 0.2 s; the
    // path is line_motion's (same start, end and line), starting and ending slowly.
    let a2 = &trace[after_a1..];
    assert!((a2.last().unwrap().t_s - t0 - 0.4).abs() < 1e-9, "{}", a2.last().unwrap().t_s - t0);
    let speed = |w: &[robot_io::TraceEntry]| (w[1].pose.0[0] - w[0].pose.0[0]) / (w[1].t_s - w[0].t_s);
    let speeds: Vec<f64> = a2.windows(2).map(speed).collect();
    assert!(speeds[0] < 0.01 && *speeds.last().unwrap() < 0.01, "{} {}", speeds[0], speeds.last().unwrap());
    // (v²/a = 20 mm: the move just reaches 0.1 m/s at its middle.)
    let top = speeds.iter().copied().fold(0.0, f64::max);
    assert!(top <= 0.1 + 1e-9 && top > 0.098, "{top}");
    assert!(a2.windows(2).all(|w| w[1].t_s - w[0].t_s <= robot_io::TRACE_STEP_S + 1e-12));
    assert_eq!(
        a2.last().unwrap().pose,
        line_motion(&robot_io::Pose(p1), &robot_io::Pose(p2), 0.1, 0.0).last().unwrap().pose
    );
    // Once A's connection closes, motion is free and B moves.
    drop(a);
    assert_eq!(line_to(&mut b, p1, 0.1).unwrap(), 0);
    assert_eq!(b.tcp_pose("rob1").unwrap().0, p1);
}

#[test]
fn slow_moves_and_tiny_speed_fractions_are_refused_or_bounded() {
    let sim = start(&[Transport::Framed], SimOptions { trace_window: 5_000, ..SimOptions::default() });
    let mut c = framed(&sim);
    assert_eq!(line_to(&mut c, HOME_POSE_NEAR, 0.1).unwrap(), 0);
    let far = moved(HOME_POSE_NEAR, -0.1);
    // Speeds below 0.1 mm/s, and speed fractions below 1 %, are refused (status −5).
    for v in [1e-6, 9.9e-5, 0.0, -0.1, 3.3] {
        let e = line_to(&mut c, far, v).unwrap_err();
        assert!(matches!(e, RobotError::Controller { code: -5, .. }), "v = {v}: {e}");
    }
    for f in [1e-300, 0.009, 0.0, 1.5] {
        let e = c.set_speed_fraction("rob1", f).unwrap_err();
        assert!(matches!(e, RobotError::Controller { code: -5, .. }), "fraction {f}: {e}");
    }
    // Accepted speeds that the fraction brings below the minimum are refused too.
    assert_eq!(c.set_speed_fraction("rob1", 0.01).unwrap(), 0);
    let e = line_to(&mut c, far, 0.005).unwrap_err();
    assert!(matches!(e, RobotError::Controller { code: -5, .. }), "{e}");
    // The slowest accepted moves (0.1 m at 0.1 mm/s: 1000 s) record a bounded trace, and the
    // memory keeps only the window; every sample was counted.
    assert_eq!(line_to(&mut c, far, 0.015).unwrap(), 0);
    let n1 = sim.samples_recorded();
    assert_eq!(c.set_speed_fraction("rob1", 1.0).unwrap(), 0);
    assert_eq!(line_to(&mut c, HOME_POSE_NEAR, 1e-4).unwrap(), 0);
    let n2 = sim.samples_recorded() - n1;
    assert!(n1 > 5_000 && n2 as usize <= MAX_SAMPLES_PER_MOVE, "{n1} then {n2} samples");
    assert_eq!(sim.trace().len(), 5_000);
    let last = sim.trace().last().copied().unwrap();
    assert_eq!(last.pose.0, HOME_POSE_NEAR);
    // The move took its simulated time (0.1 m at 0.1 mm/s: 1000 s), in fewer, sparser samples.
    let t = sim.trace();
    assert!((t[t.len() - 1].t_s - t[t.len() - 2].t_s) > 0.005, "samples of a slow move are further apart");
}

#[test]
fn requests_are_parsed_under_a_byte_limit() {
    let lines = [Transport::Lines];
    // An unfinished 8 MiB JSON array in 16 KiB pieces: refused once it passes 1 MiB.
    let piece = [&b"["[..], &vec![b'1'; 16 * 1024 - 1][..]].concat();
    let mut pieces = vec![piece.as_slice()];
    let more = vec![b','; 16 * 1024];
    pieces.extend(std::iter::repeat_n(more.as_slice(), 8 * 64));
    let (out, closed) = serve_bytes(SimOptions::default(), &lines, &pieces).unwrap();
    let text = String::from_utf8(out).unwrap();
    assert!(closed && text.contains("longer than the limit of 1048576 bytes"), "{text}");
    // 32 MiB of whitespace before the transport is known: closed after 1 MiB, nothing kept.
    let ws = vec![b' '; 16 * 1024];
    let pieces = vec![ws.as_slice(); 2 * 1024];
    let (out, closed) = serve_bytes(SimOptions::default(), &Transport::ALL, &pieces).unwrap();
    assert!(closed && out.is_empty());
    // Requests split at every byte offset, several in one piece, with whitespace between:
    // every one answered, in order.
    let req = |id: u64| format!(r#"{{"jsonrpc":"2.0","id":{id},"method":"getRobotNames","params":["]}}\\"]}}"#);
    let stream = format!(" \n{}\r\n{} {}\n", req(1), req(2), req(3)).into_bytes();
    for k in 0..stream.len() {
        let (out, closed) = serve_bytes(SimOptions::default(), &lines, &[&stream[..k], &stream[k..]]).unwrap();
        let answers: Vec<Value> =
            String::from_utf8(out).unwrap().lines().map(|l| serde_json::from_str(l).unwrap()).collect();
        assert!(!closed, "split at {k}");
        assert_eq!(answers.iter().map(|a| a["id"].as_u64().unwrap()).collect::<Vec<_>>(), [1, 2, 3], "at {k}");
        assert!(answers.iter().all(|a| a["result"] == json!(["rob1"])));
    }
    // Over a socket: the same limit on the lines transport, with a clear error before closing.
    let sim = start(&lines, SimOptions::default());
    let mut s = TcpStream::connect(sim.addr).unwrap();
    let big = format!(r#"{{"jsonrpc":"2.0","id":1,"method":"x","params":["{}"]}}"#, "y".repeat(MAX_REQUEST_BYTES));
    let _ = s.write_all(big.as_bytes());
    let (closed, out) = read_to_close(&mut s);
    let text = String::from_utf8_lossy(&out);
    assert!(closed && text.contains("-32700") && text.contains("limit of 1048576 bytes"), "{text}");
}

#[test]
fn connections_are_bounded_in_number_and_idle_time() {
    let options = SimOptions { max_connections: 3, idle_timeout: Duration::from_millis(400), ..SimOptions::default() };
    let sim = start(&[Transport::Framed], options);
    let held: Vec<TcpStream> = (0..3).map(|_| TcpStream::connect(sim.addr).unwrap()).collect();
    for _ in 0..200 {
        if sim.connections() == 3 {
            break;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(sim.connections(), 3);
    // The fourth is closed at once, unanswered.
    let mut extra = TcpStream::connect(sim.addr).unwrap();
    let _ = extra.write_all(&robot_io::wire::encode_frame(b"{}").unwrap());
    assert_eq!(read_to_close(&mut extra), (true, Vec::new()));
    // The held ones, silent, are closed after the idle time-out; then new ones are served.
    for mut h in held {
        assert!(read_to_close(&mut h).0, "an idle connection stays open");
    }
    for _ in 0..200 {
        if sim.connections() == 0 {
            break;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(sim.connections(), 0);
    assert_eq!(framed(&sim).robot_names().unwrap(), ["rob1"]);
}

#[test]
fn the_unauthenticated_transports_are_served_only_when_asked() {
    // The framed transport alone (the CLI's default): lines and HTTP are hung up on.
    let sim = start(&[Transport::Framed], SimOptions::default());
    for req in [
        [&br#"{"jsonrpc":"2.0","id":1,"method":"getRobotNames"}"#[..], &b"\n"[..]].concat(),
        robot_io::wire::http_post("x", br#"{"jsonrpc":"2.0","id":"1","method":"getRobotNames"}"#),
    ] {
        let mut s = TcpStream::connect(sim.addr).unwrap();
        s.write_all(&req).unwrap();
        let (closed, out) = read_to_close(&mut s);
        assert!(closed && !String::from_utf8_lossy(&out).contains("rob1"), "{}", String::from_utf8_lossy(&out));
    }
    // Framed without the login cannot move either.
    let mut c = AuboClient::connect_with(&sim.addr.to_string(), Transport::Framed, T).unwrap();
    let e = line_to(&mut c, HOME_POSE_NEAR, 0.1).unwrap_err();
    assert!(matches!(e, RobotError::Rpc { code: -32000, .. }), "{e}");
    assert!(sim.trace().is_empty());
    // Asked for: lines on its own port.
    let sim = start(&[Transport::Lines], SimOptions::default());
    let mut c = AuboClient::connect(&sim.addr.to_string(), T).unwrap();
    assert_eq!(c.robot_names().unwrap(), ["rob1"]);
}

#[test]
fn a_full_trace_disk_does_not_stop_the_simulator() {
    let full = std::path::Path::new("/dev/full");
    if !full.exists() {
        let _ = writeln!(std::io::stderr(), "SKIPPED a_full_trace_disk_does_not_stop_the_simulator: no /dev/full");
        return;
    }
    let sim = start(&[Transport::Framed], SimOptions { trace_path: Some(full.into()), ..SimOptions::default() });
    let mut c = framed(&sim);
    assert_eq!(line_to(&mut c, HOME_POSE_NEAR, 0.1).unwrap(), 0);
    let e = sim.trace_error().expect("the failed write is reported");
    assert!(e.contains("/dev/full") && e.contains("goes on"), "{e}");
    // It goes on serving and moving, its state and memory trace intact.
    let p = moved(HOME_POSE_NEAR, 0.01);
    assert_eq!(line_to(&mut c, p, 0.1).unwrap(), 0);
    assert_eq!(c.tcp_pose("rob1").unwrap().0, p);
    assert_eq!(sim.trace().last().unwrap().pose.0, p);
    // A writable trace file gets every sample, one JSON line each.
    let dir = std::env::temp_dir().join(format!("maobi-sim-trace-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join("trace.jsonl");
    let sim = start(&[Transport::Framed], SimOptions { trace_path: Some(path.clone()), ..SimOptions::default() });
    let mut c = framed(&sim);
    assert_eq!(line_to(&mut c, HOME_POSE_NEAR, 0.1).unwrap(), 0);
    assert_eq!(line_to(&mut c, p, 0.1).unwrap(), 0);
    let text = std::fs::read_to_string(&path).unwrap();
    assert_eq!(text.lines().count() as u64, sim.samples_recorded());
    assert!(sim.trace_error().is_none());
    // It reads back as the samples the simulator executed.
    let back = robot_io::read_trace(&path).unwrap();
    assert_eq!((back.samples, back.cut_line), (sim.trace(), None));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn out_of_range_tcp_offsets_and_conflicting_http_lengths_are_refused() {
    let sim = start(&[Transport::Framed, Transport::Http], SimOptions::default());
    let mut c = framed(&sim);
    let q = c.joint_positions("rob1").unwrap();
    for bad in [
        [1e300, 0.0, 0.2, 0.0, 0.0, 0.0],
        [0.0, -1e300, 0.2, 0.0, 0.0, 0.0],
        [0.4, 0.0, 0.4, 0.0, 0.0, 0.0],
        [0.0, 0.0, 0.1, 7.0, 0.0, 0.0],
    ] {
        let e = c.set_tcp_offset("rob1", bad).unwrap_err();
        assert!(matches!(e, RobotError::Controller { code: -5, .. }), "{bad:?}: {e}");
    }
    // An offset in range is used as a whole (x and y too): the pose is the flange's moved by it.
    let flange = c.tcp_pose("rob1").unwrap().to_iso();
    assert_eq!(c.set_tcp_offset("rob1", [0.0, 0.1, 0.2, 0.0, 0.0, 0.0]).unwrap(), 0);
    let want = flange * nalgebra::Translation3::new(0.0, 0.1, 0.2);
    let got = c.tcp_pose("rob1").unwrap().to_iso();
    assert!((got.translation.vector - want.translation.vector).norm() < 1e-9);
    assert_eq!(c.joint_positions("rob1").unwrap(), q);
    // HTTP: two Content-Length headers that disagree are refused (400), identical ones accepted.
    let body = br#"{"jsonrpc":"2.0","id":"1","method":"getRobotNames"}"#;
    for (lengths, status) in [((body.len(), body.len() - 10), "400"), ((body.len(), body.len()), "200")] {
        let mut s = TcpStream::connect(sim.addr).unwrap();
        let head = format!(
            "POST /jsonrpc HTTP/1.1\r\nHost: x\r\nContent-Length: {}\r\nContent-Length: {}\r\nConnection: close\r\n\r\n",
            lengths.0, lengths.1
        );
        s.write_all(&[head.as_bytes(), &body[..]].concat()).unwrap();
        let (_, out) = read_to_close(&mut s);
        let text = String::from_utf8_lossy(&out);
        assert!(text.starts_with(&format!("HTTP/1.1 {status}")), "{lengths:?}: {text}");
        if status == "400" {
            assert!(text.contains("two Content-Length headers that disagree"), "{text}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Random byte streams, in random pieces, over every transport: the session answers or
    /// closes, never panics, and answers at most one message per request byte.
    #[test]
    fn random_byte_streams_never_break_a_session(
        prefix in prop::sample::select(vec![
            &b""[..],
            &b"SOF\x01"[..],
            &b"{\"jsonrpc\":\"2.0\","[..],
            &b"POST / HTTP/1.1\r\n"[..],
            &b"\n \t"[..],
        ]),
        bytes in prop::collection::vec(any::<u8>(), 0..2048),
        cuts in prop::collection::vec(0usize..2048, 0..6),
    ) {
        let stream = [prefix, bytes.as_slice()].concat();
        let mut at: Vec<usize> = cuts.into_iter().map(|c| c.min(stream.len())).collect();
        at.push(0);
        at.push(stream.len());
        at.sort_unstable();
        let pieces: Vec<&[u8]> = at.windows(2).map(|w| &stream[w[0]..w[1]]).collect();
        let (out, _) = serve_bytes(SimOptions::default(), &Transport::ALL, &pieces).unwrap();
        prop_assert!(out.len() <= 4096 + 512 * stream.len());
    }
}

#[test]
fn the_fault_injection_still_drops_and_fills_the_queue() {
    let sim = start(
        &[Transport::Framed],
        SimOptions { faults: Faults { queue_full_every: Some(2), ..Faults::default() }, ..SimOptions::default() },
    );
    let mut c = framed(&sim);
    assert_eq!(line_to(&mut c, HOME_POSE_NEAR, 0.1).unwrap(), 0);
    assert_eq!(line_to(&mut c, HOME_POSE_NEAR, 0.1).unwrap(), robot_io::aubo::QUEUE_FULL);
}

#[test]
fn the_simulator_moves_and_answers_with_the_kinematics_it_is_given() {
    use std::f64::consts::{FRAC_PI_2, PI};
    // A real controller's reported arrays and a waypoint it saved (issue 26), TCP offset 0.1 m
    // along the flange's y.
    let dh = robot_io::DhParams {
        a_m: [0.0, 5.8e-5, 0.36851, 0.31634, 4.53e-5, 3.166e-4],
        alpha_rad: [0.0, -1.56995, 3.13975, 3.14489, -1.57019, 1.56620],
        d_m: [0.122, 0.12161, -1.145e-4, 1.145e-4, 0.10210, 0.094],
        theta_rad: [PI, -FRAC_PI_2, 0.0, -FRAC_PI_2, 0.0, 0.0],
    };
    let q = [-0.17556, 0.13348, -0.76781, 0.73389, -1.55988, -0.60547];
    let saved = robot_io::Pose([-0.49913, -0.09370, 0.57777, -3.09482, -0.04559, -1.14230]);
    let sim = start(&[Transport::Framed], SimOptions { kinematics: dh, ..SimOptions::default() });
    let mut c = framed(&sim);
    assert_eq!(c.set_tcp_offset("rob1", [0.0, 0.1, 0.0, 0.0, 0.0, 0.0]).unwrap(), 0);
    let mj = json!({"q": q, "a": 1.0, "v": 1.0, "blend_radius": 0.0, "duration": 0.0});
    assert_eq!(c.call_status("rob1.MotionControl.moveJoint", mj).unwrap(), 0);
    let near = |p: &robot_io::Pose| {
        let (a, b) = (p.to_iso(), saved.to_iso());
        ((a.translation.vector - b.translation.vector).norm(), a.rotation.angle_to(&b.rotation))
    };
    // Within what the saved numbers (5 decimals) and that controller's model allow: 1.5 mm,
    // 0.33°; the i5's nominal arrays put the same joints centimetres away.
    let (dp, dr) = near(&c.tcp_pose("rob1").unwrap());
    assert!(dp < 2e-3 && dr < 1e-2, "{dp} m, {dr} rad from the saved waypoint");
    let tcp = robot_io::Pose([0.0, 0.1, 0.0, 0.0, 0.0, 0.0]).to_iso();
    let nominal = robot_io::Pose::from_iso(&robot_io::DhParams::AUBO_I5.forward(&q, &tcp));
    assert!(near(&nominal).0 > 0.01, "the nominal model is {} m away", near(&nominal).0);
    // Its kinematics services: the same model, (values, status) pairs, the arrays it was given.
    let fk = c.call("rob1.RobotAlgorithm.forwardKinematics", json!({"q": q})).unwrap();
    assert_eq!(fk[1], 0);
    let p: [f64; 6] = serde_json::from_value(fk[0].clone()).unwrap();
    assert!(near(&robot_io::Pose(p)).0 < 2e-3);
    let ik = c.call("rob1.RobotAlgorithm.inverseKinematics", json!({"qnear": q, "pose": saved.0})).unwrap();
    assert_eq!(ik[1], 0, "{ik}");
    let solved: [f64; 6] = serde_json::from_value(ik[0].clone()).unwrap();
    let back = c.call("rob1.RobotAlgorithm.forwardKinematics", json!({"q": solved})).unwrap();
    let back: [f64; 6] = serde_json::from_value(back[0].clone()).unwrap();
    let (dp, dr) = near(&robot_io::Pose(back));
    assert!(dp < 1e-5 && dr < 1e-4, "FK of IK: {dp} m, {dr} rad (the inverse's tolerance)");
    let far = c.call("rob1.RobotAlgorithm.inverseKinematics", json!({"qnear": q, "pose": [3.0, 0, 0.1, PI, 0, 0]}));
    assert_eq!(far.unwrap()[1], -10);
    let k = c.call("rob1.RobotConfig.getKinematicsParam", json!({"real": true})).unwrap();
    assert_eq!(serde_json::from_value::<[f64; 6]>(k["alpha"].clone()).unwrap(), dh.alpha_rad);
    assert_eq!(serde_json::from_value::<[f64; 6]>(k["d"].clone()).unwrap(), dh.d_m);
    // As `arm.json` records them: the calibrated parameters, where they were read, valid.
    let addr = sim.addr.to_string();
    let mut client =
        robot_io::aubo::AuboClient::open(&addr, &robot_io::aubo::Link::default(), Duration::from_secs(2)).unwrap().0;
    let arm = client.arm_kinematics("rob1").unwrap();
    assert_eq!((arm.robot.as_str(), arm.real, arm.kinematics), ("rob1", true, dh));
    assert_eq!(arm.source, format!("{addr} (framed): RobotConfig.getKinematicsParam(true)"));
    arm.validate(std::path::Path::new("arm.json")).unwrap();
    // Kinematics that are not finite are refused at start.
    let bad = robot_io::DhParams { a_m: [f64::NAN; 6], ..dh };
    let e = Simulator::start_with(
        &[Listen { bind: "127.0.0.1:0".into(), transports: vec![Transport::Framed] }],
        SimOptions { kinematics: bad, ..SimOptions::default() },
    )
    .err()
    .unwrap();
    assert!(e.to_string().contains("kinematics: a[0]"), "{e}");
}

#[test]
fn idle_connections_give_their_place_to_a_new_client() {
    // Issue 43: as many idle sockets as places once locked every well-formed client out until
    // they timed out. Now the one longest without an answer gives its place up (after
    // EVICT_AFTER); one that is answering keeps it.
    let options = SimOptions { max_connections: 3, ..SimOptions::default() };
    let sim = start(&[Transport::Framed], options);
    let mut busy = framed(&sim);
    let mut idle: Vec<TcpStream> = (0..2).map(|_| TcpStream::connect(sim.addr).unwrap()).collect();
    for _ in 0..200 {
        if sim.connections() == 3 {
            break;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(sim.connections(), 3);
    std::thread::sleep(robot_io::sim::EVICT_AFTER + Duration::from_millis(200));
    assert_eq!(busy.robot_names().unwrap(), ["rob1"]);
    // Two newcomers, each served: the two idle sockets are closed for them, the busy one stays.
    let mut a = framed(&sim);
    let mut b = framed(&sim);
    assert_eq!(a.robot_names().unwrap(), ["rob1"]);
    assert_eq!(b.robot_names().unwrap(), ["rob1"]);
    for s in &mut idle {
        assert!(read_to_close(s).0, "an idle connection kept its place");
    }
    assert_eq!(busy.robot_names().unwrap(), ["rob1"]);
    // All three answering within the last second: a fourth is closed at once.
    let mut extra = TcpStream::connect(sim.addr).unwrap();
    let _ = extra.write_all(&robot_io::wire::encode_frame(b"{}").unwrap());
    assert_eq!(read_to_close(&mut extra), (true, Vec::new()));
}

#[test]
fn whitespace_does_not_keep_a_connection_alive() {
    let options = SimOptions { idle_timeout: Duration::from_millis(400), ..SimOptions::default() };
    let sim = start(&[Transport::Lines], options);
    let mut s = TcpStream::connect(sim.addr).unwrap();
    s.set_read_timeout(Some(Duration::from_millis(50))).unwrap();
    let t0 = std::time::Instant::now();
    let mut closed = false;
    let mut buf = [0u8; 64];
    // A space every 100 ms for up to 3 s: closed after the idle time-out all the same.
    while t0.elapsed() < Duration::from_secs(3) {
        if s.write_all(b" ").is_err() {
            closed = true;
            break;
        }
        match s.read(&mut buf) {
            Ok(0) => {
                closed = true;
                break;
            }
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionReset => {
                closed = true;
                break;
            }
            _ => std::thread::sleep(Duration::from_millis(50)),
        }
    }
    assert!(closed && t0.elapsed() < Duration::from_millis(1500), "open after {:?}", t0.elapsed());
}

#[test]
fn the_trace_file_stops_at_its_size_limit_and_says_so() {
    let dir = std::env::temp_dir().join(format!("maobi-sim-trace-limit-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join("trace.jsonl");
    let options = SimOptions { trace_path: Some(path.clone()), trace_max_bytes: 20_000, ..SimOptions::default() };
    let sim = start(&[Transport::Framed], options);
    let mut c = framed(&sim);
    assert_eq!(line_to(&mut c, HOME_POSE_NEAR, 0.1).unwrap(), 0);
    assert_eq!(line_to(&mut c, moved(HOME_POSE_NEAR, -0.05), 0.1).unwrap(), 0);
    let e = sim.trace_error().expect("the limit is reported");
    assert!(e.contains("size limit") && e.contains("goes on"), "{e}");
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.len() <= 20_000 && text.ends_with('\n'), "{} bytes", text.len());
    assert!(text.lines().all(|l| serde_json::from_str::<Value>(l).is_ok()), "whole lines only");
    // It goes on moving.
    let p = moved(HOME_POSE_NEAR, 0.01);
    assert_eq!(line_to(&mut c, p, 0.1).unwrap(), 0);
    assert_eq!(c.tcp_pose("rob1").unwrap().0, p);
    let _ = std::fs::remove_dir_all(&dir);
}
