//! Brush profile JSON: no panic; an accepted profile predicts bounded positive footprints at
//! every corner of its range and gives a finite canvas scale.
#![no_main]

use brush_model::{BrushProfile, Extrapolation};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(p) = BrushProfile::from_json(text, "fuzz.json") else { return };
    for c in p.ranges.corners() {
        let f = p.predict(&c, Extrapolation::Refuse).expect("a validated profile predicts at its corners");
        for v in [f.lt_mm, f.lh_mm, f.lr_mm] {
            assert!(v > 0.0 && v <= p.max_footprint_mm());
        }
    }
    let s = bezier_raster::StrokeCanvas::for_profile(&p, 64).px_per_mm;
    assert!(s.is_finite() && s > 0.0);
    let _ = p.h_for_half_width(1.0, p.ranges.alpha_rad.min, p.ranges.beta_rad.min);
});
