//! `maobi fit-stroke` and `maobi calibrate --images` on the committed synthetic photo set.

use crate::common::{fails, maobi, ok, s};
use std::path::{Path, PathBuf};

fn photos() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/photos")
}

#[test]
fn fit_stroke_reads_the_scale_and_draws_the_overlay() {
    let dir = tempfile::tempdir().unwrap();
    let ov = dir.path().join("ov.png");
    let j: serde_json::Value = serde_json::from_str(&ok(&maobi(&[
        "fit-stroke",
        s(&photos().join("stroke_01.png")),
        "--json",
        "--overlay",
        s(&ov),
    ])))
    .unwrap();
    // stroke_01: pen1 at h = 11 mm, α = 0: lt 9.9, lh 3.85, lr 2.2 mm.
    for (k, want) in [("lt_mm", 9.9), ("lh_mm", 3.85), ("lr_mm", 2.2)] {
        let got = j[k].as_f64().unwrap();
        assert!((got - want).abs() / want < 0.03, "{k}: {got} vs {want}");
    }
    assert!(j["iou"].as_f64().unwrap() > 0.95);
    let img = image::open(&ov).unwrap().to_rgb8();
    assert!(img.pixels().any(|p| p.0 == [230, 20, 20]), "outline drawn in red");
}

#[test]
fn calibrate_from_photos_recovers_the_generating_model() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cal/profile.json");
    let o = maobi(&["calibrate", "--images", s(&photos()), "-o", s(&out), "--json"]);
    let r: serde_json::Value = serde_json::from_str(&ok(&o)).unwrap();
    assert_eq!(r["n"], 12);
    // The photos were made from nominal pen1: lt = 0.9 h + 12.4 α, lh = 0.35 h + 3.1 α,
    // lr = 0.2 h + 0.6 α, no intercept, no β term. Each estimate within 3 standard errors.
    let truth = [("lt_mm", [0.0, 0.9, 12.4, 0.0]), ("lh_mm", [0.0, 0.35, 3.1, 0.0]), ("lr_mm", [0.0, 0.2, 0.6, 0.0])];
    for (out_name, t) in truth {
        for (k, term) in ["intercept", "h_mm", "alpha_rad", "beta_rad"].iter().enumerate() {
            let c = r["outputs"][out_name]["coef"][term].as_f64().unwrap();
            let se = r["outputs"][out_name]["std_err"][term].as_f64().unwrap();
            assert!((c - t[k]).abs() < 3.0 * se, "{out_name}.{term}: {c} ± {se} vs {}", t[k]);
        }
    }
    let m = std::fs::read_to_string(dir.path().join("cal/measurements.csv")).unwrap();
    assert!(m.starts_with("file,h_mm,alpha_deg,beta_deg,lt_mm,lh_mm,lr_mm,iou\n"));
    assert_eq!(m.lines().count(), 13);
    assert!(dir.path().join("cal/regression.png").is_file());
    let p: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(p["source"], "calibrated");
}

#[test]
fn bad_photos_are_listed_or_refused() {
    let dir = tempfile::tempdir().unwrap();
    let blank = dir.path().join("blank.png");
    image::GrayImage::from_pixel(64, 64, image::Luma([240])).save(&blank).unwrap();
    fails(&maobi(&["fit-stroke", s(&blank), "--px-per-mm", "8"]), "no ink");
    let black = dir.path().join("black.png");
    image::GrayImage::from_pixel(64, 64, image::Luma([5])).save(&black).unwrap();
    fails(&maobi(&["fit-stroke", s(&black), "--px-per-mm", "8"]), "ink");
    let two = dir.path().join("two.png");
    let mut img = image::GrayImage::from_pixel(120, 60, image::Luma([240]));
    for y in 10..40 {
        for x in 10..40 {
            img.put_pixel(x, y, image::Luma([10]));
            img.put_pixel(x + 60, y, image::Luma([10]));
        }
    }
    img.save(&two).unwrap();
    fails(&maobi(&["fit-stroke", s(&two), "--px-per-mm", "8"]), "2 large ink blobs");
    fails(
        &maobi(&["fit-stroke", s(&blank)]),
        "no scale: none was given and the file stores no resolution (PNG pHYs or JPEG density); give the scale (--px-per-mm)",
    );
    let junk = dir.path().join("junk.png");
    std::fs::write(&junk, b"nope").unwrap();
    fails(&maobi(&["fit-stroke", s(&junk), "--px-per-mm", "8"]), "junk.png");
    // In a calibration, unfittable photos are listed and left out; the rest are used.
    let set = dir.path().join("set");
    std::fs::create_dir_all(&set).unwrap();
    let mut labels = std::fs::read_to_string(photos().join("labels.csv")).unwrap();
    for l in labels.lines().skip(1) {
        let f = l.split(',').next().unwrap();
        std::fs::copy(photos().join(f), set.join(f)).unwrap();
    }
    std::fs::copy(&two, set.join("two.png")).unwrap();
    labels.push_str("two.png,15,5,0\n");
    std::fs::write(set.join("labels.csv"), labels).unwrap();
    let o = maobi(&["calibrate", "--images", s(&set), "-o", s(&dir.path().join("p.json"))]);
    ok(&o);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("left out 1 photo(s)") && e.contains("two.png"), "{e}");
    fails(&maobi(&["calibrate", "--images", s(&set)]), "needs -o");
    // (Into another folder: measurements.csv and regression.png beside p.json are not replaced.)
    let q = dir.path().join("q/q.json");
    fails(&maobi(&["calibrate", "--images", s(dir.path()), "-o", s(&dir.path().join("q.json"))]), "already exists");
    fails(&maobi(&["calibrate", "--images", s(dir.path()), "-o", s(&q)]), "labels.csv");
}

#[test]
fn a_refused_fit_from_photos_writes_none_of_its_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cal/profile.json");
    // Every fit below an IoU of 1: no photo is used, the fit is refused.
    let o = maobi(&["calibrate", "--images", s(&photos()), "--min-iou", "1", "-o", s(&out)]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.code() == Some(2) && e.contains("left out 12 photo(s)") && e.contains("cannot fit"), "{e}");
    for f in ["profile.json", "measurements.csv", "regression.png"] {
        assert!(!dir.path().join("cal").join(f).exists(), "{f} was written");
    }
}
