//! Rendered footprints against the analytic invariants, the compositor, I/O and datasets.

use bezier_raster::{
    Bsm, Compositor, Coverage, DatasetSpec, ModelKind, Rasterizer, Stamp, StrokeCanvas, StrokeModel, render_batch,
};
use brush_model::{BrushProfile, Extrapolation, Footprint, PointMm, Press};
use proptest::prelude::*;

fn pen1() -> BrushProfile {
    BrushProfile::builtin("pen1").unwrap()
}

fn render(model: &dyn StrokeModel, fp: &Footprint, anchor: PointMm, beta: f64, s: f64, size: u32) -> Coverage {
    let mut img = Coverage::new(size, size);
    Rasterizer::new().render(model, fp, anchor, beta, s, &mut img);
    img
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Rendered ink equals the analytic area of every model to within 2 %.
    #[test]
    fn ink_equals_area(fh in 0.0f64..1.0, fa in 0.0f64..1.0, beta in -3.2f64..3.2) {
        let p = pen1();
        let press = Press::new(p.ranges.h_mm.lerp(fh), p.ranges.alpha_rad.lerp(fa), beta);
        let fp = p.predict(&press, Extrapolation::Allow).unwrap();
        let canvas = StrokeCanvas::for_profile(&p, 128);
        let s2 = canvas.px_per_mm * canvas.px_per_mm;
        let anchor = canvas.anchor_mm(&fp, beta);
        let len = fp.length_mm();
        let areas = [
            (ModelKind::Bsm, fp.area_mm2()),
            (ModelKind::Circle, std::f64::consts::PI * fp.lr_mm * fp.lr_mm),
            (ModelKind::Ellipse, std::f64::consts::PI * 0.5 * len * fp.lr_mm),
            (ModelKind::Line, len * 2.0 * fp.lr_mm),
        ];
        for (m, area) in areas {
            let img = render(m.model(), &fp, anchor, beta, canvas.px_per_mm, 128);
            let ink = img.ink();
            // tiny-skia's anti-aliasing samples 4×4 sub-pixels, so edge pixels are quantised;
            // over a whole footprint that stays within 2 % (docs/stroke-models.md).
            prop_assert!((ink - area * s2).abs() < 0.02 * area * s2, "{}: ink {} vs area {}", m.name(), ink, area * s2);
        }
    }

    /// The footprint is centred and fits on the default canvas at any rotation.
    #[test]
    fn fits_and_is_centred(fh in 0.0f64..1.0, fa in 0.0f64..1.0, beta in -3.2f64..3.2) {
        let p = pen1();
        let press = Press::new(p.ranges.h_mm.lerp(fh), p.ranges.alpha_rad.lerp(fa), beta);
        let fp = p.predict(&press, Extrapolation::Allow).unwrap();
        let canvas = StrokeCanvas::for_profile(&p, 96);
        let img = render(&Bsm, &fp, canvas.anchor_mm(&fp, beta), beta, canvas.px_per_mm, 96);
        let n = 96u32;
        let (mut x0, mut y0, mut x1, mut y1) = (n, n, 0, 0);
        for y in 0..n {
            for x in 0..n {
                if img.get(x, y) > 0.0 {
                    x0 = x0.min(x); y0 = y0.min(y); x1 = x1.max(x); y1 = y1.max(y);
                }
            }
        }
        prop_assert!(x0 > 0 && y0 > 0 && x1 < n - 1 && y1 < n - 1, "touches the border: {x0} {y0} {x1} {y1}");
        let (cx, cy) = ((x0 + x1 + 1) as f64 / 2.0, (y0 + y1 + 1) as f64 / 2.0);
        prop_assert!((cx - 48.0).abs() <= 1.0 && (cy - 48.0).abs() <= 1.0, "centre {cx} {cy}");
    }
}

