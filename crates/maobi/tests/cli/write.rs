//! `maobi write` end to end: outputs, sources, methods, and bad input.

use crate::common::{fails, maobi, ok, s};
use std::path::{Path, PathBuf};

use brush_model::Track;

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures")
}

fn json(p: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

#[test]
fn one_character_gets_all_five_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("yong");
    ok(&maobi(&["write", "永", "--size", "128", "--out", s(&out)]));
    for f in
        ["render.png", "reference.png", "overlay.png", "executed.png", "side-by-side.png", "track.json", "report.json"]
    {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let img = image::open(out.join("render.png")).unwrap();
    assert_eq!((img.width(), img.height()), (128, 128));
    // The pictures explain themselves: labels above the three panels, a legend below the overlay.
    let row = image::open(out.join("side-by-side.png")).unwrap().to_rgb8();
    assert_eq!(row.width(), 3 * 128 + 2 * 4);
    let strip = row.height() - 128;
    assert!(strip >= 9, "a label strip above the panels: {}", row.height());
    for panel in 0..3 {
        let x0 = panel * (128 + 4);
        let dark =
            (x0..x0 + 128).flat_map(|x| (0..strip).map(move |y| (x, y))).filter(|&(x, y)| row.get_pixel(x, y)[0] < 128);
        assert!(dark.count() > 10, "panel {panel} has a label");
    }
    let ovl = image::open(out.join("overlay.png")).unwrap().to_rgb8();
    assert_eq!(ovl.width(), 128);
    assert!(ovl.height() > 128 + 20, "a legend below the overlay");
    let below = |f: &dyn Fn(&image::Rgb<u8>) -> bool| {
        (128..ovl.height()).flat_map(|y| (0..128).map(move |x| (x, y))).filter(|&(x, y)| f(ovl.get_pixel(x, y))).count()
    };
    assert!(below(&|p| p[0] > 150 && p[1] < 80 && p[2] < 80) > 5, "red legend text");
    assert!(below(&|p| p[2] > 150 && p[0] < 80 && p[1] < 80) > 5, "blue legend text");
    let r = json(&out.join("report.json"));
    assert_eq!(r["char"], "永");
    assert_eq!(r["source"], "embedded");
    assert_eq!(r["method"], "medians");
    assert_eq!(r["plan"]["strokes_expected"], 5);
    assert_eq!(r["plan"]["strokes_found"], 5);
    for k in ["csim", "ssim", "iou", "chamfer_pct"] {
        assert!(r["plan"][k].as_f64().unwrap() > 0.0, "{k}");
    }
    assert!(r["timing_ms"]["plan"].as_f64().unwrap() > 0.0, "{r}");
    assert!(r["plan"]["csim"].as_f64().unwrap() > 0.7, "{r}");
    // What the robot would write: the program executed as the simulator moves, through the same
    // forward model. It scores like the plan, and the two images agree.
    assert!(r["executed"]["csim"].as_f64().unwrap() > 0.7, "{r}");
    assert!(r["agreement"]["csim"].as_f64().unwrap() > 0.97, "{r}");
    assert!((r["executed"]["csim"].as_f64().unwrap() - r["plan"]["csim"].as_f64().unwrap()).abs() < 0.02, "{r}");
    // The plan with footprints sized freely from the glyph is a diagnostic, off unless asked.
    assert!(r["plan"]["free_widths"].is_null(), "{r}");
    assert!(r.get("upper_bound").is_none(), "{r}");
    // The track parses back into brush-model's Track and sits inside the char box.
    let t = json(&out.join("track.json"));
    let b: Vec<f64> = t["char_box_mm"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    let track: Track = serde_json::from_value(serde_json::json!({"strokes": t["strokes"]})).unwrap();
    assert_eq!(track.strokes.len(), 5);
    assert_eq!(track.point_count() as u64, r["plan"]["points"].as_u64().unwrap());
    let pen1 = brush_model::BrushProfile::builtin("pen1").unwrap();
    for p in track.points() {
        assert!(
            p.x_mm >= b[0] - 1.0 && p.x_mm <= b[0] + b[2] + 1.0 && p.y_mm >= b[1] - 1.0 && p.y_mm <= b[1] + b[2] + 1.0
        );
        // Pressed within the calibrated range, or gliding lighter (turning over, between pieces:
        // at most the glide's depth, past the hairs' contact depth).
        assert!(
            pen1.ranges.h_mm.contains(p.h_mm) || (0.0..=trajectory::glide_h_mm(&pen1)).contains(&p.h_mm),
            "h {}",
            p.h_mm
        );
    }
    assert_eq!(t["brush"]["name"], "pen1");
    // The report is grouped, and says which brush.
    assert_eq!(r["brush"]["name"], "pen1");
    for k in ["clamped_low_points", "clamped_high_points"] {
        assert!(r["brush"][k].is_u64(), "{k}: {r}");
    }
    assert!(r.get("csim").is_none() && r.get("millis").is_none(), "no ungrouped figures: {r}");
    every_field_is_documented(&r, "report.json");
}

/// Every field (as a dotted path, array items as `[]`) of a JSON output appears in
/// docs/outputs.md, written as `` `path` ``.
fn every_field_is_documented(v: &serde_json::Value, file: &str) {
    fn paths(v: &serde_json::Value, prefix: &str, out: &mut Vec<String>) {
        match v {
            serde_json::Value::Object(m) => {
                for (k, x) in m {
                    let p = if prefix.is_empty() { k.clone() } else { format!("{prefix}.{k}") };
                    out.push(p.clone());
                    paths(x, &p, out);
                }
            }
            serde_json::Value::Array(a) => {
                if let Some(x) = a.first() {
                    paths(x, &format!("{prefix}[]"), out);
                }
            }
            _ => {}
        }
    }
    let doc = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/outputs.md")).unwrap();
    let mut all = Vec::new();
    paths(v, "", &mut all);
    let missing: Vec<&String> = all.iter().filter(|p| !doc.contains(&format!("`{p}`"))).collect();
    assert!(missing.is_empty(), "{file}: fields not described in docs/outputs.md: {missing:?}");
}

#[test]
fn several_characters_make_a_sheet() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sheet");
    ok(&maobi(&["write", "十口人", "--size", "96", "--out", s(&out)]));
    for sub in ["01-十", "02-口", "03-人"] {
        assert!(out.join(sub).join("track.json").is_file(), "{sub}");
    }
    let sum = json(&out.join("summary.json"));
    assert_eq!(sum["chars"].as_array().unwrap().len(), 3);
    let m = sum["plan_mean"]["csim"].as_f64().unwrap();
    let direct: f64 =
        sum["chars"].as_array().unwrap().iter().map(|c| c["plan"]["csim"].as_f64().unwrap()).sum::<f64>() / 3.0;
    assert!((m - direct).abs() < 1e-12);
    // Each of `chars` is a report.json, documented as such.
    let mut top = sum.clone();
    top.as_object_mut().unwrap().remove("chars");
    every_field_is_documented(&top, "summary.json");
    // The layout the README describes: sheet.png, summary.json, track.json and preview.html at
    // the top, one NN-字 folder per character with its own outputs.
    for f in ["sheet.png", "summary.json", "track.json", "preview.html"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    for f in ["render.png", "reference.png", "executed.png", "overlay.png", "side-by-side.png", "report.json"] {
        assert!(out.join("02-口").join(f).is_file(), "02-口/{f}");
    }
    let readme = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md")).unwrap();
    assert!(readme.contains("NN-") && readme.contains("summary.json") && readme.contains("docs/outputs.md"));
    let sheet = image::open(out.join("sheet.png")).unwrap();
    // Columns right to left: three characters in one column of four.
    assert!(sheet.height() > 3 * 96 && sheet.width() < 2 * 96, "{}×{}", sheet.width(), sheet.height());
    // The first character is at the top of the column: its box starts a gap below the top.
    let t1 = json(&out.join("01-十/track.json"));
    let t3 = json(&out.join("03-人/track.json"));
    assert!(t1["char_box_mm"][1].as_f64().unwrap() < t3["char_box_mm"][1].as_f64().unwrap());
    ok(&maobi(&["write", "十口", "--rows", "--size", "96", "--out", s(&dir.path().join("rows"))]));
    let rows = image::open(dir.path().join("rows/sheet.png")).unwrap();
    assert!(rows.width() > rows.height());
}

#[test]
fn skeleton_font_and_image_sources() {
    let dir = tempfile::tempdir().unwrap();
    let sk = dir.path().join("sk");
    ok(&maobi(&["write", "十", "--from", "skeleton", "--size", "128", "-o", s(&sk)]));
    let r = json(&sk.join("report.json"));
    assert_eq!(r["method"], "skeleton");
    assert_eq!(r["plan"]["strokes_found"], 2);
    assert!(r["plan"]["chamfer_pct"].as_f64().unwrap() < 3.0);
    let font = fixtures().join("fonts/ukai-subset.ttf");
    let f = dir.path().join("font");
    ok(&maobi(&["write", "永", "--font", s(&font), "--from", "skeleton", "--size", "128", "--out", s(&f)]));
    let r = json(&f.join("report.json"));
    assert_eq!((r["source"].as_str(), r["method"].as_str()), (Some("font"), Some("skeleton")));
    assert!(r["plan"]["chamfer_pct"].is_null() && r["plan"]["strokes_expected"].is_null() && r["template"].is_null());
    assert!(r["plan"]["csim"].as_f64().unwrap() > 0.6);
    // A photo of a character: use the reference image written above.
    let img = dir.path().join("img");
    ok(&maobi(&["write", "十", "--image", s(&sk.join("reference.png")), "--size", "128", "--out", s(&img)]));
    let r = json(&img.join("report.json"));
    assert_eq!(r["source"], "image");
    assert_eq!(r["plan"]["strokes_found"], 2);
}

#[test]
fn bad_input_fails_cleanly_without_output() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    fails(&maobi(&["write", "𪚥", "--out", s(&out)]), "not in the embedded hanzi-writer-data");
    fails(&maobi(&["write", "永𪚥", "--out", s(&out)]), "U+2A6A5");
    let junk = dir.path().join("junk.ttf");
    std::fs::write(&junk, b"not a font").unwrap();
    fails(&maobi(&["write", "永", "--font", s(&junk), "--out", s(&out)]), "not a font: expected a TrueType");
    let font = fixtures().join("fonts/ukai-subset.ttf");
    fails(&maobi(&["write", "永", "--font", s(&font), "--from", "medians", "--out", s(&out)]), "no stroke medians");
    fails(&maobi(&["write", "我", "--font", s(&font), "--out", s(&out)]), "ukai-subset.ttf");
    let blank = dir.path().join("blank.png");
    image::GrayImage::from_pixel(64, 64, image::Luma([255])).save(&blank).unwrap();
    fails(&maobi(&["write", "永", "--image", s(&blank), "--out", s(&out)]), "no ink");
    let black = dir.path().join("black.png");
    image::GrayImage::from_pixel(64, 64, image::Luma([0])).save(&black).unwrap();
    fails(&maobi(&["write", "永", "--image", s(&black), "--out", s(&out)]), "no ink");
    fails(&maobi(&["write", "永", "--image", s(&dir.path().join("none.png")), "--out", s(&out)]), "none.png");
    fails(&maobi(&["write", "永", "--char-mm", "-3", "--out", s(&out)]), "--char-mm");
    fails(&maobi(&["write", "永", "--alpha", "30", "--out", s(&out)]), "--alpha");
    fails(&maobi(&["write", "永", "--font", s(&font), "--image", "x.png", "--out", s(&out)]), "cannot be used with");
    // With --font, --hanzi-data is where the stroke templates come from.
    fails(&maobi(&["write", "永", "--font", s(&font), "--hanzi-data", "x", "--out", s(&out)]), "x: cannot read");
    assert!(!out.exists(), "nothing may be written on error");
}

#[test]
fn the_free_width_plan_is_asked_for_and_changes_nothing_else() {
    let dir = tempfile::tempdir().unwrap();
    let (plain, free) = (dir.path().join("plain"), dir.path().join("free"));
    ok(&maobi(&["write", "十", "--size", "96", "--out", s(&plain)]));
    ok(&maobi(&["write", "十", "--size", "96", "--free-widths", "--out", s(&free)]));
    let (mut a, mut b) = (json(&plain.join("report.json")), json(&free.join("report.json")));
    assert!(a["plan"]["free_widths"].is_null(), "{a}");
    // Named for what it is (not a bound).
    assert!(b["plan"]["free_widths"]["csim"].as_f64().unwrap() > 0.5, "{b}");
    assert!(b.get("upper_bound").is_none(), "{b}");
    // Scored beside the plan: everything else is the same run.
    for r in [&mut a, &mut b] {
        r["plan"]["free_widths"] = serde_json::Value::Null;
        r["timing_ms"] = serde_json::Value::Null;
    }
    assert_eq!(a, b);
    for f in ["render.png", "executed.png", "track.json"] {
        assert_eq!(std::fs::read(plain.join(f)).unwrap(), std::fs::read(free.join(f)).unwrap(), "{f}");
    }
}

#[test]
fn evaluate_reports_means_and_refuses_unknown_characters() {
    let j: serde_json::Value =
        serde_json::from_str(&ok(&maobi(&["evaluate", "--chars", "十口", "--size", "128", "--json"]))).unwrap();
    assert_eq!(j["summary"]["count"], 2);
    let mean =
        (j["chars"][0]["plan"]["csim"].as_f64().unwrap() + j["chars"][1]["plan"]["csim"].as_f64().unwrap()) / 2.0;
    assert!((j["summary"]["csim"].as_f64().unwrap() - mean).abs() < 1e-12);
    assert_eq!(j["summary"]["strokes_match_fraction"], 1.0);
    assert!(j["summary"]["free_widths"]["csim"].as_f64().unwrap() > 0.5, "{j}");
    assert!(j["summary"].get("unconstrained").is_none(), "{j}");
    fails(&maobi(&["evaluate", "--chars", "十𪚥"]), "not in the embedded hanzi-writer-data");
    fails(&maobi(&["evaluate", "--chars", "十", "--from", "bones"]), "unknown method");
}

#[test]
fn without_a_terminal_long_loops_print_progress_lines() {
    // stderr is a pipe here; the quiet period is set to 0 so two characters are "long".
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_maobi"))
        .args(["evaluate", "--chars", "十人", "--size", "64"])
        .env("MAOBI_PROGRESS_AFTER_S", "0")
        .output()
        .unwrap();
    assert!(o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("evaluate: 2/2 (100%)"), "{e}");
    assert!(e.contains("ETA"), "{e}");
    // With the default quiet period a short run prints nothing on stderr.
    let o = maobi(&["evaluate", "--chars", "十", "--size", "64"]);
    assert!(o.status.success() && o.stderr.is_empty(), "{}", String::from_utf8_lossy(&o.stderr));
}
