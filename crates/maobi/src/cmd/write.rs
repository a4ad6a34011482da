//! `maobi write`: characters → brush tracks, renders, references and scores.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use bezier_raster::ModelKind;
use brush_model::BrushProfile;
use pipeline::{
    BrushChoice, BrushMiss, CharReport, CharResult, Flow, Grid, Layout, NextAttempt, NextOptions, ObservedRun,
    Prepared, Sheet, SheetTrack, TextOptions, TextSummary, WriteOptions, WrittenText, auto_layout, layout_on_sheet,
    parse_sheet, rerender_with_generator, write_text, write_text_each,
};
use rayon::prelude::*;
use serde_json::json;
use trajectory::Method;

use crate::generator::committed_gen_model;

use crate::common::{
    MAX_CHAR_MM, MIN_CHAR_MM, OutputLock, PlacementArg, RefineArgs, RendererArgs, Stage, check_output_apart,
    check_output_folder, check_range, glyph_input, load_brush, parse_method, parse_model, prepare_char, print_json,
    progress, recover_leftovers, sheet_advice, write_atomic, write_atomic_with,
};

/// The `--execution` argument: how the executed figure runs the program.
fn parse_execution() -> crate::common::Named<pipeline::Execution> {
    crate::common::Named::new(&pipeline::Execution::ALL.map(pipeline::Execution::name))
}

