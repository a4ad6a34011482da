//! Measurements CSV → rows → regression → calibrated profile: no panic, accepted rows within
//! the documented bounds, R² never above 1, accepted profiles bounded.
#![no_main]

use brush_model::{Brush, BrushProfile, Extrapolation, Form, PressRanges, Range, fit, read_measurements};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(rows) = read_measurements(data, "fuzz.csv") else { return };
    for r in &rows {
        assert!((0.0..=1000.0).contains(&r.press.h_mm));
        assert!(r.footprint.lt_mm > 0.0 && r.footprint.lt_mm <= 2000.0);
    }
    for form in [Form::General, Form::Paper] {
        let Ok(rep) = fit(&rows, form) else { continue };
        for o in rep.outputs.values() {
            assert!(o.r2.is_nan() || o.r2 <= 1.0 + 1e-9, "R² {}", o.r2);
        }
        let span = |f: fn(&brush_model::Measurement) -> f64| {
            Range::new(rows.iter().map(f).fold(f64::INFINITY, f64::min), rows.iter().map(f).fold(f64::NEG_INFINITY, f64::max))
        };
        let ranges = PressRanges {
            h_mm: span(|m| m.press.h_mm),
            alpha_rad: span(|m| m.press.alpha_rad),
            beta_rad: span(|m| m.press.beta_rad),
        };
        let p = BrushProfile::calibrated("fuzz", Brush { length_mm: 48.0, radius_mm: 6.0 }, ranges, rep);
        if p.validate("fuzz").is_ok() {
            // The profile round-trips through JSON (an undefined R² is null).
            let again = BrushProfile::from_json(&p.to_json(), "again").expect("a valid profile reloads");
            for c in again.ranges.corners() {
                let f = again.predict(&c, Extrapolation::Refuse).expect("predicts at its corners");
                assert!(f.lt_mm <= again.max_footprint_mm());
            }
        }
    }
});
