//! Profile loading, validation, prediction ranges and the inverse model.

use brush_model::{BrushProfile, Clamp, Extrapolation, Press, ProfileError, Source};

#[test]
fn builtins_are_nominal_and_valid() {
    for name in BrushProfile::BUILTINS {
        let p = BrushProfile::builtin(name).unwrap();
        assert_eq!(p.source, Source::Nominal);
        p.validate(name).unwrap();
        // Belly width never exceeds the brush diameter over the range.
        for c in p.ranges.corners() {
            let f = p.predict(&c, Extrapolation::Refuse).unwrap();
            assert!(f.lr_mm < p.brush.radius_mm, "{name}: lr {} at {c:?}", f.lr_mm);
            // The paper keeps the contact length under about half the bundle.
            assert!(f.length_mm() < 0.75 * p.brush.length_mm);
        }
    }
    let pen2 = BrushProfile::builtin("pen2").unwrap();
    assert!((pen2.ranges.h_mm.max - 20.0 * 32.0 / 48.0).abs() < 1e-12);
    assert!(matches!(BrushProfile::builtin("pen9"), Err(ProfileError::UnknownBuiltin(_))));
}

#[test]
fn refuses_presses_outside_the_range_unless_asked() {
    let p = BrushProfile::builtin("pen1").unwrap();
    let deep = Press::from_degrees(25.0, 5.0, 0.0);
    let e = p.predict(&deep, Extrapolation::Refuse).unwrap_err();
    assert!(e.to_string().contains("h_mm") && e.to_string().contains("outside"), "{e}");
    let f = p.predict(&deep, Extrapolation::Allow).unwrap();
    assert!(
        f.length_mm() > p.predict(&Press::from_degrees(20.0, 5.0, 0.0), Extrapolation::Refuse).unwrap().length_mm()
    );
    let tilted = Press::from_degrees(15.0, 20.0, 0.0);
    assert!(p.predict(&tilted, Extrapolation::Refuse).unwrap_err().to_string().contains("alpha_rad"));
}

#[test]
fn inverse_model_round_trips_and_clamps() {
    let p = BrushProfile::builtin("pen1").unwrap();
    let a = 4f64.to_radians();
    let f = p.predict(&Press::new(14.5, a, 0.0), Extrapolation::Refuse).unwrap();
    let inv = p.h_for_half_width(f.lr_mm, a, 0.0).unwrap();
    assert_eq!(inv.clamped, Clamp::None);
    assert!((inv.h_mm - 14.5).abs() < 1e-9);
    let wide = p.h_for_half_width(50.0, a, 0.0).unwrap();
    assert_eq!((wide.clamped, wide.h_mm), (Clamp::Max, 20.0));
    assert!(wide.exact_h_mm > 20.0);
    let thin = p.h_for_half_width(0.1, a, 0.0).unwrap();
    assert_eq!((thin.clamped, thin.h_mm), (Clamp::Min, 11.0));
}

fn pen1_json() -> serde_json::Value {
    serde_json::from_str(&BrushProfile::builtin("pen1").unwrap().to_json()).unwrap()
}

/// The error and its causes, joined as `anyhow` prints them with `{:#}`.
fn chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        s += &format!(": {c}");
        cause = c.source();
    }
    s
}