/// Arguments of `maobi write`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The character(s) to write.
    text: String,
    /// Glyphs from another hanzi-writer-data version instead of the embedded 2.0.1 (all 9,574
    /// characters): the folder `npm pack hanzi-writer-data` unpacked into, its `package/`
    /// folder, or a folder of `<char>.json` files; with --font or --image, the stroke templates
    /// registered onto their glyphs (`--from template`).
    #[arg(long)]
    hanzi_data: Option<PathBuf>,
    /// Glyphs from fonts: TTF, OTF, TTC/OTC (see --font-index), WOFF or WOFF2 files, or folders
    /// of them (a web font split into unicode-range subsets). Repeat for several; the first file
    /// that covers a character is used.
    #[arg(long, group = "source", value_name = "FILE|DIR")]
    font: Vec<PathBuf>,
    /// Face of a font collection (TTC/OTC) given to --font, from 0.
    #[arg(long, requires = "font")]
    font_index: Option<u32>,
    /// The glyph from a photo or scan of one character (dark ink on light paper).
    #[arg(long, group = "source")]
    image: Option<PathBuf>,
    /// Centre lines: the source's stroke medians, a skeleton of the glyph, or the character's
    /// stroke template (embedded or --hanzi-data) registered onto a font or image glyph
    /// (default: medians for stroke data; template for a font or image glyph whose character
    /// has stroke data; skeleton otherwise).
    #[arg(long = "from", value_parser = parse_method())]
    method: Option<Method>,
    /// Brush: pen1, pen2, a scaled pen1 (pen1-s84, -s71, -s59, -s50, -s42, -s35, -s30, -s25), a
    /// profile JSON file, or `auto`: the built-in whose width range suits the glyphs at the box
    /// size, said in the summary (the default with --sheet or --char-mm; otherwise pen1, and the
    /// box size follows its widths).
    #[arg(long)]
    brush: Option<String>,
    /// Stroke model that draws the footprints (`--renderer analytic`).
    #[arg(long, default_value = "bsm", value_parser = parse_model())]
    model: ModelKind,
    /// Side of each character's images, px.
    #[arg(long, default_value_t = 512)]
    size: u32,
    /// How the executed figure runs each character's program on the simulator's arm:
    /// path-buffer (as `robot send` sends it: each stroke one path buffer on its timing),
    /// moves (as `robot send --motion moves`: compacted, blended) or plain (every move straight
    /// at its speed, no ramps or blends: no controller moves so).
    #[arg(long, default_value = "path-buffer", value_parser = parse_execution())]
    execution: pipeline::Execution,
    /// Also score each plan with its footprints sized freely from the glyph (the press depth not
    /// clamped to the brush's range): `plan.free_widths` in report.json, what the brush's range
    /// costs. A diagnostic that builds and renders a second track (off by default).
    #[arg(long)]
    free_widths: bool,
    /// Side of the character box on paper, mm (default: chosen so the brush's width range
    /// covers the glyphs' stroke widths; see docs/trajectory.md).
    #[arg(long, allow_negative_numbers = true)]
    char_mm: Option<f64>,
    /// Constant brush tilt α, degrees.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    alpha: f64,
    /// Lay several characters out in rows, left to right (default: columns, right to left).
    #[arg(long)]
    rows: bool,
    /// Characters per column (or row) (default: 4; with --sheet, the count that gives the largest
    /// characters).
    #[arg(long)]
    per_line: Option<usize>,
    /// The paper: A0–A6, B3–B5 (portrait; A4L for landscape), WxH in mm (180x680 for a couplet
    /// strip), or a paper.json (its size_mm). The characters are laid out inside --margin-mm and
    /// sized from the paper and their count unless --char-mm is given (docs/sheet.md).
    #[arg(long)]
    sheet: Option<String>,
    /// Margin kept free on every side of --sheet, mm.
    #[arg(long, default_value_t = 15.0, allow_negative_numbers = true)]
    margin_mm: f64,
    /// Leave out the registration marks that --sheet writes in the margin before the characters
    /// (they let `maobi observe` map a photo of the sheet onto the paper; docs/closed-loop.md).
    #[arg(long, conflicts_with = "marks")]
    no_marks: bool,
    /// Write registration marks without --sheet too (the automatic layout gets the margin they
    /// need); with --sheet, refuse a sheet too small for them (by default it is written without).
    #[arg(long)]
    marks: bool,
    /// Grid drawn under each character in the preview (never written): none, mi (米字格), tian (田字格).
    #[arg(long, default_value = "none")]
    grid: Grid,
    /// Output folder. An existing non-empty folder is refused unless --force is given.
    #[arg(short, long, visible_alias = "out", value_name = "DIR")]
    output: PathBuf,
    /// Replace an existing output folder that maobi wrote (the new run is written beside it
    /// and swapped in once complete; an error or Ctrl-C leaves the old one in place). A folder
    /// holding files maobi did not write (not in its `.maobi-written` list) is refused, naming
    /// them: nothing else is ever deleted.
    #[arg(long)]
    force: bool,
    /// Print the summary as JSON on stdout.
    #[arg(long)]
    json: bool,
    /// Write the sheet again, corrected from a photo of the last attempt: OUT is the folder
    /// `maobi observe` wrote for it (its summary.json names the sheet it observed; TEXT and the
    /// layout flags must give the same sheet). The brush the sheet was written with is re-fitted
    /// to the observed ink (width, length, spread); when it is a built-in, the built-in whose
    /// corrected footprints suit the boxes (as --brush auto) writes the next attempt (put it in
    /// the robot; saved corrected as brush.json in the output, named on stdout) and each track is
    /// refined against the glyph shifted by what the photo showed beyond the model (iterative
    /// learning control; with --refine's options, its defaults without --refine). summary.json
    /// gains every round's figures (docs/closed-loop.md).
    #[arg(long, value_name = "OUT", requires = "sheet", conflicts_with = "brush")]
    observed: Option<PathBuf>,
    /// With --observed: correct the brush only. The next attempt's tracks are built with the
    /// corrected brush and not refined against the observed residual: faster, but what the
    /// brush does beyond its footprints' sizes (such as how far its tip trails round a curve)
    /// is then left as it was (docs/closed-loop.md).
    #[arg(long, requires = "observed", conflicts_with = "refine")]
    brush_only: bool,
    #[command(flatten)]
    renderer: RendererArgs,
    #[command(flatten)]
    placement: PlacementArg,
    #[command(flatten)]
    refine: RefineArgs,
}

/// The brush a run writes with and the levers that act, decided once the glyphs are loaded.
struct BrushPlan {
    /// The brush the characters are written with.
    profile: BrushProfile,
    /// The brush tilt, rad.
    alpha_rad: f64,
    /// `--brush auto`'s choice.
    choice: Option<BrushChoice>,
    /// With `--observed`: the next attempt as the closed loop planned it.
    next: Option<NextAttempt>,
    /// The refinement: `--refine`'s, or with `--observed` the closed loop's.
    refine: Option<track_refine::RefineOptions>,
}

