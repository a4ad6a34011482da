//! Track building on synthetic glyphs with known geometry, and on embedded characters.

use bezier_raster::{ModelKind, render_track};
use brush_model::{BrushProfile, Extrapolation, PointMm};
use kurbo::{BezPath, Point, Rect, Shape as _};
use trajectory::{
    CharBox, DEFAULT_SPACING_MM, Glyph, GlyphSource, Method, Shape, Sizing, TrackOptions, build_track, centre_lines,
    embedded_chars, embedded_glyph, glyph_from_hanzi_dir, render_glyph,
};

fn bar_glyph(x0: f64, x1: f64, y0: f64, y1: f64) -> Glyph {
    let outline: BezPath = Rect::new(x0, y0, x1, y1).to_path(0.1);
    let ym = 0.5 * (y0 + y1);
    Glyph {
        ch: '一',
        source: GlyphSource::Embedded,
        shape: Shape::Outlines(vec![outline.clone()]),
        stroke_outlines: Some(vec![outline]),
        // A hand-drawn median, off-centre by 10 em units.
        medians: Some(vec![vec![Point::new(x0 + 20.0, ym + 10.0), Point::new(x1 - 20.0, ym + 10.0)]]),
    }
}

#[test]
fn half_widths_come_from_the_ridge() {
    let g = bar_glyph(100.0, 900.0, 440.0, 540.0);
    let paths = centre_lines(&g, Method::Medians, 256).unwrap();
    let p = &paths[0];
    let mid = p.points.len() / 2;
    assert!((p.points[mid].y - 490.0).abs() < 4.0, "re-centred onto the ridge: {}", p.points[mid].y);
    assert!((p.half_widths[mid] - 50.0).abs() < 4.0, "half-width {}", p.half_widths[mid]);
}

#[test]
fn a_bar_is_written_at_its_own_width() {
    let g = bar_glyph(100.0, 900.0, 440.0, 540.0);
    let paths = centre_lines(&g, Method::Medians, 256).unwrap();
    let pen1 = BrushProfile::builtin("pen1").unwrap();
    // 100 em wide bar; choose the box so that this is a mid-range width (2·lr = 6 mm).
    let size_mm = 6.0 / 100.0 * 1024.0;
    let b = CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm };
    let opts = TrackOptions { char_box: b, spacing_mm: 0.25, alpha_rad: 0.0, sizing: Sizing::Brush };
    let built = build_track(&paths, &pen1, &opts).unwrap();
    let img = render_track(
        &built.track,
        &pen1,
        ModelKind::Bsm.model(),
        Extrapolation::Refuse,
        PointMm::new(0.0, 0.0),
        512.0 / size_mm,
        512,
        512,
    )
    .unwrap();
    // Column through the middle of the bar: ink height ≈ 100 em = 50 px.
    let ink: f64 = (0..512).map(|y| img.get(256, y) as f64).sum();
    assert!((ink - 50.0).abs() < 3.0, "column ink {ink}");
    let reference = render_glyph(&g, 512);
    let iou = stroke_metrics::iou(reference.as_gray(), img.as_gray()).unwrap();
    // The ends are square in the glyph and rounded by the footprints: IoU stays below 1.
    assert!(iou > 0.8, "IoU {iou}");
}

#[test]
fn every_embedded_test_character_parses() {
    for ch in "永字八法十口人丁".chars() {
        let g = embedded_glyph(ch).unwrap();
        let m = g.medians.as_ref().unwrap();
        assert_eq!(m.len(), g.stroke_outlines.as_ref().unwrap().len());
        for line in m {
            for p in line {
                assert!((-150.0..1200.0).contains(&p.x) && (-150.0..1200.0).contains(&p.y), "{ch}: {p:?}");
            }
        }
    }
    assert!(embedded_chars().len() >= 1000);
    assert!(embedded_glyph('\u{10FFFF}').is_err());
}

