//! Track building on synthetic glyphs with known geometry, and on embedded characters.

use bezier_raster::{render_track, ModelKind};
use brush_model::{BrushProfile, Extrapolation, PointMm};
use kurbo::{BezPath, Point, Rect, Shape as _};
use trajectory::{build_track, centre_lines, glyph, raster, CharBox, Glyph, GlyphSource, Method, Shape, Sizing, TrackOptions};

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
    let img = render_track(&built.track, &pen1, ModelKind::Bsm.model(), Extrapolation::Refuse, PointMm::new(0.0, 0.0), 512.0 / size_mm, 512, 512).unwrap();
    // Column through the middle of the bar: ink height ≈ 100 em = 50 px.
    let ink: f64 = (0..512).map(|y| img.get(256, y) as f64).sum();
    assert!((ink - 50.0).abs() < 3.0, "column ink {ink}");
    let reference = raster::render_glyph(&g, 512);
    let iou = stroke_metrics::iou(
        stroke_metrics::GrayRef::new(reference.data(), 512, 512).unwrap(),
        stroke_metrics::GrayRef::new(img.data(), 512, 512).unwrap(),
    )
    .unwrap();
    // The ends are square in the glyph and rounded by the footprints: IoU stays below 1.
    assert!(iou > 0.8, "IoU {iou}");
}

#[test]
fn every_embedded_test_character_parses() {
    for ch in "永字八法十口人丁".chars() {
        let g = glyph::embedded(ch).unwrap();
        let m = g.medians.as_ref().unwrap();
        assert_eq!(m.len(), g.stroke_outlines.as_ref().unwrap().len());
        for line in m {
            for p in line {
                assert!((-150.0..1200.0).contains(&p.x) && (-150.0..1200.0).contains(&p.y), "{ch}: {p:?}");
            }
        }
    }
    assert!(glyph::embedded_chars().len() >= 1000);
    assert!(glyph::embedded('\u{10FFFF}').is_err());
}
