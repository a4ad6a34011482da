//! The executed figure on the controller's time law: for each character, executed CSIM against
//! the glyph with the plain executor (no ramps, no blends), with the program sent as path
//! buffers (what `maobi write` reports), sent as compacted blended moves (`robot send --motion moves`), and as compacted
//! moves without blends (`blend_mm` 0: what compaction and ramps alone cost), as the simulator
//! server runs them (compaction leaves no blend where the path turns back by more than 90°);
//! prints each and the means. A character whose program the timing refuses is
//! named and left out of the means.
//!
//! ```sh
//! cargo run -p pipeline --example executed_time_law -- HANZI_DIR SET_FILE FIRST LAST [SIZE]
//! ```
//!
//! `HANZI_DIR` is an unpacked `npm pack hanzi-writer-data`, or `embedded` for the data compiled
//! into maobi; `SET_FILE` a character list, one
//! per line, `#` comments (`fixtures/hanzi/heldout-2000.txt`); `FIRST`..`LAST` the lines
//! (1-based, inclusive, comments not counted); `SIZE` the render side (default 512, as `maobi
//! write`).

use std::path::PathBuf;

use brush_model::BrushProfile;
use pipeline::{
    BoxRule, Execution, GlyphInput, WriteOptions, execute_track_with, level_frame_for, render_states, similarity,
    write_placed,
};
use robot_io::RobotConfig;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [dir, set, first, last, rest @ ..] = args.as_slice() else {
        return Err("usage: executed_time_law HANZI_DIR SET_FILE FIRST LAST [SIZE]".into());
    };
    let (first, last): (usize, usize) = (first.parse()?, last.parse()?);
    let size: u32 = rest.first().map_or(Ok(512), |s| s.parse())?;
    let text = std::fs::read_to_string(set)?;
    let chars: Vec<char> = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .filter_map(|l| l.trim().chars().next())
        .skip(first.saturating_sub(1))
        .take(last + 1 - first.max(1))
        .collect();
    let input = GlyphInput::Hanzi((dir != "embedded").then(|| PathBuf::from(dir)));
    let pen1 = BrushProfile::builtin("pen1")?;
    let opts = WriteOptions { size, free_widths: false, execution: Execution::Plain, ..WriteOptions::default() };
    let cfg = RobotConfig::default();
    // Moves without blends: what the compaction and the ramps alone cost.
    let stops = RobotConfig { blend_mm: 0.0, ..RobotConfig::default() };
    let mut sums = [0.0f64; 4];
    let mut worst_drop = [0.0f64; 3];
    let mut n = 0usize;
    println!("char\tplain\tpath_buffer\tmoves\tmoves_without_blends");
    let mut refused = Vec::new();
    'chars: for ch in chars {
        let p = match input.prepare(ch, None) {
            Ok(p) => p,
            Err(e) => {
                println!("{ch}\tskipped ({e})");
                continue;
            }
        };
        let r = write_placed(&p, &pen1, &opts, BoxRule::Auto)?;
        let plain = r.report.executed.ok_or("not executed")?.csim;
        let frame = level_frame_for(&r.char_box);
        let mut scores = [plain, 0.0, 0.0, 0.0];
        for (k, how, c) in
            [(1, Execution::PathBuffer, &cfg), (2, Execution::Moves, &cfg), (3, Execution::Moves, &stops)]
        {
            let states = match execute_track_with(&r.track, &pen1, &frame, c, how) {
                Ok(s) => s,
                Err(e) => {
                    refused.push(format!("{ch} ({how:?}): {e}"));
                    continue 'chars;
                }
            };
            let img = render_states(&states, &pen1, opts.model, brush_model::Extrapolation::Refuse, &r.char_box, size);
            scores[k] = similarity(&r.reference, &img)?.csim;
            worst_drop[k - 1] = worst_drop[k - 1].max(plain - scores[k]);
        }
        println!("{ch}\t{:.5}\t{:.5}\t{:.5}\t{:.5}", scores[0], scores[1], scores[2], scores[3]);
        for k in 0..4 {
            sums[k] += scores[k];
        }
        n += 1;
    }
    for r in &refused {
        println!("refused, left out of the means: {r}");
    }
    let m = n.max(1) as f64;
    println!(
        "mean over {n}: plain {:.5}, path buffer {:.5} ({:+.5}; largest drop {:.5}), moves {:.5} ({:+.5}; largest drop {:.5}), moves without blends {:.5} ({:+.5}; largest drop {:.5})",
        sums[0] / m,
        sums[1] / m,
        (sums[1] - sums[0]) / m,
        worst_drop[0],
        sums[2] / m,
        (sums[2] - sums[0]) / m,
        worst_drop[1],
        sums[3] / m,
        (sums[3] - sums[0]) / m,
        worst_drop[2]
    );
    Ok(())
}
