//! The neural generator from the command line: train (tiny), evaluate, render.

use crate::common::{fails, maobi, ok, s};

#[test]
fn train_a_tiny_generator_and_use_it() {
    let dir = tempfile::tempdir().unwrap();
    let m = dir.path().join("g/tiny.safetensors");
    let run = maobi(&[
        "train",
        "--arch",
        "tiny",
        "--steps",
        "30",
        "--batch",
        "16",
        "--val-every",
        "10",
        "--eval-n",
        "16",
        "-o",
        s(&m),
    ]);
    let out = ok(&run);
    assert!(out.contains("30 steps"), "{out}");
    // stderr is a pipe here, not a terminal: a progress line every 5 % instead of a bar.
    let err = String::from_utf8_lossy(&run.stderr);
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("train: step ")).collect();
    assert!(lines.len() >= 10 && lines.len() <= 21, "{err}");
    assert!(lines.iter().all(|l| l.contains("loss ") && l.contains("elapsed ") && l.contains("ETA ")), "{err}");
    assert!(lines.iter().any(|l| l.contains("validation 0.")), "{err}");
    assert!(lines.last().unwrap().starts_with("train: step 30/30 (100%)"), "{err}");
    for f in ["tiny.safetensors", "tiny.json", "loss.csv", "loss.png"] {
        assert!(dir.path().join("g").join(f).is_file(), "{f}");
    }
    let csv = std::fs::read_to_string(dir.path().join("g/loss.csv")).unwrap();
    assert!(csv.starts_with("step,train_mse,val_mse,lr\n") && csv.lines().count() == 31);
    let cfg: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("g/tiny.json")).unwrap()).unwrap();
    assert_eq!(cfg["recipe"]["steps"], 30);
    assert!(cfg["metrics"]["ssim_mean"].as_f64().is_some());
    let j: serde_json::Value =
        serde_json::from_str(&ok(&maobi(&["eval-generator", "--generator", s(&m), "--n", "16", "--json"]))).unwrap();
    assert_eq!(j["n"], 16);
    assert!(j["models"]["b-bsmg"]["csim"]["mean"].as_f64().unwrap() > 0.0);
    // Which weights were scored is said, in JSON and in the table's heading.
    assert_eq!(j["generator"].as_str(), Some(s(&m)));
    let table = ok(&maobi(&["eval-generator", "--generator", s(&m), "--n", "4"]));
    assert!(table.lines().next().unwrap().contains(s(&m)), "{table}");
    // Resume continues from the checkpoint.
    ok(&maobi(&[
        "train",
        "--resume",
        s(&m),
        "--steps",
        "5",
        "--batch",
        "8",
        "--val-every",
        "5",
        "--eval-n",
        "8",
        "-o",
        s(&dir.path().join("g/more.safetensors")),
    ]));
    // A corrupted checkpoint is a clear error.
    std::fs::write(&m, b"not weights").unwrap();
    fails(&maobi(&["eval-generator", "--generator", s(&m), "--n", "4"]), "safetensors");
    fails(&maobi(&["train", "--steps", "0", "-o", s(&m)]), "--steps 0: expected 1..");
    fails(&maobi(&["train", "--steps", "3", "-o", s(&dir.path().join("g.bin"))]), ".safetensors");
}

#[test]
fn the_committed_generator_renders_strokes_and_characters() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("n.png");
    let j: serde_json::Value = serde_json::from_str(&ok(&maobi(&[
        "stroke",
        "--h",
        "15",
        "--alpha",
        "5",
        "--renderer",
        "neural",
        "-o",
        s(&png),
        "--json",
    ])))
    .unwrap();
    assert_eq!(j["size"], 128);
    let a = dir.path().join("a.png");
    ok(&maobi(&["stroke", "--h", "15", "--alpha", "5", "-o", s(&a)]));
    let c: serde_json::Value = serde_json::from_str(&ok(&maobi(&["compare", s(&a), s(&png), "--json"]))).unwrap();
    assert!(c["csim"].as_f64().unwrap() > 0.85, "{c}");
    fails(
        &maobi(&["stroke", "--h", "25", "--alpha", "5", "--renderer", "neural", "-o", s(&png)]),
        "outside the calibrated range",
    );
    fails(
        &maobi(&["stroke", "--h", "15", "--alpha", "5", "--renderer", "neural", "-o", s(&dir.path().join("n.svg"))]),
        "PNG only",
    );
    let w = dir.path().join("w");
    ok(&maobi(&["write", "十", "--renderer", "neural", "--size", "128", "-o", s(&w)]));
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(w.join("report.json")).unwrap()).unwrap();
    assert_eq!(r["model"], "b-bsmg");
    assert!(r["plan"]["csim"].as_f64().unwrap() > 0.7, "{r}");
    fails(
        &maobi(&["write", "十", "--renderer", "neural", "--brush", "pen2", "--out", s(&dir.path().join("x"))]),
        "trained for brush `pen1`",
    );
    let j: serde_json::Value = serde_json::from_str(&ok(&maobi(&["eval-generator", "--n", "20", "--json"]))).unwrap();
    assert_eq!(j["generator"], "committed");
    for m in ["b-bsmg", "circle", "ellipse", "line", "qbc"] {
        assert!(j["models"][m]["ssim"]["mean"].as_f64().unwrap() > 0.5, "{m}");
    }
}
