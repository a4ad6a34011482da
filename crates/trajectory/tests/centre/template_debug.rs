//! Overlays for looking at registrations by eye (ignored; `cargo test -p trajectory --test
//! centre -- --ignored template_debug`, images in `$TMPDIR/template-debug/`, fonts from
//! `TEMPLATE_DEBUG_FONT` or the UKai fixture, characters from `TEMPLATE_DEBUG_CHARS`; with
//! `TEMPLATE_DEBUG_SELF` set, the template onto its own outline). Grey: the target; yellow: the
//! template before any fit; coloured dots: the registered centre lines, a square at each start.

use std::path::PathBuf;

use image::{Rgb, RgbImage};
use trajectory::{TemplateOptions, embedded_glyph, glyph_from_font, register_template, render_glyph};

#[test]
#[ignore]
fn overlays() {
    let font = std::env::var("TEMPLATE_DEBUG_FONT")
        .map(PathBuf::from)
        .unwrap_or_else(|_| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/fonts/ukai-subset.ttf"));
    let chars = std::env::var("TEMPLATE_DEBUG_CHARS").unwrap_or_else(|_| "永字八法十口人丁山水".into());
    let out = std::env::temp_dir().join("template-debug");
    std::fs::create_dir_all(&out).unwrap();
    let n = 512u32;
    for c in chars.chars() {
        let template = embedded_glyph(c).unwrap();
        let target = if std::env::var("TEMPLATE_DEBUG_SELF").is_ok() {
            trajectory::shape_only(&template)
        } else {
            glyph_from_font(&font, c).unwrap()
        };
        let reg = register_template(&template, &target, &TemplateOptions::default()).unwrap();
        let cov = render_glyph(&target, n);
        let tcov = render_glyph(&template, n);
        let mut img = RgbImage::new(n, n);
        for (i, p) in img.pixels_mut().enumerate() {
            let v = 255 - (120.0 * cov.data()[i]) as u8;
            let t = (60.0 * tcov.data()[i]) as u8;
            *p = Rgb([v, v, v - t]);
        }
        let s = n as f64 / 1024.0;
        let colours = [[230, 0, 0], [0, 150, 0], [0, 0, 230], [200, 0, 200], [0, 160, 160], [200, 120, 0]];
        for (k, path) in reg.paths.iter().enumerate() {
            let col = Rgb(colours[k % colours.len()]);
            for (j, p) in path.points.iter().enumerate() {
                let r = if j == 0 { 3 } else { 1 };
                for dy in -r..=r {
                    for dx in -r..=r {
                        let (x, y) = ((p.x * s) as i64 + dx, (p.y * s) as i64 + dy);
                        if (0..n as i64).contains(&x) && (0..n as i64).contains(&y) {
                            img.put_pixel(x as u32, y as u32, col);
                        }
                    }
                }
            }
        }
        img.save(out.join(format!("{c}.png"))).unwrap();
        eprintln!(
            "{c}: uncovered {:.3} affine {:?} nonrigid {:.1} {:?}",
            reg.uncovered_ink, reg.affine, reg.nonrigid_mean_em, reg.strokes
        );
    }
}
