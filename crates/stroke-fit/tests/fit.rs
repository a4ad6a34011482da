//! Fitting recovers known footprints from synthetic photos with real-scan defects.

use brush_model::{BrushProfile, Extrapolation, PointMm, Press};
use stroke_fit::{Degradation, png_with_scale, synthetic_photo};
use stroke_fit::{PhotoError, fit_footprint, load_ink, mask_from_gray, scale_from_metadata};

struct Case {
    press: Press,
    rotation_deg: f64,
    px_per_mm: f64,
    d: Degradation,
}

fn cases() -> Vec<Case> {
    let base = Degradation::default();
    vec![
        Case { press: Press::from_degrees(11.0, 0.0, 0.0), rotation_deg: 0.0, px_per_mm: 10.0, d: base },
        Case {
            press: Press::from_degrees(15.0, 5.0, 5.0),
            rotation_deg: 2.0,
            px_per_mm: 9.0,
            d: Degradation { blur_px: 2.0, ..base },
        },
        Case {
            press: Press::from_degrees(20.0, 10.0, 0.0),
            rotation_deg: -3.0,
            px_per_mm: 11.0,
            d: Degradation { noise: 0.08, jpeg_quality: Some(70), ..base },
        },
        Case {
            press: Press::from_degrees(13.0, 10.0, 5.0),
            rotation_deg: 1.0,
            px_per_mm: 10.0,
            d: Degradation { gradient: 0.4, specks: 12, ..base },
        },
        Case {
            press: Press::from_degrees(17.0, 0.0, 5.0),
            rotation_deg: -1.5,
            px_per_mm: 10.5,
            d: Degradation { bleed_px: 0.5, ..base },
        },
        Case { press: Press::from_degrees(19.0, 5.0, 0.0), rotation_deg: 178.0, px_per_mm: 10.0, d: base },
    ]
}

#[test]
fn recovers_lengths_within_3_percent_and_direction_within_1_degree() {
    let pen1 = BrushProfile::builtin("pen1").unwrap();
    let mut worst = [0.0f64; 4];
    for (i, c) in cases().iter().enumerate() {
        let fp = pen1.predict(&c.press, Extrapolation::Refuse).unwrap();
        let beta = c.press.beta_rad + c.rotation_deg.to_radians();
        let (w, h) = (((fp.length_mm() + 12.0) * c.px_per_mm) as u32, ((fp.length_mm() + 12.0) * c.px_per_mm) as u32);
        let size_mm = w as f64 / c.px_per_mm;
        let centre = fp.placed_bounds(PointMm::default(), beta).centre();
        let anchor = PointMm::new(size_mm / 2.0 - centre.x_mm, size_mm / 2.0 - centre.y_mm);
        let g = synthetic_photo(&fp, anchor, beta, c.px_per_mm, w, h, &c.d, 100 + i as u64);
        let mask = mask_from_gray(g, w as usize, h as usize, "synthetic").unwrap();
        let f = fit_footprint(&mask, c.px_per_mm);
        // Ink bleed grows every length by the bleed: compare with the grown footprint.
        let grow = c.d.bleed_px / c.px_per_mm;
        let rel = |a: f64, b: f64| (a - b).abs() / b;
        let errs = [rel(f.lt_mm, fp.lt_mm + grow), rel(f.lh_mm, fp.lh_mm + grow), rel(f.lr_mm, fp.lr_mm + grow)];
        let dbeta = brush_model::wrap_angle_rad(f.beta_rad - beta).abs().to_degrees();
        println!(
            "case {i}: lt {:.3}/{:.3} lh {:.3}/{:.3} lr {:.3}/{:.3} β err {dbeta:.3}° IoU {:.4}",
            f.lt_mm, fp.lt_mm, f.lh_mm, fp.lh_mm, f.lr_mm, fp.lr_mm, f.iou
        );
        for k in 0..3 {
            worst[k] = worst[k].max(errs[k]);
        }
        worst[3] = worst[3].max(dbeta);
        assert!(errs.iter().all(|e| *e < 0.03), "case {i}: relative errors {errs:?}");
        assert!(dbeta < 1.0, "case {i}: β off by {dbeta}°");
        assert!(
            (f.anchor_mm[0] - anchor.x_mm).hypot(f.anchor_mm[1] - anchor.y_mm) < 0.5,
            "case {i}: anchor {:?} vs {anchor:?}",
            f.anchor_mm
        );
        assert!(f.iou > 0.9);
    }
    println!(
        "worst: lt {:.2}% lh {:.2}% lr {:.2}% β {:.3}°",
        100.0 * worst[0],
        100.0 * worst[1],
        100.0 * worst[2],
        worst[3]
    );
}

#[test]
fn scale_comes_from_png_metadata() {
    let g = vec![1.0f32; 32 * 32];
    let dir = std::env::temp_dir().join(format!("stroke-fit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("s.png");
    std::fs::write(&p, png_with_scale(&g, 32, 32, 12.5)).unwrap();
    assert!((scale_from_metadata(&p).unwrap() - 12.5).abs() < 1e-9);
    // A plain PNG has no scale.
    let q = dir.join("plain.png");
    image::GrayImage::new(8, 8).save(&q).unwrap();
    assert_eq!(scale_from_metadata(&q), None);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_photos_are_refused_with_reasons() {
    let (w, h) = (80usize, 60usize);
    let blank = vec![0.95f32; w * h];
    assert!(matches!(mask_from_gray(blank, w, h, "blank.png"), Err(PhotoError::NoInk { .. })));
    let black = vec![0.02f32; w * h];
    assert!(matches!(mask_from_gray(black, w, h, "black.png"), Err(PhotoError::AllInk { .. })));
    let mut two = vec![0.95f32; w * h];
    for y in 10..30 {
        for x in 5..25 {
            two[y * w + x] = 0.05;
            two[y * w + x + 45] = 0.05;
        }
    }
    let e = mask_from_gray(two, w, h, "two.png").unwrap_err();
    assert!(matches!(e, PhotoError::SeveralBlobs { count: 2, .. }), "{e}");
    assert!(e.to_string().contains("two.png"));
    let junk = std::env::temp_dir().join(format!("junk-{}.png", std::process::id()));
    std::fs::write(&junk, b"nope").unwrap();
    assert!(matches!(load_ink(&junk), Err(PhotoError::Image { .. })));
    std::fs::remove_file(&junk).unwrap();
}
