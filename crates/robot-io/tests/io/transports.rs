//! The three transports against one simulator: the same program runs over each (and survives a
//! dropped connection), the framed login is checked, calls before it are refused, and a client
//! on the wrong port or a failing HTTP server ends in a clear error.

use std::io::{Read, Write};
use std::net::TcpListener;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use brush_model::{BrushProfile, Stroke, Track, TrackPoint};
use robot_io::aubo::{AuboClient, Link, RunOptions, run_program};
use robot_io::sim::{Faults, Listen, SimOptions, Simulator};
use robot_io::wire::Transport;
use robot_io::{PaperFrame, Program, RobotConfig, RobotError, build_program};

fn program() -> (Program, PaperFrame) {
    let paper = PaperFrame::level([0.35, 0.15, 0.05], [200.0, 200.0]);
    let pt = |x: f64, y: f64| TrackPoint { x_mm: x, y_mm: y, h_mm: 14.0, alpha_rad: 0.0, beta_rad: 0.0 };
    let track = Track {
        strokes: vec![
            Stroke { points: (0..6).map(|i| pt(40.0 + 4.0 * i as f64, 60.0)).collect() },
            Stroke { points: (0..6).map(|i| pt(50.0, 45.0 + 4.0 * i as f64)).collect() },
        ],
    };
    // Each press ends at rest on its point (no blend), so the trace passes through it exactly.
    let stops = RobotConfig { blend_mm: 0.0, ..RobotConfig::default() };
    let (p, _) = build_program(&track, &BrushProfile::builtin("pen1").unwrap(), &paper, &stops).unwrap();
    (p, paper)
}

/// One simulator with a port per transport (and the shared port first).
fn sim(options: SimOptions) -> Simulator {
    let alone = Transport::ALL.map(|t| (0, t));
    Simulator::start_with(&Listen::loopback_ports(0, &Transport::ALL, alone), options).unwrap()
}

/// The loopback listeners as asked: the shared port first, then one per transport alone; and
/// whether any of them serves a transport without login.
#[test]
fn loopback_listeners_serve_what_they_name_and_say_when_one_has_no_login() {
    let s = sim(SimOptions::default());
    let served: Vec<Vec<Transport>> = s.addrs().iter().map(|(t, _)| t.clone()).collect();
    assert_eq!(
        served,
        [Transport::ALL.to_vec(), vec![Transport::Framed], vec![Transport::Lines], vec![Transport::Http]]
    );
    assert!(s.addrs().iter().all(|(_, a)| a.ip().is_loopback() && a.port() != 0));
    assert!(s.serves_without_login());
    let framed = Simulator::start_with(
        &Listen::loopback_ports(0, &[Transport::Framed], [(0, Transport::Framed)]),
        SimOptions::default(),
    )
    .unwrap();
    assert_eq!(framed.addrs().len(), 2);
    assert!(!framed.serves_without_login());
    for t in [Transport::Lines, Transport::Http] {
        let one = Simulator::start_with(&[Listen::loopback(0, &[t])], SimOptions::default()).unwrap();
        assert!(one.serves_without_login(), "{t}");
    }
    let ur = robot_io::sim::UrListen::loopback(robot_io::ur::UrPorts { script: 1, rtde: 2, dashboard: 3 });
    assert_eq!([ur.script, ur.rtde, ur.dashboard], ["127.0.0.1:1", "127.0.0.1:2", "127.0.0.1:3"]);
}

fn port_of(s: &Simulator, t: Transport) -> String {
    s.addrs().iter().find(|(x, _)| *x == [t]).unwrap().1.to_string()
}

#[test]
fn a_program_runs_over_every_transport_and_resumes_after_a_drop() {
    let (prog, paper) = program();
    for t in Transport::ALL {
        for drop in [None, Some(9)] {
            let s = sim(SimOptions {
                faults: Faults { drop_after_moves: drop, ..Faults::default() },
                ..SimOptions::default()
            });
            let stop = AtomicBool::new(false);
            let opts = RunOptions {
                timeout: Duration::from_millis(500),
                backoff: Duration::from_millis(5),
                link: Link::new(t),
                ..RunOptions::new(&stop)
            };
            let r = run_program(&port_of(&s, t), &prog, None, &opts, |_| {}).unwrap();
            assert_eq!(r.strokes_completed, vec![0, 1], "{t}");
            assert_eq!(r.reconnects, usize::from(drop.is_some()), "{t} {drop:?}");
            assert_eq!(r.strokes_resumed, usize::from(drop.is_some()), "{t} {drop:?}");
            // Every pressed point was reached, and the brush ended at the safe height.
            let trace = s.trace();
            for st in &prog.strokes {
                for m in &st.press {
                    let robot_io::Move::Line { pose, .. } = m else { panic!("line") };
                    assert!(trace.iter().any(|e| e.pose.position() == pose.position()), "{t}: a press missed");
                }
            }
            let last = paper.to_paper(trace.last().unwrap().pose.position());
            assert!((last[2] + 20.0).abs() < 1e-6, "{t}: ends {} mm deep", last[2]);
        }
    }
}

