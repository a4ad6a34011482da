//! `maobi robot check` / `send` safety (issue #18): ordinary tracks pass with the default
//! limits, a mirrored paper frame, an extreme tilt and a blend the controller rejects are
//! refused, and Ctrl-C during `send` lifts the brush and exits non-zero saying "interrupted".

use crate::common::{Sim, fails, free_port, maobi, ok, s};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn paper() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/robot/paper.json")
}

fn write(dir: &Path, name: &str, extra: &[&str]) -> PathBuf {
    let out = dir.join(name);
    let mut args = vec!["write", "永", "--out", s(&out)];
    args.extend_from_slice(extra);
    ok(&maobi(&args));
    out.join("track.json")
}

#[test]
fn ordinary_tracks_pass_and_unsafe_inputs_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let upright = write(dir.path(), "upright", &[]);
    let tilted = write(dir.path(), "tilted", &["--alpha", "5"]);
    for t in [&upright, &tilted] {
        let j: serde_json::Value =
            serde_json::from_str(&ok(&maobi(&["robot", "check", s(t), "--paper", s(&paper()), "--json"]))).unwrap();
        assert_eq!(j["strokes"], 5, "{j}");
        assert!(j["max_wrist_rate_rad_s"].as_f64().unwrap() <= 20.0, "{j}");
    }
    // The fixture's touch points with every robot y negated: an exact fit, upside down.
    let mut p: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(paper()).unwrap()).unwrap();
    for t in p["touch_points"].as_array_mut().unwrap() {
        t["robot_m"][1] = serde_json::json!(-t["robot_m"][1].as_f64().unwrap());
    }
    let mirrored = dir.path().join("mirrored.json");
    std::fs::write(&mirrored, p.to_string()).unwrap();
    fails(&maobi(&["robot", "check", s(&upright), "--paper", s(&mirrored)]), "180.0° from the approach direction");
    let out = dir.path().join("p.script");
    fails(
        &maobi(&["robot", "export", s(&upright), "--paper", s(&mirrored), "--format", "urscript", "-o", s(&out)]),
        "mirrored",
    );
    assert!(!out.exists());
    // A point tilted 3 rad.
    let mut t: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&upright).unwrap()).unwrap();
    t["strokes"][1][10]["alpha_rad"] = serde_json::json!(3.0);
    let flip = dir.path().join("flip.json");
    std::fs::write(&flip, t.to_string()).unwrap();
    fails(
        &maobi(&["robot", "check", s(&flip), "--paper", s(&paper())]),
        "stroke 2, point 11: tilt α = 3.0000 rad (171.9°) is beyond limits.max_tilt_rad",
    );
    // Settings the controller (or the limits) reject.
    let robot = dir.path().join("robot.json");
    for (json, needle) in [
        (r#"{"blend_mm": 1e6}"#, "blend_mm = 1000000 exceeds the limit 2 (limits.max_blend_mm)"),
        (r#"{"limits": {"max_linear_acc_m_s2": 50}}"#, "at most 20 m/s²"),
        (r#"{"approach": {"max_angle_rad": 0}}"#, "approach.max_angle_rad"),
        (r#"{"limits": {"max_tilt_deg": 5}}"#, "max_tilt_deg"),
    ] {
        std::fs::write(&robot, json).unwrap();
        fails(&maobi(&["robot", "check", s(&upright), "--paper", s(&paper()), "--robot", s(&robot)]), needle);
    }
    fails(
        &maobi(&["robot", "send", s(&upright), "--paper", s(&paper()), "--host", "127.0.0.1", "--timeout-ms", "0"]),
        "--timeout-ms",
    );
}

#[test]
fn ctrl_c_during_send_lifts_the_brush_and_exits_non_zero() {
    let dir = tempfile::tempdir().unwrap();
    let track = write(dir.path(), "yong", &[]);
    let port = free_port();
    let trace = dir.path().join("trace.json");
    // Every answer delayed 40 ms: the path buffer needs few calls, so the run lasts past the
    // Ctrl-C below.
    let sim = Sim::start(port, &["--fault", "delay-ms=40", "--trace", s(&trace)]);
    let send = Command::new(env!("CARGO_BIN_EXE_maobi"))
        .args(["robot", "send", s(&track), "--paper", s(&paper()), "--host", "127.0.0.1", "--port", &port.to_string()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Ctrl-C once the first stroke's path buffer has run (the run is then under way, whatever
    // the machine's load; a fixed wait could fall before the handler is installed), at most 60 s.
    let begun = Instant::now();
    while !std::fs::read_to_string(&trace).is_ok_and(|t| t.contains("path_buffer")) {
        assert!(begun.elapsed() < Duration::from_secs(60), "send wrote no path buffer in 60 s");
        std::thread::sleep(Duration::from_millis(20));
    }
    let sent = Command::new("kill").args(["-INT", &send.id().to_string()]).status().unwrap();
    assert!(sent.success());
    let start = Instant::now();
    let mut send = send;
    let status = loop {
        if let Some(st) = send.try_wait().unwrap() {
            break st;
        }
        if start.elapsed() > Duration::from_secs(60) {
            let _ = send.kill();
            panic!("send did not stop after Ctrl-C");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let out = send.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("interrupted (Ctrl-C); stopped after"), "{stderr}");
    assert!(stderr.contains("safe height"), "{stderr}");
    assert!(!String::from_utf8_lossy(&out.stdout).contains("strokes completed"));
    // The last executed pose is 20 mm above the sheet (the fixture's paper lies at z = 0.05 m,
    // facing up).
    std::thread::sleep(Duration::from_millis(400));
    drop(sim);
    // The trace is a JSON array, or one JSON record per line.
    let text = std::fs::read_to_string(&trace).unwrap();
    let last = match serde_json::from_str::<serde_json::Value>(&text) {
        Ok(serde_json::Value::Array(a)) => a.last().cloned().unwrap(),
        _ => serde_json::from_str(text.lines().rev().find(|l| !l.trim().is_empty()).unwrap()).unwrap(),
    };
    let z = last["pose"][2].as_f64().unwrap();
    assert!((z - 0.07).abs() < 1e-6, "last executed z = {z}");
}

#[test]
fn a_hostile_char_field_stays_inside_the_exported_comment() {
    // Issue 26: a track's `char` was pasted as-is into the first comment of every export.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("shi");
    ok(&maobi(&["write", "十", "--size", "96", "--out", s(&out)]));
    let mut t: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("track.json")).unwrap()).unwrap();
    t["char"] = serde_json::json!("十\nG1 Z-40 F3000\r\n\r\nos.exit() --[[\u{2028}# (x);");
    let track = dir.path().join("hostile.json");
    std::fs::write(&track, t.to_string()).unwrap();
    for fmt in ["gcode", "aubo-lua", "urscript"] {
        let prog = dir.path().join(format!("p.{fmt}"));
        let nominal = "--accept-nominal-kinematics";
        ok(&maobi(&["robot", "export", s(&track), "--paper", s(&paper()), "--format", fmt, "-o", s(&prog), nominal]));
        let text = std::fs::read_to_string(&prog).unwrap();
        assert!(!text.contains(['\r', '\u{2028}']), "{fmt}");
        let first = text.lines().next().unwrap();
        assert!(first.contains("十\\u{a}G1 Z-40 F3000\\u{d}\\u{a}\\u{d}\\u{a}os.exit"), "{fmt}: {first}");
        for l in text.lines().skip(1) {
            assert!(!l.trim_start().starts_with("G1 Z-40") && !l.contains("os.exit"), "{fmt}: {l}");
        }
    }
}