/// What writing the characters left: the layout, each character's report, track and box, the
/// box side the brush suits, and whether the refinement started from the last attempt's tracks.
struct Outcome {
    lay: Layout,
    results: Vec<Written>,
    brush_mm: f64,
    warm_started: bool,
}

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    let chars = checked_chars(&args)?;
    let flow = if args.rows { Flow::Rows } else { Flow::Columns };
    let (sheet, sheet_layout) = planned_sheet(&args, chars.len(), flow)?;
    // A corrected attempt is written with the brush the observed sheet was written with,
    // re-fitted to its ink.
    let observed = match &args.observed {
        Some(dir) => Some(ObservedRun::load(dir, &chars, sheet_layout.as_ref()).context("--observed")?),
        None => None,
    };
    check_inputs_apart(&args, observed.as_ref())?;
    let auto = brush_auto(&args, sheet_layout.as_ref());
    let base = base_brush(&args, auto, observed.as_ref())?;
    let alpha_rad = checked_alpha_rad(args.alpha, &base)?;
    // One run per output folder at a time; what a run that died left beside it is cleaned up
    // (or the old folder put back) before deciding whether the folder may be replaced.
    let _lock = OutputLock::acquire("--output", &args.output)?;
    recover_leftovers(&args.output)?;
    check_output_folder("--output", &args.output, args.force)?;
    // Load and analyse every glyph before writing anything.
    let prepared = prepare_all(&args, &chars)?;
    let box_mm = sheet_layout.as_ref().map(|l| l.char_mm).or(args.char_mm);
    let plan = plan_brush(&args, base, alpha_rad, box_mm, auto, observed.as_ref(), &prepared)?;
    let text = TextOptions {
        layout: sheet_layout,
        char_mm: args.char_mm,
        per_line: args.per_line.unwrap_or(4),
        flow,
        search_templates: args.placement.search(),
        mark_margin_mm: (args.marks && sheet.is_none()).then_some(pipeline::tuning::MARK_MARGIN_MM),
    };
    // Everything goes to a staging folder beside --output, swapped in at the end: a run never
    // mixes with an older one, and a failed or interrupted run leaves the old folder as it was.
    let stage = Stage::new(&args.output)?;
    let on_sheet = sheet.as_ref().and(text.layout.clone());
    let out = write_chars(&args, &plan, prepared, &text, observed.as_ref(), on_sheet.as_ref(), &stage)?;
    let reports: Vec<&CharReport> = out.results.iter().map(|r| &r.report).collect();
    let mut text_summary =
        TextSummary::new(&reports, &out.lay, flow, &plan.profile.name, args.model.name(), out.brush_mm);
    text_summary.brush_choice = plan.choice.as_ref().or(plan.next.as_ref().and_then(|n| n.choice.as_ref()));
    let fit = &mut text_summary.brush_fit;
    match fit.miss {
        Some(BrushMiss::TooWide) => fit.note.push_str(": give a larger sheet, fewer characters or a smaller brush"),
        Some(BrushMiss::TooNarrow) => fit.note.push_str(": give --char-mm or a larger brush"),
        None => {}
    }
    let mut summary = serde_json::to_value(&text_summary)?;
    if let (Some(o), Some(n)) = (&observed, &plan.next) {
        let this = n.round(o, out.warm_started);
        let rounds = NextAttempt::rounds(o, &this);
        summary["observed"] = json!(this);
        summary["rounds"] = json!(rounds);
        write_atomic(&stage.path().join("brush.json"), plan.profile.to_json().as_bytes())?;
    }
    let (sheet_track, marks_on) = sheet_track(&args, sheet.is_some(), &out, flow, &plan.profile)?;
    let single = chars.len() == 1;
    if single && marks_on {
        // The marks make one character a sheet of one: its track.json is the sheet's.
        write_atomic_with(&stage.path().join("track.json"), |w| Ok(serde_json::to_writer_pretty(w, &sheet_track)?))?;
    }
    if single && observed.is_some() {
        // The rounds live in summary.json.
        write_atomic(&stage.path().join("summary.json"), serde_json::to_string_pretty(&summary)?.as_bytes())?;
    }
    if !single {
        let tracks: Vec<&brush_model::Track> = out.results.iter().map(|r| &r.track).collect();
        let marks = &sheet_track.strokes[..sheet_track.mark_strokes];
        let img = pipeline::sheet_image_with_marks(&tracks, marks, &plan.profile, args.model, &out.lay, args.size)
            .context("sheet.png")?;
        write_atomic(&stage.path().join("sheet.png"), &img.encode_png()?)?;
        write_atomic(&stage.path().join("summary.json"), serde_json::to_string_pretty(&summary)?.as_bytes())?;
        write_atomic_with(&stage.path().join("track.json"), |w| Ok(serde_json::to_writer_pretty(w, &sheet_track)?))?;
    }
    let ran = out.results.first().filter(|_| single).and_then(|r| r.run.as_ref());
    let preview = figures::sheet_preview(&sheet_track, None, None, ran)?;
    write_atomic(&stage.path().join("preview.html"), preview.as_bytes())?;
    stage.install("--output", &args.output, args.force)?;
    if args.json {
        return print_json(&summary);
    }
    for r in &reports {
        print_char(r);
    }
    print_closing(&args, &out.lay, &text_summary.brush_fit.note, &plan, observed.as_ref());
    Ok(())
}

