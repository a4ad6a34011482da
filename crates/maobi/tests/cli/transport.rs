//! `maobi robot send` over each transport against `maobi robot sim` (issue #16): 永 over the
//! framed transport through a dropped link, the same program over lines and HTTP, a refused
//! login; and the official AUBO SDK client (`pyaubo_sdk`) driving the simulator end to end.

use crate::common::{Sim, fails, free_port, maobi, ok, s};
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

fn paper() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/robot/paper.json")
}

#[test]
fn send_writes_yong_over_every_transport_and_resumes_after_a_drop() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("yong");
    ok(&maobi(&["write", "永", "--size", "128", "--out", s(&out)]));
    let track = out.join("track.json");
    let check: serde_json::Value =
        serde_json::from_str(&ok(&maobi(&["robot", "check", s(&track), "--paper", s(&paper()), "--json"]))).unwrap();
    let (strokes, moves) = (check["strokes"].as_u64().unwrap(), check["moves"].as_u64().unwrap());
    // Each stroke through the path buffer is four motion requests (travel, descent,
    // movePathBuffer, lift) after the start move: drop the link at the third stroke's
    // movePathBuffer, inside the stroke with the brush on the paper.
    let _ = moves;
    let (port, lines, http) = (free_port(), free_port(), free_port());
    let trace = dir.path().join("trace.jsonl");
    let drop = format!("drop-after={}", 1 + 4 * 2 + 3);
    let (lines_s, http_s) = (lines.to_string(), http.to_string());
    let _sim =
        Sim::start(port, &["--lines-port", &lines_s, "--http-port", &http_s, "--fault", &drop, "--trace", s(&trace)]);
    let paper_json = paper();
    let send = |extra: &[&str]| {
        let mut args = vec!["robot", "send", s(&track), "--paper", s(&paper_json), "--host", "127.0.0.1"];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--timeout-ms", "1000"]);
        maobi(&args)
    };
    let p = port.to_string();
    let framed = ok(&send(&["--port", &p]));
    assert!(
        framed.contains(&format!("{strokes} of {strokes} strokes completed; 1 reconnect(s), 1 stroke(s) resumed")),
        "{framed}"
    );
    assert!(framed.contains(&format!("{strokes} path buffer(s)")), "{framed}");
    // A few controller calls per stroke (3,300 points).
    let calls = number_before(&framed, "controller calls");
    assert!(calls < 40 * strokes, "{framed}");
    // The drop fires once: the other transports run straight through on their own ports,
    // lines with a move per point of the compacted track.
    for (t, port, motion) in [("lines", &lines_s, "moves"), ("http", &http_s, "path-buffer")] {
        let o = ok(&send(&["--transport", t, "--port", port, "--motion", motion]));
        assert!(o.contains(&format!("{strokes} of {strokes} strokes completed; 0 reconnect(s)")), "{t}: {o}");
    }
    // --motion moves: at least 5× fewer moves than points, every blend valid (checked by send).
    let dry = ok(&send(&["--port", &p, "--motion", "moves", "--dry-run"]));
    let compact = number_before(&dry, "moves would be sent");
    assert!(compact * 5 <= moves, "{compact} moves of {moves}: {dry}");
    // The executed path renders back to the planned image.
    std::thread::sleep(Duration::from_millis(300));
    let img = dir.path().join("trace.png");
    ok(&maobi(&[
        "robot",
        "render-trace",
        s(&trace),
        "--track",
        s(&track),
        "--paper",
        s(&paper()),
        "--size",
        "128",
        "-o",
        s(&img),
    ]));
    let j: serde_json::Value =
        serde_json::from_str(&ok(&maobi(&["compare", s(&out.join("render.png")), s(&img), "--json"]))).unwrap();
    assert!(j["csim"].as_f64().unwrap() > 0.9, "{j}");
    // A wrong password is refused before anything moves, naming the user.
    fails(&send(&["--port", &p, "--password", "nope"]), "login as `aubo` refused");
    // An unknown transport names the choices.
    let o = send(&["--transport", "tcp"]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("expected framed, lines, http or script"));
    // The simulator's help says which transports have no login.
    let help = ok(&maobi(&["robot", "sim", "--help"]));
    assert!(help.contains("UNAUTHENTICATED"), "{help}");
}

