//! `maobi observe`: a photo of a written sheet → each character's ink in its own frame, its
//! scores against the glyph and the plan, and what the brush did differently (docs/closed-loop.md).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use bezier_raster::Coverage;
use observe::{Frame, KnownMark, Photo, Registration, diagnose, ink_map, rectify, register};
use pipeline::{Mark, MarkRole, SheetTrack, similarity};
use serde_json::json;

use crate::common::{OutputLock, Stage, check_output_folder, print_json, recover_leftovers, write_atomic};

/// Below this CSIM of the observed ink against the plan (mean over the characters) the photo is
/// taken to be of another sheet.
pub const MIN_PLAN_CSIM: f64 = 0.5;

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

/// One character of the sheet as planned.
struct Planned {
    name: String,
    frame: Frame,
    reference: Coverage,
    plan: Coverage,
    paths: Vec<Vec<[f64; 2]>>,
}

/// Reads the sheet folder: its track.json (with marks) and each character's images.
/// `marks` in the order `observe::register` takes them, the four corners first, then the others;
/// `None` when a corner is missing.
pub(super) fn known_marks(marks: &[Mark]) -> Option<Vec<KnownMark>> {
    let order = [MarkRole::TopLeft, MarkRole::TopRight, MarkRole::BottomRight, MarkRole::BottomLeft];
    let mut ordered: Vec<&Mark> = order.iter().filter_map(|r| marks.iter().find(|m| m.role == *r)).collect();
    if ordered.len() != 4 {
        return None;
    }
    ordered.extend(marks.iter().filter(|m| !order.contains(&m.role)));
    Some(
        ordered
            .iter()
            .map(|m| KnownMark {
                role: m.role.name().into(),
                centre_mm: m.centre_mm,
                half_length_mm: m.half_length_mm,
                half_width_mm: m.half_width_mm,
            })
            .collect(),
    )
}

