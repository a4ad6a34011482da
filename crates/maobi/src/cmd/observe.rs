//! `maobi observe`: a photo of a written sheet → each character's ink in its own frame, its
//! scores against the glyph and the plan, and what the brush did differently (docs/closed-loop.md).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use bezier_raster::Coverage;
use observe::{Frame, KnownMark, Photo, Registration, diagnose, ink_map, rectify, register};
use pipeline::{
    OBSERVATION_VERSION, Observation, ObservedChar, ObservedRegistration, ObservedSheet, SheetTrack, similarity,
};

use crate::common::{
    OutputLock, Stage, check_output_apart, check_output_folder, print_json, recover_leftovers, write_atomic,
    write_under,
};

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

/// The sheet folder read back: its validated track.json (and that file's bytes, for the
/// fingerprint), the marks in `observe::register`'s order, and each character's frame and
/// paths (images are read one character at a time, [`Planned::images`]).
pub(super) struct SheetFolder {
    /// The folder, absolute.
    pub dir: PathBuf,
    pub track: SheetTrack,
    pub track_bytes: Vec<u8>,
    pub marks: Vec<KnownMark>,
    chars: Vec<Planned>,
}

/// One character of the sheet as planned.
struct Planned {
    name: String,
    /// Its folder (the sheet's own for a sheet of one).
    dir: PathBuf,
    frame: Frame,
    paths: Vec<Vec<[f64; 2]>>,
}

impl Planned {
    /// Its reference.png and render.png (sizes checked against the frame before decoding).
    fn images(&self) -> Result<(Coverage, Coverage)> {
        let load = |f: &str| -> Result<Coverage> {
            let p = self.dir.join(f);
            let img = Coverage::load(&p).with_context(|| format!("--sheet: cannot read {}", p.display()))?;
            if (img.width(), img.height()) != (self.frame.width, self.frame.height) {
                bail!(
                    "--sheet: {} is {}×{} px, expected {}×{} px (the size of the sheet's first reference.png)",
                    p.display(),
                    img.width(),
                    img.height(),
                    self.frame.width,
                    self.frame.height
                );
            }
            Ok(img)
        };
        Ok((load("reference.png")?, load("render.png")?))
    }
}

/// Reads and validates the sheet folder `dir` (`flag` names it in errors).
pub(super) fn load_sheet(flag: &str, dir: &Path) -> Result<SheetFolder> {
    let dir =
        std::fs::canonicalize(dir).with_context(|| format!("{flag}: cannot read the folder {}", dir.display()))?;
    let path = dir.join("track.json");
    let (track, track_bytes) = SheetTrack::load(&path).with_context(|| flag.to_string())?;
    if track.marks.is_empty() {
        bail!(
            "{flag}: {} has no registration marks (written with --no-marks?): write the sheet again with marks",
            path.display()
        );
    }
    let Some(known) = pipeline::known_marks(&track.marks) else {
        bail!("{flag}: {} lacks one of the four corner registration marks", path.display());
    };
    if known.len() < 5 {
        bail!("{flag}: {} has only the four corner registration marks (a sheet has six)", path.display());
    }
    let single = track.chars.len() == 1;
    let h_min = track.brush.ranges.h_mm.min;
    // Every character's images have the first one's size (one --size for the sheet), read from
    // its header before anything is decoded.
    let first = if single { dir.clone() } else { dir.join(pipeline::char_folder(0, &track.chars[0].char)) };
    let side = image_side(flag, &first.join("reference.png"))?;
    let mut chars = Vec::new();
    for (i, c) in track.chars.iter().enumerate() {
        let name = pipeline::char_folder(i, &c.char);
        let cdir = if single { dir.clone() } else { dir.join(&name) };
        let [x0, y0, size] = c.char_box_mm;
        for f in ["reference.png", "render.png"] {
            let p = cdir.join(f);
            if image_side(flag, &p)? != side {
                bail!(
                    "{flag}: {} is not the size of {} ({side}×{side} px): every character image of a sheet has one size",
                    p.display(),
                    first.join("reference.png").display()
                );
            }
        }
        let frame = Frame { x0_mm: x0, y0_mm: y0, px_per_mm: side as f64 / size, width: side, height: side };
        let paths = track.strokes[c.strokes[0]..c.strokes[1]]
            .iter()
            // The inking part of each stroke (the entry glide with only the tip touching leaves
            // nothing).
            .map(|s| s.points.iter().filter(|p| p.h_mm >= h_min).map(|p| [p.x_mm, p.y_mm]).collect())
            .collect();
        chars.push(Planned { name, dir: cdir, frame, paths });
    }
    Ok(SheetFolder { dir, track, track_bytes, marks: known, chars })
}