/// The number just before `words` in `text`.
fn number_before(text: &str, words: &str) -> u64 {
    let at = text.find(words).unwrap_or_else(|| panic!("no `{words}` in {text}"));
    text[..at].split_whitespace().last().and_then(|n| n.parse().ok()).unwrap_or_else(|| panic!("{text}"))
}

/// A one-stroke track (一, 60 mm, points 4 mm apart) with the built-in pen1 brush.
fn one_stroke_track(dir: &Path) -> PathBuf {
    let brush = brush_model::BrushProfile::builtin("pen1").unwrap();
    let pt = |x: f64| brush_model::TrackPoint { x_mm: x, y_mm: 60.0, h_mm: 14.0, alpha_rad: 0.0, beta_rad: 0.0 };
    let track = dir.join("track.json");
    let t = serde_json::json!({
        "char": "一",
        "brush": brush,
        "strokes": [brush_model::Stroke { points: (0..16).map(|i| pt(30.0 + 4.0 * f64::from(i))).collect() }],
        "char_box_mm": [20.0, 20.0, 80.0],
    });
    std::fs::write(&track, t.to_string()).unwrap();
    track
}

#[test]
fn the_simulator_serves_framed_by_default_and_lines_only_where_asked() {
    let dir = tempfile::tempdir().unwrap();
    let track = one_stroke_track(dir.path());
    let (port, lines) = (free_port(), free_port());
    let trace = dir.path().join("trace.jsonl");
    let _sim = Sim::start(port, &["--lines-port", &lines.to_string(), "--trace", s(&trace)]);
    let paper_json = paper();
    let send = |extra: &[&str]| {
        let mut args = vec!["robot", "send", s(&track), "--paper", s(&paper_json), "--host", "127.0.0.1"];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--timeout-ms", "1000"]);
        maobi(&args)
    };
    let p = port.to_string();
    let o = ok(&send(&["--port", &p]));
    assert!(o.contains("1 of 1 strokes completed"), "{o}");
    // One program after the other: the second session gets motion once the first has closed.
    let o = ok(&send(&["--transport", "lines", "--port", &lines.to_string()]));
    assert!(o.contains("1 of 1 strokes completed"), "{o}");
    // The default port does not speak the unauthenticated lines transport.
    let o = send(&["--transport", "lines", "--port", &p]);
    assert!(!o.status.success());
    // The simulator wrote every executed sample as it went; the trace renders.
    let img = dir.path().join("trace.png");
    let out = ok(&maobi(&[
        "robot",
        "render-trace",
        s(&trace),
        "--track",
        s(&track),
        "--paper",
        s(&paper()),
        "--size",
        "64",
        "-o",
        s(&img),
    ]));
    let n = std::fs::read_to_string(&trace).unwrap().lines().count();
    assert!(out.contains(&format!("{n} trace samples")) && !out.contains("(0 pressed)"), "{out}");
}

