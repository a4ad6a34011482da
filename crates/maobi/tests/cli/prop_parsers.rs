//! Property tests over every parser and the numeric flags (issue 18): random measurement CSVs,
//! brush profiles, hanzi-writer-data JSON and SVG paths, paper/robot/track files, generator
//! architectures, and CLI numbers never panic, finish in bounded time, and whatever they accept
//! stays inside the documented caps (which is what bounds allocation downstream).
//!
//! Case counts are small: CI runs on 2 cores. The fuzz targets in `fuzz/` (docs/testing.md)
//! explore the same parsers far longer.

use std::time::{Duration, Instant};

use brush_model::{BrushProfile, Extrapolation, read_measurements};
use proptest::prelude::*;
use trajectory::{GlyphSource, limits, parse_hanzi_json};

/// Numbers as a careless file would hold them: ordinary, huge, tiny, negative, not finite.
fn wild_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => -50.0f64..200.0,
        1 => any::<f64>(),
        1 => prop::sample::select(vec![0.0, -0.0, 1e-300, 1e300, -1e300, 1e308, 1e7, f64::MAX, f64::MIN_POSITIVE]),
    ]
}

/// The same as text, with the spellings Rust and serde accept or refuse.
fn wild_token() -> impl Strategy<Value = String> {
    prop_oneof![
        6 => wild_f64().prop_map(|v| v.to_string()),
        1 => prop::sample::select(vec!["NaN", "inf", "-inf", "", "1e308", "1e309", "abc", "0x10", "\"1\""]).prop_map(str::to_string),
    ]
}

/// A glyph coordinate: mostly in and around the em box, sometimes wild.
fn coord() -> impl Strategy<Value = f64> {
    prop_oneof![8 => -100.0f64..1100.0, 1 => wild_f64()]
}

/// One SVG path segment, mostly well formed, with mostly sensible numbers.
fn svg_segment() -> impl Strategy<Value = String> {
    let n = coord;
    prop_oneof![
        3 => (n(), n()).prop_map(|(x, y)| format!("L {x} {y} ")),
        1 => (n(), n()).prop_map(|(x, y)| format!("M {x} {y} ")),
        2 => (n(), n(), n(), n()).prop_map(|(a, b, x, y)| format!("Q {a} {b} {x} {y} ")),
        2 => (n(), n(), n(), n(), n(), n()).prop_map(|(a, b, c, d, x, y)| format!("C {a} {b} {c} {d} {x} {y} ")),
        1 => (wild_f64(), wild_f64(), n(), n()).prop_map(|(rx, ry, x, y)| format!("A {rx} {ry} 0 0 1 {x} {y} ")),
        1 => Just("Z ".to_string()),
        1 => "[MLQCZAHV0-9 .,eE+-]{0,12}",
    ]
}

fn pen1_json() -> serde_json::Value {
    serde_json::from_str(&BrushProfile::builtin("pen1").unwrap().to_json()).unwrap()
}

/// Sets the number at `path` (a JSON pointer) to `v`; JSON cannot hold NaN or ±inf, so those
/// become strings (a type error the parser must report).
fn set(doc: &mut serde_json::Value, path: &str, v: f64) {
    if let Some(slot) = doc.pointer_mut(path) {
        *slot =
            serde_json::Number::from_f64(v).map_or_else(|| serde_json::json!(v.to_string()), serde_json::Value::Number);
    }
}

const PROFILE_NUMBERS: [&str; 14] = [
    "/brush/length_mm",
    "/brush/radius_mm",
    "/ranges/h_mm/min",
    "/ranges/h_mm/max",
    "/ranges/alpha_rad/min",
    "/ranges/alpha_rad/max",
    "/ranges/beta_rad/min",
    "/ranges/beta_rad/max",
    "/model/lt_mm/intercept",
    "/model/lt_mm/h_mm",
    "/model/lt_mm/alpha_rad",
    "/model/lh_mm/h_mm",
    "/model/lr_mm/h_mm",
    "/model/lr_mm/alpha_rad",
];