/// Refuses an output folder over an input (the glyph sources, the observation and its sheet).
fn check_inputs_apart(args: &Args, observed: Option<&ObservedRun>) -> Result<()> {
    let mut inputs: Vec<(&str, &Path)> = args.font.iter().map(|f| ("--font", f.as_path())).collect();
    inputs.extend(args.image.as_deref().map(|p| ("--image", p)));
    inputs.extend(args.hanzi_data.as_deref().map(|p| ("--hanzi-data", p)));
    if let Some(o) = observed {
        inputs.push(("--observed", o.dir.as_path()));
        inputs.push(("--observed's sheet", o.sheet_dir.as_path()));
    }
    check_output_apart("--output", &args.output, &inputs)
}

/// Whether `--brush auto` picks the brush: asked for, or by default with a box size known
/// before any glyph work (a sheet, --char-mm); never with `--observed`.
fn brush_auto(args: &Args, sheet_layout: Option<&Layout>) -> bool {
    let box_known = sheet_layout.is_some() || args.char_mm.is_some();
    match args.brush.as_deref() {
        Some("auto") => args.observed.is_none(),
        Some(_) => false,
        None => box_known && args.observed.is_none(),
    }
}

/// The brush named (pen1 until `auto` picks one), or the one the observed sheet was written with.
fn base_brush(args: &Args, auto: bool, observed: Option<&ObservedRun>) -> Result<BrushProfile> {
    if let Some(o) = observed {
        return Ok(o.track.brush.clone());
    }
    let named = if auto { "pen1" } else { args.brush.as_deref().unwrap_or("pen1") };
    load_brush(named)
}

/// The brush and the levers: with `--observed`, the closed loop's next attempt
/// ([`pipeline::ObservedRun::plan`]); with `--brush auto`, the built-in that suits the boxes
/// (every built-in has pen1's tilt range). The generator is trained for pen1: the neural
/// renderer keeps the brush.
fn plan_brush(
    args: &Args,
    base: BrushProfile,
    alpha_rad: f64,
    box_mm: Option<f64>,
    auto: bool,
    observed: Option<&ObservedRun>,
    prepared: &[Prepared],
) -> Result<BrushPlan> {
    let refine = args.refine.options()?;
    if let Some(o) = observed {
        let opts = NextOptions {
            model: args.model,
            refine,
            brush_only: args.brush_only,
            char_mm: box_mm,
            choose_brush: !args.renderer.neural(),
            alpha_rad,
        };
        let next = o.plan(prepared, &opts).context("--observed")?;
        if let Some(e) = &next.kept_because {
            eprintln!("note: --observed: the brush {} is kept (no other brush considered): {e}", next.corrected.name);
        }
        let (profile, refine) = (next.brush.clone(), next.refine);
        return Ok(BrushPlan { profile, alpha_rad, choice: None, next: Some(next), refine });
    }
    let choice = match box_mm {
        Some(mm) if auto && !args.renderer.neural() => {
            Some(pipeline::choose_brush(prepared, &pipeline::builtin_brushes(), mm, alpha_rad))
        }
        _ => None,
    };
    let profile = choice.as_ref().map_or(base, |c| c.profile.clone());
    Ok(BrushPlan { profile, alpha_rad, choice, next: None, refine })
}

