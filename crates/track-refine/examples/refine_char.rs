//! Refines the track of embedded characters and prints the planned render's scores before and
//! after (the B-BSM render of the track at 256², against the glyph), with timings.
//!
//! ```sh
//! cargo run --release -p track-refine --example refine_char -- 永 [OPTIONS_JSON]
//! ```
//!
//! `OPTIONS_JSON` overrides fields of `RefineOptions`, e.g. `'{"iterations": 20}'`;
//! `REFINE_JUDGE_PX` sets the side of the judging render (default 256). The
//! headline figure of the project is the *executed* render (`maobi write 永 --refine`); the
//! plan's render agrees with it to CSIM 0.9999 and is what this example shows.

use std::time::Instant;

use bezier_raster::{ModelKind, render_track};
use brush_model::{BrushProfile, Extrapolation, PointMm, Track};
use stroke_metrics::GrayRef;
use track_refine::{RefineOptions, Target, refine};
use trajectory::{CharBox, Method, Sizing, TrackOptions, build_track, centre_lines, glyph, raster::render_glyph};

fn scores(track: &Track, profile: &BrushProfile, b: &CharBox, reference: &bezier_raster::Coverage) -> (f64, f64) {
    let size = reference.width();
    let img = render_track(
        track,
        profile,
        ModelKind::Bsm.model(),
        Extrapolation::Refuse,
        PointMm::new(b.x0_mm, b.y0_mm),
        size as f64 / b.size_mm,
        size,
        size,
    )
    .expect("a built or refined track renders");
    fn g(c: &bezier_raster::Coverage) -> GrayRef<'_> {
        GrayRef::new(c.data(), c.width() as usize, c.height() as usize).expect("w × h values")
    }
    (stroke_metrics::csim(g(reference), g(&img)).unwrap(), stroke_metrics::iou(g(reference), g(&img)).unwrap())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let text = args.first().cloned().unwrap_or_else(|| "永".into());
    let mut opts = RefineOptions::default();
    if let Some(js) = args.get(1) {
        let mut v = serde_json::to_value(opts)?;
        for (k, x) in serde_json::from_str::<serde_json::Map<String, serde_json::Value>>(js)? {
            v[k] = x;
        }
        opts = serde_json::from_value(v)?;
    }
    let pen1 = BrushProfile::builtin("pen1")?;
    let (mut sum_before, mut sum_after, mut sum_iou0, mut sum_iou1, mut ms) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let n = text.chars().count();
    for ch in text.chars() {
        let g = glyph::embedded(ch)?;
        let paths = centre_lines(&g, Method::Medians, 512)?;
        let char_box = CharBox { x0_mm: 10.0, y0_mm: 10.0, size_mm: trajectory::auto_char_mm(&paths, &pen1, 0.0) };
        let topts = TrackOptions {
            char_box,
            spacing_mm: trajectory::DEFAULT_SPACING_MM,
            alpha_rad: 0.0,
            sizing: Sizing::Brush,
        };
        let built = build_track(&paths, &pen1, &topts)?;
        let px = opts.analysis_px;
        let glyph_img = render_glyph(&g, px);
        let target = Target::new(
            px,
            px,
            glyph_img.data().to_vec(),
            PointMm::new(char_box.x0_mm, char_box.y0_mm),
            char_box.size_mm / px as f64,
        )?;
        let t0 = Instant::now();
        let out = refine(&built.track, &pen1, &target, &opts)?;
        let dt = t0.elapsed().as_secs_f64() * 1e3;
        let judge_px = std::env::var("REFINE_JUDGE_PX").ok().and_then(|v| v.parse().ok()).unwrap_or(256);
        let reference = render_glyph(&g, judge_px);
        let (c0, i0) = scores(&built.track, &pen1, &char_box, &reference);
        let (c1, i1) = scores(&out.track, &pen1, &char_box, &reference);
        let (l0, l1) = (out.curve[0], out.curve[out.curve.len() - 1]);
        println!(
            "{ch}: planned CSIM {c0:.4} → {c1:.4}, IoU {i0:.4} → {i1:.4}; loss {:.4} → {:.4} (image {:.4} → {:.4}); {} variables, {} footprints, {dt:.0} ms",
            l0.total, l1.total, l0.image, l1.image, out.variables, out.footprints
        );
        if std::env::var_os("REFINE_CURVE").is_some() {
            let c: Vec<String> = out.curve.iter().map(|l| format!("{:.4}", l.image)).collect();
            println!("  image loss: {}", c.join(" "));
        }
        (sum_before, sum_after, sum_iou0, sum_iou1, ms) =
            (sum_before + c0, sum_after + c1, sum_iou0 + i0, sum_iou1 + i1, ms + dt);
    }
    let k = n as f64;
    println!(
        "mean over {n}: planned CSIM {:.4} → {:.4}, IoU {:.4} → {:.4}, {:.0} ms per character",
        sum_before / k,
        sum_after / k,
        sum_iou0 / k,
        sum_iou1 / k,
        ms / k
    );
    Ok(())
}
