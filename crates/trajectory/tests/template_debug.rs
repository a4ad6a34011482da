//! Overlays for looking at registrations by eye (ignored; `cargo test -p trajectory --test
//! template_debug -- --ignored`, images in `$TMPDIR/template-debug/`, fonts from
//! `TEMPLATE_DEBUG_FONT` or the UKai fixture, characters from `TEMPLATE_DEBUG_CHARS`).

use std::path::PathBuf;

use image::{Rgb, RgbImage};
use trajectory::template::{TemplateOptions, register};
use trajectory::{glyph, raster};

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
        let template = glyph::embedded(c).unwrap();
        let target = if std::env::var("TEMPLATE_DEBUG_SELF").is_ok() {
            trajectory::template::shape_only(&template)
        } else {
            glyph::from_font(&font, c).unwrap()
        };
        let reg = register(&template, &target, &TemplateOptions::default()).unwrap();
        let cov = raster::render_glyph(&target, n);
        let tcov = raster::render_glyph(&template, n);
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
        eprintln!("{c}: affine {:?} nonrigid {:.1} {:?}", reg.affine, reg.nonrigid_mean_em, reg.strokes);
    }
}

#[test]
#[ignore]
fn probe() {
    let g = glyph::embedded('永').unwrap();
    let t = trajectory::template::shape_only(&g);
    let reg = register(&g, &t, &TemplateOptions::default()).unwrap();
    let n = 512usize;
    let mask = raster::mask_of(&raster::render_glyph(&t, n as u32));
    let dt = trajectory::distance::distance_to_background(&mask, n, n);
    let p = &reg.paths[4];
    for k in (0..p.points.len()).step_by(10) {
        let q = p.points[k];
        let prof: Vec<String> = (-10..=10)
            .map(|o| {
                format!(
                    "{:.1}",
                    trajectory::distance::sample(&dt, n, n, q.x / 2.0 + o as f64 * 0.7, q.y / 2.0 - o as f64 * 0.7)
                )
            })
            .collect();
        eprintln!("{:?} w {:.1} {}", q, p.half_widths[k], prof.join(" "));
    }
}

#[test]
#[ignore]
fn probe2() {
    let c = std::env::var("TEMPLATE_DEBUG_CHARS").unwrap_or_else(|_| "法".into()).chars().next().unwrap();
    let g = glyph::embedded(c).unwrap();
    let t = trajectory::template::shape_only(&g);
    let iters = std::env::var("CPD_ITERS").map(|v| v.parse().unwrap()).unwrap_or(40);
    let reg = register(&g, &t, &TemplateOptions { cpd_iters: iters, ..TemplateOptions::default() }).unwrap();
    eprintln!("nonrigid {:.1}", reg.nonrigid_mean_em);
    let med = trajectory::centre_lines(&g, trajectory::Method::Medians, 512).unwrap();
    for (i, (a, b)) in reg.paths.iter().zip(&med).enumerate() {
        let f = |p: &trajectory::StrokePath| {
            format!(
                "n{} first ({:.0},{:.0}) last ({:.0},{:.0}) corners {:?} wmean {:.1}",
                p.points.len(),
                p.points[0].x,
                p.points[0].y,
                p.points.last().unwrap().x,
                p.points.last().unwrap().y,
                p.corners,
                p.half_widths.iter().sum::<f64>() / p.half_widths.len() as f64
            )
        };
        eprintln!("{i} T {}\n  M {}\n  raw {:?}", f(a), f(b), g.medians.as_ref().unwrap()[i]);
    }
}