#[test]
fn render_trace_reads_a_cut_trace_up_to_its_last_complete_line() {
    // A one-stroke track and the trace the simulator records for it (a pressed line on the
    // paper between two lifted points), written as `robot sim --trace` writes it.
    let dir = tempfile::tempdir().unwrap();
    let brush = brush_model::BrushProfile::builtin("pen1").unwrap();
    let pt = |x: f64, h: f64| brush_model::TrackPoint { x_mm: x, y_mm: 60.0, h_mm: h, alpha_rad: 0.0, beta_rad: 0.0 };
    let track = dir.path().join("track.json");
    let t = serde_json::json!({
        "char": "一",
        "brush": brush,
        "strokes": [brush_model::Stroke { points: vec![pt(30.0, 2.0), pt(90.0, 2.0)] }],
        "char_box_mm": [20.0, 20.0, 80.0],
    });
    std::fs::write(&track, t.to_string()).unwrap();
    let frame = robot_io::PaperFrame::load(&paper()).unwrap();
    let poses =
        [pt(30.0, -10.0), pt(30.0, 2.0), pt(90.0, 2.0), pt(90.0, -10.0)].map(|p| robot_io::brush_pose(&frame, &p));
    let mut samples = vec![];
    for w in poses.windows(2) {
        let t0 = samples.last().map_or(0.0, |s: &robot_io::TraceEntry| s.t_s);
        samples.extend(robot_io::line_motion(&w[0], &w[1], 0.02, t0));
    }
    let full: String = samples.iter().map(|s| serde_json::to_string(s).unwrap() + "\n").collect();
    let n = samples.len();
    let img = dir.path().join("trace.png");
    let render = |t: &Path| {
        maobi(&[
            "robot",
            "render-trace",
            s(t),
            "--track",
            s(&track),
            "--paper",
            s(&paper()),
            "--size",
            "64",
            "-o",
            s(&img),
            "--force",
        ])
    };
    let whole = dir.path().join("whole.jsonl");
    std::fs::write(&whole, &full).unwrap();
    let o = render(&whole);
    assert!(ok(&o).contains(&format!("{n} trace samples")));
    assert!(o.stderr.is_empty(), "{}", String::from_utf8_lossy(&o.stderr));
    // Cut inside the last line (as a full disk or a kill mid-write leaves it): rendered up to
    // the line before, saying what was skipped.
    let cut = dir.path().join("cut.jsonl");
    let last_at = full.trim_end().rfind('\n').unwrap() + 1;
    for keep in [1, 29, full.trim_end().len() - last_at - 1] {
        let at = last_at + keep;
        std::fs::write(&cut, &full[..at]).unwrap();
        let o = render(&cut);
        assert!(ok(&o).contains(&format!("{} trace samples", n - 1)), "keep {keep}");
        let warn = String::from_utf8_lossy(&o.stderr);
        assert!(warn.contains(&format!("cut.jsonl:{n}: skipped a cut last line")), "keep {keep}: {warn}");
    }
    // A bad line before the last is still an error, naming its line.
    let mut bad: Vec<&str> = full.lines().collect();
    bad[1] = "{\"t_s\": 1,";
    std::fs::write(&cut, bad.join("\n") + "\n").unwrap();
    fails(&render(&cut), "cut.jsonl:2: not a simulator trace sample");
}

/// Drives the simulator with the official SDK: every call maobi makes, and what the SDK sees.
const SDK_SCRIPT: &str = r#"
import json, sys, pyaubo_sdk
port = int(sys.argv[1])
c = pyaubo_sdk.RpcClient()
c.setRequestTimeout(3000)
out = {"connect": c.connect("127.0.0.1", port)}
out["login"] = c.login("aubo", "123456")
out["logined"] = c.hasLogined()
out["names"] = c.getRobotNames()
r = c.getRobotInterface(out["names"][0])
mc, rs = r.getMotionControl(), r.getRobotState()
out["setTcpOffset"] = r.getRobotConfig().setTcpOffset([0.0, 0.0, 0.2, 0.0, 0.0, 0.0])
out["setSpeedFraction"] = mc.setSpeedFraction(0.5)
out["moveJoint"] = mc.moveJoint([0.0, 0.3, 1.6, 0.3, 1.57, 0.0], 1.0, 0.5, 0.0, 0.0)
start = rs.getTcpPose()
target = list(start)
target[2] -= 0.05
out["moveLine"] = mc.moveLine(target, 0.3, 0.05, 0.0, 0.0)
out["moveLine_too_fast"] = mc.moveLine(start, 0.3, 9.0, 0.0, 0.0)
out["getExecId"] = mc.getExecId()
out["isSteady"] = rs.isSteady()
out["target"] = target
out["getTcpPose"] = rs.getTcpPose()
out["getJointPositions"] = rs.getJointPositions()
alg = r.getRobotAlgorithm()
ik_target = list(out["getTcpPose"])
ik_target[0] += 0.02
out["ik"] = alg.inverseKinematics(out["getJointPositions"], ik_target)
out["fk"] = alg.forwardKinematics(list(out["ik"][0]))
out["ik_target"] = ik_target
out["ik_far"] = alg.inverseKinematics(out["getJointPositions"], [3.0, 0.0, 0.1, 3.14, 0.0, 0.0])
out["kinematics"] = r.getRobotConfig().getKinematicsParam(True)
out["nominal"] = r.getRobotConfig().getKinematicsParam(False)
out["compensate"] = r.getRobotConfig().getKinematicsCompensate(20.0)
try:
    rs.getJointSpeeds()
