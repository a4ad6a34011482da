//! `maobi write` and `maobi evaluate` on other styles: fonts in every container (one or several
//! files, folders), stroke templates registered onto font and image glyphs.

use std::path::{Path, PathBuf};

use crate::common::{fails, maobi, ok, ok_json, s};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures")
}

fn json(p: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

#[test]
fn a_font_glyph_is_written_from_its_registered_template() {
    let dir = tempfile::tempdir().unwrap();
    // A web font split in unicode-range files: the folder is given, the covering file is used.
    let msz = fixtures().join("fonts/msz");
    let out = dir.path().join("msz");
    ok(&maobi(&["write", "永", "--font", s(&msz), "--size", "128", "-o", s(&out)]));
    let r = json(&out.join("report.json"));
    assert_eq!((r["source"].as_str(), r["method"].as_str()), (Some("font"), Some("template")));
    assert_eq!((r["plan"]["strokes_expected"].as_u64(), r["plan"]["strokes_found"].as_u64()), (Some(5), Some(5)));
    let t = &r["template"];
    assert_eq!(t["strokes"], 5);
    assert_eq!(t["fits"].as_array().unwrap().len(), 5);
    assert!((0.0..0.5).contains(&t["uncovered_ink"].as_f64().unwrap()), "{t}");
    assert_eq!(t["strokes_ok"].as_bool(), Some(t["missing"].as_array().unwrap().is_empty()));
    assert!(r["executed"]["csim"].as_f64().unwrap() > 0.7, "{r}");
    // The skeleton stays available and reports no template.
    let sk = dir.path().join("sk");
    ok(&maobi(&["write", "永", "--font", s(&msz), "--from", "skeleton", "--size", "128", "-o", s(&sk)]));
    assert!(json(&sk.join("report.json"))["template"].is_null());
}

#[test]
fn every_font_container_and_a_collection_face() {
    let dir = tempfile::tempdir().unwrap();
    let fonts = fixtures().join("fonts");
    let mut csims = Vec::new();
    for f in ["ukai-subset.ttf", "ukai-subset.woff", "ukai-subset.woff2", "ukai-subset-cff.otf"] {
        let out = dir.path().join(f);
        ok(&maobi(&["write", "十", "--font", s(&fonts.join(f)), "--size", "96", "-o", s(&out)]));
        let r = json(&out.join("report.json"));
        assert_eq!(r["method"], "template", "{f}");
        assert_eq!(r["plan"]["strokes_found"], 2, "{f}");
        csims.push(r["plan"]["csim"].as_f64().unwrap());
    }
    // The same glyph in every container (CFF outlines are rounded to font units).
    for c in &csims[1..] {
        assert!((c - csims[0]).abs() < 0.01, "{csims:?}");
    }
    let ttc = fonts.join("ukai-two-faces.ttc");
    ok(&maobi(&["write", "永", "--font", s(&ttc), "--size", "96", "-o", s(&dir.path().join("f0"))]));
    // Face 1 holds only 中大小: 永 is not in it, 大 is.
    fails(&maobi(&["write", "永", "--font", s(&ttc), "--font-index", "1", "-o", s(&dir.path().join("x"))]), "face 1");
    ok(&maobi(&[
        "write",
        "大",
        "--font",
        s(&ttc),
        "--font-index",
        "1",
        "--size",
        "96",
        "-o",
        s(&dir.path().join("f1")),
    ]));
    fails(
        &maobi(&["write", "永", "--font", s(&ttc), "--font-index", "7", "-o", s(&dir.path().join("x"))]),
        "no face 7",
    );
    // Several --font: the first covering file is used.
    let both = dir.path().join("both");
    ok(&maobi(&[
        "write",
        "人",
        "--font",
        s(&fonts.join("msz")),
        "--font",
        s(&fonts.join("ukai-subset.ttf")),
        "--size",
        "96",
        "-o",
        s(&both),
    ]));
    assert!(json(&both.join("report.json"))["plan"]["strokes_found"] == 2);
}

#[test]
fn template_needs_stroke_data() {
    let dir = tempfile::tempdir().unwrap();
    let empty = dir.path().join("empty-hanzi");
    std::fs::create_dir(&empty).unwrap();
    let font = fixtures().join("fonts/ukai-subset.ttf");
    let out = dir.path().join("o");
    // The template comes from --hanzi-data when given; an empty folder has none.
    fails(
        &maobi(&["write", "永", "--font", s(&font), "--hanzi-data", s(&empty), "--from", "template", "-o", s(&out)]),
        "needs the character's stroke data",
    );
    assert!(!out.exists());
    // Without --from the skeleton is used then.
    ok(&maobi(&["write", "永", "--font", s(&font), "--hanzi-data", s(&empty), "--size", "96", "-o", s(&out)]));
    assert_eq!(json(&out.join("report.json"))["method"], "skeleton");
}

#[test]
fn evaluate_a_font_and_a_folder_of_images() {
    let dir = tempfile::tempdir().unwrap();
    let font = fixtures().join("fonts/ukai-subset.ttf");
    // 我 is not in the subset: skipped and counted.
    let v = ok_json(&maobi(&["evaluate", "--font", s(&font), "--chars", "十人我", "--size", "96", "--json"]));
    assert_eq!(v["method"], "template");
    assert_eq!(v["summary"]["count"], 2);
    assert_eq!(v["summary"]["uncovered"]["chars"], "我");
    assert!(v["summary"]["strokes_match_fraction"].as_f64().is_some());
    assert_eq!(v["chars"][0]["template"]["strokes"], 2);
    // Images named after their character: use the references `write` draws.
    let imgs = dir.path().join("imgs");
    std::fs::create_dir(&imgs).unwrap();
    for c in ["十", "人"] {
        let o = dir.path().join(format!("w{c}"));
        ok(&maobi(&["write", c, "--size", "128", "-o", s(&o)]));
        std::fs::copy(o.join("reference.png"), imgs.join(format!("{c}.png"))).unwrap();
    }
    let v = ok_json(&maobi(&["evaluate", "--images", s(&imgs), "--size", "96", "--json"]));
    assert_eq!(v["summary"]["count"], 2);
    assert_eq!(v["summary"]["strokes_match_fraction"], 1.0);
    assert!(v["summary"]["executed"]["csim"].as_f64().unwrap() > 0.75, "{v}");
    std::fs::write(imgs.join("two.png"), b"x").unwrap();
    fails(&maobi(&["evaluate", "--images", s(&imgs)]), "named after its one character");
}

#[test]
fn template_placement_is_searched_unless_asked_not_to() {
    let msz = fixtures().join("fonts/msz");
    let run = |placement: &str| {
        let v = ok_json(&maobi(&[
            "evaluate",
            "--font",
            s(&msz),
            "--chars",
            "永",
            "--size",
            "128",
            "--placement",
            placement,
            "--json",
        ]));
        let c = &v["chars"][0];
        (c["char_mm"].as_f64().unwrap(), c["plan"]["csim"].as_f64().unwrap())
    };
    let (auto_mm, auto_csim) = run("auto");
    let (mm, csim) = run("search");
    // The searched box is one of the tried multiples of the automatic one.
    let scale = mm / auto_mm;
    assert!(
        pipeline::tuning::CHAR_BOX_SEARCH_SCALES.iter().any(|s| (s - scale).abs() < 1e-9),
        "searched {mm} mm is {scale}× the automatic {auto_mm} mm"
    );
    // Chosen by the plan at a coarser raster: never clearly worse than the automatic placement.
    assert!(csim > auto_csim - 0.01, "search {csim} vs auto {auto_csim}");
    // `write` on one character searches the size the same way.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("w");
    ok(&maobi(&["write", "永", "--font", s(&msz), "--size", "128", "-o", s(&out)]));
    assert!((json(&out.join("report.json"))["char_mm"].as_f64().unwrap() - mm).abs() < 1e-9);
    fails(&maobi(&["evaluate", "--font", s(&msz), "--chars", "永", "--placement", "best"]), "search");
}