#[test]
fn loading_names_what_is_wrong() {
    let mut v = pen1_json();
    v.as_object_mut().unwrap().remove("ranges");
    let e = BrushProfile::from_json(&v.to_string(), "p.json").unwrap_err();
    let msg = chain(&e);
    assert!(msg.contains("p.json") && msg.contains("ranges"), "{msg}");

    let mut v = pen1_json();
    v["brush"]["radius_mm"] = serde_json::json!(-6.0);
    let e = BrushProfile::from_json(&v.to_string(), "p.json").unwrap_err();
    assert!(e.to_string().contains("brush.radius_mm"), "{e}");

    let mut v = pen1_json();
    v["ranges"]["h_mm"] = serde_json::json!({"min": 20.0, "max": 11.0});
    let e = BrushProfile::from_json(&v.to_string(), "p.json").unwrap_err();
    assert!(e.to_string().contains("ranges.h_mm") && e.to_string().contains("empty"), "{e}");

    let mut v = pen1_json();
    v["version"] = serde_json::json!(99);
    assert!(BrushProfile::from_json(&v.to_string(), "p.json").unwrap_err().to_string().contains("version"));

    let mut v = pen1_json();
    v["model"]["lr_mm"]["intercept"] = serde_json::json!(-100.0);
    let e = BrushProfile::from_json(&v.to_string(), "p.json").unwrap_err();
    assert!(e.to_string().contains("model.lr_mm"), "{e}");

    let e = BrushProfile::from_json("{ not json", "p.json").unwrap_err();
    assert!(matches!(e, ProfileError::Json { .. }));
    let e = BrushProfile::load(std::path::Path::new("/nonexistent/p.json")).unwrap_err();
    assert!(e.to_string().contains("/nonexistent/p.json"));
    // The I/O error is kept as the cause.
    let io = std::error::Error::source(&e).and_then(|c| c.downcast_ref::<std::io::Error>());
    assert_eq!(io.map(std::io::Error::kind), Some(std::io::ErrorKind::NotFound), "{}", chain(&e));
}

#[test]
fn oriented_prediction_ignores_the_writing_direction() {
    let p = BrushProfile::builtin("pen1").unwrap();
    let base = p.predict(&Press::from_degrees(15.0, 5.0, 0.0), Extrapolation::Refuse).unwrap();
    for beta in [-170.0, -90.0, 0.0, 45.0, 180.0, 400.0] {
        let f = p.predict_oriented(&Press::from_degrees(15.0, 5.0, beta), Extrapolation::Refuse).unwrap();
        assert_eq!(f, base, "beta {beta}");
    }
    // h is still checked.
    assert!(p.predict_oriented(&Press::from_degrees(25.0, 5.0, 90.0), Extrapolation::Refuse).is_err());
}

/// A version 1 profile (no `hairs`) still reads, with the nominal hair motion, and comes back as
/// the current version; bad hair values are named.
#[test]
fn version_1_profiles_read_with_nominal_hairs() {
    use brush_model::{HairMotion, PROFILE_VERSION};
    let mut v = pen1_json();
    assert_eq!(v["version"], serde_json::json!(PROFILE_VERSION));
    assert_eq!(v["hairs"]["contact_h_mm"], serde_json::json!(brush_model::CONTACT_H_MM));
    v.as_object_mut().unwrap().remove("hairs");
    v["version"] = serde_json::json!(1);
    let p = BrushProfile::from_json(&v.to_string(), "old.json").unwrap();
    assert_eq!((p.version, p.hairs), (PROFILE_VERSION, HairMotion::NOMINAL));
    assert_eq!(p, BrushProfile::builtin("pen1").unwrap());
    // One field of the two given: the other takes its nominal value.
    let mut v = pen1_json();
    v["hairs"] = serde_json::json!({"trail_reach": 0.3});
    let p = BrushProfile::from_json(&v.to_string(), "p.json").unwrap();
    assert_eq!((p.hairs.trail_reach, p.hairs.contact_h_mm), (0.3, brush_model::CONTACT_H_MM));
    for (field, bad) in [("trail_reach", 0.0), ("trail_reach", 1.5), ("contact_h_mm", -0.1), ("contact_h_mm", 60.0)] {
        let mut v = pen1_json();
        v["hairs"][field] = serde_json::json!(bad);
        let e = BrushProfile::from_json(&v.to_string(), "p.json").unwrap_err();
        assert!(e.to_string().contains(&format!("hairs.{field}")), "{e}");
    }
    let mut v = pen1_json();
    v["hairs"]["stiffness"] = serde_json::json!(1.0);
    let e = BrushProfile::from_json(&v.to_string(), "p.json").unwrap_err();
    assert!(chain(&e).contains("stiffness"), "{}", chain(&e));
}