/// Writes every character (each one's files as soon as it is done where nothing works on all
/// of them together; with `--observed`, refined against the residual after writing; with the
/// neural renderer, rendered again).
fn write_chars(
    args: &Args,
    plan: &BrushPlan,
    prepared: Vec<Prepared>,
    text: &TextOptions,
    observed: Option<&ObservedRun>,
    on_sheet: Option<&Layout>,
    stage: &Stage,
) -> Result<Outcome> {
    let generator = match plan.refine {
        Some(r) if r.gradients == track_refine::Gradients::Generator => Some(committed_gen_model()?),
        _ => None,
    };
    let opts = WriteOptions {
        model: args.model,
        size: args.size,
        execution: args.execution,
        free_widths: args.free_widths,
        // One character's preview plays the program its executed figure ran.
        keep_run: prepared.len() == 1,
        alpha_rad: plan.alpha_rad,
        // With --observed the refinement runs after writing, against the ILC target.
        refine: if observed.is_some() { None } else { plan.refine },
        generator,
        ..WriteOptions::default()
    };
    let profile = &plan.profile;
    let pb = progress(prepared.len() as u64, "write");
    let single = prepared.len() == 1;
    let char_dir = |i: usize, r: &CharResult| {
        if single { stage.path().to_path_buf() } else { stage.path().join(pipeline::char_folder(i, &r.report.char)) }
    };
    // Without --observed or the neural renderer, only each character's report and track are
    // kept once its files are written: a long text is written in bounded memory.
    if observed.is_none() && !args.renderer.neural() {
        let (lay, results, brush_mm) = write_text_each(prepared, profile, &opts, text, &|i, r| {
            write_outputs(&char_dir(i, &r), &r, profile, on_sheet)?;
            pb.inc(1);
            Ok::<_, anyhow::Error>(Written::from(r))
        })?;
        pb.finish_and_clear();
        return Ok(Outcome { lay, results, brush_mm, warm_started: false });
    }
    let kept = observed.map(|_| prepared.clone());
    let written = write_text(prepared, profile, &opts, text, &|| pb.inc(1))?;
    let WrittenText { layout: lay, mut results, brush_char_mm: brush_mm } = written;
    let mut warm_started = false;
    if let (Some(o), Some(next), Some(prepared)) = (observed, &plan.next, &kept) {
        warm_started = next.refine(o, &mut results, prepared, &opts).context("--observed")?;
    }
    if args.renderer.neural() {
        let g = args.renderer.generator()?;
        rerender_with_generator(&mut results, &g, profile, args.size).context("--renderer neural")?;
    }
    let mut kept = Vec::new();
    for (i, r) in results.into_iter().enumerate() {
        write_outputs(&char_dir(i, &r), &r, profile, on_sheet)?;
        kept.push(Written::from(r));
    }
    pb.finish_and_clear();
    Ok(Outcome { lay, results: kept, brush_mm, warm_started })
}

/// The sheet's track, with registration marks by default with --sheet (a sheet too small for
/// them is written without, and says so, unless --marks asked for them); whether it has marks.
fn sheet_track(
    args: &Args,
    on_sheet: bool,
    out: &Outcome,
    flow: Flow,
    profile: &BrushProfile,
) -> Result<(SheetTrack, bool)> {
    let lay = &out.lay;
    let chars: Vec<_> =
        out.results.iter().map(|r| (r.report.char.clone(), r.char_box, r.track.strokes.as_slice())).collect();
    let sheet_track = SheetTrack::new(lay, flow, args.grid, &chars, profile);
    if !(if on_sheet { !args.no_marks } else { args.marks }) {
        return Ok((sheet_track, false));
    }
    match pipeline::registration_marks(lay, profile) {
        Ok(marks) => Ok((sheet_track.with_marks(&marks, profile), true)),
        Err(e) if !args.marks => {
            eprintln!("written without registration marks (`maobi observe` needs them): {e}");
            Ok((sheet_track, false))
        }
        Err(e) => Err(anyhow::Error::new(e).context(if on_sheet {
            format!("--marks with --margin-mm {}", lay.margin_mm)
        } else {
            "--marks (give a larger --sheet)".to_string()
        })),
    }
}