#[test]
fn outline_is_mirror_symmetric_and_widest_at_the_belly() {
    // Axis along a pixel boundary (y = 32 px), beta = 0: rows mirror each other.
    let fp = Footprint::new(30.0, 12.0, 8.0).unwrap();
    let s = 1.0;
    let img = render(&Bsm, &fp, PointMm::new(10.0, 32.0), 0.0, s, 64);
    // tiny-skia samples 4 sub-scanlines per pixel, so an edge pixel and its mirror image can
    // differ by up to a quarter of a pixel's coverage; the halves' totals agree closely.
    let (mut top, mut bottom) = (0.0f64, 0.0f64);
    for y in 0..32 {
        for x in 0..64 {
            let (a, b) = (img.get(x, y), img.get(x, 63 - y));
            assert!((a - b).abs() <= 0.26, "({x},{y}): {a} vs {b}");
            top += a as f64;
            bottom += b as f64;
        }
    }
    assert!((top - bottom).abs() < 0.005 * top, "{top} vs {bottom}");
    // Column ink (the local width) peaks at x = anchor + lh and equals 2·lr there.
    let col = |x: u32| (0..64).map(|y| img.get(x, y) as f64).sum::<f64>();
    let widest = (0..64).max_by(|&a, &b| col(a).total_cmp(&col(b))).unwrap();
    assert!((widest as f64 + 0.5 - 22.0).abs() <= 1.5, "widest column {widest}");
    assert!((col(21) - 16.0).abs() < 0.2 && (col(22) - 16.0).abs() < 0.2, "{} {}", col(21), col(22));
    // The root end is at the anchor and the tip lh + lt further.
    let ink_cols: Vec<u32> = (0..64).filter(|&x| col(x) > 0.01).collect();
    assert_eq!((ink_cols[0], *ink_cols.last().unwrap()), (10, 51));
}

#[test]
fn compositing_is_a_per_pixel_max() {
    let fp = Footprint::new(10.0, 4.0, 3.0).unwrap();
    let a = Stamp { footprint: fp, anchor: PointMm::new(5.0, 10.0), beta_rad: 0.0 };
    let b = Stamp { footprint: fp, anchor: PointMm::new(9.0, 11.0), beta_rad: 0.3 };
    let mut once = Compositor::new(48, 32, 2.0);
    once.stamp(&Bsm, &a);
    let mut twice = Compositor::new(48, 32, 2.0);
    twice.stamp_all(&Bsm, [&a, &a, &a]);
    assert_eq!(once.image(), twice.image(), "re-stamping must not darken");
    let mut both = Compositor::new(48, 32, 2.0);
    both.stamp_all(&Bsm, [&a, &b]);
    let mut ia = Coverage::new(48, 32);
    let mut ib = Coverage::new(48, 32);
    let mut r = Rasterizer::new();
    r.render(&Bsm, &fp, a.anchor, a.beta_rad, 2.0, &mut ia);
    r.render(&Bsm, &fp, b.anchor, b.beta_rad, 2.0, &mut ib);
    for i in 0..48 * 32 {
        let want = ia.data()[i].max(ib.data()[i]);
        assert!((both.image().data()[i] - want).abs() <= 1.0 / 255.0 + 1e-6);
    }
    assert!(both.image().data().iter().all(|&v| (0.0..=1.0).contains(&v)));
    assert!(both.image().ink() < ia.ink() + ib.ink());
}

#[test]
fn stamps_clip_at_the_image_edge() {
    let fp = Footprint::new(10.0, 4.0, 3.0).unwrap();
    let mut c = Compositor::new(20, 20, 2.0);
    c.stamp(&Bsm, &Stamp { footprint: fp, anchor: PointMm::new(-3.0, 5.0), beta_rad: 0.0 });
    c.stamp(&Bsm, &Stamp { footprint: fp, anchor: PointMm::new(100.0, 100.0), beta_rad: 0.0 });
    assert!(c.image().ink() > 10.0 && c.image().ink() < fp.area_mm2() * 4.0);
}

#[test]
fn batch_equals_one_by_one() {
    let p = pen1();
    let spec = DatasetSpec::new(p, 64, 9);
    let stamps: Vec<Stamp> = (0..40)
        .map(|i| {
            let s = spec.sample(i).unwrap();
            Stamp {
                footprint: s.footprint,
                anchor: spec.canvas.anchor_mm(&s.footprint, s.press.beta_rad),
                beta_rad: s.press.beta_rad,
            }
        })
        .collect();
    let batch = render_batch(&Bsm, &stamps, 64, 64, spec.canvas.px_per_mm);
    let mut r = Rasterizer::new();
    for (s, img) in stamps.iter().zip(&batch) {
        let mut one = Coverage::new(64, 64);
        r.render(&Bsm, &s.footprint, s.anchor, s.beta_rad, spec.canvas.px_per_mm, &mut one);
        assert_eq!(&one, img);
    }
}