#[test]
fn the_framed_login_is_checked() {
    let s = sim(SimOptions { password: "brush".into(), ..SimOptions::default() });
    let addr = port_of(&s, Transport::Framed);
    let (mut c, names) =
        AuboClient::open(&addr, &Link { password: "brush".into(), ..Link::default() }, Duration::from_millis(500))
            .unwrap();
    assert_eq!(names, vec!["rob1".to_string()]);
    assert_eq!(c.interface_version(), Some(robot_io::wire::INTERFACE_VERSION));
    assert_eq!(c.joint_positions("rob1").unwrap(), robot_io::HOME_JOINTS);
    // A wrong password or user: refused, saying who.
    for link in [Link::default(), Link { user: "root".into(), password: "brush".into(), ..Link::default() }] {
        let e = AuboClient::open(&addr, &link, Duration::from_millis(500)).err().unwrap();
        assert!(matches!(&e, RobotError::Login { user, .. } if *user == link.user), "{e}");
        assert!(e.to_string().contains("FAILED"), "{e}");
    }
    // Before the login only the version query is answered.
    let mut c = AuboClient::connect_with(&addr, Transport::Framed, Duration::from_millis(500)).unwrap();
    assert_eq!(c.call("SystemInfo.getInterfaceVersionCode", serde_json::Value::Null).unwrap(), 24000);
    let e = c.robot_names().unwrap_err();
    assert!(matches!(&e, RobotError::Rpc { code: -32000, message, .. } if message.contains("not logged in")), "{e}");
    // The runner reports a refused login as it is, before anything moves.
    let stop = AtomicBool::new(false);
    let e = run_program(&addr, &program().0, None, &RunOptions::new(&stop), |_| {}).unwrap_err();
    assert!(matches!(e, RobotError::Login { .. }), "{e}");
    assert!(s.trace().is_empty());
}

#[test]
fn named_and_positional_params_are_both_understood() {
    let s = sim(SimOptions::default());
    let mut named =
        AuboClient::connect_with(&port_of(&s, Transport::Http), Transport::Http, Duration::from_secs(1)).unwrap();
    let pose = [0.4, 0.1, 0.1, std::f64::consts::PI, 0.0, 0.0];
    let m = "rob1.MotionControl.moveLine";
    let ok = serde_json::json!({"pose": pose, "a": 0.5, "v": 0.1, "blend_radius": 0.0, "duration": 0.0});
    assert_eq!(named.call_status(m, ok).unwrap(), 0);
    // A misspelt or missing name is an invalid argument (−5), as is a positional list too short.
    for bad in [
        serde_json::json!({"pose": pose, "a": 0.5, "v": 0.1, "blend": 0.0, "duration": 0.0}),
        serde_json::json!({"pose": pose, "a": 0.5, "v": 0.1}),
        serde_json::json!([pose, 0.5, 0.1]),
    ] {
        let e = named.call_status(m, bad.clone()).unwrap_err();
        assert!(matches!(e, RobotError::Controller { code: -5, .. }), "{bad}: {e}");
    }
    let e = named.call(m, serde_json::json!("pose")).unwrap_err();
    assert!(matches!(e, RobotError::Rpc { code: -32602, .. }), "{e}");
    assert!(named.is_steady("rob1").unwrap());
    // The HTTP session owns motion until its connection closes; then positional params move.
    drop(named);
    let mut positional = AuboClient::connect(&port_of(&s, Transport::Lines), Duration::from_secs(2)).unwrap();
    assert_eq!(positional.call_status(m, serde_json::json!([pose, 0.5, 0.1, 0.0, 0.0])).unwrap(), 0);
}

#[test]
fn the_wrong_port_or_a_failing_server_is_a_clear_error() {
    let s = sim(SimOptions::default());
    let t = Duration::from_millis(500);
    // Framed bytes to the lines-only port: the answer is not a frame.
    let e = AuboClient::open(&port_of(&s, Transport::Lines), &Link::default(), t).err().unwrap();
    assert!(matches!(&e, RobotError::Framing(m) if m.contains("SOF")), "{e}");
    // Lines to the framed-only port: the simulator hangs up.
    let mut c = AuboClient::connect(&port_of(&s, Transport::Framed), t).unwrap();
    assert!(matches!(c.robot_names(), Err(RobotError::Io { .. })));
    // An HTTP server answering 500: the status is reported.
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    std::thread::spawn(move || {
        let (mut s, _) = listener.accept().unwrap();
        s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
        let mut buf = [0u8; 4096];
        let _ = s.read(&mut buf);
        let _ = s.write_all(b"HTTP/1.1 500 Internal Server Error\r\nContent-Length: 4\r\n\r\noops");
        std::thread::sleep(Duration::from_millis(500));
    });
    let t0 = Instant::now();
    let mut c = AuboClient::connect_with(&addr, Transport::Http, t).unwrap();
    let e = c.robot_names().unwrap_err();
    assert!(matches!(&e, RobotError::Protocol(m) if m.contains("500 Internal Server Error")), "{e}");
    assert!(t0.elapsed() < t);
    // A GET is refused by the simulator's HTTP port with 405.
    let mut raw = std::net::TcpStream::connect(port_of(&s, Transport::Http)).unwrap();
    raw.write_all(b"GET / HTTP/1.1\r\nHost: x\r\n\r\n").unwrap();
    raw.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    let mut text = String::new();
    let _ = raw.read_to_string(&mut text);
    assert!(text.starts_with("HTTP/1.1 405"), "{text}");
}
