//! `maobi robot` end to end: check, refusals, exports, and a run against the simulator process.

use crate::common::{Sim, fails, free_port, maobi, ok, s};
use std::path::{Path, PathBuf};

fn paper() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/robot/paper.json")
}

fn written(dir: &Path) -> PathBuf {
    let out = dir.join("shi");
    ok(&maobi(&["write", "十", "--size", "96", "--out", s(&out)]));
    out.join("track.json")
}

#[test]
fn check_and_export_a_written_character() {
    let dir = tempfile::tempdir().unwrap();
    let track = written(dir.path());
    let j: serde_json::Value =
        serde_json::from_str(&ok(&maobi(&["robot", "check", s(&track), "--paper", s(&paper()), "--json"]))).unwrap();
    assert_eq!(j["strokes"], 2);
    assert!(j["max_press_mm"].as_f64().unwrap() <= 20.0);
    // Timed strokes: each with its duration and peaks within the default limits.
    let timing = &j["timing"];
    let strokes = timing["strokes"].as_array().unwrap();
    assert_eq!(strokes.len(), 2, "{timing}");
    let mut total = 0.0;
    for t in strokes {
        total += t["duration_s"].as_f64().unwrap();
        assert!(t["duration_s"].as_f64().unwrap() > 0.5, "{t}");
        assert!(t["peak_speed_m_s"].as_f64().unwrap() <= 0.02 + 1e-9, "{t}");
        assert!(t["peak_joint_acc_rad_s2"].as_f64().unwrap() <= 3.0, "{t}");
        let qd: Vec<f64> = serde_json::from_value(t["peak_joint_speed_rad_s"].clone()).unwrap();
        assert!(qd.len() == 6 && qd.iter().all(|v| *v <= 1.5), "{t}");
    }
    assert!((timing["writing_s"].as_f64().unwrap() - total).abs() < 1e-9, "{timing}");
    let text = ok(&maobi(&["robot", "check", s(&track), "--paper", s(&paper())]));
    assert!(text.contains("stroke 2: ") && text.contains("writing time "), "{text}");
    // A jerk limit so low the strokes would take hours: refused, naming the stroke.
    let tight = dir.path().join("tight.json");
    std::fs::write(&tight, r#"{"timing": {"joint_jerk_rad_s3": 0.01}, "limits": {"max_joint_jerk_rad_s3": 0.01}}"#)
        .unwrap();
    fails(
        &maobi(&["robot", "check", s(&track), "--paper", s(&paper()), "--robot", s(&tight)]),
        "refused at stroke 1: the timed stroke would take",
    );
    for (fmt, needle) in [("aubo-lua", "return function(api)"), ("urscript", "movel(p["), ("gcode", "G1 X")] {
        let out = dir.path().join(format!("prog.{fmt}"));
        let nominal = "--accept-nominal-kinematics";
        let o = maobi(&["robot", "export", s(&track), "--paper", s(&paper()), "--format", fmt, "-o", s(&out), nominal]);
        let said = ok(&o);
        assert!(said.contains(&format!("{fmt} program of")) && said.contains(&out.display().to_string()), "{said}");
        assert!(std::fs::read_to_string(&out).unwrap().contains(needle), "{fmt}");
        if fmt == "gcode" {
            assert!(String::from_utf8_lossy(&o.stderr).contains("β is ignored"));
        }
    }
}

#[test]
fn refusals_name_the_problem_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let track = written(dir.path());
    // A sheet too small for the character.
    let small = dir.path().join("small.json");
    std::fs::write(
        &small,
        std::fs::read_to_string(paper()).unwrap().replace("\"size_mm\": [300, 300]", "\"size_mm\": [20, 20]"),
    )
    .unwrap();
    let out = dir.path().join("p.lua");
    fails(
        &maobi(&["robot", "export", s(&track), "--paper", s(&small), "--format", "aubo-lua", "-o", s(&out)]),
        "outside the paper",
    );
    assert!(!out.exists());
    // A press deeper than the brush's range.
    let mut t: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&track).unwrap()).unwrap();
    t["strokes"][0][3]["h_mm"] = serde_json::json!(26.0);
    let deep = dir.path().join("deep.json");
    std::fs::write(&deep, t.to_string()).unwrap();
    fails(
        &maobi(&["robot", "check", s(&deep), "--paper", s(&paper())]),
        "stroke 1, point 4: press h = 26.000 mm is deeper",
    );
    // Robot config over the limits, collinear paper points, malformed files.
    let fast = dir.path().join("robot.json");
    std::fs::write(&fast, r#"{"travel_speed_m_s": 1.0}"#).unwrap();
    fails(
        &maobi(&["robot", "check", s(&track), "--paper", s(&paper()), "--robot", s(&fast)]),
        "travel_speed_m_s = 1 exceeds the limit",
    );
    let line = dir.path().join("line.json");
    std::fs::write(&line, r#"{"touch_points": [{"paper_mm": [0, 0], "robot_m": [0.3, 0.2, 0.05]}, {"paper_mm": [100, 0], "robot_m": [0.4, 0.2, 0.05]}, {"paper_mm": [200, 0], "robot_m": [0.5, 0.2, 0.05]}]}"#).unwrap();
    fails(&maobi(&["robot", "check", s(&track), "--paper", s(&line)]), "collinear");
    std::fs::write(&line, r#"{"touch_points": [}"#).unwrap();
    fails(&maobi(&["robot", "check", s(&track), "--paper", s(&line)]), "line.json");
    fails(&maobi(&["robot", "sim", "--fault", "explode=1"]), "unknown fault");
}

#[test]
fn send_runs_on_the_simulator_and_survives_a_drop() {
    // Through the path buffer (the default): the link dropped at the fourth motion request, the
    // first stroke's movePathBuffer (after the start move, the travel and the descent), with
    // the brush on the paper.
    let dir = tempfile::tempdir().unwrap();
    let track = written(dir.path());
    let port = free_port();
    let trace = dir.path().join("trace.json");
    let sim = Sim::start(port, &["--fault", "drop-after=4", "--trace", s(&trace)]);
    let o = maobi(&[
        "robot",
        "send",
        s(&track),
        "--paper",
        s(&paper()),
        "--host",
        "127.0.0.1",
        "--port",
        &port.to_string(),
        "--timeout-ms",
        "1000",
    ]);
    let out = ok(&o);
    assert!(out.contains("2 of 2 strokes completed; 1 reconnect(s), 1 stroke(s) resumed"), "{out}");
    assert!(out.contains("2 path buffer(s)"), "{out}");
    std::thread::sleep(std::time::Duration::from_millis(300));
    drop(sim);
    // The executed path renders back to the planned image: the same forward model sees the same
    // motion (the stroke cut by the drop is written again over itself).
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
        "96",
        "-o",
        s(&img),
    ]));
    let render = track.parent().unwrap().join("render.png");
    let j: serde_json::Value = serde_json::from_str(&ok(&maobi(&["compare", s(&render), s(&img), "--json"]))).unwrap();
    assert!(j["csim"].as_f64().unwrap() > 0.97, "{j}");
    // The Lua script goes to the script port framed by \r\n\r\n.
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let reader = std::thread::spawn(move || {
        use std::io::Read;
        let (mut c, _) = listener.accept().unwrap();
        let mut buf = String::new();
        c.read_to_string(&mut buf).unwrap();
        buf
    });
    let nominal = "--accept-nominal-kinematics";
    ok(&maobi(&[
        "robot",
        "export",
        s(&track),
        "--paper",
        s(&paper()),
        "--format",
        "aubo-lua",
        "--send-script",
        &addr,
        nominal,
    ]));
    let got = reader.join().unwrap();
    assert!(got.starts_with("-- maobi") && got.ends_with("end\n\r\n\r\n"), "{}", &got[got.len() - 20..]);
    // A file that is not a trace is refused, naming it.
    let bad = dir.path().join("bad-trace.json");
    std::fs::write(&bad, "{}").unwrap();
    fails(
        &maobi(&[
            "robot",
            "render-trace",
            s(&bad),
            "--track",
            s(&track),
            "--paper",
            s(&paper()),
            "-o",
            s(&dir.path().join("t.png")),
        ]),
        "bad-trace.json:1: not a simulator trace",
    );
    // Dry run connects to nothing.
    ok(&maobi(&["robot", "send", s(&track), "--paper", s(&paper()), "--host", "192.0.2.1", "--dry-run"]));
}

