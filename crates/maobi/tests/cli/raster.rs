//! `maobi stroke`, `compare`, `dataset` and `models` end to end, with their bad-input paths.

use crate::common::{fails, maobi, ok, ok_json, s};

#[test]
fn stroke_writes_the_footprint_described_by_its_json() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("f.png");
    let j = ok_json(&maobi(&["stroke", "--h", "15", "--alpha", "5", "--beta", "0", "-o", s(&png), "--json"]));
    assert_eq!(j["size"], 128);
    let (u, v) = (j["anchor_px"][0].as_f64().unwrap(), j["anchor_px"][1].as_f64().unwrap());
    let k = j["px_per_mm"].as_f64().unwrap();
    let lh = j["footprint"]["lh_mm"].as_f64().unwrap();
    let lt = j["footprint"]["lt_mm"].as_f64().unwrap();
    let lr = j["footprint"]["lr_mm"].as_f64().unwrap();
    let img = image::open(&png).unwrap().to_luma8();
    assert_eq!(img.dimensions(), (128, 128));
    // β = 0: the axis is the row through v; ink spans u .. u + (lh + lt)·k along it.
    let row = v.floor() as u32;
    let inked: Vec<u32> = (0..128).filter(|&x| img.get_pixel(x, row).0[0] < 128).collect();
    let (first, last) = (*inked.first().unwrap() as f64 + 0.5, *inked.last().unwrap() as f64 + 0.5);
    assert!((first - u).abs() < 1.5, "root at {first}, anchor {u}");
    assert!((last - (u + (lh + lt) * k)).abs() < 2.0, "tip at {last}");
    // At the belly column the ink is 2·lr·k tall.
    let col = (u + lh * k).floor() as u32;
    let tall = (0..128).map(|y| 1.0 - img.get_pixel(col, y).0[0] as f64 / 255.0).sum::<f64>();
    assert!((tall - 2.0 * lr * k).abs() < 0.5, "{tall} vs {}", 2.0 * lr * k);
    // SVG too; without --json it says what it wrote, where.
    let svg = dir.path().join("f.svg");
    let said = ok(&maobi(&["stroke", "--h", "15", "--alpha", "5", "--model", "ellipse", "-o", s(&svg)]));
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<path d=\"M"));
    assert!(said.starts_with(&format!("wrote {}: ellipse footprint", svg.display())), "{said}");
}

#[test]
fn compare_scores_identical_and_different_images() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
    ok_json(&maobi(&["stroke", "--h", "15", "--alpha", "5", "-o", s(&a)]));
    ok_json(&maobi(&["stroke", "--h", "15", "--alpha", "5", "--model", "circle", "-o", s(&b)]));
    let same = ok_json(&maobi(&["compare", s(&a), s(&a), "--json"]));
    assert_eq!(same["ssim"], 1.0);
    assert_eq!(same["csim"], 1.0);
    assert!(same["psnr"].is_null());
    let diff = ok_json(&maobi(&["compare", s(&a), s(&b), "--json"]));
    for k in ["csim", "ssim", "iou"] {
        let v = diff[k].as_f64().unwrap();
        assert!(v > 0.2 && v < 0.99, "{k} = {v}");
    }
    assert!(diff["psnr"].as_f64().unwrap() > 0.0);
}

#[test]
fn compare_refuses_bad_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
    ok_json(&maobi(&["stroke", "--h", "15", "--alpha", "5", "-o", s(&a)]));
    ok_json(&maobi(&["stroke", "--h", "15", "--alpha", "5", "--size", "64", "-o", s(&b)]));
    fails(&maobi(&["compare", s(&a), s(&b)]), "differ in size");
    let junk = dir.path().join("junk.png");
    std::fs::write(&junk, b"nope").unwrap();
    fails(&maobi(&["compare", s(&a), s(&junk)]), "junk.png");
    fails(&maobi(&["compare", s(&a), "/no/such.png"]), "/no/such.png");
}

