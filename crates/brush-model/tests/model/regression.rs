//! The fits recover known coefficients and handle degenerate designs honestly.

use brush_model::{BrushProfile, Extrapolation, FitError, Footprint, Measurement, Press, fit_general, fit_paper};

/// Measurements from known coefficients with Gaussian noise of `sigma` mm (a `SplitMix64` stream).
fn synthetic(n_per_cell: usize, sigma: f64, beta_values: &[f64], seed: u64) -> Vec<Measurement> {
    let mut noise = numerics::SplitMix64(seed);
    let mut rows = Vec::new();
    for h in [11.0, 13.0, 15.0, 17.0, 20.0] {
        for a in [0.0, 5.0, 10.0] {
            for &b in beta_values {
                for _ in 0..n_per_cell {
                    let p = Press::from_degrees(h, a, b);
                    let lt = 0.5 + 0.9 * p.h_mm + 12.0 * p.alpha_rad + 4.0 * p.beta_rad;
                    let lh = 0.2 + 0.35 * p.h_mm + 3.0 * p.alpha_rad - 2.0 * p.beta_rad;
                    let lr = 0.1 + 0.2 * p.h_mm + 0.6 * p.alpha_rad + 1.0 * p.beta_rad;
                    rows.push(Measurement {
                        press: p,
                        footprint: Footprint {
                            lt_mm: lt + sigma * noise.normal(),
                            lh_mm: lh + sigma * noise.normal(),
                            lr_mm: lr + sigma * noise.normal(),
                        },
                    });
                }
            }
        }
    }
    rows
}

#[test]
fn recovers_known_coefficients_within_standard_errors() {
    let rows = synthetic(10, 0.2, &[0.0, 5.0], 7);
    let fit = fit_general(&rows).unwrap();
    let truth = [("lt_mm", [0.5, 0.9, 12.0, 4.0]), ("lh_mm", [0.2, 0.35, 3.0, -2.0]), ("lr_mm", [0.1, 0.2, 0.6, 1.0])];
    for (name, t) in truth {
        let o = &fit.outputs[name];
        let c = [o.coef.intercept, o.coef.h_mm.unwrap(), o.coef.alpha_rad.unwrap(), o.coef.beta_rad.unwrap()];
        let se =
            [o.std_err.intercept, o.std_err.h_mm.unwrap(), o.std_err.alpha_rad.unwrap(), o.std_err.beta_rad.unwrap()];
        for k in 0..4 {
            // 4 standard errors: a false failure has probability ~6e-5 per coefficient.
            assert!((c[k] - t[k]).abs() < 4.0 * se[k], "{name}[{k}]: {} vs {} (se {})", c[k], t[k], se[k]);
            assert!(se[k] > 0.0 && se[k] < 1.0);
        }
        assert!(o.r2 > 0.9 && o.adj_r2 <= o.r2);
        assert!((o.resid_se - 0.2).abs() < 0.05, "resid_se {}", o.resid_se);
    }
}

#[test]
fn noiseless_data_is_fitted_exactly() {
    let rows = synthetic(1, 0.0, &[0.0, 2.0, 5.0], 1);
    let fit = fit_general(&rows).unwrap();
    let lt = &fit.outputs["lt_mm"];
    assert!((lt.coef.h_mm.unwrap() - 0.9).abs() < 1e-10);
    assert!((lt.coef.alpha_rad.unwrap() - 12.0).abs() < 1e-9);
    assert!(lt.r2 > 1.0 - 1e-12);
}

#[test]
fn constant_column_is_reported_and_dropped_never_nan() {
    let rows = synthetic(3, 0.1, &[5.0], 3);
    let fit = fit_general(&rows).unwrap();
    assert_eq!(fit.unidentifiable, vec!["beta_rad".to_string()]);
    let json = serde_json::to_string(&fit).unwrap();
    assert!(!json.contains("NaN") && !json.contains("null"), "{json}");
    for o in fit.outputs.values() {
        assert!(o.coef.beta_rad.is_none());
        assert!(o.coef.h_mm.unwrap().is_finite() && o.std_err.h_mm.unwrap().is_finite());
    }
    // The paper form says the same.
    let paper = fit_paper(&rows).unwrap();
    assert_eq!(paper.unidentifiable, vec!["beta_rad".to_string()]);
}

