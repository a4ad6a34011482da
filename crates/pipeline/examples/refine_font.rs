//! Refines the template tracks of a font's glyphs (the track `maobi evaluate --font F` builds:
//! the embedded character's stroke medians registered onto the glyph, in the automatic char
//! box) and prints the scores before and after, with timings.
//!
//! ```sh
//! cargo run --release -p pipeline --example refine_font -- FONT[:FACE] CHARS [OPTIONS_JSON]
//! ```
//!
//! `FONT` is a font file or folder (`/path/ukai.ttc:0` picks a collection's face);
//! `OPTIONS_JSON` overrides fields of `RefineOptions`; `REFINE_JUDGE_PX` sets the side of the
//! judging renders (default 512, as `maobi evaluate`); `REFINE_DIAG` prints where the refined
//! plan misses ink; `REFINE_PNG=DIR` writes each refined plan over its glyph.

use std::path::PathBuf;

use brush_model::BrushProfile;
use pipeline::{BoxRule, CharResult, GlyphInput, RefineOptions, WriteOptions, write_placed};
use trajectory::Method;

/// Shares of the glyph's ink the plan misses and of the plan's ink outside the glyph, and the
/// shares of pressed points at the lightest and at the deepest press.
fn diagnose(r: &CharResult, profile: &BrushProfile) -> [f64; 4] {
    let (mut miss, mut extra, mut ink, mut drawn) = (0.0, 0.0, 0.0, 0.0);
    for (&g, &d) in r.reference.data().iter().zip(r.render.data()) {
        let (g, d) = (g as f64, d as f64);
        miss += (g - d).max(0.0);
        extra += (d - g).max(0.0);
        ink += g;
        drawn += d;
    }
    let range = profile.ranges.h_mm;
    let pressed: Vec<f64> =
        r.track.strokes.iter().flat_map(|s| s.points.iter()).filter(|p| p.h_mm >= range.min).map(|p| p.h_mm).collect();
    let n = pressed.len().max(1) as f64;
    let lo = pressed.iter().filter(|&&h| h <= range.min + 1e-9).count() as f64 / n;
    let hi = pressed.iter().filter(|&&h| h >= range.max - 1e-9).count() as f64 / n;
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
    let input = GlyphInput::fonts(&[PathBuf::from(path)], face, None)?;
    let refine: RefineOptions = serde_json::from_str(args.get(2).map_or("{}", String::as_str))?;
    let size = std::env::var("REFINE_JUDGE_PX").ok().and_then(|v| v.parse().ok()).unwrap_or(512);
    let opts = WriteOptions { size, free_widths: false, refine: Some(refine), ..WriteOptions::default() };
    let pen1 = BrushProfile::builtin("pen1")?;
    let (mut before, mut after, mut ms, mut n) = (0.0, 0.0, 0.0, 0usize);
    for ch in text.chars() {
        let p = match input.prepare(ch, Some(Method::Template)) {
            Ok(p) => p,
            Err(e) => {
                println!("{ch}: skipped ({e})");
                continue;
            }
        };
        let r = write_placed(&p, &pen1, &opts, BoxRule::Auto)?;
        let rf = r.report.refine.as_ref().expect("refinement was asked for");
        let (l0, l1) = (rf.curve[0], rf.curve[rf.curve.len() - 1]);
        let (c0, c1) = (rf.planned_before.csim, rf.planned_after.csim);
        println!(
            "{ch}: planned CSIM {c0:.4} → {c1:.4} ({:+.4}); image loss {:.4} → {:.4}; {} points, {} footprints, {} variables, {:.0} ms",
            c1 - c0,
            l0.image,
            l1.image,
            r.report.plan.points,
            rf.footprints,
            rf.variables,
            rf.millis,
        );
        if std::env::var_os("REFINE_DIAG").is_some() {
            let [m, e, lo, hi] = diagnose(&r, &pen1);
            println!("  ink missed {m:.3}, ink outside {e:.3}; presses at the lightest {lo:.3}, deepest {hi:.3}");
        }
        if let Some(dir) = std::env::var_os("REFINE_PNG") {
            let png = bezier_raster::overlay_png(&r.reference, &r.render)?;
            std::fs::write(PathBuf::from(dir).join(format!("{ch}_refined.png")), png)?;
        }
        (before, after, ms, n) = (before + c0, after + c1, ms + rf.millis, n + 1);
    }
    let k = n.max(1) as f64;
    println!("mean over {n}: planned CSIM {:.4} → {:.4}, {:.0} ms per character", before / k, after / k, ms / k);
    Ok(())
}