#[test]
fn stroke_refuses_bad_inputs_without_writing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    fails(&maobi(&["stroke", "--h", "40", "--alpha", "5", "-o", s(&out)]), "give --extrapolate to use it anyway");
    fails(&maobi(&["stroke", "--h", "15", "--alpha", "5", "--model", "brushy", "-o", s(&out)]), "brushy");
    fails(&maobi(&["stroke", "--h", "15", "--alpha", "5", "-o", s(&dir.path().join("x.gif"))]), ".png or .svg");
    fails(&maobi(&["stroke", "--h", "15", "--alpha", "5", "--px-per-mm", "-1", "-o", s(&out)]), "--px-per-mm");
    fails(&maobi(&["stroke", "--h", "15", "--alpha", "5", "--size", "0", "-o", s(&out)]), "--size");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn dataset_is_deterministic_and_labelled() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    ok_json(&maobi(&["dataset", "--n", "20", "--size", "64", "--seed", "5", "-o", s(&a)]));
    ok_json(&maobi(&["dataset", "--n", "20", "--size", "64", "--seed", "5", "-o", s(&b)]));
    let la = std::fs::read_to_string(a.join("labels.csv")).unwrap();
    assert_eq!(la, std::fs::read_to_string(b.join("labels.csv")).unwrap());
    let lines: Vec<&str> = la.lines().collect();
    assert_eq!(lines[0], "file,h_mm,alpha_deg,beta_deg,lt_mm,lh_mm,lr_mm,px_per_mm,anchor_u,anchor_v");
    assert_eq!(lines.len(), 21);
    for l in &lines[1..] {
        let f: Vec<&str> = l.split(',').collect();
        assert_eq!(f.len(), 10);
        let h: f64 = f[1].parse().unwrap();
        assert!((11.0..=20.0).contains(&h));
        assert_eq!(std::fs::read(a.join(f[0])).unwrap(), std::fs::read(b.join(f[0])).unwrap());
    }
    fails(&maobi(&["dataset", "--n", "0", "-o", s(&a)]), "--n 0");
}

#[test]
fn models_table_ranks_the_baselines_below_identity() {
    let j = ok_json(&maobi(&["models", "--n", "24", "--size", "64", "--json"]));
    assert_eq!(j["n"], 24);
    assert_eq!(j["reference"], "bsm");
    for m in ["circle", "ellipse", "line", "qbc"] {
        let c = &j["models"][m]["csim"];
        let (best, worst, mean) =
            (c["best"].as_f64().unwrap(), c["worst"].as_f64().unwrap(), c["mean"].as_f64().unwrap());
        assert!(worst <= mean && mean <= best && best < 0.99 && worst > 0.3, "{m}: {c}");
    }
    // The circle ignores the footprint's length: it is the worst by CSIM.
    let mean = |m: &str| j["models"][m]["csim"]["mean"].as_f64().unwrap();
    assert!(mean("circle") < mean("ellipse") && mean("circle") < mean("qbc"));
}

#[test]
fn models_plot_draws_the_five_models_with_axes() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("models.png");
    let o = maobi(&["models", "--n", "2", "--size", "64", "--plot", s(&png)]);
    ok(&o);
    assert!(String::from_utf8_lossy(&o.stderr).contains(&format!("wrote {}", png.display())));
    let img = image::open(&png).unwrap().to_rgb8();
    // Five panels, 300 px each; each holds some ink (the outline) and some paper.
    assert_eq!(img.width(), 1500);
    for k in 0..5 {
        let dark = (k * 300..(k + 1) * 300)
            .flat_map(|x| (0..img.height()).map(move |y| (x, y)))
            .filter(|&(x, y)| img.get_pixel(x, y).0[0] < 40)
            .count();
        assert!(dark > 500, "panel {k}: {dark} dark pixels");
    }
    fails(&maobi(&["models", "--n", "2", "--plot", s(&dir.path().join("m.jpg"))]), "--plot");
}

#[test]
fn models_against_reference_photos() {
    // Photos that are exactly the B-BSM footprints: the B-BSM scores 1, baselines less.
    let dir = tempfile::tempdir().unwrap();
    let mut labels = String::from("file,h_mm,alpha_deg,beta_deg\n");
    for (i, (h, a)) in [(12.0, 0.0), (16.0, 5.0), (19.0, 10.0)].iter().enumerate() {
        let f = format!("p{i}.png");
        ok_json(&maobi(&[
            "stroke",
            "--h",
            &h.to_string(),
            "--alpha",
            &a.to_string(),
            "--size",
            "64",
            "-o",
            s(&dir.path().join(&f)),
        ]));
        labels.push_str(&format!("{f},{h},{a},0\n"));
    }
    std::fs::write(dir.path().join("labels.csv"), labels).unwrap();
    let j = ok_json(&maobi(&["models", "--reference", s(dir.path()), "--json"]));
    assert_eq!(j["n"], 3);
    assert!(j["models"]["bsm"]["ssim"]["worst"].as_f64().unwrap() > 0.999);
    assert!(j["models"]["line"]["ssim"]["mean"].as_f64().unwrap() < 0.95);
    std::fs::write(dir.path().join("labels.csv"), "file,h_mm,alpha_deg,beta_deg\np0.png,12,zero,0\n").unwrap();
    fails(&maobi(&["models", "--reference", s(dir.path())]), "line 2, column `alpha_deg`");
    std::fs::write(dir.path().join("labels.csv"), "file,h_mm,alpha_deg\np0.png,12,0\n").unwrap();
    fails(&maobi(&["models", "--reference", s(dir.path())]), "beta_deg");
}
