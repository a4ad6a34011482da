//! Refines the tracks of embedded characters and prints the scores before and after: the plan
//! (the B-BSM render of the track) and the executed program, against the glyph, with timings.
//!
//! ```sh
//! cargo run --release -p pipeline --example refine_char -- 永 [OPTIONS_JSON]
//! ```
//!
//! `OPTIONS_JSON` overrides fields of `RefineOptions`, e.g. `'{"iterations": 20}'`;
//! `REFINE_JUDGE_PX` sets the side of the judging renders (default 256); `REFINE_CURVE` prints
//! the image loss at each step.

use brush_model::BrushProfile;
use pipeline::{BoxRule, RefineOptions, WriteOptions, prepare, write_placed};
use trajectory::{Method, embedded_glyph};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let text = args.first().cloned().unwrap_or_else(|| "永".into());
    let refine: RefineOptions = serde_json::from_str(args.get(1).map_or("{}", String::as_str))?;
    let size = std::env::var("REFINE_JUDGE_PX").ok().and_then(|v| v.parse().ok()).unwrap_or(256);
    let opts = WriteOptions { size, free_widths: false, refine: Some(refine), ..WriteOptions::default() };
    let pen1 = BrushProfile::builtin("pen1")?;
    let mut sums = [0.0; 5];
    for ch in text.chars() {
        let p = prepare(embedded_glyph(ch)?, Some(Method::Medians))?;
        let r = write_placed(&p, &pen1, &opts, BoxRule::Auto)?.report;
        let rf = r.refine.as_ref().expect("refinement was asked for");
        let ex = |s: Option<pipeline::Similarity>| s.map_or(f64::NAN, |s| s.csim);
        let (l0, l1) = (rf.curve[0], rf.curve[rf.curve.len() - 1]);
        println!(
            "{ch}: planned CSIM {:.4} → {:.4}, executed CSIM {:.4} → {:.4}; loss {:.4} → {:.4} (image {:.4} → {:.4}); {} variables, {} footprints, {:.0} ms{}",
            rf.planned_before.csim,
            rf.planned_after.csim,
            ex(rf.executed_before),
            ex(rf.executed_after),
            l0.total,
            l1.total,
            l0.image,
            l1.image,
            rf.variables,
            rf.footprints,
            rf.millis,
            rf.rejected.as_ref().map_or(String::new(), |w| format!(" (not used: {w})"))
        );
        if std::env::var_os("REFINE_CURVE").is_some() {
            let c: Vec<String> = rf.curve.iter().map(|l| format!("{:.4}", l.image)).collect();
            println!("  image loss: {}", c.join(" "));
        }
        let add =
            [rf.planned_before.csim, rf.planned_after.csim, ex(rf.executed_before), ex(rf.executed_after), rf.millis];
        for (s, a) in sums.iter_mut().zip(add) {
            *s += a;
        }
    }
    let k = text.chars().count() as f64;
    println!(
        "mean over {k}: planned CSIM {:.4} → {:.4}, executed CSIM {:.4} → {:.4}, {:.0} ms per character",
        sums[0] / k,
        sums[1] / k,
        sums[2] / k,
        sums[3] / k,
        sums[4] / k
    );
    Ok(())
}