#[test]
fn export_and_render_trace_replace_a_file_only_with_force() {
    let dir = tempfile::tempdir().unwrap();
    let track = written(dir.path());
    let pp = paper();
    let out = dir.path().join("p.script");
    std::fs::write(&out, "mine").unwrap();
    let export = |force: bool| {
        let mut a = vec!["robot", "export", s(&track), "--paper", s(&pp), "--format", "urscript", "-o", s(&out)];
        if force {
            a.push("--force");
        }
        maobi(&a)
    };
    fails(&export(false), "already exists; give --force");
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "mine");
    ok(&export(true));
    assert!(std::fs::read_to_string(&out).unwrap().contains("movep(p["));
    // render-trace refuses before reading anything; with --force it goes on (to the trace,
    // which is not one here).
    let png = dir.path().join("t.png");
    std::fs::write(&png, "mine").unwrap();
    let trace = dir.path().join("trace.jsonl");
    std::fs::write(&trace, "{}\n").unwrap();
    let render = |force: bool| {
        let mut a = vec!["robot", "render-trace", s(&trace), "--track", s(&track), "--paper", s(&pp), "-o", s(&png)];
        if force {
            a.push("--force");
        }
        maobi(&a)
    };
    fails(&render(false), "already exists; give --force");
    fails(&render(true), "not a simulator trace");
    assert_eq!(std::fs::read_to_string(&png).unwrap(), "mine");
}

