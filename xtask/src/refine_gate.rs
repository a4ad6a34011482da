//! The refinement gate: `maobi write --refine` on a few gate characters, bounded in time (the
//! figure group `refine` of `cargo xtask gates`, baseline `fixtures/baselines/refine.json`).

use anyhow::{Result, bail};
use brush_model::BrushProfile;
use pipeline::{BoxRule, RefineMeans, RefineOptions, WriteOptions, prepare, write_placed};
use rayon::prelude::*;
use trajectory::{Method, embedded_glyph};

use crate::figures::{Better, Figures, fig};

/// The characters the refinement gate writes: the first four gate characters (one stroke-rich,
/// one short, two with crossings). At the default settings (256² analysis raster) each refines
/// in about 1.4 s of CPU on one core, so the gate takes a few seconds on two.
pub const REFINE_GATE_CHARS: &str = "永字八十";

/// Refinement figures on [`REFINE_GATE_CHARS`] (medians, B-BSM, 256², default refinement):
/// mean executed CSIM and IoU of the refined tracks against the glyph, the mean gain in executed
/// CSIM over the built tracks, and how many refined tracks the robot check refused (must stay 0).
///
/// # Errors
/// When a character cannot be written, or a refined track fails the robot check.
pub fn refine_figures() -> Result<Figures> {
    let pen1 = BrushProfile::builtin("pen1")?;
    let opts = WriteOptions {
        size: 256,
        free_widths: false,
        refine: Some(RefineOptions::default()),
        ..WriteOptions::default()
    };
    let chars: Vec<char> = REFINE_GATE_CHARS.chars().collect();
    let reports = chars
        .par_iter()
        .map(|&c| {
            let p = prepare(embedded_glyph(c)?, Some(Method::Medians))?;
            Ok(write_placed(&p, &pen1, &opts, BoxRule::Auto)?.report)
        })
        .collect::<Result<Vec<_>>>()?;
    for r in &reports {
        let Some(rf) = &r.refine else { bail!("{}: no refinement report", r.char) };
        if rf.executed_before.is_none() || rf.executed_after.is_none() {
            bail!("{}: the refined track was not executed ({:?})", r.char, rf.rejected)
        }
    }
    let m = RefineMeans::of(reports.iter().filter_map(|r| r.refine.as_ref())).expect("every report refined");
    let (after, gain) = (m.executed_after.expect("executed"), m.executed_csim_gain.expect("executed"));
    Ok(Figures::from([
        ("refine/medians/bsm/executed_csim".to_string(), fig(after.csim, 0.003, Better::Higher)),
        ("refine/medians/bsm/executed_iou".to_string(), fig(after.iou, 0.005, Better::Higher)),
        ("refine/medians/bsm/executed_csim_gain".to_string(), fig(gain, 0.003, Better::Higher)),
        ("refine/medians/bsm/rejected".to_string(), fig(m.rejected as f64, 0.0, Better::Lower)),
    ]))
}