/// The closing lines on stdout: the sheet, the outputs and the brush (with `--observed`, what
/// the photo corrected).
fn print_closing(args: &Args, lay: &Layout, fit_note: &str, plan: &BrushPlan, observed: Option<&ObservedRun>) {
    println!(
        "{} sheet {:.0}×{:.0} mm, char box {:.1} mm ({}); outputs in {} (preview.html to watch it)",
        lay.sheet.name,
        lay.sheet.width_mm,
        lay.sheet.height_mm,
        lay.char_mm,
        fit_note,
        args.output.display()
    );
    let profile = &plan.profile;
    let (next, o) = match (&plan.choice, &plan.next, observed) {
        (Some(c), _, _) => return println!("brush (--brush auto): {}", c.reason),
        (None, Some(n), Some(o)) => (n, o),
        _ => return println!("brush: {}", profile.name),
    };
    let c = &next.correction;
    let then = next.choice.as_ref().map_or(String::new(), |c| format!("; brush for the next attempt: {}", c.reason));
    let ilc = if next.refine.is_some() {
        "; tracks refined against the glyph shifted by the observed residual (ILC)"
    } else {
        ""
    };
    let brush_json = args.output.join("brush.json");
    let corrected_name = &next.corrected.name;
    match c.not_taken {
        Some(v) => println!(
            "brush kept from the photo (--observed): {corrected_name}; the best re-fit (width ×{:.3}, length ×{:.3}, spread {:+.2} mm, {}) explains only {:.0} % of the ink error {:.4} (under {:.0} %){then}; written to {}{ilc}",
            v[0],
            v[1],
            v[2],
            hairs_text(&profile.hairs),
            100.0 * (1.0 - v[3] / c.ink_error_before),
            c.ink_error_before,
            100.0 * pipeline::tuning::MIN_CORRECTION_GAIN,
            brush_json.display(),
        ),
        None => println!(
            "brush re-fitted from the photo (--observed): {corrected_name} = width ×{:.3}, length ×{:.3}, spread {:+.2} mm on top of {} ({}; ink error {:.4} → {:.4}){then}; written to {}{ilc}",
            c.width_factor,
            c.length_factor,
            c.spread_mm,
            o.track.brush.name,
            hairs_text(&profile.hairs),
            c.ink_error_before,
            c.ink_error_after,
            brush_json.display(),
        ),
    }
}

/// The characters of TEXT, after checking every flag that needs no file.
fn checked_chars(args: &Args) -> Result<Vec<char>> {
    let chars: Vec<char> = args.text.chars().filter(|c| !c.is_whitespace()).collect();
    if chars.is_empty() {
        bail!("TEXT is empty: give at least one character");
    }
    let spaces = args.text.chars().count() - chars.len();
    if spaces > 0 {
        eprintln!(
            "note: TEXT has {spaces} space(s) or line break(s); they are left out and the characters laid out one after another (use --per-line to break lines)"
        );
    }
    if args.image.is_some() && chars.len() != 1 {
        bail!("--image holds one character; TEXT has {}", chars.len());
    }
    if !(64..=4096).contains(&args.size) {
        bail!("--size {}: expected 64..=4096 px", args.size);
    }
    if args.per_line == Some(0) {
        bail!("--per-line 0: expected at least 1");
    }
    if let Some(mm) = args.char_mm {
        check_range("--char-mm", mm, MIN_CHAR_MM, MAX_CHAR_MM, "mm")?;
    }
    check_range("--margin-mm", args.margin_mm, 0.0, 500.0, "mm")?;
    Ok(chars)
}

/// Loads every character's glyph from the source the flags name and finds its centre lines.
fn prepare_all(args: &Args, chars: &[char]) -> Result<Vec<Prepared>> {
    let images = args.image.as_ref().map(|img| vec![(chars[0], img.clone())]);
    let input = glyph_input(&args.font, args.font_index, images, args.hanzi_data.clone())?;
    chars.par_iter().map(|&c| prepare_char(&input, c, args.method, args.json)).collect()
}