#[test]
fn lua_path_buffers_use_the_kinematics_read_from_the_controller() {
    let dir = tempfile::tempdir().unwrap();
    let track = written(dir.path());
    let pp = paper();
    let lua = dir.path().join("p.lua");
    let export = |extra: &[&str]| {
        let mut a = vec!["robot", "export", s(&track), "--paper", s(&pp), "--format", "aubo-lua", "-o", s(&lua)];
        a.extend_from_slice(extra);
        a.push("--force");
        maobi(&a)
    };
    // Nominal parameters never silently: refused without a file or the flag.
    fails(&export(&[]), "--kinematics ARM.json");
    assert!(!lua.exists());
    // The simulator's parameters, read as a controller's.
    let port = free_port();
    let sim = Sim::start(port, &[]);
    let arm = dir.path().join("arm.json");
    let port = port.to_string();
    let read = || maobi(&["robot", "kinematics", "--host", "127.0.0.1", "--port", &port, "-o", s(&arm)]);
    let said = ok(&read());
    drop(sim);
    assert!(said.contains("getKinematicsParam(true)") && said.contains(s(&arm)), "{said}");
    let j: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&arm).unwrap()).unwrap();
    assert_eq!(j["real"], true);
    assert_eq!(j["kinematics"]["a_m"][2].as_f64(), Some(0.408), "{j}");
    fails(&read(), "already exists; give --force");
    let said = ok(&export(&["--kinematics", s(&arm)]));
    assert!(said.contains("2 path buffers"), "{said}");
    let text = std::fs::read_to_string(&lua).unwrap();
    assert!(
        text.contains("getKinematicsParam(true)") && text.contains("local want = {a = {0.000000, 0.000000, 0.408000")
    );
    assert_eq!(text.matches("    movePathBuffer(name)").count(), 2);
    // The flag gives the same program, with a warning.
    let o = export(&["--accept-nominal-kinematics"]);
    ok(&o);
    assert!(String::from_utf8_lossy(&o.stderr).contains("nominal AUBO-i5"));
    assert_eq!(std::fs::read_to_string(&lua).unwrap(), text);
    // A move per point of the compacted track instead: no joints, no kinematics needed.
    let said = ok(&export(&["--motion", "moves"]));
    let moves = std::fs::read_to_string(&lua).unwrap();
    assert!(!moves.contains("pathBuffer") && moves.contains("\n  moveLine("), "{said}");
    let points: usize =
        serde_json::from_str::<serde_json::Value>(&std::fs::read_to_string(&track).unwrap()).unwrap()["strokes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|st| st.as_array().unwrap().len())
            .sum();
    assert!(moves.matches("  moveLine(").count() < points, "{said}");
    fails(
        &maobi(&[
            "robot",
            "export",
            s(&track),
            "--paper",
            s(&paper()),
            "--format",
            "gcode",
            "-o",
            s(&lua),
            "--motion",
            "moves",
            "--force",
        ]),
        "--motion moves applies to --format aubo-lua",
    );
    // A file of nominal (not real) parameters, or one out of range, is refused, naming it.
    let mut bad = j.clone();
    bad["real"] = serde_json::json!(false);
    std::fs::write(&arm, bad.to_string()).unwrap();
    fails(&export(&["--kinematics", s(&arm)]), "`real` is false");
    bad["real"] = serde_json::json!(true);
    bad["kinematics"]["d_m"][1] = serde_json::json!(1e9);
    std::fs::write(&arm, bad.to_string()).unwrap();
    fails(&export(&["--kinematics", s(&arm)]), "arm.json: kinematics: d[1]");
}

