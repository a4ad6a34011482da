//! `maobi calibrate` and `maobi footprint` end to end, including their bad-input paths.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn maobi(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_maobi")).args(args).output().expect("maobi runs")
}

fn sample() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/measurements/pen1-sample.csv")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn calibrate_writes_a_profile_that_footprint_can_use() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p.json");
    let o = maobi(&["calibrate", sample().to_str().unwrap(), "-o", out.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["form"], "general");
    assert_eq!(report["n"], 90);
    let h = report["outputs"]["lr_mm"]["coef"]["h_mm"].as_f64().unwrap();
    // The sample is the nominal pen1 model (1.6·R/L = 0.2 mm per mm) plus noise.
    assert!((h - 0.2).abs() < 0.02, "{h}");
    for key in ["std_err", "t"] {
        assert!(report["outputs"]["lt_mm"][key]["alpha_rad"].is_number());
    }
    // The profile is named after the file it was written to, and says so.
    let profile: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(profile["name"], "p");
    assert!(stderr(&o).contains(&format!("profile `p` written to {}", out.display())), "{}", stderr(&o));
    // The table prints the outputs in the footprint's order.
    let table = String::from_utf8_lossy(&maobi(&["calibrate", sample().to_str().unwrap()]).stdout).into_owned();
    let at = |n: &str| table.find(n).unwrap_or_else(|| panic!("{n}: {table}"));
    assert!(at("lt_mm:") < at("lh_mm:") && at("lh_mm:") < at("lr_mm:"), "{table}");
    let o = maobi(&["footprint", "--h", "15", "--alpha", "5", "--brush", out.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let fp: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let lr = fp["lr_mm"].as_f64().unwrap();
    assert!((lr - 3.0).abs() < 0.2, "{lr}");
}

#[test]
fn calibrate_paper_form_reports_k4_k5() {
    let o = maobi(&["calibrate", sample().to_str().unwrap(), "--form", "paper", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(r["outputs"]["sum_mm"]["coef"]["h_mm"].as_f64().unwrap() > 1.0);
    for k in ["k4", "k4_std_err", "k5", "k5_std_err"] {
        assert!(r[k].as_f64().unwrap() > 0.0, "{k}");
    }
}

#[test]
fn footprint_matches_the_nominal_model() {
    let o = maobi(&["footprint", "--h", "20", "--alpha", "0", "--beta", "0", "--json"]);
    assert!(o.status.success());
    let fp: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!((fp["lt_mm"].as_f64().unwrap() - 18.0).abs() < 1e-9);
    assert!((fp["lh_mm"].as_f64().unwrap() - 7.0).abs() < 1e-9);
    assert!((fp["lr_mm"].as_f64().unwrap() - 4.0).abs() < 1e-9);
}

#[test]
fn bad_input_is_a_one_line_error_with_exit_2_and_no_output_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p.json");
    let outs = out.to_str().unwrap();
    let write = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let header = "h_mm,alpha_deg,beta_deg,lt_mm,lh_mm,lr_mm\n";
    let non_numeric = write("nn.csv", &format!("{header}11,0,0,9,3,2\n12,x,0,9,3,2\n"));
    let few = write("few.csv", &format!("{header}11,0,0,9,3,2\n12,5,0,10,3,2\n"));
    let ragged = write("rag.csv", &format!("{header}11,0,0,9,3\n"));
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["calibrate", "/no/such/file.csv", "-o", outs], "/no/such/file.csv"),
        (vec!["calibrate", &non_numeric, "-o", outs], "line 3, column `alpha_deg`"),
        (vec!["calibrate", &few, "-o", outs], "too few measurements"),
        (vec!["calibrate", &ragged, "-o", outs], "line 2"),
        (vec!["footprint", "--h", "30", "--alpha", "0"], "outside the calibrated range"),
        (vec!["footprint", "--h", "15", "--alpha", "0", "--brush", "pen7"], "pen7"),
    ];
    for (args, needle) in cases {
        let o = maobi(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let e = stderr(&o);
        assert!(e.contains(needle), "{args:?}: {e}");
        assert_eq!(e.trim_end().lines().count(), 1, "{args:?}: {e}");
        assert!(!out.exists(), "{args:?} left an output file");
    }
    // Nothing else was left in the folder either (no temporary files).
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(left.len(), 3, "{left:?}");
}
