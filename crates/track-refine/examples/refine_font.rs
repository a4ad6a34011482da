//! Refines the template tracks of a font's glyphs (the track `maobi evaluate --font F` builds:
//! the embedded character's stroke medians registered onto the glyph) and prints the planned
//! render's scores before and after, with timings.
//!
//! ```sh
//! cargo run --release -p track-refine --example refine_font -- FONT[:FACE] CHARS [OPTIONS_JSON]
//! ```
//!
//! `FONT` is a font file or folder (`/path/ukai.ttc:0` picks a collection's face);
//! `OPTIONS_JSON` overrides fields of `RefineOptions`; `REFINE_JUDGE_PX` sets the side of the
//! judging render (default 512, as `maobi evaluate`). The headline figure of the project is the
//! *executed* render (`maobi evaluate --font F --refine`); the plan's render agrees with it to
//! a few 1e-4 and is what this example shows, which is quicker for tuning.

mod common;

use std::path::PathBuf;
use std::time::Instant;

use brush_model::{BrushProfile, Track};
use common::{built_track, options, render, scores, target_for};
use track_refine::refine;
use trajectory::{CharBox, DEFAULT_ANALYSIS_PX, centre_lines_from_template, glyph, raster::render_glyph};

/// Shares of the glyph's ink the render misses and of the render's ink outside the glyph, and
/// the shares of pressed points at the lightest and at the deepest press.
fn diagnose(track: &Track, profile: &BrushProfile, b: &CharBox, reference: &bezier_raster::Coverage) -> [f64; 4] {
    let img = render(track, profile, b, reference.width());
    let (mut miss, mut extra, mut ink, mut drawn) = (0.0, 0.0, 0.0, 0.0);
    for (&g, &r) in reference.data().iter().zip(img.data()) {
        let (g, r) = (g as f64, r as f64);
        miss += (g - r).max(0.0);
        extra += (r - g).max(0.0);
        ink += g;
        drawn += r;
    }
    let r = profile.ranges.h_mm;
    let pressed: Vec<f64> =
        track.strokes.iter().flat_map(|s| s.points.iter()).filter(|p| p.h_mm >= r.min).map(|p| p.h_mm).collect();
    let n = pressed.len().max(1) as f64;
    let lo = pressed.iter().filter(|&&h| h <= r.min + 1e-9).count() as f64 / n;
    let hi = pressed.iter().filter(|&&h| h >= r.max - 1e-9).count() as f64 / n;
    [miss / ink, extra / drawn.max(1e-9), lo, hi]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(font), Some(text)) = (args.first(), args.get(1)) else {
        return Err("usage: refine_font FONT[:FACE] CHARS [OPTIONS_JSON]".into());
    };
    let (path, face) = match font.rsplit_once(':') {
        Some((p, f)) if f.parse::<u32>().is_ok() => (p.to_string(), Some(f.parse::<u32>()?)),
        _ => (font.clone(), None),
    };
    let fonts = glyph::FontSet::open(&[PathBuf::from(path)], face)?;
    let opts = options(args.get(2))?;
    let judge_px = std::env::var("REFINE_JUDGE_PX").ok().and_then(|v| v.parse().ok()).unwrap_or(512);
    let pen1 = BrushProfile::builtin("pen1")?;
    let (mut sum_before, mut sum_after, mut sum_iou0, mut sum_iou1, mut ms, mut n) = (0.0, 0.0, 0.0, 0.0, 0.0, 0);
    for ch in text.chars() {
        let (Ok(g), Ok(template)) = (fonts.glyph(ch), glyph::embedded(ch)) else {
            println!("{ch}: skipped (not in the font or not embedded)");
            continue;
        };
        let reg = centre_lines_from_template(&template, &g, DEFAULT_ANALYSIS_PX)?;
        let (track, char_box) = built_track(&reg.paths, &pen1, (0.0, 0.0));
        let target = target_for(&g, &char_box, opts.analysis_px);
        let t0 = Instant::now();
        let out = refine(&track, &pen1, &target, &opts)?;
        let dt = t0.elapsed().as_secs_f64() * 1e3;
        let reference = render_glyph(&g, judge_px);
        let (c0, i0) = scores(&track, &pen1, &char_box, &reference);
        let (c1, i1) = scores(&out.track, &pen1, &char_box, &reference);
        let (l0, l1) = (out.curve[0], out.curve[out.curve.len() - 1]);
        println!(
            "{ch}: planned CSIM {c0:.4} → {c1:.4} ({:+.4}), IoU {i0:.4} → {i1:.4}; image loss {:.4} → {:.4}; {} points, {} footprints, {} variables, {dt:.0} ms",
            c1 - c0,
            l0.image,
            l1.image,
            track.point_count(),
            out.footprints,
            out.variables,
        );
        if std::env::var_os("REFINE_DIAG").is_some() {
            let [m0, e0, lo0, hi0] = diagnose(&track, &pen1, &char_box, &reference);
            let [m1, e1, lo1, hi1] = diagnose(&out.track, &pen1, &char_box, &reference);
            println!(
                "  ink missed {m0:.3} → {m1:.3}, ink outside {e0:.3} → {e1:.3}; presses at the lightest {lo0:.3} → {lo1:.3}, deepest {hi0:.3} → {hi1:.3}"
            );
        }
        if let Some(dir) = std::env::var_os("REFINE_PNG") {
            let dir = PathBuf::from(dir);
            for (name, t) in [("before", &track), ("after", &out.track)] {
                let img = render(t, &pen1, &char_box, judge_px);
                std::fs::write(
                    dir.join(format!("{ch}_{name}.png")),
                    bezier_raster::coverage::overlay_png(&reference, &img)?,
                )?;
            }
        }
        if std::env::var_os("REFINE_CURVE").is_some() {
            let c: Vec<String> = out.curve.iter().map(|l| format!("{:.4}", l.image)).collect();
            println!("  image loss: {}", c.join(" "));
        }
        (sum_before, sum_after, sum_iou0, sum_iou1, ms) =
            (sum_before + c0, sum_after + c1, sum_iou0 + i0, sum_iou1 + i1, ms + dt);
        n += 1;
    }
    let k = n.max(1) as f64;
    println!(
        "mean over {n}: planned CSIM {:.4} → {:.4} ({:+.4}), IoU {:.4} → {:.4}, {:.0} ms per character",
        sum_before / k,
        sum_after / k,
        (sum_after - sum_before) / k,
        sum_iou0 / k,
        sum_iou1 / k,
        ms / k
    );
    Ok(())
}