/// One character's line (and its refinement's) on stdout.
fn print_char(r: &CharReport) {
    // The executed figure (what the robot would write) is the headline.
    let executed = match (r.executed, r.agreement) {
        (Some(e), Some(a)) => format!(
            "executed CSIM {:.4}  SSIM {:.4}  IoU {:.4}  (planned CSIM {:.4}, planned vs executed {:.4})",
            e.csim, e.ssim, e.iou, r.plan.csim, a.csim
        ),
        _ => format!("planned CSIM {:.4}  SSIM {:.4}  IoU {:.4}", r.plan.csim, r.plan.ssim, r.plan.iou),
    };
    println!(
        "{} ({} via {}, {}): {executed}{}  strokes {}{}  points {}  {:.1} ms",
        r.char,
        r.source,
        r.method,
        r.model,
        r.plan.chamfer_pct.map_or(String::new(), |c| format!("  chamfer {c:.2}%")),
        r.plan.strokes_found,
        r.plan.strokes_expected.map_or(String::new(), |e| format!("/{e}")),
        r.plan.points,
        r.timing_ms.plan
    );
    if let Some(rf) = &r.refine {
        let fig = |s: Option<pipeline::Similarity>| s.map_or("-".into(), |s| format!("{:.4}", s.csim));
        println!(
            "  refined ({} steps, {:.0} ms): executed CSIM {} → {}, planned CSIM {:.4} → {:.4}{}",
            rf.options.iterations,
            rf.millis,
            fig(rf.executed_before),
            fig(rf.executed_after),
            rf.planned_before.csim,
            rf.planned_after.csim,
            rf.rejected.as_ref().map_or(String::new(), |w| format!("; not used: {w}"))
        );
    }
}

/// `--alpha` in radians, checked against the brush's calibrated tilt range.
fn checked_alpha_rad(alpha_deg: f64, profile: &BrushProfile) -> Result<f64> {
    let alpha_rad = alpha_deg.to_radians();
    if !profile.ranges.alpha_rad.contains(alpha_rad) {
        bail!(
            "--alpha {alpha_deg}: outside the brush's calibrated tilt range {:.1}–{:.1}°",
            profile.ranges.alpha_rad.min.to_degrees(),
            profile.ranges.alpha_rad.max.to_degrees()
        );
    }
    Ok(alpha_rad)
}

/// The `--sheet` and, with one, the layout on it (known before any glyph work unless the size
/// comes from the glyphs); refuses a sheet image over the size limit either way.
fn planned_sheet(args: &Args, n: usize, flow: Flow) -> Result<(Option<Sheet>, Option<Layout>)> {
    let Some(spec) = args.sheet.as_deref() else {
        // Without a sheet the image's size in px does not depend on the box side: check it at 1 mm.
        if n >= 2 {
            let per_line = args.per_line.unwrap_or(4);
            auto_layout(n, 1.0, per_line, flow).check_image_size(args.size).with_context(|| {
                format!("--size {} with --per-line {per_line}: lower --size or change --per-line", args.size)
            })?;
        }
        return Ok((None, None));
    };
    let advice = |e| sheet_advice(e, spec, args.margin_mm);
    let sheet = parse_sheet(spec).map_err(advice)?;
    let layout = layout_on_sheet(&sheet, n, flow, args.per_line, args.margin_mm, args.char_mm).map_err(advice)?;
    layout.check_image_size(args.size).with_context(|| format!("--size {}: lower --size", args.size))?;
    Ok((Some(sheet), Some(layout)))
}

/// What is kept of a character once its files are written: its report, track and box, and
/// its program as it ran when kept for the preview ([`WriteOptions::keep_run`]).
struct Written {
    report: CharReport,
    track: brush_model::Track,
    char_box: trajectory::CharBox,
    run: Option<pipeline::ExecutedRun>,
}

impl From<CharResult> for Written {
    fn from(r: CharResult) -> Self {
        Written { report: r.report, track: r.track, char_box: r.char_box, run: r.executed_run }
    }
}

/// One character's files in `dir` (created by the first write, under the output gate).
fn write_outputs(dir: &Path, r: &CharResult, profile: &BrushProfile, sheet: Option<&Layout>) -> Result<()> {
    // The pictures encoded at once, then written in order.
    for (name, png) in figures::char_pictures(r)? {
        write_atomic(&dir.join(name), &png)?;
    }
    // Where this character sits: in its box and, with --sheet, on the sheet, in paper mm.
    let track = r.track_file(profile, sheet.map(|l| [l.sheet.width_mm, l.sheet.height_mm]));
    write_atomic(&dir.join("track.json"), serde_json::to_string_pretty(&track)?.as_bytes())?;
    write_atomic(&dir.join("report.json"), serde_json::to_string_pretty(&r.report)?.as_bytes())?;
    Ok(())
}

/// The fitted hairs in words, for the closing line of `write --observed`.
fn hairs_text(h: &brush_model::HairMotion) -> String {
    format!(
        "the tip trailing {:.1} footprint lengths, the hairs following from {:.2} mm of press",
        h.trail_reach, h.contact_h_mm
    )
}