/// `永` at the defaults (3,308 points): the G-code's merged moves, read by `gcodeparser` (PyPI;
/// skipped, saying so, where python3 cannot import it), are at least 5× fewer than one move per
/// point, and every feed rate is positive and at most the write speed (20 mm/s: 1200 mm/min).
#[test]
fn yong_gcode_is_merged_five_times_shorter_with_feeds_from_the_timing() {
    let have = std::process::Command::new("python3")
        .args(["-c", "import gcodeparser"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !have {
        eprintln!("SKIPPED yong_gcode_is_merged_five_times_shorter_with_feeds_from_the_timing: no gcodeparser");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("yong");
    ok(&maobi(&["write", "永", "--out", s(&out)]));
    let track = out.join("track.json");
    let t: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&track).unwrap()).unwrap();
    let points: usize = t["strokes"].as_array().unwrap().iter().map(|st| st.as_array().unwrap().len()).sum();
    let g = dir.path().join("yong.gcode");
    ok(&maobi(&["robot", "export", s(&track), "--paper", s(&paper()), "--format", "gcode", "-o", s(&g)]));
    let script = "import json, sys\nfrom gcodeparser import parse_gcode_lines\n\
                  print(json.dumps([[l.command_str, l.params] for l in parse_gcode_lines(open(sys.argv[1]).read())]))";
    let o = std::process::Command::new("python3").args(["-c", script, s(&g)]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let commands: Vec<(String, serde_json::Value)> = serde_json::from_slice(&o.stdout).unwrap();
    let g1: Vec<&serde_json::Value> = commands.iter().filter(|(c, _)| c == "G1").map(|(_, p)| p).collect();
    assert!(points >= 3000 && g1.len() * 5 <= points, "{} G1 moves for {points} points", g1.len());
    let feeds: Vec<f64> = g1.iter().map(|p| p["F"].as_f64().unwrap()).collect();
    assert!(feeds.iter().all(|f| *f > 0.0 && *f <= 1200.0 * (1.0 + 1e-9)), "{feeds:?}");
    // From the timing: most moves slower than the write speed (turns, depth changes, ends).
    assert!(feeds.iter().filter(|f| **f < 1000.0).count() * 2 > feeds.len(), "{feeds:?}");
}
