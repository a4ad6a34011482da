//! A whole sheet: layout on real paper, one sheet-level track.json that `robot check` and
//! `robot send` take, ink dips on the simulator through a dropped link, and --out/--force.

use crate::common::{Sim, fails, free_port, maobi, ok, s};
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/robot").join(name)
}

fn json(p: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

#[test]
fn a4_sheet_is_one_program_with_ink_dips_through_a_dropped_link() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sheet");
    // pen1 as given: the ink pot test below knows pen1's tool geometry (the default for a sheet,
    // --brush auto, is tested in newcomer.rs); without registration marks (observe.rs has
    // them), so the dips counted below are the characters' own.
    ok(&maobi(&[
        "write",
        "永字八法",
        "--sheet",
        "A4",
        "--size",
        "96",
        "--grid",
        "mi",
        "--brush",
        "pen1",
        "--no-marks",
        "--out",
        s(&out),
    ]));
    for f in ["sheet.png", "summary.json", "track.json", "preview.html", "01-永/render.png", "04-法/report.json"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    let t = json(&out.join("track.json"));
    assert_eq!(t["kind"], "sheet");
    assert_eq!(t["sheet_mm"], serde_json::json!([210.0, 297.0]));
    let chars = t["chars"].as_array().unwrap();
    assert_eq!(chars.len(), 4);
    let strokes = t["strokes"].as_array().unwrap();
    assert_eq!(t["stroke_chars"].as_array().unwrap().len(), strokes.len());
    assert_eq!(chars[3]["strokes"][1].as_u64().unwrap() as usize, strokes.len());
    // Every point inside the 15 mm margins of the A4 sheet; the first column on the right.
    for st in strokes {
        for p in st.as_array().unwrap() {
            let (x, y) = (p["x_mm"].as_f64().unwrap(), p["y_mm"].as_f64().unwrap());
            assert!((15.0..=195.0).contains(&x) && (15.0..=282.0).contains(&y), "({x}, {y})");
        }
    }
    assert!(chars[0]["char_box_mm"][0].as_f64() > chars[2]["char_box_mm"][0].as_f64());
    let summary = json(&out.join("summary.json"));
    assert!(summary["brush_fit"]["note"].as_str().unwrap().contains("mm"));
    // robot check takes the sheet as it takes one character, dips included.
    let track = out.join("track.json");
    let (paper, robot) = (fixture("paper.json"), fixture("robot-ink.json"));
    let check: serde_json::Value = serde_json::from_str(&ok(&maobi(&[
        "robot",
        "check",
        s(&track),
        "--paper",
        s(&paper),
        "--robot",
        s(&robot),
        "--json",
    ])))
    .unwrap();
    assert_eq!(check["strokes"].as_u64().unwrap() as usize, strokes.len());
    let dips = check["dips"].as_u64().unwrap();
    assert!(dips >= 2, "{check}");
    // Reloading before each character uses the sheet's stroke_chars: one dip per character,
    // and G-code carries them too.
    let mut cfg = json(&robot);
    cfg["ink"]["reload"] = serde_json::json!("before_each_char");
    let per_char = dir.path().join("robot-per-char.json");
    std::fs::write(&per_char, cfg.to_string()).unwrap();
    let c: serde_json::Value = serde_json::from_str(&ok(&maobi(&[
        "robot",
        "check",
        s(&track),
        "--paper",
        s(&paper),
        "--robot",
        s(&per_char),
        "--json",
    ])))
    .unwrap();
    assert_eq!(c["dips"].as_u64().unwrap(), 4, "{c}");
    // Sent to the simulator, which drops the link once: the whole sheet, resumed at a stroke.
    let port = free_port();
    let trace = dir.path().join("trace.jsonl");
    let sim = Sim::start(port, &["--fault", "drop-after=50", "--trace", s(&trace)]);
    let sent = ok(&maobi(&[
        "robot",
        "send",
        s(&track),
        "--paper",
        s(&paper),
        "--robot",
        s(&robot),
        "--host",
        "127.0.0.1",
        "--port",
        &port.to_string(),
        "--timeout-ms",
        "2000",
    ]));
    std::thread::sleep(std::time::Duration::from_millis(300));
    drop(sim);
    let n = strokes.len();
    assert!(sent.contains(&format!("{n} of {n} strokes completed; 1 reconnect(s), 1 stroke(s) resumed")), "{sent}");
    // The trace goes to the ink pot (beside the sheet, base x 0.63 m, below the paper plane) once
    // per dip.
    let mut visits = 0;
    let mut in_pot = false;
    for line in std::fs::read_to_string(&trace).unwrap().lines() {
        let e: serde_json::Value = serde_json::from_str(line).unwrap();
        let p = &e["pose"];
        let now = p[0].as_f64().unwrap() > 0.62 && p[2].as_f64().unwrap() < 0.05;
        visits += usize::from(now && !in_pot);
        in_pot = now;
    }
    assert_eq!(visits as u64, dips);
}

#[test]
fn out_is_never_mixed_force_replaces_and_sizes_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("w");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("old.txt"), "old run").unwrap();
    fails(&maobi(&["write", "十口", "--size", "64", "--out", s(&out)]), "--force");
    assert!(out.join("old.txt").is_file());
    // --force replaces only what maobi wrote: a file it did not write is kept, and named.
    fails(&maobi(&["write", "十口", "--size", "64", "--out", s(&out), "--force"]), "maobi did not write (old.txt)");
    assert_eq!(std::fs::read_to_string(out.join("old.txt")).unwrap(), "old run");
    std::fs::remove_file(out.join("old.txt")).unwrap();
    ok(&maobi(&["write", "十口", "--size", "64", "--out", s(&out)]));
    let manifest = std::fs::read_to_string(out.join(".maobi-written")).unwrap();
    assert!(
        manifest.lines().any(|l| l == "02-口/render.png") && manifest.lines().any(|l| l == "sheet.png"),
        "{manifest}"
    );
    ok(&maobi(&["write", "十口", "--size", "64", "--sheet", "A5", "--out", s(&out), "--force"]));
    assert!(out.join("track.json").is_file() && out.join("02-口/render.png").is_file());
    // A file added to maobi's folder (a model trained into it, notes) stops --force.
    std::fs::create_dir_all(out.join("gen")).unwrap();
    std::fs::write(out.join("gen/pen1.safetensors"), "weights").unwrap();
    fails(&maobi(&["write", "十口", "--size", "64", "--out", s(&out), "--force"]), "gen/pen1.safetensors");
    assert!(out.join("gen/pen1.safetensors").is_file());
    std::fs::remove_dir_all(out.join("gen")).unwrap();
    // A single-file output is refused as well unless --force.
    let html = dir.path().join("p.html");
    std::fs::write(&html, "mine").unwrap();
    fails(&maobi(&["preview", s(&out.join("track.json")), "-o", s(&html)]), "already exists; give --force");
    assert_eq!(std::fs::read_to_string(&html).unwrap(), "mine");
    ok(&maobi(&["preview", s(&out.join("track.json")), "-o", s(&html), "--force"]));
    std::fs::remove_file(&html).unwrap();
    // Nothing staged is left beside it.
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(left.len(), 1, "{left:?}");
    // An empty folder is fine; a file is not replaced.
    let empty = dir.path().join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    ok(&maobi(&["write", "十", "--size", "64", "--out", s(&empty)]));
    assert!(empty.join("track.json").is_file() && empty.join("preview.html").is_file());
    let file = dir.path().join("file");
    std::fs::write(&file, "x").unwrap();
    fails(&maobi(&["write", "十", "--size", "64", "--out", s(&file), "--force"]), "not a folder");
    // Sizes: an asked character size that does not fit; a bad sheet; margins that leave nothing.
    let o = dir.path().join("x");
    fails(&maobi(&["write", "永字八法", "--sheet", "A4", "--char-mm", "130", "--out", s(&o)]), "--char-mm 130");
    fails(&maobi(&["write", "十", "--sheet", "A9", "--out", s(&o)]), "--sheet A9");
    fails(&maobi(&["write", "十", "--sheet", "A4", "--margin-mm", "120", "--out", s(&o)]), "--margin-mm 120");
    assert!(!o.exists());
    // A couplet strip: one column.
    let c = dir.path().join("couplet");
    ok(&maobi(&["write", "十口十", "--sheet", "90x300", "--size", "64", "--out", s(&c)]));
    let t = json(&c.join("track.json"));
    let xs: Vec<f64> = t["chars"].as_array().unwrap().iter().map(|c| c["char_box_mm"][0].as_f64().unwrap()).collect();
    assert!(xs.iter().all(|x| (x - xs[0]).abs() < 1e-9), "{xs:?}");
}