except Exception as e:
    out["unknown_method"] = str(e)
c.disconnect()
print(json.dumps(out))
"#;

#[test]
fn the_official_sdk_client_drives_the_simulator() {
    let have = Command::new("python3").args(["-c", "import pyaubo_sdk"]).output().is_ok_and(|o| o.status.success());
    if !have {
        // Written to the terminal directly (not captured), so a skipped run says so.
        let _ = writeln!(
            std::io::stderr(),
            "SKIPPED the_official_sdk_client_drives_the_simulator: python3 cannot import pyaubo_sdk \
             (`python3 -m pip install pyaubo-sdk`, CPython 3.11 on x86-64 Linux)"
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let trace = dir.path().join("trace.jsonl");
    let port = free_port();
    let sim = Sim::start(port, &["--trace", s(&trace)]);
    let mut py = Command::new("python3")
        .args(["-c", SDK_SCRIPT, &port.to_string()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Bounded: the SDK's own request timeout is 3 s per call.
    let mut done = None;
    for _ in 0..300 {
        if let Some(st) = py.try_wait().unwrap() {
            done = Some(st);
            break;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    if done.is_none() {
        let _ = py.kill();
    }
    let o = py.wait_with_output().unwrap();
    let (stdout, stderr) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "the SDK script failed:\n{stdout}\n{stderr}");
    let j: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
    for k in ["connect", "login", "setTcpOffset", "setSpeedFraction", "moveJoint", "moveLine"] {
        assert_eq!(j[k], 0, "{k}: {j}");
    }
    assert_eq!(j["logined"], true);
    assert_eq!(j["names"], serde_json::json!(["rob1"]));
    assert_eq!(j["moveLine_too_fast"], -5, "the simulator's range check reaches the SDK");
    assert_eq!(j["getExecId"], -1);
    assert_eq!(j["isSteady"], true);
    let pose: Vec<f64> = serde_json::from_value(j["getTcpPose"].clone()).unwrap();
    let target: Vec<f64> = serde_json::from_value(j["target"].clone()).unwrap();
    assert!(pose.iter().zip(&target).all(|(a, b)| (a - b).abs() < 1e-12), "{pose:?} vs {target:?}");
    assert_eq!(serde_json::from_value::<Vec<f64>>(j["getJointPositions"].clone()).unwrap().len(), 6);
    // The kinematics services reach the SDK as its (values, status) tuples and its dict: the
    // forward kinematics of the inverse's answer reproduces the pose asked for.
    assert_eq!(j["ik"][1], 0, "{j}");
    assert_eq!(j["fk"][1], 0, "{j}");
    let fk: Vec<f64> = serde_json::from_value(j["fk"][0].clone()).unwrap();
    let want: Vec<f64> = serde_json::from_value(j["ik_target"].clone()).unwrap();
    let (a, b) = (robot_io::Pose(fk.try_into().unwrap()), robot_io::Pose(want.try_into().unwrap()));
    let (a, b) = (a.to_iso(), b.to_iso());
    // Within the inverse's own tolerance (0.01 mm, 1e-4 rad: `kinematics::DhParams::inverse`).
    assert!((a.translation.vector - b.translation.vector).norm() < 1e-5, "{j}");
    assert!(a.rotation.angle_to(&b.rotation) < 1e-4, "{j}");
    assert_eq!(j["ik_far"][1], -10, "an unreachable pose: {j}");
    let k = robot_io::DhParams::AUBO_I5;
    for (name, want) in [("a", k.a_m), ("alpha", k.alpha_rad), ("d", k.d_m), ("theta", k.theta_rad)] {
        let got: Vec<f64> = serde_json::from_value(j["kinematics"][name].clone()).unwrap();
        assert_eq!(got, want, "{name}");
    }
    // The nominal parameters and the compensation (the SDK's getKinematicsCompensate(20.0)
    // reaches the simulator with its params and reads its answer as a dict): the simulator's arm
    // is the nominal one, so every increment is zero.
    for name in ["a", "alpha", "d", "theta", "beta"] {
        let got: Vec<f64> = serde_json::from_value(j["compensate"][name].clone()).unwrap();
        assert_eq!(got, vec![0.0; 6], "{name}: {j}");
    }
    assert_eq!(j["nominal"]["a"], j["kinematics"]["a"]);
    // A JSON-RPC error reaches the SDK as an exception naming the method, code and message.
    let e = j["unknown_method"].as_str().unwrap();
    assert!(e.contains("getJointSpeeds") && e.contains("-32601") && e.contains("method not found"), "{e}");
    // The simulator executed the SDK's moves: a joint move, then a line 50 mm straight down.
    std::thread::sleep(Duration::from_millis(300));
    drop(sim);
    let text = std::fs::read_to_string(&trace).unwrap();
    let samples: Vec<serde_json::Value> = text.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    assert!(samples.iter().any(|t| t["kind"] == "joint") && samples.iter().any(|t| t["kind"] == "line"));
    let last: Vec<f64> = serde_json::from_value(samples.last().unwrap()["pose"].clone()).unwrap();
    assert!(last.iter().zip(&target).all(|(a, b)| (a - b).abs() < 1e-9), "{last:?}");
}

/// Runs a path buffer stroke with the official SDK: its calls in its argument order.
const SDK_PATH_BUFFER: &str = r#"
import json, math, sys, pyaubo_sdk
port = int(sys.argv[1])
c = pyaubo_sdk.RpcClient()
c.setRequestTimeout(3000)
c.connect("127.0.0.1", port)
c.login("aubo", "123456")
r = c.getRobotInterface(c.getRobotNames()[0])
mc, rs = r.getMotionControl(), r.getRobotState()
q0 = rs.getJointPositions()
n, dt = 101, 0.01
w = []
for k in range(n):
    q = list(q0)
    q[0] += 0.1 * (0.5 - 0.5 * math.cos(math.pi * k / (n - 1)))
    w.append(q)
out = {}
out["alloc"] = mc.pathBufferAlloc("stroke1", 2, n)
out["move_early"] = mc.movePathBuffer("stroke1")
out["append"] = [mc.pathBufferAppend("stroke1", w[:50]), mc.pathBufferAppend("stroke1", w[50:])]
out["eval_too_slow"] = mc.pathBufferEval("stroke1", [2.0] * 6, [0.05] * 6, dt)
out["valid_after_refusal"] = mc.pathBufferValid("stroke1")
out["eval"] = mc.pathBufferEval("stroke1", [2.0] * 6, [0.5] * 6, dt)
out["valid"] = mc.pathBufferValid("stroke1")
out["list"] = mc.pathBufferList()
out["move"] = mc.movePathBuffer("stroke1")
out["joints"] = rs.getJointPositions()
out["last"] = w[-1]
out["free"] = mc.pathBufferFree("stroke1")
out["free_again"] = mc.pathBufferFree("stroke1")
out["move_unknown"] = mc.movePathBuffer("stroke1")
out["type1"] = mc.pathBufferAlloc("other", 1, 10)
c.disconnect()
print(json.dumps(out))
"#;

#[test]
fn the_official_sdk_client_runs_a_path_buffer_on_the_simulator() {
    let have = Command::new("python3").args(["-c", "import pyaubo_sdk"]).output().is_ok_and(|o| o.status.success());
    if !have {
        let _ = writeln!(
            std::io::stderr(),
            "SKIPPED the_official_sdk_client_runs_a_path_buffer_on_the_simulator: python3 cannot import pyaubo_sdk"
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let trace = dir.path().join("trace.jsonl");
    let port = free_port();
    let sim = Sim::start(port, &["--trace", s(&trace)]);
    let mut py = Command::new("python3")
        .args(["-c", SDK_PATH_BUFFER, &port.to_string()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut done = false;
    for _ in 0..300 {
        if py.try_wait().unwrap().is_some() {
            done = true;
            break;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    if !done {
        let _ = py.kill();
    }
    let o = py.wait_with_output().unwrap();
    let (stdout, stderr) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "the SDK script failed:\n{stdout}\n{stderr}");
    let j: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
    assert_eq!(j["alloc"], 0, "{j}");
    assert_eq!(j["move_early"], -5, "moving before an evaluation is refused: {j}");
    assert_eq!(j["append"], serde_json::json!([0, 0]));
    assert_eq!(j["eval_too_slow"], -5, "{j}");
    assert_eq!(j["valid_after_refusal"], false);
    assert_eq!(j["eval"], 0);
    assert_eq!(j["valid"], true);
    assert_eq!(j["list"], serde_json::json!(["stroke1"]));
    assert_eq!(j["move"], 0);
    let (q, last): (Vec<f64>, Vec<f64>) =
        (serde_json::from_value(j["joints"].clone()).unwrap(), serde_json::from_value(j["last"].clone()).unwrap());
    assert!(q.iter().zip(&last).all(|(a, b)| (a - b).abs() < 1e-12), "{q:?} vs {last:?}");
    assert_eq!(j["free"], 0);
    assert_eq!(j["free_again"], -5);
    assert_eq!(j["move_unknown"], -5);
    assert_eq!(j["type1"], -5, "the simulator executes type 2 only");
    // The trace has the buffer's samples, by time: 1 s of motion, every 5 ms.
    std::thread::sleep(Duration::from_millis(300));
    drop(sim);
    let text = std::fs::read_to_string(&trace).unwrap();
    let samples: Vec<serde_json::Value> = text.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    let path: Vec<f64> =
        samples.iter().filter(|t| t["kind"] == "path_buffer").map(|t| t["t_s"].as_f64().unwrap()).collect();
    assert_eq!(path.len(), 201);
    assert!((path[200] - path[0] - 1.0).abs() < 1e-9, "{} .. {}", path[0], path[200]);
}

#[test]
fn send_writes_held_out_characters_through_the_path_buffer_on_the_time_law() {
    let dir = tempfile::tempdir().unwrap();
    let paper_json = paper();
    // Three characters of fixtures/hanzi/heldout-2000.txt, from the embedded data.
    for ch in ["玉", "午", "肉"] {
        let out = dir.path().join(ch);
        ok(&maobi(&["write", ch, "--size", "128", "--out", s(&out)]));
        let track = out.join("track.json");
        // `robot check` reports the timing: each stroke's duration and peaks, and the writing time.
        let check = ok(&maobi(&["robot", "check", s(&track), "--paper", s(&paper_json)]));
        let strokes = number_before(&check, "strokes,");
        assert!(check.contains("stroke 1: ") && check.contains("writing time"), "{check}");
        let (port, trace) = (free_port(), dir.path().join(format!("{ch}.jsonl")));
        let sim = Sim::start(port, &["--trace", s(&trace)]);
        let sent = ok(&maobi(&[
            "robot",
            "send",
            s(&track),
            "--paper",
            s(&paper_json),
            "--host",
            "127.0.0.1",
            "--port",
            &port.to_string(),
        ]));
        drop(sim);
        assert!(sent.contains(&format!("{strokes} of {strokes} strokes completed")), "{ch}: {sent}");
        assert!(sent.contains(&format!("{strokes} path buffer(s)")), "{ch}: {sent}");
        assert!(
            sent.contains("on the controller's kinematics (getKinematicsParam, its compensation checked)"),
            "{sent}"
        );
        // What the simulator executed renders back to the plan.
        let img = dir.path().join(format!("{ch}.png"));
        let size = ["--size", "128"];
        let mut args = vec!["robot", "render-trace", s(&trace), "--track", s(&track), "--paper", s(&paper_json)];
        args.extend_from_slice(&size);
        args.extend_from_slice(&["-o", s(&img)]);
        ok(&maobi(&args));
        let j: serde_json::Value =
            serde_json::from_str(&ok(&maobi(&["compare", s(&out.join("render.png")), s(&img), "--json"]))).unwrap();
        assert!(j["csim"].as_f64().unwrap() > 0.95, "{ch}: {j}");
    }
}

#[test]
fn send_refuses_nominal_kinematics_unless_accepted() {
    let dir = tempfile::tempdir().unwrap();
    let track = one_stroke_track(dir.path());
    let (old, new) = (free_port(), free_port());
    let _old = Sim::start(old, &["--no-kinematics-param"]);
    let _new = Sim::start(new, &[]);
    let paper_json = paper();
    let send = |port: u16, extra: &[&str]| {
        let p = port.to_string();
        let mut args =
            vec!["robot", "send", s(&track), "--paper", s(&paper_json), "--host", "127.0.0.1", "--port", p.as_str()];
        args.extend_from_slice(extra);
        maobi(&args)
    };
    // A controller that does not report its parameters: refused, nothing moved, the flag named.
    let o = send(old, &[]);
    fails(&o, "computed from maobi's nominal AUBO-i5 parameters");
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("--accept-nominal-kinematics") && e.contains("nothing was moved"), "{e}");
    // Accepted: written, and said so.
    let o = ok(&send(old, &["--accept-nominal-kinematics"]));
    assert!(o.contains("1 of 1 strokes completed") && o.contains("nominal AUBO-i5 parameters (accepted)"), "{o}");
    // Asked for on a controller that reports its own: refused unless accepted.
    fails(&send(new, &["--nominal-kinematics"]), "nominal parameters were asked for");
    let o = ok(&send(new, &["--nominal-kinematics", "--accept-nominal-kinematics"]));
    assert!(o.contains("nominal AUBO-i5 parameters (accepted)"), "{o}");
    // By default its own, its compensation checked.
    let o = ok(&send(new, &[]));
    assert!(o.contains("on the controller's kinematics (getKinematicsParam, its compensation checked)"), "{o}");
}

/// The distance (mm) a refusal names in "put the TCP D mm".
fn refused_distance_mm(e: &str) -> f64 {
    let at = e.find("put the TCP ").unwrap_or_else(|| panic!("no distance in {e}")) + "put the TCP ".len();
    e[at..].split_whitespace().next().and_then(|d| d.parse().ok()).unwrap_or_else(|| panic!("{e}"))
}

#[test]
fn an_arm_whose_kinematics_differ_refuses_nominal_joints_and_follows_its_own() {
    use robot_io::DhParams;
    let dir = tempfile::tempdir().unwrap();
    let track = one_stroke_track(dir.path());
    let paper_json = paper();
    // Another i5: its upper arm 20 mm longer and its shoulder's zero 0.3° off (a calibration
    // far from nominal), as `robot kinematics -o` would save it.
    let mut theirs = DhParams::AUBO_I5;
    theirs.a_m[2] += 0.020;
    theirs.theta_rad[1] += 0.3f64.to_radians();
    let arm = dir.path().join("arm.json");
    let file =
        robot_io::ArmKinematics { robot: "rob1".into(), source: "a test arm".into(), real: true, kinematics: theirs };
    std::fs::write(&arm, serde_json::to_string_pretty(&file).unwrap()).unwrap();
    let (quiet, reporting) = (free_port(), free_port());
    let (quiet_trace, trace) = (dir.path().join("quiet.jsonl"), dir.path().join("trace.jsonl"));
    // An arm whose controller does not report its parameters, and one that does.
    let _quiet = Sim::start(quiet, &["--kinematics", s(&arm), "--no-kinematics-param", "--trace", s(&quiet_trace)]);
    let _reporting = Sim::start(reporting, &["--kinematics", s(&arm), "--trace", s(&trace)]);
    let send = |port: u16, extra: &[&str]| {
        let p = port.to_string();
        let mut args =
            vec!["robot", "send", s(&track), "--paper", s(&paper_json), "--host", "127.0.0.1", "--port", p.as_str()];
        args.extend_from_slice(extra);
        maobi(&args)
    };
    // Nominal joints accepted by the user: the controller's forward kinematics refuse them
    // before anything moves, naming the waypoint and how far the TCP would be.
    for (port, extra) in [
        (quiet, &["--accept-nominal-kinematics"][..]),
        (reporting, &["--nominal-kinematics", "--accept-nominal-kinematics"][..]),
    ] {
        let o = send(port, extra);
        fails(&o, "waypoint 0 of the path buffer: the controller's forward kinematics put the TCP");
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains("nothing was moved") && e.contains("stroke 1"), "{e}");
        // 20 mm of upper arm and 0.3° at the shoulder: centimetres, far beyond the 0.1 mm allowed.
        let d = refused_distance_mm(&e);
        assert!(d > 10.0 && d < 100.0, "{d} mm: {e}");
    }
    for t in [&quiet_trace, &trace] {
        assert_eq!(std::fs::read_to_string(t).unwrap(), "", "{} moved", t.display());
    }
    // The parameters read from that controller are its own.
    let read = dir.path().join("read.json");
    let p = reporting.to_string();
    ok(&maobi(&["robot", "kinematics", "--host", "127.0.0.1", "--port", &p, "-o", s(&read)]));
    let got = robot_io::ArmKinematics::load(&read).unwrap();
    assert_eq!(got.kinematics, theirs);
    // Sent on them (the default): written, and what the arm executed lies on the stroke (y 60
    // mm, depth 14 mm, x 30..90 mm) within the timing's path tolerance.
    let o = ok(&send(reporting, &[]));
    assert!(o.contains("1 of 1 strokes completed") && o.contains("on the controller's kinematics"), "{o}");
    let text = std::fs::read_to_string(&trace).unwrap();
    let samples: Vec<robot_io::TraceEntry> = text.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    let pressed: Vec<_> = samples.into_iter().filter(|t| t.kind == robot_io::TraceKind::PathBuffer).collect();
    assert!(pressed.len() > 100, "{} samples", pressed.len());
    let frame = robot_io::PaperFrame::load(&paper_json).unwrap();
    let tol_mm = robot_io::PATH_TOLERANCE_M * 1e3;
    let states = robot_io::trace_to_states(&pressed, &frame);
    let worst = states.iter().map(|p| (p.y_mm - 60.0).abs().max((p.h_mm - 14.0).abs())).fold(0.0, f64::max);
    assert!(worst <= tol_mm, "{worst} mm off the stroke");
    let (x0, x1) = states.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.x_mm), b.max(p.x_mm)));
    assert!((x0 - 30.0).abs() <= tol_mm && (x1 - 90.0).abs() <= tol_mm, "x {x0}..{x1}");
}

#[test]
fn sim_refuses_a_kinematics_file_it_cannot_use_before_listening() {
    let dir = tempfile::tempdir().unwrap();
    let port = free_port().to_string();
    let sim = |arm: &Path| maobi(&["robot", "sim", "--port", &port, "--kinematics", s(arm)]);
    fails(&sim(&dir.path().join("none.json")), "none.json");
    // The nominal parameters saved as if real would not be another arm; a length out of range
    // is named by its array and joint.
    let arm = dir.path().join("arm.json");
    let mut file = robot_io::ArmKinematics {
        robot: "rob1".into(),
        source: "a test arm".into(),
        real: false,
        kinematics: robot_io::DhParams::AUBO_I5,
    };
    std::fs::write(&arm, serde_json::to_string(&file).unwrap()).unwrap();
    fails(&sim(&arm), "`real` is false");
    file.real = true;
    file.kinematics.d_m[1] = 1e9;
    std::fs::write(&arm, serde_json::to_string(&file).unwrap()).unwrap();
    fails(&sim(&arm), "arm.json: kinematics: d[1]");
}
