//! `maobi robot send --controller grbl` against the real GRBL 1.1h firmware (grbl-sim built
//! from `third_party/grbl`) over a pseudo-terminal, and every kind of G-code maobi writes
//! (a character, a sheet with its registration marks, a calibration sheet) through GRBL's own
//! parser (`gvalidate`). Skipped, saying so, where there is no C compiler.

#[path = "../../../robot-grbl/tests/firmware/harness.rs"]
mod harness;

use std::time::Duration;

use crate::common::{fails, maobi, ok, s};
use harness::{Inject, Machine, firmware, mpos, validate};

/// Fast axes; the work zero (the paper's top-left corner, the tip touching) at machine
/// (-20, 15, -20).
const SETUP: &[&str] =
    &["$110=6000", "$111=6000", "$112=3000", "$120=800", "$121=800", "$122=800", "G10L2P1X-20Y15Z-20"];

#[test]
fn a_character_is_written_on_the_grbl_firmware_from_the_command_line() {
    let Some(fw) = firmware("a_character_is_written_on_the_grbl_firmware_from_the_command_line") else { return };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("one");
    // A 30 mm box with the brush scaled to it, written fast: the firmware runs in real time.
    ok(&maobi(&["write", "一", "--size", "64", "--char-mm", "30", "--brush", "pen1-s30", "--out", s(&out)]));
    let track = out.join("track.json");
    let robot = dir.path().join("robot.json");
    let fast = r#"{"lift_mm": 5, "write_speed_m_s": 0.05, "write_acc_m_s2": 1.0,
                   "timing": {"write_jerk_m_s3": 30, "max_depth_rate_mm_s": 100}}"#;
    std::fs::write(&robot, fast).unwrap();
    // Neither a device nor an address.
    fails(&maobi(&["robot", "send", s(&track), "--controller", "grbl"]), "--serial DEVICE or --tcp HOST:PORT");
    // The plan, without connecting (and without paper.json: the plotter's paper is its work
    // coordinates).
    let dry = ok(&maobi(&["robot", "send", s(&track), "--controller", "grbl", "--serial", "/dev/null", "--dry-run"]));
    assert!(dry.contains("lines of G-code") && dry.contains("nothing connected"), "{dry}");
    let mut m = Machine::start(fw, SETUP);
    m.relay(Inject::None);
    // Progress from the start (without a terminal: plain lines on stderr).
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_maobi"))
        .args(["robot", "send", s(&track), "--robot", s(&robot), "--controller", "grbl", "--serial", &m.device])
        .env("MAOBI_PROGRESS_AFTER_S", "0")
        .output()
        .unwrap();
    let stdout = ok(&o);
    // The plotter's progress counts the G-code lines acknowledged.
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.lines().any(|l| l.starts_with("send: ") && l.contains(" strokes, line ")), "{stderr}");
    // Shown with --nocapture: the time taken beside the planned time.
    println!("{stdout}");
    assert!(stdout.contains("Grbl 1.1h: checked before moving"), "{stdout}");
    assert!(stdout.contains("1 of 1 strokes completed") && stdout.contains("G-code lines"), "{stdout}");
    assert!(stdout.contains("written in") && stdout.contains("planned"), "{stdout}");
    m.stop_relay();
    let st = m.wait_idle(Duration::from_secs(30));
    // Idle at the travel height, 5 mm above the paper.
    assert!(st.starts_with("<Idle") && (mpos(&st)[2] - (-20.0 + 5.0)).abs() < 1e-3, "{st}");
    let blocks = m.finish();
    // The stroke was written on the paper: blocks below the touching plane (machine Z -20).
    assert!(blocks.iter().any(|b| (b[2] as f64) / 250.0 < -20.5), "{blocks:?}");
}

#[test]
fn every_gcode_maobi_writes_is_accepted_by_grbls_own_parser() {
    let Some(fw) = firmware("every_gcode_maobi_writes_is_accepted_by_grbls_own_parser") else { return };
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n);
    ok(&maobi(&["write", "永", "--size", "64", "--out", s(&d("yong"))]));
    // A sheet with its registration marks (the default), and a calibration sheet.
    ok(&maobi(&["write", "十口", "--size", "64", "--sheet", "A5", "--out", s(&d("sheet"))]));
    ok(&maobi(&["calibrate-sheet", "--brush", "pen1", "--sheet", "A4", "-o", s(&d("cal"))]));
    for (what, track) in [
        ("a character", d("yong/track.json")),
        ("a sheet with marks", d("sheet/track.json")),
        ("a calibration sheet", d("cal/track.json")),
    ] {
        let g = dir.path().join("p.gcode");
        ok(&maobi(&["robot", "export", s(&track), "--format", "gcode", "-o", s(&g), "--force"]));
        let text = std::fs::read_to_string(&g).unwrap();
        assert!(text.lines().filter(|l| l.starts_with("G1 X")).count() > 10, "{what}: {text}");
        if let Err(e) = validate(fw, &text) {
            panic!("{what}: {e}");
        }
    }
}
