//! The simulator's script port (issue 41): scripts in AUBO's documented form run in a real Lua
//! 5.4 against the simulator's `aubo` bindings; what would fail on a controller fails there,
//! naming the line; a hostile script is bounded (no file, process or module access, a memory
//! limit, a stop request); the runtime's state and named integers are served over JSON-RPC.

use std::io::Write;
use std::time::{Duration, Instant};

use robot_io::aubo::AuboClient;
use robot_io::sim::{Listen, SimOptions, Simulator};
use robot_io::wire::Transport;
use robot_io::{DhParams, RobotConfig, aubo_lua, aubo_lua_path_buffer, build_program};
use serde_json::{Value, json};

use crate::common::{paper, pen1, small_track};

/// A simulator serving the line-delimited transport and a script port.
fn sim() -> (Simulator, std::net::SocketAddr) {
    let listen = [Listen { bind: "127.0.0.1:0".into(), transports: vec![Transport::Lines] }];
    let sim = Simulator::start_with(&listen, SimOptions::default()).unwrap();
    let script = sim.serve_scripts("127.0.0.1:0").unwrap();
    (sim, script)
}

fn send(addr: std::net::SocketAddr, text: &str) {
    let mut s = std::net::TcpStream::connect(addr).unwrap();
    s.write_all(text.as_bytes()).unwrap();
    s.write_all(b"\r\n\r\n").unwrap();
}

/// Waits (at most 30 s) until `n` scripts ran, then returns the errors.
fn ran(sim: &Simulator, n: usize) -> Vec<String> {
    let t0 = Instant::now();
    while sim.scripts_run() < n || status(sim) == "Running" {
        assert!(t0.elapsed() < Duration::from_secs(30), "{} scripts ran", sim.scripts_run());
        std::thread::sleep(Duration::from_millis(10));
    }
    sim.script_errors()
}

fn rpc(sim: &Simulator, method: &str, params: Value) -> Value {
    let mut c = AuboClient::connect(&sim.addr.to_string(), Duration::from_secs(2)).unwrap();
    c.call(method, params).unwrap()
}

fn status(sim: &Simulator) -> String {
    rpc(sim, "RuntimeMachine.getStatus", json!([])).as_str().unwrap().to_string()
}

#[test]
fn the_exported_scripts_run_in_lua_and_publish_their_progress() {
    // The small track's points are 10 mm apart.
    let cfg =
        RobotConfig { limits: robot_io::Limits { max_step_mm: 16.0, ..Default::default() }, ..Default::default() };
    let (program, _) = build_program(&small_track(), &pen1(), &paper(), &cfg).unwrap();
    let (sim, port) = sim();
    assert_eq!(status(&sim), "Stopped");
    send(port, &aubo_lua_path_buffer(&program, &DhParams::AUBO_I5, &cfg, "十").unwrap());
    assert_eq!(ran(&sim, 1), Vec::<String>::new());
    assert_eq!(rpc(&sim, "RegisterControl.getInt32", json!(["maobi_strokes", -1])), json!(program.strokes.len()));
    let pressed = sim.trace().iter().filter(|t| t.kind == robot_io::TraceKind::PathBuffer).count();
    assert!(pressed > 100, "{pressed}");
    // The move-per-point form, from where the first one left the arm.
    let compact = robot_io::compact_program(&program, &cfg);
    send(port, &aubo_lua(&compact, "十").unwrap());
    assert_eq!(ran(&sim, 2), Vec::<String>::new());
    // The last pose is the last lift's.
    let end = compact.strokes.last().unwrap().lift.target().unwrap();
    let here: Vec<f64> = serde_json::from_value(rpc(&sim, "rob1.RobotState.getTcpPose", json!([]))).unwrap();
    assert!((0..3).all(|k| (here[k] - end.0[k]).abs() < 1e-9), "{here:?}");
}

#[test]
fn scripts_fail_where_a_controller_would_naming_the_line() {
    let (sim, port) = sim();
    let head = "return function(api)\n  local _ENV = require('aubo').sched.select_robot(1)\n";
    let cases = [
        // A function outside the bindings.
        (
            format!("{head}  setPayload(1, {{0, 0, 0}})\nend\n"),
            "script:3: attempt to call a nil value (global 'setPayload')",
        ),
        // A wrong argument, as AUBO's prototypes type them.
        (
            format!("{head}  moveLine({{0.4, 0, 0.3, 3.14, 0}}, 1, 1, 0, 0)\nend\n"),
            "script:3: moveLine(table of six numbers",
        ),
        (
            format!("{head}  setSpeedFraction(\"fast\")\nend\n"),
            "script:3: setSpeedFraction(number): argument 1 is a string",
        ),
        // A move the controller refuses (a blend radius of 1 m).
        (format!("{head}  moveLine({{0.4, 0, 0.3, 3.14, 0, 0}}, 1, 0.1, 1, 0)\nend\n"), "script:3: moveLine refused"),
        // Another robot, another module; no files, processes or chunks.
        (
            "return function(api)\n  local _ENV = require('aubo').sched.select_robot(2)\nend\n".into(),
            "script:2: select_robot: no robot",
        ),
        ("local x = require('socket')\n".into(), "script:1: module"),
        ("os.exit(3)\n".into(), "script:1: attempt to index a nil value (global 'os')"),
        ("io.open('/etc/passwd')\n".into(), "global 'io'"),
        ("load('return 1')()\n".into(), "global 'load'"),
        (
            "return function(api)\n  error('maobi: nothing was moved')\nend\n".into(),
            "script:2: maobi: nothing was moved",
        ),
        ("return function(api\n".into(), "syntax error"),
    ];
    for (i, (text, needle)) in cases.iter().enumerate() {
        send(port, text);
        let errors = ran(&sim, i + 1);
        assert_eq!(errors.len(), i + 1, "{needle}: {errors:?}");
        assert!(errors[i].contains(needle), "{needle}: {}", errors[i]);
    }
    // Nothing moved.
    assert!(sim.trace().is_empty());
}

#[test]
fn a_hostile_script_is_bounded_and_stoppable() {
    let (sim, port) = sim();
    // Memory: stopped at the limit.
    send(port, "local t = {}\nwhile true do t[#t + 1] = string.rep('x', 1 << 20) end\n");
    let e = ran(&sim, 1);
    assert!(e[0].contains("memory"), "{e:?}");
    // A loop without end: stopped on request, and the port takes the next script.
    send(port, "while true do end\n");
    let t0 = Instant::now();
    while status(&sim) != "Running" {
        assert!(t0.elapsed() < Duration::from_secs(10));
        std::thread::sleep(Duration::from_millis(5));
    }
    // One script at a time.
    send(port, "return 1\n");
    std::thread::sleep(Duration::from_millis(100));
    assert_eq!(rpc(&sim, "RuntimeMachine.stop", json!([])), json!(0));
    let e = ran(&sim, 2);
    assert!(e.iter().any(|e| e.contains("stopped (RuntimeMachine.stop)")), "{e:?}");
    assert!(e.iter().any(|e| e.contains("another script is running")), "{e:?}");
    // Named integers are bounded too.
    let c = rpc(&sim, "RegisterControl.setInt32", json!(["k", 7]));
    assert_eq!((c, rpc(&sim, "RegisterControl.getInt32", json!(["k", 0]))), (json!(0), json!(7)));
    let mut client = AuboClient::connect(&sim.addr.to_string(), Duration::from_secs(2)).unwrap();
    let e = client.call("RegisterControl.setInt32", json!(["x".repeat(65), 1])).unwrap_err().to_string();
    assert!(e.contains("1 to 64 bytes"), "{e}");
}
