//! `maobi write --refine` and `maobi evaluate --refine` end to end.

use crate::common::{fails, maobi, ok, ok_json, s};

use brush_model::Track;

fn json(p: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

#[test]
fn write_refine_reports_before_and_after_and_plots_the_loss() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("yong");
    ok(&maobi(&["write", "永", "--size", "128", "--refine", "--iters", "4", "--out", s(&out)]));
    assert!(out.join("refine.png").is_file());
    let r = json(&out.join("report.json"));
    let rf = &r["refine"];
    assert_eq!(rf["options"]["iterations"], 4);
    assert_eq!(rf["curve"].as_array().unwrap().len(), 5, "{rf}");
    assert!(rf["rejected"].is_null(), "{rf}");
    for k in ["executed_before", "executed_after", "planned_before", "planned_after"] {
        assert!(rf[k]["csim"].as_f64().unwrap() > 0.7, "{k}: {rf}");
    }
    // The headline figures are the refined track's.
    assert_eq!(r["executed"], rf["executed_after"]);
    // The refined track is what track.json holds: pressed inside the range or gliding lighter.
    let t = json(&out.join("track.json"));
    let track: Track = serde_json::from_value(serde_json::json!({"strokes": t["strokes"]})).unwrap();
    assert_eq!(track.strokes.len(), 5);
    let pen1 = brush_model::BrushProfile::builtin("pen1").unwrap();
    for p in track.points() {
        assert!(
            pen1.ranges.h_mm.contains(p.h_mm) || (0.0..=trajectory::glide_h_mm(&pen1)).contains(&p.h_mm),
            "h {}",
            p.h_mm
        );
    }
}

#[test]
fn write_without_refine_has_no_refine_report() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ren");
    ok(&maobi(&["write", "人", "--size", "96", "--out", s(&out)]));
    assert!(!out.join("refine.png").exists());
    assert!(json(&out.join("report.json")).get("refine").is_none());
}

#[test]
fn refine_flags_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x");
    fails(&maobi(&["write", "人", "--refine", "--iters", "0", "--out", s(&out)]), "--iters 0: expected 1..=10000");
    // clap refuses --iters without --refine (its usage message names the missing flag).
    let o = maobi(&["write", "人", "--iters", "3", "--out", s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--refine"));
}

#[test]
fn evaluate_refine_adds_means_before_and_after() {
    let v = ok_json(&maobi(&["evaluate", "--chars", "十人", "--size", "96", "--refine", "--iters", "3", "--json"]));
    let r = &v["summary"]["refine"];
    assert_eq!(r["count"], 2, "{v}");
    assert_eq!(r["rejected"], 0, "{v}");
    assert!(r["executed_after"]["csim"].as_f64().unwrap() > 0.7, "{v}");
    assert!(r["executed_before"]["csim"].as_f64().unwrap() > 0.7, "{v}");
}

#[test]
fn refine_through_the_generator_is_judged_by_the_analytic_render() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ten");
    ok(&maobi(&["write", "十", "--size", "96", "--refine", "--iters", "1", "--gradients", "generator", "-o", s(&out)]));
    let r = json(&out.join("report.json"));
    let rf = &r["refine"];
    assert_eq!(rf["options"]["gradients"], "generator");
    assert_eq!(rf["curve"].as_array().unwrap().len(), 2, "{rf}");
    // The model that drew the scored images is the analytic one, not the generator.
    assert_eq!(r["model"], "bsm");
    assert!(rf["executed_after"]["csim"].as_f64().unwrap() > 0.7, "{rf}");
    fails(&maobi(&["write", "十", "--gradients", "generator", "-o", s(&out)]), "--refine");
    fails(&maobi(&["write", "十", "--refine", "--gradients", "soft", "-o", s(&out)]), "soft");
}