#[test]
fn paper_form_implies_consistent_linear_model() {
    // Exact ratios lh = 0.4·lt, lr = 0.25·lt recover k4, k5 exactly.
    let mut rows = Vec::new();
    for h in [11.0, 14.0, 17.0, 20.0] {
        for a in [0.0, 10.0] {
            let p = Press::from_degrees(h, a, 0.0);
            let lt = 1.0 + 0.8 * h + 10.0 * p.alpha_rad;
            rows.push(Measurement { press: p, footprint: Footprint { lt_mm: lt, lh_mm: 0.4 * lt, lr_mm: 0.25 * lt } });
        }
    }
    let fit = fit_paper(&rows).unwrap();
    assert!((fit.k4.unwrap() - 0.4).abs() < 1e-12);
    assert!((fit.k5.unwrap() - 0.25).abs() < 1e-12);
    let m = fit.linear_model();
    let p = Press::from_degrees(15.0, 5.0, 0.0);
    let lt = 1.0 + 0.8 * 15.0 + 10.0 * p.alpha_rad;
    assert!((m.lt_mm.eval(p.h_mm, p.alpha_rad, p.beta_rad) - lt).abs() < 1e-9);
    assert!((m.lr_mm.eval(p.h_mm, p.alpha_rad, p.beta_rad) - 0.25 * lt).abs() < 1e-9);
}

#[test]
fn too_few_rows_and_collinear_designs_are_errors() {
    let rows = synthetic(1, 0.1, &[0.0, 5.0], 2);
    assert!(matches!(fit_general(&rows[..3]), Err(FitError::TooFewRows { .. })));
    assert!(matches!(fit_general(&[]), Err(FitError::TooFewRows { .. })));
    // alpha proportional to h: collinear.
    let mut col = Vec::new();
    for (i, h) in [11.0, 12.0, 13.0, 14.0, 15.0, 16.0].iter().enumerate() {
        col.push(Measurement {
            press: Press::new(*h, h * 0.01, if i % 2 == 0 { 0.0 } else { 0.05 }),
            footprint: Footprint { lt_mm: 9.0 + i as f64, lh_mm: 3.0, lr_mm: 2.0 },
        });
    }
    let e = fit_general(&col).unwrap_err();
    assert!(matches!(e, FitError::Collinear { .. }), "{e}");
}

#[test]
fn calibrated_profile_predicts_like_the_fit() {
    let rows = synthetic(2, 0.05, &[0.0, 5.0], 11);
    let fit = fit_general(&rows).unwrap();
    let nominal = BrushProfile::builtin("pen1").unwrap();
    let prof = BrushProfile::calibrated("test", nominal.brush, nominal.ranges, fit.clone());
    let text = prof.to_json();
    let back = BrushProfile::from_json(&text, "mem").unwrap();
    assert_eq!(back, prof);
    let p = Press::from_degrees(16.0, 7.0, 2.0);
    let fp = back.predict(&p, Extrapolation::Refuse).unwrap();
    let c = &fit.outputs["lr_mm"].coef;
    assert!((fp.lr_mm - c.eval(p.h_mm, p.alpha_rad, p.beta_rad)).abs() < 1e-12);
}

#[test]
fn the_report_prints_lt_lh_lr_in_order_and_exact_fits_as_undefined() {
    // Noisy data: a normal table, outputs in the footprint's order.
    let noisy = fit_general(&synthetic(3, 0.05, &[0.0, 10.0], 7)).unwrap().to_string();
    let at = |s: &str, n: &str| s.find(n).unwrap_or_else(|| panic!("{n} missing: {s}"));
    assert!(at(&noisy, "lt_mm:") < at(&noisy, "lh_mm:") && at(&noisy, "lh_mm:") < at(&noisy, "lr_mm:"), "{noisy}");
    assert!(!noisy.contains("undefined"), "{noisy}");
    // Data made by the model itself: zero residuals, so no standard errors or t values.
    let exact: Vec<Measurement> = [(11.0, 0.0), (14.0, 5.0), (17.0, 0.0), (20.0, 10.0), (12.0, 10.0), (18.0, 5.0)]
        .iter()
        .map(|&(h, a)| {
            let p = Press::from_degrees(h, a, 0.0);
            Measurement {
                press: p,
                footprint: Footprint { lt_mm: 0.9 * h + 12.0 * p.alpha_rad, lh_mm: 0.35 * h, lr_mm: 0.2 * h },
            }
        })
        .collect();
    let text = fit_general(&exact).unwrap().to_string();
    assert!(text.contains("an exact fit: std err and t are undefined"), "{text}");
    // No t value of rounding noise (the old output printed t = 775173491632631.125).
    assert!(text.lines().all(|l| l.chars().count() < 100 && !l.contains("e14") && !l.contains("000000000")), "{text}");
}