fn load_sheet(dir: &Path) -> Result<(SheetTrack, Vec<KnownMark>, Vec<Planned>)> {
    let path = dir.join("track.json");
    let text = std::fs::read_to_string(&path).with_context(|| format!("--sheet: cannot read {}", path.display()))?;
    let track: SheetTrack = serde_json::from_str(&text).with_context(|| {
        format!("--sheet: {} is not a sheet's track.json (written by `maobi write … --sheet …`)", path.display())
    })?;
    if track.marks.is_empty() {
        bail!(
            "--sheet: {} has no registration marks (written with --no-marks?): write the sheet again with marks",
            path.display()
        );
    }
    let Some(known) = known_marks(&track.marks) else {
        bail!("--sheet: {} lacks one of the four corner registration marks", path.display());
    };
    let single = track.chars.len() == 1;
    let h_min = track.brush.ranges.h_mm.min;
    let mut chars = Vec::new();
    for (i, c) in track.chars.iter().enumerate() {
        let name = format!("{:02}-{}", i + 1, c.char);
        let cdir = if single { dir.to_path_buf() } else { dir.join(&name) };
        let load = |f: &str| {
            let p = cdir.join(f);
            Coverage::load(&p).with_context(|| format!("--sheet: cannot read {}", p.display()))
        };
        let (reference, plan) = (load("reference.png")?, load("render.png")?);
        let [x0, y0, size] = c.char_box_mm;
        let frame = Frame {
            x0_mm: x0,
            y0_mm: y0,
            px_per_mm: reference.width() as f64 / size,
            width: reference.width(),
            height: reference.height(),
        };
        let paths = track.strokes[c.strokes[0]..c.strokes[1]]
            .iter()
            // The inking part of each stroke (the entry glide with only the tip touching leaves
            // nothing).
            .map(|s| s.points.iter().filter(|p| p.h_mm >= h_min).map(|p| [p.x_mm, p.y_mm]).collect())
            .collect();
        chars.push(Planned { name, frame, reference, plan, paths });
    }
    Ok((track, known, chars))
}

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    let (track, marks, chars) = load_sheet(&args.sheet)?;
    let img = bezier_raster::decode_image(&args.photo).with_context(|| format!("PHOTO {}", args.photo.display()))?;
    let photo = Photo::from_image(&img).with_context(|| format!("PHOTO {}", args.photo.display()))?;
    let ink = ink_map(&photo).with_context(|| format!("PHOTO {}", args.photo.display()))?;
    let reg = register(&ink, &marks).with_context(|| format!("PHOTO {}", args.photo.display()))?;
    let mut observed = Vec::new();
    let mut reports = Vec::new();
    for c in &chars {
        let obs = rectify(&ink, &reg, &c.frame);
        let glyph = similarity(&c.reference, &obs)?;
        let plan = similarity(&c.plan, &obs)?;
        let d = diagnose(&obs, &c.plan, &c.frame, &c.paths);
        reports.push(json!({
            "char": c.name,
            "vs_glyph": glyph,
            "vs_plan": plan,
            "diagnosis": d,
            "verdict": d.verdict(&track.brush.name),
        }));
        observed.push((obs, plan.csim));
    }
    let mean_plan = observed.iter().map(|o| o.1).sum::<f64>() / observed.len().max(1) as f64;
    if mean_plan < MIN_PLAN_CSIM {
        bail!(
            "PHOTO {}: the ink does not match the characters of {} (CSIM against the plan {mean_plan:.2}, below {MIN_PLAN_CSIM}): a photo of another sheet?",
            args.photo.display(),
            args.sheet.display()
        );
    }
    let summary = summary_json(&args, &track, &reg, &photo, &reports);
    let _lock = OutputLock::acquire("--output", &args.output)?;
    recover_leftovers(&args.output)?;
    check_output_folder("--output", &args.output, args.force)?;
    let stage = Stage::new(&args.output)?;
    for (c, (obs, _)) in chars.iter().zip(&observed) {
        write_atomic(&stage.path().join(&c.name).join("observed.png"), &obs.encode_png()?)?;
    }
    write_atomic(&stage.path().join("summary.json"), serde_json::to_string_pretty(&summary)?.as_bytes())?;
    stage.install("--output", &args.output, args.force)?;
    if args.json {
        print_json(&summary)?;
    } else {
        println!(
            "marks: residual {:.2} mm RMS, {:.2} mm max; photo {:.1} px/mm, edges {:.2} mm",
            reg.residual_rms_mm, reg.residual_max_mm, reg.px_per_mm, reg.edge_mm
        );
        for r in &reports {
            println!(
                "{}: CSIM vs glyph {:.4}, vs plan {:.4}; IoU vs plan {:.4}; {}",
                r["char"].as_str().unwrap_or(""),
                r["vs_glyph"]["csim"].as_f64().unwrap_or(f64::NAN),
                r["vs_plan"]["csim"].as_f64().unwrap_or(f64::NAN),
                r["vs_plan"]["iou"].as_f64().unwrap_or(f64::NAN),
                r["verdict"].as_str().unwrap_or("")
            );
        }
        println!("outputs in {}", args.output.display());
    }
    Ok(())
}

fn summary_json(
    args: &Args,
    track: &SheetTrack,
    reg: &Registration,
    photo: &Photo,
    reports: &[serde_json::Value],
) -> serde_json::Value {
    json!({
        "photo": args.photo.display().to_string(),
        "sheet": args.sheet.display().to_string(),
        "text": track.char,
        "brush": track.brush.name,
        "registration": {
            "residual_rms_mm": reg.residual_rms_mm,
            "residual_max_mm": reg.residual_max_mm,
            "edge_mm": reg.edge_mm,
            "photo_px_per_mm": reg.px_per_mm,
            "photo_reduced_by": photo.reduced_by,
            "corner_shift": reg.corner_shift,
            "lens_distortion": "not modelled",
            "paper_to_photo": reg.paper_to_photo,
            "marks": reg.marks,
        },
        "chars": reports,
    })
}