#[test]
fn halving_the_spacing_changes_the_render_by_under_half_a_percent() {
    let pen1 = BrushProfile::builtin("pen1").unwrap();
    for ch in "永法".chars() {
        let g = embedded_glyph(ch).unwrap();
        let paths = centre_lines(&g, Method::Medians, 256).unwrap();
        let mm = trajectory::auto_char_mm(&paths, &pen1, 0.0);
        let b = CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm: mm };
        let render = |spacing: f64| {
            let opts = TrackOptions { char_box: b, spacing_mm: spacing, alpha_rad: 0.0, sizing: Sizing::Brush };
            let t = build_track(&paths, &pen1, &opts).unwrap().track;
            render_track(
                &t,
                &pen1,
                ModelKind::Bsm.model(),
                Extrapolation::Refuse,
                PointMm::new(0.0, 0.0),
                512.0 / mm,
                512,
                512,
            )
            .unwrap()
        };
        let (a, b2) = (render(trajectory::DEFAULT_SPACING_MM), render(trajectory::DEFAULT_SPACING_MM / 2.0));
        let iou = stroke_metrics::iou(a.as_gray(), b2.as_gray()).unwrap();
        assert!(iou > 0.995, "{ch}: IoU between spacings {iou}");
    }
}

/// The character's line of the frequency subset (`data/hanzi-subset.jsonl`), a
/// hanzi-writer-data file with the character added.
fn subset_line(ch: char) -> String {
    let subset = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/data/hanzi-subset.jsonl")).unwrap();
    subset.lines().find(|l| l.starts_with(&format!("{{\"c\":\"{ch}\""))).unwrap().to_string()
}

