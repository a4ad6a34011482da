//! `maobi observe`: a photo of a written sheet → each character's ink in its own frame, its
//! scores against the glyph and the plan, and what the brush did differently (docs/closed-loop.md).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use observe::{SheetPhoto, read_sheet_photo};
use pipeline::tuning::MIN_PLAN_CSIM;
use pipeline::{SheetFolder, SheetFolderError, plan_csim_mean};

use crate::common::{
    OutputLock, Stage, check_output_apart, check_output_folder, print_json, recover_leftovers, write_atomic,
    write_under,
};

/// Arguments of `maobi observe`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// A photo of the written sheet (JPEG or PNG, any size, taken roughly from above; the whole
    /// sheet and its registration marks in view).
    photo: PathBuf,
    /// The folder `maobi write … --sheet …` wrote the sheet to (its track.json, and each
    /// character's reference.png and render.png).
    #[arg(long, value_name = "DIR")]
    sheet: PathBuf,
    /// Output folder: `NN-<char>/observed.png` per character and summary.json. An existing
    /// non-empty folder is refused unless --force is given.
    #[arg(short, long, visible_alias = "out", value_name = "DIR")]
    output: PathBuf,
    /// Replace an existing output folder.
    #[arg(long)]
    force: bool,
    /// Print the summary as JSON on stdout.
    #[arg(long)]
    json: bool,
}

/// A sheet folder's error with the flag that named it (`--sheet`) and, for a sheet written
/// without marks, how it came to lack them.
fn sheet_error(flag: &str, e: SheetFolderError) -> anyhow::Error {
    match e {
        SheetFolderError::NoMarks { path } => anyhow::anyhow!(
            "{flag}: {} has no registration marks (written with --no-marks?): write the sheet again with marks",
            path.display()
        ),
        SheetFolderError::Score(e) => (*e).into(),
        e => anyhow::Error::new(e).context(flag.to_string()),
    }
}

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    check_output_apart("--output", &args.output, &[("--sheet", &args.sheet), ("PHOTO", &args.photo)])?;
    let sheet = SheetFolder::load(&args.sheet).map_err(|e| sheet_error("--sheet", e))?;
    let SheetPhoto { photo, ink, registration: reg } =
        read_sheet_photo(&args.photo, &sheet.marks).with_context(|| format!("PHOTO {}", args.photo.display()))?;
    let _lock = OutputLock::acquire("--output", &args.output)?;
    recover_leftovers(&args.output)?;
    check_output_folder("--output", &args.output, args.force)?;
    // One character at a time: its observed.png goes to the staging folder at once (removed
    // again if the photo turns out to be of another sheet).
    let stage = Stage::new(&args.output)?;
    let mut chars = Vec::new();
    for i in 0..sheet.chars.len() {
        let (observed, ink) = sheet.observe_char(i, &ink, &reg).map_err(|e| sheet_error("--sheet", e))?;
        write_under(stage.path(), &Path::new(&observed.folder).join("observed.png"), &ink.encode_png()?)?;
        chars.push(observed);
    }
    let mean_plan = plan_csim_mean(&chars);
    if mean_plan < MIN_PLAN_CSIM {
        bail!(
            "PHOTO {}: the ink does not match the characters of {} (CSIM against the plan {mean_plan:.2}, below {MIN_PLAN_CSIM}): a photo of another sheet?",
            args.photo.display(),
            args.sheet.display()
        );
    }
    let summary = sheet.observation(&args.photo.display().to_string(), &photo, &reg, chars);
    write_atomic(&stage.path().join("summary.json"), serde_json::to_string_pretty(&summary)?.as_bytes())?;
    stage.install("--output", &args.output, args.force)?;
    if args.json {
        print_json(&summary)?;
    } else {
        println!(
            "marks: residual {:.2} mm RMS, {:.2} mm max, each against the others at most {:.2} mm; photo {:.1} px/mm, edges {:.2} mm",
            reg.residual_rms_mm, reg.residual_max_mm, reg.leave_one_out_max_mm, reg.px_per_mm, reg.edge_mm
        );
        for r in &summary.chars {
            println!(
                "{}: CSIM vs glyph {:.4}, vs plan {:.4}; IoU vs plan {:.4}; {}",
                r.folder, r.vs_glyph.csim, r.vs_plan.csim, r.vs_plan.iou, r.verdict
            );
        }
        println!("outputs in {}", args.output.display());
    }
    Ok(())
}
