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

mod common;

use std::time::Instant;

use brush_model::BrushProfile;
use common::{built_track, options, scores, target_for};
use track_refine::refine;
use trajectory::{Method, centre_lines, glyph, raster::render_glyph};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let text = args.first().cloned().unwrap_or_else(|| "永".into());
    let opts = options(args.get(1))?;
    let pen1 = BrushProfile::builtin("pen1")?;
    let (mut sum_before, mut sum_after, mut sum_iou0, mut sum_iou1, mut ms) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let n = text.chars().count();
    for ch in text.chars() {
        let g = glyph::embedded(ch)?;
        let paths = centre_lines(&g, Method::Medians, 512)?;
        let (track, char_box) = built_track(&paths, &pen1, (10.0, 10.0));
        let target = target_for(&g, &char_box, opts.analysis_px);
        let t0 = Instant::now();
        let out = refine(&track, &pen1, &target, &opts)?;
        let dt = t0.elapsed().as_secs_f64() * 1e3;
        let judge_px = std::env::var("REFINE_JUDGE_PX").ok().and_then(|v| v.parse().ok()).unwrap_or(256);
        let reference = render_glyph(&g, judge_px);
        let (c0, i0) = scores(&track, &pen1, &char_box, &reference);
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