#[test]
fn hanzi_folders_and_malformed_data() {
    let dir = std::env::temp_dir().join(format!("maobi-hanzi-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("十.json"), subset_line('十')).unwrap();
    let g = glyph_from_hanzi_dir(&dir, '十').unwrap();
    assert_eq!(g.medians.unwrap().len(), 2);
    assert!(matches!(glyph_from_hanzi_dir(&dir, '口'), Err(trajectory::GlyphError::Unknown { .. })));
    std::fs::write(dir.join("口.json"), r#"{"strokes": ["M 0 0 L 10 10 Z"], "medians": []}"#).unwrap();
    let e = glyph_from_hanzi_dir(&dir, '口').unwrap_err().to_string();
    assert!(e.contains("口.json") && e.contains("1 strokes but 0 medians"), "{e}");
    std::fs::write(dir.join("口.json"), r#"{"strokes": ["M 0 0 X"], "medians": [[[0, 0]]]}"#).unwrap();
    let e = glyph_from_hanzi_dir(&dir, '口').unwrap_err().to_string();
    assert!(e.contains("stroke 1: bad SVG path"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn em_frame_follows_the_design_notes() {
    // Make Me a Hanzi's (x, y) with y up maps to (x, 900 − y).
    let g = embedded_glyph('十').unwrap();
    let raw: serde_json::Value = serde_json::from_str(&subset_line('十')).unwrap();
    let (x, y) = (raw["medians"][0][0][0].as_f64().unwrap(), raw["medians"][0][0][1].as_f64().unwrap());
    let p = g.medians.unwrap()[0][0];
    assert_eq!((p.x, p.y), (x, 900.0 - y));
}

/// A 横折 (one stroke: right, then down) with a square outer corner at (600, 200).
fn corner_glyph() -> Glyph {
    let mut outline = Rect::new(100.0, 200.0, 600.0, 280.0).to_path(0.1);
    outline.extend(Rect::new(520.0, 200.0, 600.0, 800.0).to_path(0.1));
    Glyph {
        ch: '㇕',
        source: GlyphSource::Embedded,
        shape: Shape::Outlines(vec![outline.clone()]),
        stroke_outlines: Some(vec![outline]),
        medians: Some(vec![vec![Point::new(120.0, 240.0), Point::new(560.0, 240.0), Point::new(560.0, 780.0)]]),
    }
}

#[test]
fn corners_are_found_on_sharp_turns_only() {
    let line = |pts: &[(f64, f64)]| -> Vec<Point> {
        let mut out = Vec::new();
        for w in pts.windows(2) {
            for i in 0..25 {
                let t = i as f64 / 25.0;
                out.push(Point::new(w[0].0 + t * (w[1].0 - w[0].0), w[0].1 + t * (w[1].1 - w[0].1)));
            }
        }
        out.push(Point::new(pts[pts.len() - 1].0, pts[pts.len() - 1].1));
        out
    };
    let l = line(&[(0.0, 0.0), (400.0, 0.0), (400.0, 400.0)]);
    assert_eq!(trajectory::find_corners(&l), vec![25], "one corner, at the bend");
    assert!(trajectory::find_corners(&line(&[(0.0, 0.0), (800.0, 0.0)])).is_empty());
    // A gentle bend (20°) is not a corner.
    let gentle = line(&[(0.0, 0.0), (400.0, 0.0), (776.0, 137.0)]);
    assert!(trajectory::find_corners(&gentle).is_empty());
}

#[test]
fn corner_knobs_reach_into_the_outer_corner() {
    let g = corner_glyph();
    let paths = centre_lines(&g, Method::Medians, 256).unwrap();
    let p = &paths[0];
    assert_eq!(p.corners.len(), 1, "corners {:?}", p.corners);
    let tip = p.points[p.corners[0]];
    // The centre-line corner is near (560, 240); the knob runs out towards (600, 200) and stays
    // inside the glyph.
    assert!(tip.x > 568.0 && tip.y < 232.0, "knob tip {tip:?}");
    assert!(tip.x < 600.0 && tip.y > 200.0, "knob tip {tip:?} left the glyph");
    // The stroke is written as two pieces: the second starts at the tip with an entry press.
    let pen1 = BrushProfile::builtin("pen1").unwrap();
    let b = CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm: 6.0 / 80.0 * 1024.0 };
    let opts = TrackOptions { char_box: b, spacing_mm: 0.25, alpha_rad: 0.0, sizing: Sizing::Brush };
    let t = build_track(&paths, &pen1, &opts).unwrap().track;
    // Pressed at the tip: the end of the first piece, and the end of the second piece's reverse
    // entry (it presses back to the tip before turning over).
    let starts = t.strokes[0]
        .points
        .iter()
        .filter(|q| q.h_mm >= pen1.ranges.h_mm.min && b.to_em(q.anchor()).distance(tip) < 1e-6)
        .count();
    assert_eq!(starts, 2, "the first piece ends and the second's entry ends at the knob tip");
}

#[test]
fn the_reverse_entry_moves_backwards_at_full_width_then_writes_forwards() {
    let g = bar_glyph(100.0, 900.0, 440.0, 540.0);
    let paths = centre_lines(&g, Method::Medians, 256).unwrap();
    let pen1 = BrushProfile::builtin("pen1").unwrap();
    let b = CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm: 6.0 / 100.0 * 1024.0 };
    let opts = TrackOptions { char_box: b, spacing_mm: 0.25, alpha_rad: 0.0, sizing: Sizing::Brush };
    let pts = &build_track(&paths, &pen1, &opts).unwrap().track.strokes[0].points;
    let body_h = pts[pts.len() - pts.len() / 4].h_mm;
    // Written left to right: it touches down inside the bar and presses back to the left end, the
    // tip ahead (β ≈ 0) because the hairs trail the backward motion.
    let entry: Vec<_> = pts.iter().take_while(|q| q.h_mm >= pen1.ranges.h_mm.min).collect();
    assert!(entry.len() > 10, "{} entry presses", entry.len());
    assert!(entry.windows(2).all(|w| w[1].x_mm < w[0].x_mm), "the entry moves backwards");
    assert!(entry.iter().all(|q| q.beta_rad.cos() > 0.9), "the tip points ahead during the entry");
    for q in &entry[1..entry.len() - 1] {
        assert!((q.h_mm - body_h).abs() < 0.05 * body_h, "entry pressed at {} (body {body_h})", q.h_mm);
    }
    // Then it turns over pressed lightly (no footprint), and writes forwards with the hairs
    // trailing.
    let rest = &pts[entry.len()..];
    assert_eq!(rest[0].h_mm, trajectory::glide_h_mm(&pen1), "eases up before turning over");
    let last = pts[pts.len() - 1];
    assert!(last.x_mm > entry[0].x_mm && last.beta_rad.cos() < -0.9, "the body trails");
}

#[test]
fn a_track_holds_only_motion_the_forward_model_explains() {
    let pen1 = BrushProfile::builtin("pen1").unwrap();
    let g = embedded_glyph('永').unwrap();
    let paths = centre_lines(&g, Method::Medians, 256).unwrap();
    for alpha_deg in [0.0f64, 5.0] {
        let mm = trajectory::auto_char_mm(&paths, &pen1, alpha_deg.to_radians());
        let b = CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm: mm };
        let opts = TrackOptions {
            char_box: b,
            spacing_mm: DEFAULT_SPACING_MM,
            alpha_rad: alpha_deg.to_radians(),
            sizing: Sizing::Brush,
        };
        let t = build_track(&paths, &pen1, &opts).unwrap().track;
        let model = brush_model::ForwardModel::default();
        for s in &t.strokes {
            // No jumps: the brush never moves more than one spacing between two points while
            // it presses at either (the end station may stretch a piece's last step by up to a
            // twentieth of a spacing).
            for w in s.points.windows(2) {
                let d = w[0].anchor().distance(w[1].anchor());
                let pressed = w[0].h_mm >= pen1.ranges.h_mm.min || w[1].h_mm >= pen1.ranges.h_mm.min;
                assert!(!pressed || d <= 1.05 * DEFAULT_SPACING_MM + 1e-6, "a pressed jump of {d} mm at {alpha_deg}°");
            }
            // Every pressed point's β is what the forward model derives from the motion (tilt
            // below the threshold) or the lean it commands (above).
            let sweep = model.sweep(&pen1, &s.points, brush_model::Extrapolation::Refuse);
            for (p, d) in s.points.iter().zip(&sweep.directions) {
                if p.h_mm >= pen1.ranges.h_mm.min {
                    let d = d.expect("a pressed point has a direction");
                    assert!(brush_model::wrap_angle_rad(p.beta_rad - d).abs() < 1e-9, "β {} vs model {d}", p.beta_rad);
                }
            }
        }
    }
}

#[test]
fn a_piece_shorter_than_any_footprint_is_glided_into_so_its_head_trails_forward() {
    // A 5 mm piece along +x, a corner, then 40 mm the other way round (−y in the em frame).
    let (x0, y0) = (300.0, 600.0);
    let mut points: Vec<Point> = (0..=10).map(|i| Point::new(x0 + 5.0 * f64::from(i), y0)).collect();
    points.extend((1..=80).map(|i| Point::new(x0 + 50.0, y0 - 5.0 * f64::from(i))));
    let half_widths = vec![25.0; points.len()];
    let paths = vec![trajectory::StrokePath { points, half_widths, corners: vec![10] }];
    let pen1 = BrushProfile::builtin("pen1").unwrap();
    let b = CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm: 102.4 };
    let opts = TrackOptions { char_box: b, spacing_mm: DEFAULT_SPACING_MM, alpha_rad: 0.0, sizing: Sizing::Brush };
    let pts = &build_track(&paths, &pen1, &opts).unwrap().track.strokes[0].points;
    // The head is pressed once, at the lightest press, where the piece starts.
    let head = pts.iter().position(|q| q.h_mm >= pen1.ranges.h_mm.min).unwrap();
    let start = b.to_paper(Point::new(x0, y0));
    let end = b.to_paper(Point::new(x0 + 50.0, y0));
    assert!(pts[head].anchor().distance(start) < 1e-9, "{:?}", pts[head]);
    assert!(pts[head + 1].h_mm < pen1.ranges.h_mm.min, "a lone press");
    // Before it the brush glides back along the piece pressed lightly (never lifted, deeper than
    // its hairs need to follow the motion, lighter than any footprint), so the head's footprint
    // trails forward along the piece by the drag rule.
    let glide = trajectory::glide_h_mm(&pen1);
    assert!(glide > pen1.hairs.contact_h_mm && glide < pen1.ranges.h_mm.min);
    assert!(head > 2 && pts[..head].iter().all(|q| q.h_mm == glide), "{:?}", &pts[..head]);
    assert!(pts[0].anchor().distance(start) > 2.0, "the glide starts along the piece");
    let forward = (end.y_mm - start.y_mm).atan2(end.x_mm - start.x_mm);
    assert!(
        brush_model::wrap_angle_rad(pts[head].beta_rad - forward).abs() < 0.2,
        "β {} vs {forward}",
        pts[head].beta_rad
    );
}

/// pen1, 永's median centre lines and upright track options in its automatic box.
fn yong_upright() -> (BrushProfile, Vec<trajectory::StrokePath>, TrackOptions) {
    let pen1 = BrushProfile::builtin("pen1").unwrap();
    let paths = centre_lines(&embedded_glyph('永').unwrap(), Method::Medians, 256).unwrap();
    let mm = trajectory::auto_char_mm(&paths, &pen1, 0.0);
    let opts = TrackOptions {
        char_box: CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm: mm },
        spacing_mm: DEFAULT_SPACING_MM,
        alpha_rad: 0.0,
        sizing: Sizing::Brush,
    };
    (pen1, paths, opts)
}

#[test]
fn a_track_planned_with_another_trail_moves_the_same_way_and_points_as_that_trail_derives() {
    // 永 upright: the closed loop plans with the brush whose trailing reach it fitted to the
    // observed ink.
    let (pen1, paths, opts) = yong_upright();
    let own = build_track(&paths, &pen1, &opts).unwrap().track;
    let mut short = pen1.clone();
    short.hairs.trail_reach = 0.3;
    let t = build_track(&paths, &short, &opts).unwrap().track;
    let model = brush_model::ForwardModel::default();
    let mut turned = 0;
    for (s, o) in t.strokes.iter().zip(&own.strokes) {
        assert_eq!(s.points.len(), o.points.len());
        let sweep = model.sweep(&short, &s.points, Extrapolation::Refuse);
        for ((p, q), d) in s.points.iter().zip(&o.points).zip(&sweep.directions) {
            // The motion is the same: the trail only decides which way the footprints point.
            assert_eq!((p.x_mm, p.y_mm, p.h_mm, p.alpha_rad), (q.x_mm, q.y_mm, q.h_mm, q.alpha_rad));
            if p.h_mm >= pen1.ranges.h_mm.min {
                let d = d.expect("a pressed point has a direction");
                assert!(brush_model::wrap_angle_rad(p.beta_rad - d).abs() < 1e-9, "β {} vs model {d}", p.beta_rad);
                if brush_model::wrap_angle_rad(p.beta_rad - q.beta_rad).abs() > 1e-3 {
                    turned += 1;
                }
            }
        }
    }
    // Round the curves the tip 0.3 footprint lengths back points the footprints otherwise.
    assert!(turned > 10, "{turned} footprints turned");
}

/// The glides are pressed past the hairs' contact depth, so the footprints' directions do not
/// depend on what the hairs do below it: the track of a brush whose hairs follow only from
/// 1 mm (the nominal profile) points every footprint as the track of a brush whose hairs follow
/// any touch (contact 0, glides at 0.01 mm) does, and as the nominal brush would if its hairs
/// needed anything up to twice that (its track swept with hairs needing 1.9 mm).
#[test]
fn glides_pressed_past_the_contact_depth_point_every_footprint_as_any_touch_would() {
    let (pen1, paths, opts) = yong_upright();
    let with_contact = |c: f64| {
        let mut p = pen1.clone();
        p.hairs.contact_h_mm = c;
        p
    };
    let nominal = build_track(&paths, &pen1, &opts).unwrap().track;
    let touch = build_track(&paths, &with_contact(0.0), &opts).unwrap().track;
    let glide = trajectory::glide_h_mm(&pen1);
    let stiff = with_contact(0.95 * glide);
    let model = brush_model::ForwardModel::default();
    let mut glides = 0;
    for (n, t) in nominal.strokes.iter().zip(&touch.strokes) {
        assert_eq!(n.points.len(), t.points.len());
        let swept = model.sweep(&stiff, &n.points, Extrapolation::Refuse).directions;
        for ((p, q), d) in n.points.iter().zip(&t.points).zip(&swept) {
            assert_eq!((p.x_mm, p.y_mm), (q.x_mm, q.y_mm));
            if p.h_mm >= pen1.ranges.h_mm.min {
                assert_eq!(p.h_mm, q.h_mm);
                // (to a hundredth of a radian: where the brush comes down from the surface while
                // moving, the samples of the descent lighter than the contact depth do not
                // start the pressed path, which moves its start by a fraction of a spacing)
                let dd = brush_model::wrap_angle_rad(p.beta_rad - q.beta_rad).abs();
                assert!(dd < 0.01, "{dd} at {p:?} / {q:?}");
                let d = d.expect("a pressed point has a direction");
                assert!(brush_model::wrap_angle_rad(p.beta_rad - d).abs() < 0.01, "β {} vs {d}", p.beta_rad);
            } else if p.h_mm > 0.0 {
                // Every glide is pressed past the contact depth (0.01 mm for contact 0).
                assert_eq!((p.h_mm, q.h_mm), (glide, trajectory::GLIDE_H_MM));
                glides += 1;
            }
        }
    }
    assert!(glides > 100, "{glides} glide states");
    // Swept with hairs that need more than the glide gives, some footprints point otherwise.
    let stiffer = with_contact(1.05 * glide);
    let differs = nominal.strokes.iter().any(|n| {
        let a = model.sweep(&pen1, &n.points, Extrapolation::Refuse).directions;
        let b = model.sweep(&stiffer, &n.points, Extrapolation::Refuse).directions;
        a.iter().zip(&b).any(|(x, y)| match (x, y) {
            (Some(x), Some(y)) => brush_model::wrap_angle_rad(x - y).abs() > 0.1,
            _ => false,
        })
    });
    assert!(differs, "a glide lighter than the contact depth leaves the hairs unturned");
}