/// The side of a character image of the sheet, from its header: square and within
/// [`pipeline::OBSERVED_PX`].
fn image_side(flag: &str, p: &Path) -> Result<u32> {
    let (w, h) = bezier_raster::image_header(p).with_context(|| format!("{flag}: cannot read {}", p.display()))?;
    let [lo, hi] = pipeline::OBSERVED_PX;
    if w != h || !(lo..=hi).contains(&w) {
        bail!(
            "{flag}: {} is {w}×{h} px: expected a square of {lo}..={hi} px (a character image of the sheet)",
            p.display()
        );
    }
    Ok(w)
}

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    check_output_apart("--output", &args.output, &[("--sheet", &args.sheet), ("PHOTO", &args.photo)])?;
    let sheet = load_sheet("--sheet", &args.sheet)?;
    let photo_err = || format!("PHOTO {}", args.photo.display());
    let img = bezier_raster::decode_image(&args.photo).with_context(photo_err)?;
    let photo = Photo::from_image(&img).with_context(photo_err)?;
    drop(img);
    let ink = ink_map(&photo).with_context(photo_err)?;
    let reg = register(&ink, &sheet.marks).with_context(photo_err)?;
    let _lock = OutputLock::acquire("--output", &args.output)?;
    recover_leftovers(&args.output)?;
    check_output_folder("--output", &args.output, args.force)?;
    // One character at a time: its observed.png goes to the staging folder at once (removed
    // again if the photo turns out to be of another sheet).
    let stage = Stage::new(&args.output)?;
    let mut chars = Vec::new();
    for (c, sc) in sheet.chars.iter().zip(&sheet.track.chars) {
        let (reference, plan) = c.images()?;
        let obs = rectify(&ink, &reg, &c.frame);
        let glyph = similarity(&reference, &obs)?;
        let vs_plan = similarity(&plan, &obs)?;
        let d = diagnose(&obs, &plan, &c.frame, &c.paths);
        write_under(stage.path(), &Path::new(&c.name).join("observed.png"), &obs.encode_png()?)?;
        chars.push(ObservedChar {
            char: sc.char.clone(),
            folder: c.name.clone(),
            size_px: c.frame.width,
            vs_glyph: glyph.into(),
            vs_plan: vs_plan.into(),
            verdict: d.verdict(&sheet.track.brush.name),
            diagnosis: d,
        });
    }
    let mean_plan = chars.iter().map(|o| o.vs_plan.csim).sum::<f64>() / chars.len().max(1) as f64;
    if mean_plan < MIN_PLAN_CSIM {
        bail!(
            "PHOTO {}: the ink does not match the characters of {} (CSIM against the plan {mean_plan:.2}, below {MIN_PLAN_CSIM}): a photo of another sheet?",
            args.photo.display(),
            args.sheet.display()
        );
    }
    let summary = observation(&args, &sheet, &reg, &photo, chars);
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

/// The typed observation `summary.json` holds.
fn observation(
    args: &Args,
    sheet: &SheetFolder,
    reg: &Registration,
    photo: &Photo,
    chars: Vec<ObservedChar>,
) -> Observation {
    Observation {
        version: OBSERVATION_VERSION,
        photo: args.photo.display().to_string(),
        sheet: ObservedSheet { path: sheet.dir.clone(), track_fingerprint: pipeline::fingerprint(&sheet.track_bytes) },
        text: sheet.track.chars.iter().map(|c| c.char.as_str()).collect(),
        brush: sheet.track.brush.name.clone(),
        registration: ObservedRegistration {
            residual_rms_mm: reg.residual_rms_mm,
            residual_max_mm: reg.residual_max_mm,
            leave_one_out_max_mm: reg.leave_one_out_max_mm,
            edge_mm: reg.edge_mm,
            photo_px_per_mm: reg.px_per_mm,
            photo_reduced_by: photo.reduced_by,
            corner_shift: reg.corner_shift,
            lens_distortion: "not modelled".into(),
            paper_to_photo: reg.paper_to_photo,
            marks: reg.marks.clone(),
        },
        chars,
    }
}
