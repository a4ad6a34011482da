//! Predicts a pen1 footprint, prints its Bézier control points, and fits a model from a handful
//! of measurements.
//!
//! `cargo run -p brush-model --example footprint`

use brush_model::{BrushProfile, Clamp, Extrapolation, Footprint, Measurement, PointMm, Press, fit_general};

fn main() {
    let pen1 = BrushProfile::builtin("pen1").expect("built-in");
    let press = Press::from_degrees(15.0, 5.0, 0.0);
    let fp = pen1.predict(&press, Extrapolation::Refuse).expect("inside the range");
    println!("pen1 at h = 15 mm, α = 5°: {fp:?}");
    println!("area {:.2} mm², length {:.2} mm", fp.area_mm2(), fp.length_mm());
    let outline = fp.outline(PointMm::new(100.0, 50.0), 30f64.to_radians());
    for (name, c) in [("upper", outline.upper), ("lower", outline.lower)] {
        let pts: Vec<String> = c.points.iter().map(|p| format!("({:.2}, {:.2})", p.x_mm, p.y_mm)).collect();
        println!("{name}: {}", pts.join(" "));
    }
    let inv = pen1.h_for_half_width(3.0, 0.0, 0.0).expect("invertible");
    let clamped = match inv.clamped {
        Clamp::None => "inside the calibrated range".to_string(),
        Clamp::Min => format!("clamped up to the range's minimum; exactly {:.2} mm", inv.exact_h_mm),
        Clamp::Max => format!("clamped down to the range's maximum; exactly {:.2} mm", inv.exact_h_mm),
    };
    println!("for a 6 mm wide stroke at α = 0 press h = {:.2} mm ({clamped})", inv.h_mm);

    // A tiny calibration from exact data (no noise: the fit is exact, so the report prints its
    // standard errors and t values as undefined).
    let rows: Vec<Measurement> = [(11.0, 0.0), (14.0, 5.0), (17.0, 0.0), (20.0, 10.0), (12.0, 10.0), (18.0, 5.0)]
        .iter()
        .map(|&(h, a)| {
            let p = Press::from_degrees(h, a, 0.0);
            let f = Footprint { lt_mm: 0.9 * h + 12.0 * p.alpha_rad, lh_mm: 0.35 * h, lr_mm: 0.2 * h };
            Measurement { press: p, footprint: f }
        })
        .collect();
    let fit = fit_general(&rows).expect("fits");
    print!("{fit}");
}
