//! `maobi write`: characters → brush tracks, renders, references and scores.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use bezier_raster::ModelKind;
use brush_model::BrushProfile;
use pipeline::{
    BrushFit, BrushMiss, CharReport, CharResult, Flow, GlyphInput, Grid, Layout, Observation, Prepared, Sheet,
    SheetError, SheetTrack, TextOptions, WriteOptions, WrittenText, auto_layout, layout_on_sheet, parse_sheet,
    prepare_loaded, rerender_with_generator, write_text, write_text_each,
};
use rayon::prelude::*;
use serde_json::json;
use trajectory::Method;

use crate::generator::committed_gen_model;

use crate::common::{
    OutputLock, RendererArgs, Stage, check_output_apart, check_output_folder, check_range, load_brush, parse_method,
    parse_model, print_json, progress, recover_leftovers, write_atomic, write_atomic_with,
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

/// `--placement search|auto` of `write` and `evaluate`.
#[derive(clap::Args, Debug)]
pub(crate) struct PlacementArg {
    /// How template tracks (`--from template`, the default for font and image glyphs) are
    /// placed: `search` builds the plan at a few char box sizes (0.8–1.35× the size from the
    /// widths), with each stroke's corners split or written in one piece, and keeps the plan
    /// most like the glyph (docs/trajectory.md, "Template registration"); where the size is
    /// fixed (--char-mm, or characters sharing one box size) only the splits are searched.
    /// `auto`: the size from the widths, every corner split. Other methods are not affected.
    #[arg(long, default_value = "search", value_parser = ["search", "auto"])]
    placement: String,
}

impl PlacementArg {
    /// Whether template tracks are placed by search.
    pub(crate) fn search(&self) -> bool {
        self.placement == "search"
    }
}

/// `--refine [--iters N] [--gradients analytic|generator]` of `write` and `evaluate`.
#[derive(clap::Args, Debug)]
pub(crate) struct RefineArgs {
    /// Refine each track by gradient descent against its glyph before executing it (see
    /// docs/trajectory.md, "Refinement"): each character's report gains the before/after
    /// figures (and, when writing, refine.png the loss curve); the means before and after
    /// are printed.
    #[arg(long)]
    refine: bool,
    /// Gradient steps of --refine (default 20).
    #[arg(long, requires = "refine")]
    iters: Option<usize>,
    /// Where --refine takes its gradients from: the analytic soft footprint (default: as good
    /// to 0.001 CSIM at the defaults and about 4.5× faster) or the B-BSMG generator's VJP (see
    /// docs/trajectory.md, "Refinement"). Scores always come from the analytic renderer.
    #[arg(long, requires = "refine", value_parser = ["analytic", "generator"])]
    gradients: Option<String>,
}

impl RefineArgs {
    /// The refinement options (`None` without `--refine`).
    pub(crate) fn options(&self) -> Result<Option<track_refine::RefineOptions>> {
        if !self.refine {
            return Ok(None);
        }
        let mut o = track_refine::RefineOptions::default();
        if let Some(n) = self.iters {
            if !(1..=10_000).contains(&n) {
                bail!("--iters {n}: expected 1..=10000 gradient steps");
            }
            o.iterations = n;
        }
        if self.gradients.as_deref() == Some("generator") {
            o.gradients = track_refine::Gradients::Generator;
        }
        Ok(Some(o))
    }
}

/// The glyph source the flags name: `--font` files, an `--image` per character, or hanzi stroke
/// data (embedded, or `--hanzi-data`), which is also where templates come from.
pub(crate) fn glyph_input(
    fonts: &[PathBuf],
    face_index: Option<u32>,
    images: Option<Vec<(char, PathBuf)>>,
    hanzi: Option<PathBuf>,
) -> Result<GlyphInput> {
    Ok(if !fonts.is_empty() {
        GlyphInput::fonts(fonts, face_index, hanzi).context("--font")?
    } else if let Some(images) = images {
        GlyphInput::Images(images, hanzi)
    } else {
        GlyphInput::Hanzi(hanzi)
    })
}

/// Loads `ch` and finds its centre lines ([`pipeline::prepare_loaded`]); says on stderr (unless
/// `quiet`) which template strokes found no ink, and turns a glyph without strokes into advice.
pub(crate) fn prepare_char(input: &GlyphInput, ch: char, method: Option<Method>, quiet: bool) -> Result<Prepared> {
    let loaded = input.load(ch).map_err(|e| match e {
        pipeline::Error::Glyph(trajectory::GlyphError::Unknown { .. }) => anyhow::Error::new(e).context(format!(
            "no glyph for {ch:?}: add a source that covers it with --font FILE (a CJK font), --image FILE (a photo \
             or scan of it) or --hanzi-data DIR (another hanzi-writer-data: the folder `npm pack hanzi-writer-data` \
             unpacked into, or its package/ folder)"
        )),
        e => e.into(),
    })?;
    let p = match prepare_loaded(loaded, method) {
        Ok(p) => p,
        Err(pipeline::Error::NoStrokes { ch, image, missing }) => bail!(
            "{ch}: found no strokes{}{} (is it one character, dark ink on light paper, strokes wider than a hair?)",
            image.map_or(String::new(), |p| format!(" in --image {}", p.display())),
            missing.map_or(String::new(), |(m, n)| format!(
                " for {m} of the template's {n} strokes (try --from skeleton if it is another character)"
            ))
        ),
        Err(e) => return Err(e.into()),
    };
    if let (Some(t), false) = (&p.template, quiet) {
        if !t.missing.is_empty() {
            let list: Vec<String> = t.missing.iter().map(|i| i.to_string()).collect();
            eprintln!(
                "{}: template stroke(s) {} found no ink under them (kept where the template put them; see report.json)",
                p.glyph.ch,
                list.join(", ")
            );
        }
    }
    Ok(p)
}

/// A sheet error with the flag its value came from and what to change.
pub(crate) fn sheet_advice(e: SheetError, spec: &str, margin_mm: f64) -> anyhow::Error {
    let flag = match &e {
        SheetError::NoRoom { .. } => format!("--margin-mm {margin_mm}"),
        SheetError::DoesNotFit { char_mm, .. } => format!("--char-mm {char_mm}"),
        _ => format!("--sheet {spec}"),
    };
    anyhow::Error::new(e).context(flag)
}

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    let chars = checked_chars(&args)?;
    let flow = if args.rows { Flow::Rows } else { Flow::Columns };
    let (sheet, sheet_layout) = planned_sheet(&args, chars.len(), flow)?;
    // With a box size known before any glyph work (a sheet, --char-mm), `auto` (the default
    // then) picks the brush once the glyphs are loaded; every built-in has pen1's tilt range.
    let box_mm = sheet_layout.as_ref().map(|l| l.char_mm).or(args.char_mm);
    // A corrected attempt is written with the brush the observed sheet was written with,
    // re-fitted to its ink.
    let observed = match &args.observed {
        Some(dir) => Some(load_observed(dir, &chars, sheet_layout.as_ref())?),
        None => None,
    };
    let mut inputs: Vec<(&str, &Path)> = args.font.iter().map(|f| ("--font", f.as_path())).collect();
    inputs.extend(args.image.as_deref().map(|p| ("--image", p)));
    inputs.extend(args.hanzi_data.as_deref().map(|p| ("--hanzi-data", p)));
    if let Some(o) = &observed {
        inputs.push(("--observed", o.dir.as_path()));
        inputs.push(("--observed's sheet", o.sheet_dir.as_path()));
    }
    check_output_apart("--output", &args.output, &inputs)?;
    let auto = match args.brush.as_deref() {
        Some("auto") => observed.is_none(),
        Some(_) => false,
        None => box_mm.is_some() && observed.is_none(),
    };
    let named = if auto { "pen1" } else { args.brush.as_deref().unwrap_or("pen1") };
    let mut profile = match &observed {
        Some(o) => o.track.brush.clone(),
        None => load_brush(named)?,
    };
    let alpha_rad = checked_alpha_rad(args.alpha, &profile)?;
    // One run per output folder at a time; what a run that died left beside it is cleaned up
    // (or the old folder put back) before deciding whether the folder may be replaced.
    let _lock = OutputLock::acquire("--output", &args.output)?;
    recover_leftovers(&args.output)?;
    check_output_folder("--output", &args.output, args.force)?;
    // The brush re-fitted to the observed ink (its calibrated ranges, and so the tilt check
    // above, stay as they were).
    let correction = match &observed {
        Some(o) => {
            let (c, corrected) = o.correct_brush(&profile, args.model)?;
            profile = corrected;
            Some(c)
        }
        None => None,
    };
    // Load and analyse every glyph before writing anything.
    let prepared = prepare_all(&args, &chars)?;
    // With --observed both levers act: the tracks are refined against the glyph shifted by the
    // residual, what the brush that wrote the last attempt (corrected) does not explain (ILC),
    // with --refine's options or, without --refine, its defaults; --brush-only leaves the track
    // lever out. The next attempt is planned, refined and its residual predicted with the
    // corrected brush, its fitted hairs included.
    let refine = match (args.refine.options()?, &observed) {
        (Some(r), _) => Some(r),
        (None, Some(_)) if !args.brush_only => Some(track_refine::RefineOptions::default()),
        _ => None,
    };
    let residuals = match (&observed, refine) {
        (Some(o), Some(_)) => Some(o.residuals(&profile, args.model)?),
        _ => None,
    };
    // After the re-fit, the brush for the next attempt: the one whose corrected footprints
    // suit the box (as `--brush auto`, with the correction carried over to every built-in).
    let corrected_name = profile.name.clone();
    let next_choice = match (&observed, box_mm) {
        (Some(o), Some(mm)) if !args.renderer.neural() => {
            let c = o.next_brush(&prepared, &profile, mm, alpha_rad);
            if let Some(c) = &c {
                profile = c.profile.clone();
            }
            c
        }
        _ => None,
    };
    let choice = match box_mm {
        // The generator is trained for pen1: the neural renderer keeps it.
        Some(mm) if auto && !args.renderer.neural() => {
            let c = pipeline::choose_brush(&prepared, &pipeline::builtin_brushes(), mm, alpha_rad);
            profile = c.profile.clone();
            Some(c)
        }
        _ => None,
    };
    let generator = match refine {
        Some(r) if r.gradients == track_refine::Gradients::Generator => Some(committed_gen_model()?),
        _ => None,
    };
    // With --observed the refinement runs after writing, against the ILC target.
    let write_refine = if observed.is_some() { None } else { refine };
    let mut opts = WriteOptions {
        model: args.model,
        size: args.size,
        execution: args.execution,
        free_widths: args.free_widths,
        alpha_rad,
        refine: write_refine,
        generator,
        ..WriteOptions::default()
    };
    let text = TextOptions {
        layout: sheet_layout,
        char_mm: args.char_mm,
        per_line: args.per_line.unwrap_or(4),
        flow,
        search_templates: args.placement.search(),
        mark_margin_mm: (args.marks && sheet.is_none()).then_some(pipeline::tuning::MARK_MARGIN_MM),
    };
    let pb = progress(chars.len() as u64, "write");
    let kept = observed.as_ref().map(|_| prepared.clone());
    let single = chars.len() == 1;
    // Everything goes to a staging folder beside --output, swapped in at the end: a run never
    // mixes with an older one, and a failed or interrupted run leaves the old folder as it was.
    let stage = Stage::new(&args.output)?;
    let char_dir = |i: usize, r: &CharResult| {
        if single { stage.path().to_path_buf() } else { stage.path().join(pipeline::char_folder(i, &r.report.char)) }
    };
    let on_sheet = sheet.as_ref().and(text.layout.clone());
    // Without --observed or the neural renderer (which work on all the characters' results
    // together), each character's files are written as soon as it is done and only its report
    // and track are kept: a long text is written in bounded memory.
    let stream = observed.is_none() && !args.renderer.neural();
    let (lay, results, brush_mm, warm_started) = if stream {
        let (lay, kept, brush_mm) = write_text_each(prepared, &profile, &opts, &text, &|i, r| {
            write_outputs(&char_dir(i, &r), &r, &profile, on_sheet.as_ref())?;
            pb.inc(1);
            Ok::<_, anyhow::Error>(Written::from(r))
        })?;
        (lay, kept, brush_mm, false)
    } else {
        let written = write_text(prepared, &profile, &opts, &text, &|| pb.inc(1))?;
        let WrittenText { layout: lay, mut results, brush_char_mm: brush_mm } = written;
        let mut warm_started = false;
        if let (Some(residuals), Some(ro), Some(prepared)) = (&residuals, refine, &kept) {
            opts.refine = Some(ro);
            // With the brush the last attempt was written with, each refinement starts from the
            // last attempt's track (the residual was measured there).
            let last = observed.as_ref().filter(|o| same_brush(&o.track.brush, &profile)).map(|o| o.attempts());
            warm_started = last.is_some();
            let starts: Option<Vec<&[brush_model::Stroke]>> =
                last.as_ref().map(|a| a.iter().map(|a| a.strokes).collect());
            pipeline::refine_observed(&mut results, prepared, residuals, starts.as_deref(), &profile, &opts, &ro)
                .context("--observed: refining against the observed residual")?;
        }
        if args.renderer.neural() {
            let g = args.renderer.generator()?;
            rerender_with_generator(&mut results, &g, &profile, args.size).context("--renderer neural")?;
        }
        let mut kept = Vec::new();
        for (i, r) in results.into_iter().enumerate() {
            write_outputs(&char_dir(i, &r), &r, &profile, on_sheet.as_ref())?;
            kept.push(Written::from(r));
        }
        (lay, kept, brush_mm, warm_started)
    };
    pb.finish_and_clear();
    let char_mm = lay.char_mm;
    let reports: Vec<&CharReport> = results.iter().map(|r| &r.report).collect();
    let mut summary = summary_json(&args, &chars, &lay, flow, &profile, &reports, brush_mm);
    summary["brush_choice"] = json!(choice.as_ref().or(next_choice.as_ref()));
    if let (Some(o), Some(c)) = (&observed, &correction) {
        let (this, rounds) = o.rounds(c, &profile, next_choice.as_ref(), refine.is_some(), warm_started);
        summary["observed"] = this;
        summary["rounds"] = rounds;
        write_atomic(&stage.path().join("brush.json"), profile.to_json().as_bytes())?;
    }
    let mut sheet_track = SheetTrack::new(
        &lay,
        flow,
        args.grid,
        &results.iter().map(|r| (r.report.char.clone(), r.char_box, r.track.strokes.as_slice())).collect::<Vec<_>>(),
        &profile,
    );
    // Marks by default with --sheet; a sheet too small for them is written without (and says
    // so) unless --marks asked for them.
    let mut marks_on = if sheet.is_some() { !args.no_marks } else { args.marks };
    if marks_on {
        match pipeline::registration_marks(&lay, &profile) {
            Ok(marks) => sheet_track = sheet_track.with_marks(&marks, &profile),
            Err(e) if !args.marks => {
                eprintln!("written without registration marks (`maobi observe` needs them): {e}");
                marks_on = false;
            }
            Err(e) => {
                return Err(anyhow::Error::new(e).context(match sheet {
                    Some(_) => format!("--marks with --margin-mm {}", lay.margin_mm),
                    None => "--marks (give a larger --sheet)".to_string(),
                }));
            }
        }
    }
    if single && marks_on {
        // The marks make one character a sheet of one: its track.json is the sheet's.
        write_atomic_with(&stage.path().join("track.json"), |w| Ok(serde_json::to_writer_pretty(w, &sheet_track)?))?;
    }
    if single && observed.is_some() {
        // The rounds live in summary.json.
        write_atomic(&stage.path().join("summary.json"), serde_json::to_string_pretty(&summary)?.as_bytes())?;
    }
    if !single {
        let img = sheet_png(&results, &sheet_track, &profile, args.model, &lay, args.size)?;
        write_atomic(&stage.path().join("sheet.png"), &img.encode_png()?)?;
        write_atomic(&stage.path().join("summary.json"), serde_json::to_string_pretty(&summary)?.as_bytes())?;
        write_atomic_with(&stage.path().join("track.json"), |w| Ok(serde_json::to_writer_pretty(w, &sheet_track)?))?;
    }
    let preview = crate::cmd::preview::sheet_preview(&sheet_track, None, None)?;
    write_atomic(&stage.path().join("preview.html"), preview.as_bytes())?;
    stage.install("--output", &args.output, args.force)?;
    if args.json {
        print_json(&summary)?;
    } else {
        for r in &reports {
            print_char(r);
        }
        println!(
            "{} sheet {:.0}×{:.0} mm, char box {char_mm:.1} mm ({}); outputs in {} (preview.html to watch it)",
            lay.sheet.name,
            lay.sheet.width_mm,
            lay.sheet.height_mm,
            summary["brush_fit"]["note"].as_str().unwrap_or(""),
            args.output.display()
        );
        let next =
            next_choice.as_ref().map_or(String::new(), |c| format!("; brush for the next attempt: {}", c.reason));
        match (&choice, &correction) {
            (Some(c), _) => println!("brush (--brush auto): {}", c.reason),
            (None, Some(c)) if c.not_taken.is_some() => println!(
                "brush kept from the photo (--observed): {corrected_name}; the best re-fit (width ×{:.3}, length ×{:.3}, spread {:+.2} mm, {}) explains only {:.0} % of the ink error {:.4} (under {:.0} %){next}; written to {}{}",
                c.not_taken.map_or(1.0, |v| v[0]),
                c.not_taken.map_or(1.0, |v| v[1]),
                c.not_taken.map_or(0.0, |v| v[2]),
                hairs_text(&profile.hairs),
                c.not_taken.map_or(0.0, |v| 100.0 * (1.0 - v[3] / c.ink_error_before)),
                c.ink_error_before,
                100.0 * pipeline::tuning::MIN_CORRECTION_GAIN,
                args.output.join("brush.json").display(),
                if refine.is_some() {
                    "; tracks refined against the glyph shifted by the observed residual (ILC)"
                } else {
                    ""
                }
            ),
            (None, Some(c)) => println!(
                "brush re-fitted from the photo (--observed): {corrected_name} = width ×{:.3}, length ×{:.3}, spread {:+.2} mm on top of {} ({}; ink error {:.4} → {:.4}){next}; written to {}{}",
                c.width_factor,
                c.length_factor,
                c.spread_mm,
                observed.as_ref().map_or("", |o| o.track.brush.name.as_str()),
                hairs_text(&profile.hairs),
                c.ink_error_before,
                c.ink_error_after,
                args.output.join("brush.json").display(),
                if refine.is_some() {
                    "; tracks refined against the glyph shifted by the observed residual (ILC)"
                } else {
                    ""
                }
            ),
            (None, None) => println!("brush: {}", profile.name),
        }
    }
    Ok(())
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

/// `summary.json`: the text, the sheet, the means and every character's report.
fn summary_json(
    args: &Args,
    chars: &[char],
    lay: &Layout,
    flow: Flow,
    profile: &BrushProfile,
    reports: &[&CharReport],
    brush_mm: f64,
) -> serde_json::Value {
    let char_mm = lay.char_mm;
    let m = pipeline::ReportMeans::of(reports.iter().copied());
    // Executed figures are means over every character (null unless all were executed).
    let all = |s: Option<pipeline::SimilarityMeans>| s.filter(|s| s.count == m.count);
    json!({
        "text": chars.iter().collect::<String>(),
        "char_mm": char_mm,
        "brush": profile.name,
        "model": args.model.name(),
        "plan_mean": {"csim": m.plan.csim, "ssim": m.plan.ssim, "iou": m.plan.iou},
        "executed_mean": {
            "csim": all(m.executed).map(|s| s.csim),
            "ssim": all(m.executed).map(|s| s.ssim),
            "iou": all(m.executed).map(|s| s.iou),
        },
        "agreement_mean": {"csim": all(m.agreement).map(|s| s.csim)},
        "sheet": {
            "name": lay.sheet.name, "size_mm": [lay.sheet.width_mm, lay.sheet.height_mm],
            "margin_mm": lay.margin_mm, "flow": flow, "per_line": lay.per_line, "lines": lay.lines,
        },
        "brush_fit": brush_fit(reports, char_mm, brush_mm),
        "chars": reports,
    })
}

/// The smallest character box a flag may ask for, mm.
pub const MIN_CHAR_MM: f64 = 1.0;
/// The largest character box a flag may ask for, mm (a metre: beyond any robot's reach).
pub const MAX_CHAR_MM: f64 = 1000.0;

/// Whether the brush's width range covers the glyphs at the chosen size
/// ([`pipeline::BrushFit`]), with what to change when it does not.
fn brush_fit(reports: &[&CharReport], char_mm: f64, brush_mm: f64) -> serde_json::Value {
    let mut fit = BrushFit::of(reports, char_mm, brush_mm);
    match fit.miss {
        Some(BrushMiss::TooWide) => fit.note.push_str(": give a larger sheet, fewer characters or a smaller brush"),
        Some(BrushMiss::TooNarrow) => fit.note.push_str(": give --char-mm or a larger brush"),
        None => {}
    }
    json!(fit)
}

/// One character's files in `dir` (created by the first write, under the output gate).
/// What is kept of a character once its files are written: its report, track and box.
struct Written {
    report: CharReport,
    track: brush_model::Track,
    char_box: trajectory::CharBox,
}

impl From<CharResult> for Written {
    fn from(r: CharResult) -> Self {
        Written { report: r.report, track: r.track, char_box: r.char_box }
    }
}

fn write_outputs(dir: &Path, r: &CharResult, profile: &BrushProfile, sheet: Option<&Layout>) -> Result<()> {
    write_atomic(&dir.join("render.png"), &r.render.encode_png()?)?;
    write_atomic(&dir.join("reference.png"), &r.reference.encode_png()?)?;
    write_atomic(&dir.join("overlay.png"), &crate::plot::overlay_legend_png(&r.reference, &r.render)?)?;
    if let Some(ex) = &r.executed {
        write_atomic(&dir.join("executed.png"), &ex.encode_png()?)?;
        let row = crate::plot::labelled_row_png(&[
            ("reference (glyph)", &r.reference),
            ("plan", &r.render),
            ("executed", ex),
        ])?;
        write_atomic(&dir.join("side-by-side.png"), &row)?;
    }
    // Where this character sits: in its box and, with --sheet, on the sheet, in paper mm.
    let track = r.track_file(profile, sheet.map(|l| [l.sheet.width_mm, l.sheet.height_mm]));
    write_atomic(&dir.join("track.json"), serde_json::to_string_pretty(&track)?.as_bytes())?;
    write_atomic(&dir.join("report.json"), serde_json::to_string_pretty(&r.report)?.as_bytes())?;
    if let Some(rf) = &r.report.refine {
        let series = |f: fn(&track_refine::LossTerms) -> f64| -> Vec<(f64, f64)> {
            rf.curve.iter().enumerate().map(|(i, l)| (i as f64, f(l))).collect()
        };
        let png = crate::plot::loss_png(&[("total", series(|l| l.total)), ("image", series(|l| l.image))])?;
        write_atomic(&dir.join("refine.png"), &png)?;
    }
    Ok(())
}

/// The fitted hairs in words, for the closing line of `write --observed`.
fn hairs_text(h: &brush_model::HairMotion) -> String {
    format!(
        "the tip trailing {:.1} footprint lengths, the hairs following from {:.2} mm of press",
        h.trail_reach, h.contact_h_mm
    )
}

/// Whether two profiles are the same brush: the same name, brush and ranges, and footprint
/// models equal to 1e-9 mm (a correction carried back onto its own base rounds).
fn same_brush(a: &BrushProfile, b: &BrushProfile) -> bool {
    let terms = |x: brush_model::Terms, y: brush_model::Terms| {
        let close = |u: f64, v: f64| (u - v).abs() <= 1e-9 * (1.0 + u.abs());
        let opt = |u: Option<f64>, v: Option<f64>| close(u.unwrap_or(0.0), v.unwrap_or(0.0));
        close(x.intercept, y.intercept)
            && opt(x.h_mm, y.h_mm)
            && opt(x.alpha_rad, y.alpha_rad)
            && opt(x.beta_rad, y.beta_rad)
    };
    let (m, n) = (&a.model, &b.model);
    a.name == b.name
        && a.brush == b.brush
        && a.ranges == b.ranges
        && terms(m.lt_mm, n.lt_mm)
        && terms(m.lh_mm, n.lh_mm)
        && terms(m.lr_mm, n.lr_mm)
}

/// `sheet.png`: every character's track ([`pipeline::sheet_image`]) and the registration marks
/// the robot writes before them (the first `mark_strokes` of the sheet track, as the preview and
/// the exports show them), at the characters' image scale. The marks lie in the margin, apart
/// from the characters; their ink is joined to the characters' as a union.
fn sheet_png(
    results: &[Written],
    sheet_track: &SheetTrack,
    profile: &BrushProfile,
    model: ModelKind,
    lay: &Layout,
    size: u32,
) -> Result<bezier_raster::Coverage> {
    let tracks: Vec<&brush_model::Track> = results.iter().map(|r| &r.track).collect();
    let mut img = pipeline::sheet_image_of(&tracks, profile, model, lay, size).context("sheet.png")?;
    if sheet_track.mark_strokes > 0 {
        let marks = brush_model::Track { strokes: sheet_track.strokes[..sheet_track.mark_strokes].to_vec() };
        let (wp, hp) = lay.image_px(size);
        let stamps = bezier_raster::track_stamps(&marks, profile, brush_model::Extrapolation::Refuse)
            .context("sheet.png: the registration marks")?;
        let m = bezier_raster::render_stamps(
            &stamps,
            model.model(),
            brush_model::PointMm::new(0.0, 0.0),
            size as f64 / lay.char_mm,
            wp as u32,
            hp as u32,
        );
        for (a, &b) in img.data_mut().iter_mut().zip(m.data()) {
            *a = 1.0 - (1.0 - *a) * (1.0 - b);
        }
    }
    Ok(img)
}

/// The last attempt that `--observed OUT` names: `maobi observe`'s output, the sheet folder it
/// observed, and each character's observed ink.
struct ObservedRun {
    /// `--observed`.
    dir: PathBuf,
    /// The sheet folder it observed (absolute, as the observation records it).
    sheet_dir: PathBuf,
    /// Its summary.json.
    summary: Observation,
    /// The observed sheet's track.json.
    track: SheetTrack,
    /// Each character's observed.png, in the sheet's order.
    observed: Vec<bezier_raster::Coverage>,
    /// The rounds before this one (the observed sheet's summary.json `rounds`, when it was
    /// itself a corrected attempt).
    earlier: Vec<serde_json::Value>,
}

/// The most rounds a corrected sheet's summary.json may list.
const MAX_ROUNDS: usize = 100;

/// The largest summary.json of a sheet read back (for its rounds), bytes.
const MAX_SHEET_SUMMARY_BYTES: u64 = 16 << 20;

/// Below this share of its pixels at coverage ≥ ½, an observed character holds no ink.
const MIN_OBSERVED_INK_SHARE: f64 = 0.002;

/// Reads `--observed DIR` and the sheet it observed; refuses when the sheet is not the one
/// observed (its fingerprint) or TEXT or the layout differ from it.
fn load_observed(dir: &Path, chars: &[char], layout: Option<&Layout>) -> Result<ObservedRun> {
    let sp = dir.join("summary.json");
    let summary = Observation::load(&sp).context("--observed")?;
    let sheet_dir = summary.sheet.path.clone();
    let tp = summary.track_path();
    let (track, bytes) = SheetTrack::load(&tp).with_context(|| {
        format!(
            "--observed: {} observed the sheet {} (field `sheet.path` of {})",
            dir.display(),
            sheet_dir.display(),
            sp.display()
        )
    })?;
    summary.check_sheet(&sp, &track, &tp, &bytes).context("--observed")?;
    let text_now: String = chars.iter().collect();
    let seen: String = track.chars.iter().map(|c| c.char.as_str()).collect();
    if seen != text_now {
        bail!(
            "--observed: {} observed the sheet of {seen:?} ({}), not {text_now:?}: give the same characters",
            dir.display(),
            sheet_dir.display()
        );
    }
    if let Some(lay) = layout {
        let same = (track.sheet_mm[0] - lay.sheet.width_mm).abs() < 1e-6
            && (track.sheet_mm[1] - lay.sheet.height_mm).abs() < 1e-6
            && track.chars.iter().zip(&lay.boxes).all(|(c, b)| {
                [b.x0_mm, b.y0_mm, b.size_mm].iter().zip(&c.char_box_mm).all(|(a, b)| (a - b).abs() < 1e-6)
            });
        if !same {
            bail!(
                "--observed: the sheet {} was laid out otherwise ({:.0}×{:.0} mm, {:.1} mm boxes; here {:.0}×{:.0} mm, {:.1} mm): give the same --sheet, --margin-mm, --per-line, --rows and --char-mm",
                sheet_dir.display(),
                track.sheet_mm[0],
                track.sheet_mm[1],
                track.char_mm,
                lay.sheet.width_mm,
                lay.sheet.height_mm,
                lay.char_mm
            );
        }
    }
    let mut observed = Vec::new();
    for (i, c) in summary.chars.iter().enumerate() {
        let p = dir.join(&c.folder).join("observed.png");
        let (w, h) =
            bezier_raster::image_header(&p).with_context(|| format!("--observed: cannot read {}", p.display()))?;
        if (w, h) != (c.size_px, c.size_px) {
            bail!(
                "--observed: {} is {w}×{h} px, expected {side}×{side} px (chars[{i}].size_px of {})",
                p.display(),
                sp.display(),
                side = c.size_px,
            );
        }
        let img =
            bezier_raster::Coverage::load(&p).with_context(|| format!("--observed: cannot read {}", p.display()))?;
        let inked = img.data().iter().filter(|&&v| v >= 0.5).count();
        if (inked as f64) < MIN_OBSERVED_INK_SHARE * img.data().len() as f64 {
            bail!(
                "--observed: {} holds no ink ({inked} inked px of {}): no ink was seen of {:?} (was it written? is the photo of this sheet?)",
                p.display(),
                img.data().len(),
                c.char
            );
        }
        observed.push(img);
    }
    let earlier = earlier_rounds(&sheet_dir.join("summary.json"))?;
    Ok(ObservedRun { dir: dir.to_path_buf(), sheet_dir, summary, track, observed, earlier })
}

/// The rounds a corrected sheet's summary.json lists (none when the sheet has no summary.json
/// or lists none): a summary that is there must be whole JSON, its `rounds` a list of at most
/// [`MAX_ROUNDS`] objects.
fn earlier_rounds(p: &Path) -> Result<Vec<serde_json::Value>> {
    if !p.exists() {
        return Ok(Vec::new());
    }
    let bytes = pipeline::read_bounded(p, MAX_SHEET_SUMMARY_BYTES, "a sheet's summary.json").context("--observed")?;
    let v: serde_json::Value = serde_json::from_slice(&bytes).with_context(|| {
        format!("--observed: {} is not the summary.json of `maobi write` (cut short, or not JSON)", p.display())
    })?;
    let rounds = match v.get("rounds") {
        None | Some(serde_json::Value::Null) => return Ok(Vec::new()),
        Some(serde_json::Value::Array(r)) => r,
        Some(_) => bail!("--observed: {}: field `rounds`: expected a list of rounds", p.display()),
    };
    if rounds.len() > MAX_ROUNDS {
        bail!("--observed: {}: field `rounds`: {} rounds, expected at most {MAX_ROUNDS}", p.display(), rounds.len());
    }
    if let Some(i) = rounds.iter().position(|r| !r.is_object()) {
        bail!("--observed: {}: field `rounds[{i}]`: expected an object", p.display());
    }
    Ok(rounds.clone())
}

impl ObservedRun {
    /// Each character's last attempt (its strokes in the observed sheet, its observed ink).
    fn attempts(&self) -> Vec<pipeline::LastAttempt<'_>> {
        self.track
            .chars
            .iter()
            .zip(&self.observed)
            .map(|(c, img)| pipeline::LastAttempt {
                ch: &c.char,
                char_box: trajectory::CharBox {
                    x0_mm: c.char_box_mm[0],
                    y0_mm: c.char_box_mm[1],
                    size_mm: c.char_box_mm[2],
                },
                strokes: &self.track.strokes[c.strokes[0]..c.strokes[1]],
                observed: img,
            })
            .collect()
    }

    /// The brush correction fitted to the observed ink, and `profile` corrected (named after the
    /// round).
    fn correct_brush(
        &self,
        profile: &BrushProfile,
        model: ModelKind,
    ) -> Result<(pipeline::BrushCorrection, BrushProfile)> {
        let c = pipeline::fit_brush(&self.attempts(), profile, model)
            .with_context(|| format!("--observed {}: re-fitting the brush", self.dir.display()))?;
        let root = profile.name.split('+').next().unwrap_or(&profile.name);
        let name = match c.not_taken {
            None => format!("{root}+observed{}", self.earlier.len() + 1),
            Some(_) => profile.name.clone(),
        };
        let corrected = c.apply(profile, &name).with_context(|| format!("--observed {}", self.dir.display()))?;
        Ok((c, corrected))
    }

    /// The brush for the next attempt when the observed sheet's base brush is a built-in:
    /// among the built-ins, each with the correction from that base to `corrected` carried
    /// over, the one whose footprints suit `char_mm` boxes ([`pipeline::choose_corrected_brush`]);
    /// `None` (with a note on stderr) when the base is not a built-in or `corrected` is not a
    /// correction of it (a calibrated brush of the user's own is kept).
    fn next_brush(
        &self,
        prepared: &[pipeline::Prepared],
        corrected: &BrushProfile,
        char_mm: f64,
        alpha_rad: f64,
    ) -> Option<pipeline::BrushChoice> {
        let root = corrected.name.split('+').next().unwrap_or(&corrected.name);
        let base = BrushProfile::builtin(root).ok()?;
        let suffix = corrected.name.strip_prefix(root).unwrap_or("");
        match pipeline::choose_corrected_brush(
            prepared,
            &base,
            corrected,
            &pipeline::builtin_brushes(),
            suffix,
            char_mm,
            alpha_rad,
        ) {
            Ok(c) => Some(c),
            Err(e) => {
                eprintln!("note: --observed: the brush {} is kept (no other brush considered): {e}", corrected.name);
                None
            }
        }
    }

    /// Each character's residual: observed ink minus the last attempt through `profile` (its
    /// footprints and hairs).
    fn residuals(&self, profile: &BrushProfile, model: ModelKind) -> Result<Vec<pipeline::Residual>> {
        self.attempts()
            .iter()
            .map(|a| pipeline::Residual::of(a, profile, model))
            .collect::<Result<_, _>>()
            .with_context(|| format!("--observed {}", self.dir.display()))
    }

    /// This round's entry (what was observed, what was corrected) and every round so far.
    fn rounds(
        &self,
        c: &pipeline::BrushCorrection,
        corrected: &BrushProfile,
        choice: Option<&pipeline::BrushChoice>,
        ilc: bool,
        from_last: bool,
    ) -> (serde_json::Value, serde_json::Value) {
        let chars = &self.summary.chars;
        let mean = |f: fn(&pipeline::ObservedScores) -> f64| {
            chars.iter().map(|c| f(&c.vs_glyph)).sum::<f64>() / chars.len().max(1) as f64
        };
        let this = json!({
            "round": self.earlier.len(),
            "sheet": self.sheet_dir.display().to_string(),
            "observed": self.dir.display().to_string(),
            "brush": self.track.brush.name,
            "observed_vs_glyph_mean": {"csim": mean(|s| s.csim), "ssim": mean(|s| s.ssim), "iou": mean(|s| s.iou)},
            "chars": chars.iter().map(|c| json!({
                "char": c.folder,
                "vs_glyph": c.vs_glyph,
                "vs_plan": c.vs_plan,
                "width_ratio": c.diagnosis.width_ratio,
                "end_beyond_mm": c.diagnosis.end_beyond_mm,
                "lateral_mm": c.diagnosis.lateral_mm,
                "verdict": c.verdict,
            })).collect::<Vec<_>>(),
            "correction": c,
            "brush_after": corrected.name,
            "brush_choice": choice,
            "track": match (ilc, from_last) {
                (true, true) => "refined from the last attempt's track against the glyph shifted by the observed residual (ILC)",
                (true, false) => "refined against the glyph shifted by the observed residual (ILC)",
                (false, _) => "built with the corrected brush",
            },
        });
        let mut all = self.earlier.clone();
        all.push(this.clone());
        (this, json!(all))
    }
}