#[test]
fn datasets_are_deterministic_and_inside_the_range() {
    let p = pen1();
    let a = DatasetSpec::new(p.clone(), 128, 42);
    let b = DatasetSpec::new(p.clone(), 128, 42);
    let c = DatasetSpec::new(p.clone(), 128, 43);
    let mut distinct = std::collections::HashSet::new();
    for i in 0..200 {
        let (sa, sb) = (a.sample(i).unwrap(), b.sample(i).unwrap());
        assert_eq!(sa, sb);
        assert_ne!(sa.press, c.sample(i).unwrap().press);
        let r = p.ranges;
        assert!(
            r.h_mm.contains(sa.press.h_mm)
                && r.alpha_rad.contains(sa.press.alpha_rad)
                && r.beta_rad.contains(sa.press.beta_rad)
        );
        distinct.insert(sa.press.h_mm.to_bits());
    }
    assert_eq!(distinct.len(), 200);
}

#[test]
fn png_round_trip_and_bad_files() {
    let fp = Footprint::new(10.0, 4.0, 3.0).unwrap();
    let img = render(&Bsm, &fp, PointMm::new(3.0, 8.0), 0.2, 3.0, 50);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("f.png");
    std::fs::write(&path, img.encode_png().unwrap()).unwrap();
    let back = Coverage::load(&path).unwrap();
    assert_eq!((back.width(), back.height()), (50, 50));
    for (a, b) in img.data().iter().zip(back.data()) {
        assert!((a - b).abs() <= 0.5 / 255.0 + 1e-6);
    }
    // On disk: black ink on white paper.
    let raw = image::open(&path).unwrap().to_luma8();
    assert_eq!(raw.get_pixel(0, 0).0[0], 255);
    let bad = dir.path().join("bad.png");
    std::fs::write(&bad, b"not a png").unwrap();
    assert!(Coverage::load(&bad).unwrap_err().to_string().contains("bad.png"));
    assert!(Coverage::load(&dir.path().join("missing.png")).is_err());
    // The causes are kept: the I/O error for a missing file, "not an image" for text.
    let e = Coverage::load(&dir.path().join("missing.png")).unwrap_err();
    let Some(bezier_raster::ImageFileError::Io(io)) =
        std::error::Error::source(&e).and_then(|c| c.downcast_ref::<bezier_raster::ImageFileError>())
    else {
        panic!("{e}: the image file error is the source")
    };
    assert_eq!(io.kind(), std::io::ErrorKind::NotFound);
    let text = dir.path().join("text.dat");
    std::fs::write(&text, "hello").unwrap();
    let e = Coverage::load(&text).unwrap_err();
    let cause = std::error::Error::source(&e).map(ToString::to_string).unwrap_or_default();
    assert!(e.to_string().contains("text.dat") && cause.contains("not an image"), "{e}: {cause}");
}

#[test]
fn svg_contains_the_outline() {
    let fp = Footprint::new(10.0, 4.0, 3.0).unwrap();
    let svg = bezier_raster::svg_document(&Bsm.outline(&fp, PointMm::new(5.0, 5.0), 0.0), 20.0, 10.0);
    assert!(svg.starts_with("<svg") && svg.contains("viewBox=\"0 0 20 10\"") && svg.contains(" C"));
}

#[test]
fn model_names_round_trip() {
    for m in ModelKind::ALL {
        assert_eq!(m.name().parse::<ModelKind>().unwrap(), m);
    }
    assert!("brush".parse::<ModelKind>().unwrap_err().contains("bsm"));
}

#[test]
fn qbc_spans_root_to_tip_and_tapers() {
    let fp = Footprint::new(20.0, 8.0, 4.0).unwrap();
    let img = render(ModelKind::Qbc.model(), &fp, PointMm::new(4.0, 16.0), 0.0, 2.0, 64);
    let col = |x: u32| (0..64).map(|y| img.get(x, y) as f64).sum::<f64>();
    let ink_cols: Vec<u32> = (0..64).filter(|&x| col(x) > 0.05).collect();
    // Root end at 4 mm = 8 px; tip (with the last disc's radius 0.5 mm) at 32.5 mm = 65 px → clipped.
    assert_eq!(ink_cols[0], 8);
    assert!(col(12) > col(40) && col(40) > col(60), "must taper");
    assert!((col(16) - 16.0).abs() < 1.0, "widest near the root: {}", col(16));
}
