//! The two sources of refinement gradients side by side: the analytic soft footprint (the
//! default) and the B-BSMG generator's VJP, on embedded characters (`tuning`) or characters
//! outside the embedded set (`heldout`, from a hanzi-writer-data folder); executed CSIM and IoU
//! before and after each, with timings.
//!
//! ```sh
//! cargo run --release -p pipeline --features generator --example compare_gradients -- tuning 10
//! cargo run --release -p pipeline --features generator --example compare_gradients -- heldout 10 DIR [SKIP]
//! ```

use std::sync::Arc;

use brush_model::BrushProfile;
use pipeline::{BoxRule, RefineOptions, WriteOptions, prepare, write_placed};
use track_refine::GenModel;
use track_refine::Gradients;
use trajectory::{Method, embedded_chars, embedded_glyph, glyph_from_hanzi_dir};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let set = args.first().map_or("tuning", String::as_str).to_string();
    let n: usize = args.get(1).map_or(Ok(10), |s| s.parse())?;
    let embedded = embedded_chars();
    // The committed pen1 generator, as the `maobi` binary uses it.
    let gen_model = Arc::new(GenModel::new(&neural_gen::Generator::pen1()?)?);
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
    let base = WriteOptions { size: 256, free_widths: false, ..WriteOptions::default() };
    let mut rows: Vec<Vec<f64>> = Vec::new();
    println!("char | before CSIM IoU | analytic CSIM IoU ms | generator CSIM IoU ms");
    for &ch in chars.iter().skip(skip) {
        let g = match &dir {
            Some(d) => glyph_from_hanzi_dir(d, ch)?,
            None => embedded_glyph(ch)?,
        };
        let p = prepare(g, Some(Method::Medians))?;
        let mut row = Vec::new();
        for grad in [Gradients::Analytic, Gradients::Generator] {
            let opts = WriteOptions {
                refine: Some(RefineOptions { gradients: grad, ..RefineOptions::default() }),
                generator: Some(gen_model.clone()),
                ..base.clone()
            };
            let rf = write_placed(&p, &pen1, &opts, BoxRule::Auto)?.report.refine.expect("refinement was asked for");
            let before = rf.executed_before.ok_or("the built track fails robot check")?;
            if row.is_empty() {
                row.extend([before.csim, before.iou]);
            }
            let after = rf.executed_after.map_or([f64::NAN; 2], |s| [s.csim, s.iou]);
            row.extend([after[0], after[1], rf.millis]);
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