/// Whatever a profile parser accepts predicts bounded, positive footprints everywhere in its
/// range, and the canvas built from it has a finite, positive scale.
fn check_accepted_profile(p: &BrushProfile) {
    assert!(p.brush.length_mm <= brush_model::MAX_BRUSH_MM);
    for c in p.ranges.corners() {
        let f = p.predict(&c, Extrapolation::Refuse).expect("a validated profile predicts at its corners");
        for v in [f.lt_mm, f.lh_mm, f.lr_mm] {
            assert!(v > 0.0 && v <= p.max_footprint_mm(), "{v}");
        }
    }
    let canvas = bezier_raster::StrokeCanvas::for_profile(p, 64);
    assert!(canvas.px_per_mm.is_finite() && canvas.px_per_mm > 0.0);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn measurement_csv_never_panics_and_accepts_only_bounded_rows(
        rows in prop::collection::vec(prop::collection::vec(wild_token(), 6), 0..12),
        junk in "[ -~\n,\"]{0,80}",
    ) {
        let mut text = String::from("h_mm,alpha_deg,beta_deg,lt_mm,lh_mm,lr_mm\n");
        for r in &rows {
            text.push_str(&r.join(","));
            text.push('\n');
        }
        let t0 = Instant::now();
        let _ = read_measurements(junk.as_bytes(), "junk.csv");
        if let Ok(m) = read_measurements(text.as_bytes(), "m.csv") {
            for r in &m {
                prop_assert!((0.0..=1000.0).contains(&r.press.h_mm));
                prop_assert!(r.press.alpha_rad.abs() <= std::f64::consts::FRAC_PI_2 + 1e-12);
                prop_assert!(r.footprint.lt_mm > 0.0 && r.footprint.lt_mm <= 2000.0);
            }
            for form in [brush_model::Form::General, brush_model::Form::Paper] {
                if let Ok(rep) = brush_model::fit(&m, form) {
                    for o in rep.outputs.values() {
                        prop_assert!(o.r2.is_nan() || o.r2 <= 1.0 + 1e-9, "R² {}", o.r2);
                    }
                    // The calibrated profile either validates (and is bounded) or is refused.
                    let brush = brush_model::Brush { length_mm: 48.0, radius_mm: 6.0 };
                    let span = |f: fn(&brush_model::Measurement) -> f64| {
                        let lo = m.iter().map(f).fold(f64::INFINITY, f64::min);
                        let hi = m.iter().map(f).fold(f64::NEG_INFINITY, f64::max);
                        brush_model::Range::new(lo, hi)
                    };
                    let ranges = brush_model::PressRanges {
                        h_mm: span(|m| m.press.h_mm),
                        alpha_rad: span(|m| m.press.alpha_rad),
                        beta_rad: span(|m| m.press.beta_rad),
                    };
                    let p = BrushProfile::calibrated("p", brush, ranges, rep);
                    if p.validate("p").is_ok() {
                        check_accepted_profile(&p);
                    }
                }
            }
        }
        prop_assert!(t0.elapsed() < Duration::from_secs(5));
    }

    #[test]
    fn profile_json_never_panics_and_accepts_only_bounded_models(
        edits in prop::collection::vec((0..PROFILE_NUMBERS.len(), wild_f64()), 1..4),
        bytes in prop::collection::vec(any::<u8>(), 0..64),
    ) {
        let _ = BrushProfile::from_json(&String::from_utf8_lossy(&bytes), "bytes");
        let mut doc = pen1_json();
        for (i, v) in edits {
            set(&mut doc, PROFILE_NUMBERS[i], v);
        }
        let t0 = Instant::now();
        if let Ok(p) = BrushProfile::from_json(&doc.to_string(), "p.json") {
            check_accepted_profile(&p);
        }
        prop_assert!(t0.elapsed() < Duration::from_secs(2));
    }

    #[test]
    fn hanzi_json_and_svg_paths_never_panic_and_accepted_glyphs_stay_in_the_window(
        medians in prop::collection::vec(prop::collection::vec((coord(), coord()), 0..6), 1..4),
        path in prop::collection::vec(svg_segment(), 0..10),
        junk in prop::option::weighted(0.2, "[MLQCZmlqcz0-9 .,eE+-]{0,40}"),
    ) {
        // "M" first most of the time, so that many paths parse and the glyph gets analysed.
        let svg = format!("M 100 100 {}", path.concat());
        let meds: Vec<Vec<serde_json::Value>> = medians
            .iter()
            .map(|m| m.iter().map(|&(x, y)| serde_json::json!([x, y])).collect())
            .collect();
        let strokes: Vec<String> =
            (0..meds.len()).map(|i| if i == 1 { junk.clone().unwrap_or_else(|| svg.clone()) } else { svg.clone() }).collect();
        let doc = serde_json::json!({"strokes": strokes, "medians": meds}).to_string();
        let t0 = Instant::now();
        let parsed = parse_hanzi_json('永', &doc, GlyphSource::Embedded, "t.json");
        if let Ok(g) = parsed {
            for m in g.medians.as_ref().unwrap() {
                prop_assert!(m.len() <= limits::MAX_MEDIAN_POINTS);
                for p in m {
                    prop_assert!(p.x.abs() <= 4096.0 && p.y.abs() <= 4096.0);
                }
            }
            // The whole analysis of an accepted glyph finishes (small raster: CI budget).
            let _ = trajectory::centre_lines(&g, trajectory::Method::Medians, 64);
        }
        prop_assert!(t0.elapsed() < Duration::from_secs(10), "took {:?}", t0.elapsed());
    }

    #[test]
    fn generator_architectures_are_bounded_before_anything_is_allocated(
        hidden in prop::collection::vec(0usize..100_000, 0..20),
        seed_channels in 0usize..10_000,
        seed_side in 0usize..200,
        stages in prop::collection::vec((0usize..10_000, 0usize..10_000), 0..70),
    ) {
        let arch = neural_gen::Arch { hidden, seed_channels, seed_side, stages };
        if arch.validate().is_ok() {
            prop_assert!(arch.parameter_count() <= 50_000_000);
            prop_assert!(arch.output_side() <= 1024);
        }
    }
}

