//! Synthetic scans (uneven light, paper texture, rotation, blur, JPEG) and what `--image` and
//! `--from template` make of them.

use std::path::PathBuf;

use trajectory::{ScanOptions, decode_gray, embedded_glyph, glyph_from_font, mask_of, render_glyph, synth_scan};
use trajectory::{Shape, glyph_from_gray};
use trajectory::{TemplateOptions, register_template};

use crate::common::{PX, csim};

fn ukai() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/fonts/ukai-subset.ttf")
}

#[test]
fn scans_are_deterministic_and_degraded() {
    let g = glyph_from_font(&ukai(), '永').unwrap();
    let o = ScanOptions { light_angle_rad: 0.0, ..ScanOptions::seeded(7) };
    let a = synth_scan(&g, &o).unwrap();
    assert_eq!(a, synth_scan(&g, &o).unwrap(), "same seed, same bytes");
    assert_ne!(a, synth_scan(&g, &ScanOptions { seed: 8, ..o }).unwrap(), "another seed, other texture");
    assert!(a.starts_with(&[0xFF, 0xD8]), "a JPEG file");
    let img = decode_gray(&a).unwrap();
    assert_eq!((img.width(), img.height()), (384, 384));
    let mean = |x0: u32, x1: u32, y0: u32, y1: u32| {
        let mut s = 0.0;
        for y in y0..y1 {
            for x in x0..x1 {
                s += img.get_pixel(x, y).0[0] as f64;
            }
        }
        s / ((x1 - x0) * (y1 - y0)) as f64
    };
    // Paper strips at the left and right edges (outside the em box): lit from the left.
    let (left, right) = (mean(2, 20, 20, 364), mean(364, 382, 20, 364));
    assert!(left - right > 40.0, "light falls off to the right: {left:.0} vs {right:.0}");
    // Ink is dark: the darkest pixels are far below the paper.
    let min = img.pixels().map(|p| p.0[0]).min().unwrap();
    assert!((min as f64) < 0.4 * right, "ink {min} vs paper {right:.0}");
    let s = ScanOptions::seeded(3);
    assert!(s.rotation_rad.abs() <= 3f64.to_radians() + 1e-12);
}

#[test]
fn bad_options_are_refused() {
    let g = glyph_from_font(&ukai(), '十').unwrap();
    let e = synth_scan(&g, &ScanOptions { jpeg_quality: 0, ..ScanOptions::default() }).unwrap_err();
    assert!(e.to_string().contains("jpeg_quality"), "{e}");
    let e = synth_scan(&g, &ScanOptions { size_px: 8, ..ScanOptions::default() }).unwrap_err();
    assert!(e.to_string().contains("size_px"), "{e}");
}

#[test]
fn an_unevenly_lit_scan_cleans_to_the_glyph() {
    // No rotation, so the cleaned bitmap can be compared with the font glyph placed where the
    // scan put it (the em box is the middle 80 % of the page).
    for c in ['永', '口', '水'] {
        let g = glyph_from_font(&ukai(), c).unwrap();
        let o = ScanOptions { rotation_rad: 0.0, light_gradient: 0.5, vignette: 0.3, ..ScanOptions::seeded(11) };
        let scan = glyph_from_gray(c, "scan", &decode_gray(&synth_scan(&g, &o).unwrap()).unwrap()).unwrap();
        let Shape::Bitmap { size, ink } = &scan.shape else { panic!("a bitmap") };
        let n = *size as usize;
        let em = (n as f64 * o.em_fraction).round() as usize;
        let off = (n - em) / 2;
        let clean = mask_of(&render_glyph(&g, em as u32));
        let (mut inter, mut union) = (0usize, 0usize);
        for y in 0..n {
            for x in 0..n {
                let a = ink[y * n + x] >= 0.5;
                let b = (off..off + em).contains(&x) && (off..off + em).contains(&y) && clean[(y - off) * em + x - off];
                inter += (a && b) as usize;
                union += (a || b) as usize;
            }
        }
        let iou = inter as f64 / union as f64;
        assert!(iou > 0.85, "{c}: IoU of the cleaned scan with the glyph {iou:.3}");
    }
}

#[test]
fn registration_on_synthetic_scans_matches_the_clean_font() {
    let chars = "永字八法十口人丁山水";
    let (mut ok, mut sum_scan, mut sum_font) = (0, 0.0, 0.0);
    let opts = TemplateOptions { analysis_px: PX, ..TemplateOptions::default() };
    for (k, c) in chars.chars().enumerate() {
        let template = embedded_glyph(c).unwrap();
        let font = glyph_from_font(&ukai(), c).unwrap();
        let bytes = synth_scan(&font, &ScanOptions::seeded(100 + k as u64)).unwrap();
        let scan = glyph_from_gray(c, "scan", &decode_gray(&bytes).unwrap()).unwrap();
        let on_scan = register_template(&template, &scan, &opts).unwrap();
        let on_font = register_template(&template, &font, &opts).unwrap();
        assert_eq!(on_scan.paths.len(), template.medians.as_ref().unwrap().len(), "{c}");
        ok += on_scan.strokes_ok() as usize;
        sum_scan += csim(&on_scan.paths, &scan);
        sum_font += csim(&on_font.paths, &font);
    }
    let n = chars.chars().count() as f64;
    assert!(ok as f64 >= 0.9 * n, "strokes right on {ok} of {n} scans");
    let (s, f) = (sum_scan / n, sum_font / n);
    assert!(s > f - 0.03, "mean CSIM on scans {s:.3}, on the clean font {f:.3}");
}
