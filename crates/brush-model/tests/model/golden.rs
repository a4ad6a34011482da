//! The regression agrees with statsmodels on a committed table (see `golden/gen_regression.py`).

use brush_model::{OutputFit, Terms, fit_general, fit_paper, read_measurements};
use serde_json::Value;

fn close(a: f64, b: f64, what: &str) {
    let tol = 1e-8 * b.abs().max(1.0);
    assert!((a - b).abs() <= tol, "{what}: ours {a}, statsmodels {b}");
}

fn check_terms(ours: &Terms, theirs: &Value, what: &str) {
    close(ours.intercept, theirs["intercept"].as_f64().unwrap(), &format!("{what}.intercept"));
    close(ours.h_mm.unwrap(), theirs["h_mm"].as_f64().unwrap(), &format!("{what}.h_mm"));
    close(ours.alpha_rad.unwrap(), theirs["alpha_rad"].as_f64().unwrap(), &format!("{what}.alpha_rad"));
    close(ours.beta_rad.unwrap(), theirs["beta_rad"].as_f64().unwrap(), &format!("{what}.beta_rad"));
}

fn check_output(ours: &OutputFit, theirs: &Value, what: &str) {
    check_terms(&ours.coef, &theirs["coef"], &format!("{what}.coef"));
    check_terms(&ours.std_err, &theirs["std_err"], &format!("{what}.std_err"));
    check_terms(&ours.t, &theirs["t"], &format!("{what}.t"));
    for k in ["r2", "adj_r2", "resid_se"] {
        let v = match k {
            "r2" => ours.r2,
            "adj_r2" => ours.adj_r2,
            _ => ours.resid_se,
        };
        close(v, theirs[k].as_f64().unwrap(), &format!("{what}.{k}"));
    }
}

fn golden() -> (Value, Vec<brush_model::Measurement>) {
    let g: Value = serde_json::from_str(include_str!("../golden/regression.json")).unwrap();
    let mut csv = format!("{}\n", g["header"].as_str().unwrap());
    for r in g["rows"].as_array().unwrap() {
        let cells: Vec<String> = r.as_array().unwrap().iter().map(|v| v.to_string()).collect();
        csv.push_str(&cells.join(","));
        csv.push('\n');
    }
    let rows = read_measurements(csv.as_bytes(), "golden").unwrap();
    (g, rows)
}

#[test]
fn general_form_matches_statsmodels() {
    let (g, rows) = golden();
    let fit = fit_general(&rows).unwrap();
    assert_eq!(fit.n, rows.len());
    assert!(fit.unidentifiable.is_empty());
    let cn = g["condition_number"].as_f64().unwrap();
    assert!((fit.condition_number - cn).abs() <= 1e-6 * cn, "{} vs {cn}", fit.condition_number);
    for k in ["lt_mm", "lh_mm", "lr_mm"] {
        check_output(&fit.outputs[k], &g["general"][k], k);
    }
}

#[test]
fn paper_form_matches_statsmodels() {
    let (g, rows) = golden();
    let fit = fit_paper(&rows).unwrap();
    check_output(&fit.outputs["sum_mm"], &g["paper"]["sum_mm"], "sum_mm");
    close(fit.k4.unwrap(), g["k4"].as_f64().unwrap(), "k4");
    close(fit.k4_std_err.unwrap(), g["k4_std_err"].as_f64().unwrap(), "k4_std_err");
    close(fit.k5.unwrap(), g["k5"].as_f64().unwrap(), "k5");
    close(fit.k5_std_err.unwrap(), g["k5_std_err"].as_f64().unwrap(), "k5_std_err");
}