/// Robot files: the paper frame, the robot settings and track.json.
mod robot_files {
    use super::*;

    fn robot_json() -> serde_json::Value {
        serde_json::from_str(
            &std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/robot/robot.json")).unwrap(),
        )
        .unwrap()
    }

    fn paper_json() -> serde_json::Value {
        serde_json::from_str(
            &std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/robot/paper.json")).unwrap(),
        )
        .unwrap()
    }

    /// Every number in a JSON document, as pointers.
    fn number_paths(v: &serde_json::Value, at: String, out: &mut Vec<String>) {
        match v {
            serde_json::Value::Number(_) => out.push(at),
            serde_json::Value::Array(a) => {
                a.iter().enumerate().for_each(|(i, x)| number_paths(x, format!("{at}/{i}"), out))
            }
            serde_json::Value::Object(o) => o.iter().for_each(|(k, x)| number_paths(x, format!("{at}/{k}"), out)),
            _ => {}
        }
    }

    fn mutate(mut doc: serde_json::Value, edits: &[(usize, f64)]) -> serde_json::Value {
        let mut paths = Vec::new();
        number_paths(&doc, String::new(), &mut paths);
        for &(i, v) in edits {
            let p = &paths[i % paths.len()];
            set(&mut doc, p, v);
        }
        doc
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 32, failure_persistence: None, ..ProptestConfig::default() })]

        #[test]
        fn paper_robot_and_track_files_never_panic(
            paper_edits in prop::collection::vec((any::<usize>(), wild_f64()), 0..4),
            robot_edits in prop::collection::vec((any::<usize>(), wild_f64()), 0..4),
            points in prop::collection::vec((wild_f64(), wild_f64(), wild_f64(), wild_f64(), wild_f64()), 0..6),
        ) {
            let dir = tempfile::tempdir().unwrap();
            let (pp, rp, tp) = (dir.path().join("paper.json"), dir.path().join("robot.json"), dir.path().join("track.json"));
            std::fs::write(&pp, mutate(paper_json(), &paper_edits).to_string()).unwrap();
            std::fs::write(&rp, mutate(robot_json(), &robot_edits).to_string()).unwrap();
            let pts: Vec<serde_json::Value> = points
                .iter()
                .map(|&(x, y, h, a, b)| {
                    let n = |v: f64| serde_json::Number::from_f64(v).map_or(serde_json::json!(0.0), serde_json::Value::Number);
                    serde_json::json!({"x_mm": n(x), "y_mm": n(y), "h_mm": n(h), "alpha_rad": n(a), "beta_rad": n(b)})
                })
                .collect();
            let track = serde_json::json!({"char": "永", "brush": pen1_json(), "strokes": [{"points": pts}]});
            std::fs::write(&tp, track.to_string()).unwrap();
            let t0 = Instant::now();
            let frame = robot_io::PaperFrame::load(&pp);
            let cfg = robot_io::RobotConfig::load(&rp);
            let tf = robot_io::TrackFile::load(&tp);
            if let (Ok(frame), Ok(cfg), Ok(tf)) = (frame, cfg, tf) {
                let _ = robot_io::build_program(&tf.track(), &tf.brush, &frame, &cfg);
            }
            prop_assert!(t0.elapsed() < Duration::from_secs(10), "took {:?}", t0.elapsed());
        }
    }
}

