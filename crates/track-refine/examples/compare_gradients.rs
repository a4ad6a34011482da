//! Compares the two gradient sources of refinement, analytic and generator, on a character set:
//! executed CSIM/IoU against the glyph after refining (the program run as the simulator moves,
//! rendered with the analytic B-BSM, exactly as `maobi evaluate --refine` judges) and the time
//! per character. The judge is never the generator.
//!
//! ```sh
//! cargo run --release -p track-refine --example compare_gradients -- tuning 20
//! cargo run --release -p track-refine --example compare_gradients -- heldout 30 /path/to/hanzi-writer-data
//! ```
//!
//! `tuning N`: the first N characters of the embedded set (the set the defaults were tuned on).
//! `heldout N DIR`: the first N frequency-list characters from rank 1,002 to 1,500 that are not
//! embedded, glyphs from a hanzi-writer-data folder. Optional 4th argument: the first character
//! index to start from (to split a run). Medians, pen1, 256² judge raster, default options.

mod common;

use std::time::Instant;

use bezier_raster::{Coverage, ModelKind, render_stamps, sweep_stamps};
use brush_model::{BrushProfile, Extrapolation, PointMm, Track};
use robot_io::{PaperFrame, RobotConfig, build_program};
use track_refine::{GenModel, Gradients, RefineOptions, refine, refine_with_generator};
use trajectory::{CharBox, Method, centre_lines, glyph, raster::render_glyph};

const JUDGE_PX: u32 = 256;

fn level_frame_for(b: &CharBox) -> PaperFrame {
    let (cx, cy) = (b.x0_mm + b.size_mm / 2.0, b.y0_mm + b.size_mm / 2.0);
    let bounds = [b.x0_mm - b.size_mm, b.y0_mm - b.size_mm, b.x0_mm + 2.0 * b.size_mm, b.y0_mm + 2.0 * b.size_mm];
    robot_io::exec::level_frame_in_front([cx, cy], bounds)
}

/// Executed CSIM and IoU of a track against the glyph (None when the robot check refuses it).
fn executed(track: &Track, pen: &BrushProfile, b: &CharBox, reference: &Coverage) -> Option<(f64, f64)> {
    let frame = level_frame_for(b);
    let (program, _) = build_program(track, pen, &frame, &RobotConfig::default()).ok()?;
    let states = robot_io::exec::trace_to_states(&robot_io::exec::execute_program(&program), &frame);
    let stamps = sweep_stamps(&states, pen, Extrapolation::Refuse);
    let img = render_stamps(
        &stamps,
        ModelKind::Bsm.model(),
        PointMm::new(b.x0_mm, b.y0_mm),
        JUDGE_PX as f64 / b.size_mm,
        JUDGE_PX,
        JUDGE_PX,
    );
    let g = common::gray;
    Some((stroke_metrics::csim(g(reference), g(&img)).ok()?, stroke_metrics::iou(g(reference), g(&img)).ok()?))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let set = args.first().map_or("tuning", String::as_str).to_string();
    let n: usize = args.get(1).map_or(Ok(10), |s| s.parse())?;
    let embedded = glyph::embedded_chars();
    // The committed pen1 generator (fixtures/generator/), as the `maobi` binary uses it.
    let weights = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/generator/pen1.safetensors");
    let gen_model = std::sync::Arc::new(GenModel::new(&neural_gen::Generator::load(&weights)?)?);
    let (chars, dir): (Vec<char>, Option<std::path::PathBuf>) = match set.as_str() {
        "tuning" => (embedded.iter().copied().take(n).collect(), None),
        "heldout" => {
            let dir = args.get(2).ok_or("heldout needs the hanzi-writer-data folder")?;
            let text = include_str!("../../../fixtures/hanzi/frequency.txt");
            let freq: Vec<char> =
                text.lines().filter(|l| !l.starts_with('#')).filter_map(|l| l.trim().chars().next()).collect();
            let held: Vec<char> = freq[1001..].iter().copied().filter(|c| !embedded.contains(c)).take(n).collect();
            (held, Some(dir.into()))
        }
        _ => return Err("set: tuning | heldout".into()),
    };
    let skip: usize = args.get(3).map_or(Ok(0), |s| s.parse())?;
    let pen1 = BrushProfile::builtin("pen1")?;
    let base = RefineOptions::default();
    let mut rows = Vec::new();
    println!("char | before CSIM IoU | analytic CSIM IoU ms | generator CSIM IoU ms");
    for &ch in chars.iter().skip(skip) {
        let g = match &dir {
            Some(d) => glyph::from_hanzi_dir(d, ch)?,
            None => glyph::embedded(ch)?,
        };
        let paths = centre_lines(&g, Method::Medians, trajectory::DEFAULT_ANALYSIS_PX)?;
        let (built, char_box) = common::built_track(&paths, &pen1, (0.0, 0.0));
        let target = common::target_for(&g, &char_box, base.analysis_px);
        let reference = render_glyph(&g, JUDGE_PX);
        let before = executed(&built, &pen1, &char_box, &reference).ok_or("the built track fails robot check")?;
        let mut row = vec![before.0, before.1];
        for grad in [Gradients::Analytic, Gradients::Generator] {
            let opts = RefineOptions { gradients: grad, ..base };
            let t0 = Instant::now();
            let out = match grad {
                Gradients::Analytic => refine(&built, &pen1, &target, &opts)?,
                Gradients::Generator => refine_with_generator(&built, &pen1, &target, &opts, gen_model.clone())?,
            };
            let ms = t0.elapsed().as_secs_f64() * 1e3;
            let (c, i) = executed(&out.track, &pen1, &char_box, &reference).unwrap_or((f64::NAN, f64::NAN));
            row.extend([c, i, ms]);
        }
        println!(
            "{ch} | {:.4} {:.4} | {:.4} {:.4} {:.0} | {:.4} {:.4} {:.0}",
            row[0], row[1], row[2], row[3], row[4], row[5], row[6], row[7]
        );
        rows.push(row);
    }
    let k = rows.len() as f64;
    let mean = |i: usize| rows.iter().map(|r| r[i]).sum::<f64>() / k;
    let refused = |i: usize| rows.iter().filter(|r| r[i].is_nan()).count();
    let better = rows.iter().filter(|r| r[5] > r[2]).count();
    println!(
        "mean over {} ({set}): before CSIM {:.4} IoU {:.4}; analytic {:.4} {:.4} {:.0} ms (refused {}); generator {:.4} {:.4} {:.0} ms (refused {}); generator better on {better}",
        rows.len(),
        mean(0),
        mean(1),
        mean(2),
        mean(3),
        mean(4),
        refused(2),
        mean(5),
        mean(6),
        mean(7),
        refused(5)
    );
    Ok(())
}