/// Numeric flags through the real binary: any number, however spelt, ends in success or a
/// one-line error (exit 2), never a panic (exit 101) or a hang.
mod flags {
    use super::*;
    use crate::common::maobi;

    fn flag_value() -> impl Strategy<Value = String> {
        prop_oneof![
            3 => wild_f64().prop_map(|v| v.to_string()),
            1 => prop::sample::select(vec!["NaN", "inf", "-inf", "1e-30", "1e300", "-0", "4294967296", "-1"]).prop_map(str::to_string),
        ]
    }

    fn clean_exit(args: &[&str]) -> Result<(), TestCaseError> {
        let t0 = Instant::now();
        let o = maobi(args);
        let e = String::from_utf8_lossy(&o.stderr);
        prop_assert!(matches!(o.status.code(), Some(0) | Some(2)), "{args:?}: {:?} {e}", o.status.code());
        prop_assert!(!e.contains("panicked"), "{args:?}: {e}");
        if o.status.code() == Some(2) {
            prop_assert_eq!(e.trim_end().lines().count(), 1, "{:?}: {}", args, e);
        }
        prop_assert!(t0.elapsed() < Duration::from_secs(60), "{args:?} took {:?}", t0.elapsed());
        Ok(())
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 12, failure_persistence: None, ..ProptestConfig::default() })]

        #[test]
        fn press_flags(h in flag_value(), a in flag_value(), b in flag_value(), extrapolate in any::<bool>()) {
            let mut args = vec!["footprint", "--h", &h, "--alpha", &a, "--beta", &b, "--json"];
            if extrapolate {
                args.push("--extrapolate");
            }
            clean_exit(&args)?;
        }

        #[test]
        fn image_size_and_scale_flags(size in prop::sample::select(vec!["0", "7", "64", "8192", "70000", "-5", "1e3"]), scale in flag_value()) {
            let dir = tempfile::tempdir().unwrap();
            let out = dir.path().join("fp.svg");
            clean_exit(&["stroke", "--h", "15", "--alpha", "5", "--size", size, "--px-per-mm", &scale, "-o", out.to_str().unwrap()])?;
            clean_exit(&["models", "--n", "3", "--size", size])?;
        }

        #[test]
        fn stroke_labels_csv(rows in prop::collection::vec(prop::collection::vec(wild_token(), 5), 0..4), junk in "[ -~\n,]{0,60}") {
            // The labels parser of `models --reference` and `calibrate --images` (in the binary).
            let dir = tempfile::tempdir().unwrap();
            std::fs::copy(
                concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/photos/stroke_01.png"),
                dir.path().join("a.png"),
            )
            .unwrap();
            let mut text = String::from("file,h_mm,alpha_deg,beta_deg,px_per_mm\n");
            for r in &rows {
                text.push_str(&format!("a.png,{}\n", r[..4].join(",")));
            }
            text.push_str(&junk);
            std::fs::write(dir.path().join("labels.csv"), text).unwrap();
            clean_exit(&["models", "--reference", dir.path().to_str().unwrap()])?;
        }

        #[test]
        fn write_flags(char_mm in flag_value(), per_line in prop::sample::select(vec!["0", "1", "2", "1000000"])) {
            let dir = tempfile::tempdir().unwrap();
            let out = dir.path().join("w");
            clean_exit(&["write", "十口", "--size", "64", "--char-mm", &char_mm, "--per-line", per_line, "--out", out.to_str().unwrap()])?;
        }
    }
}
