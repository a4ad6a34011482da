//! `maobi write`: characters → brush tracks, renders, references and scores.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use bezier_raster::{ModelKind, coverage::overlay_png};
use brush_model::{BrushProfile, Extrapolation, Track};
use maobi::pipeline::{
    CharReport, CharResult, Prepared, WriteOptions, prepare_with_template, searched_placement, searched_splits,
    write_char,
};
use maobi::sheet::{Flow, Grid, Layout, Sheet, SheetTrack, layout_on_sheet, parse_sheet};
use rayon::prelude::*;
use serde_json::json;
use trajectory::{CharBox, Method, glyph};

use crate::common::{
    BrushArg, OutputLock, RendererArgs, Stage, check_output_folder, check_range, load_brush, parse_method, parse_model,
    print_json, progress, recover_leftovers, write_atomic,
};

/// Arguments of `maobi write`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The character(s) to write.
    text: String,
    /// Glyphs from an unpacked hanzi-writer-data package (files `<char>.json`); with --font or
    /// --image, the stroke templates registered onto their glyphs (`--from template`).
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
    #[command(flatten)]
    brush: BrushArg,
    /// Stroke model that draws the footprints (`--renderer analytic`).
    #[arg(long, default_value = "bsm", value_parser = parse_model())]
    model: ModelKind,
    /// Side of each character's images, px.
    #[arg(long, default_value_t = 512)]
    size: u32,
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
    /// Grid drawn under each character in the preview (never written): none, mi (米字格), tian (田字格).
    #[arg(long, default_value = "none")]
    grid: Grid,
    /// Output folder. An existing non-empty folder is refused unless --force is given.
    #[arg(short, long, visible_alias = "out", value_name = "DIR")]
    output: PathBuf,
    /// Replace an existing output folder (the new run is written beside it and swapped in once
    /// complete; an error or Ctrl-C leaves the old one in place).
    #[arg(long)]
    force: bool,
    /// Print the summary as JSON on stdout.
    #[arg(long)]
    json: bool,
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
    /// How template tracks (`--from template`, the default for --font and --image) are placed:
    /// `search` builds the plan at a few char box sizes (0.8–1.35× the size from the widths),
    /// with each stroke's corners split or written in one piece, and keeps the plan most like
    /// the glyph (docs/trajectory.md, "Template registration"); where the size is fixed
    /// (--char-mm, --sheet, several characters sharing one box) only the splits are searched.
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
    /// docs/trajectory.md, "Refinement"): `write`'s report.json gains the before/after figures
    /// and refine.png the loss curve; `evaluate`'s summary gains the means before and after.
    #[arg(long)]
    refine: bool,
    /// Gradient steps of --refine (default 20).
    #[arg(long, requires = "refine")]
    iters: Option<usize>,
    /// Where --refine takes its gradients from: the analytic soft footprint (default: as good
    /// to 0.001 CSIM at the defaults and about 7× faster) or the B-BSMG generator's VJP (see
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

/// Where `write` and `evaluate` take glyphs from, opened once.
pub(crate) enum GlyphInput {
    /// The embedded set, or a hanzi-writer-data folder.
    Hanzi(Option<PathBuf>),
    /// Fonts, with hanzi stroke data (embedded, or the folder) as templates.
    Fonts(glyph::FontSet, Option<PathBuf>),
    /// Images, with hanzi stroke data as templates: one file (`write --image`) or, for
    /// `evaluate --images`, a file per character.
    Images(Vec<(char, PathBuf)>, Option<PathBuf>),
}

impl GlyphInput {
    /// Opens the fonts of `--font` (files or folders; nothing decoded yet).
    pub(crate) fn fonts(paths: &[PathBuf], face_index: Option<u32>, hanzi: Option<PathBuf>) -> Result<Self> {
        let set = glyph::FontSet::open(paths, face_index).context("--font")?;
        Ok(GlyphInput::Fonts(set, hanzi))
    }

    /// The glyph of `ch` and, for a font or image glyph, the character's stroke template when
    /// there is one (`None` when neither the embedded set nor the folder has the character).
    pub(crate) fn load(&self, ch: char) -> Result<(glyph::Glyph, Option<glyph::Glyph>)> {
        let template = |dir: &Option<PathBuf>| -> Result<Option<glyph::Glyph>> {
            let found = match dir {
                Some(d) => glyph::from_hanzi_dir(d, ch),
                None => glyph::embedded(ch),
            };
            match found {
                Ok(g) => Ok(Some(g)),
                Err(glyph::GlyphError::Unknown { .. }) => Ok(None),
                Err(e) => Err(e).context("the stroke template"),
            }
        };
        Ok(match self {
            GlyphInput::Hanzi(Some(dir)) => (glyph::from_hanzi_dir(dir, ch)?, None),
            GlyphInput::Hanzi(None) => (glyph::embedded(ch)?, None),
            GlyphInput::Fonts(set, dir) => (set.glyph(ch)?, template(dir)?),
            GlyphInput::Images(files, dir) => {
                let path = files
                    .iter()
                    .find(|(c, _)| *c == ch)
                    .map(|(_, p)| p)
                    .with_context(|| format!("no image for {ch:?}"))?;
                (glyph::from_image(path, ch)?, template(dir)?)
            }
        })
    }
}

/// Finds the centre lines of a loaded glyph (see [`maobi::pipeline::prepare_with_template`]);
/// prints the strokes a template registration found no ink for.
pub(crate) fn prepare_loaded(
    loaded: (glyph::Glyph, Option<glyph::Glyph>),
    method: Option<Method>,
    quiet: bool,
) -> Result<Prepared> {
    let (g, template) = loaded;
    let p = prepare_with_template(g, method, template.as_ref())?;
    // A registration where most strokes find no ink means the glyph is not this character (or
    // not legible): writing the template where it landed would be a guess, not the glyph.
    let missing = p.template.as_ref().map_or((0, 0), |t| (t.missing.len(), t.strokes));
    let mostly_missing = missing.0 * 2 > missing.1;
    if p.paths.is_empty() || mostly_missing {
        let from = match &p.glyph.source {
            glyph::GlyphSource::Image(path) => format!(" in --image {path}"),
            _ => String::new(),
        };
        let why = if mostly_missing {
            format!(
                " for {} of the template's {} strokes (try --from skeleton if it is another character)",
                missing.0, missing.1
            )
        } else {
            String::new()
        };
        bail!(
            "{}: found no strokes{from}{why} (is it one character, dark ink on light paper, strokes wider than a hair?)",
            p.glyph.ch
        );
    }
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

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    let chars = checked_chars(&args)?;
    let flow = if args.rows { Flow::Rows } else { Flow::Columns };
    let (sheet, sheet_layout) = planned_sheet(&args, chars.len(), flow)?;
    let profile = load_brush(&args.brush.brush)?;
    let alpha_rad = checked_alpha_rad(args.alpha, &profile)?;
    // One run per output folder at a time; what a run that died left beside it is cleaned up
    // (or the old folder put back) before deciding whether the folder may be replaced.
    let _lock = OutputLock::acquire("--output", &args.output)?;
    recover_leftovers(&args.output)?;
    check_output_folder("--output", &args.output, args.force)?;
    // Load and analyse every glyph before writing anything.
    let prepared = prepare_all(&args, &chars)?;
    let all: Vec<_> = prepared.iter().flat_map(|p| p.paths.iter().cloned()).collect();
    let brush_mm = trajectory::auto_char_mm(&all, &profile, alpha_rad);
    let refine = args.refine.options()?;
    let opts = WriteOptions { model: args.model, size: args.size, alpha_rad, refine, ..WriteOptions::default() };
    let search = |p: &Prepared| args.placement.search() && p.method == Method::Template;
    // One template character on its own: its box size is searched too.
    let single_searched = match (&prepared[..], &sheet_layout, args.char_mm) {
        ([p], None, None) if search(p) => Some(searched_placement(p, &profile, &opts)?),
        _ => None,
    };
    let lay = match sheet_layout {
        Some(l) => l,
        None => auto_layout(
            chars.len(),
            args.char_mm.or(single_searched.as_ref().map(|pl| pl.size_mm)).unwrap_or(brush_mm),
            args.per_line.unwrap_or(4),
            args.rows,
        ),
    };
    let char_mm = lay.char_mm;
    let boxes = lay.boxes.clone();
    // Template characters sharing the box size: their corner splits are searched.
    let prepared: Vec<Prepared> = prepared
        .into_par_iter()
        .map(|p| match &single_searched {
            Some(pl) => Ok(p.placed(pl)),
            None if search(&p) => Ok(p.placed(&searched_splits(&p, &profile, &opts, char_mm)?)),
            None => Ok(p),
        })
        .collect::<Result<_>>()?;
    let pb = progress(chars.len() as u64, "write");
    let results: Vec<CharResult> = prepared
        .par_iter()
        .zip(boxes.par_iter())
        .map(|(p, b)| {
            let r = write_char(p, &profile, *b, &opts);
            pb.inc(1);
            r
        })
        .collect::<Result<_>>()?;
    pb.finish_and_clear();
    let mut results = results;
    if args.renderer.neural() {
        rerender_neural(&args, &profile, &mut results)?;
    }
    let single = results.len() == 1;
    // Everything goes to a staging folder beside --output, swapped in at the end: a run never
    // mixes with an older one, and a failed or interrupted run leaves the old folder as it was.
    let stage = Stage::new(&args.output)?;
    for (i, r) in results.iter().enumerate() {
        let dir = if single {
            stage.path().to_path_buf()
        } else {
            stage.path().join(format!("{:02}-{}", i + 1, r.report.char))
        };
        write_outputs(&dir, r, &profile, sheet.as_ref().map(|_| &lay))?;
    }
    let reports: Vec<&CharReport> = results.iter().map(|r| &r.report).collect();
    let summary = summary_json(&args, &chars, &lay, flow, &profile, &reports, brush_mm);
    let sheet_track = SheetTrack::new(
        &lay,
        flow,
        args.grid,
        &results.iter().map(|r| (r.report.char.clone(), r.char_box, r.track.strokes.as_slice())).collect::<Vec<_>>(),
        &profile,
    );
    if !single {
        let img = sheet_image(&results, &profile, args.model, &lay, args.size)?;
        write_atomic(&stage.path().join("sheet.png"), &img.encode_png()?)?;
        write_atomic(&stage.path().join("summary.json"), serde_json::to_string_pretty(&summary)?.as_bytes())?;
        write_atomic(&stage.path().join("track.json"), serde_json::to_string_pretty(&sheet_track)?.as_bytes())?;
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
    }
    Ok(())
}

/// The characters of TEXT, after checking every flag that needs no file.
fn checked_chars(args: &Args) -> Result<Vec<char>> {
    let chars: Vec<char> = args.text.chars().filter(|c| !c.is_whitespace()).collect();
    if chars.is_empty() {
        bail!("TEXT is empty: give at least one character");
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
    let input = if !args.font.is_empty() {
        GlyphInput::fonts(&args.font, args.font_index, args.hanzi_data.clone())?
    } else if let Some(img) = &args.image {
        GlyphInput::Images(vec![(chars[0], img.clone())], args.hanzi_data.clone())
    } else {
        GlyphInput::Hanzi(args.hanzi_data.clone())
    };
    let prepared: Vec<Prepared> =
        chars.par_iter().map(|&c| prepare_loaded(input.load(c)?, args.method, args.json)).collect::<Result<_>>()?;
    Ok(prepared)
}

/// Renders every result again through the B-BSMG generator (`--renderer neural`) and scores
/// those images instead.
fn rerender_neural(args: &Args, profile: &BrushProfile, results: &mut [CharResult]) -> Result<()> {
    let g = args.renderer.generator()?;
    if g.config.profile.model != profile.model || g.config.profile.ranges != profile.ranges {
        bail!(
            "--renderer neural: the generator was trained for brush `{}`, not `{}`",
            g.config.profile.name,
            profile.name
        );
    }
    for r in results.iter_mut() {
        let b = r.char_box;
        let neural = |t: &brush_model::Track| {
            neural_gen::render_track(
                &g,
                t,
                brush_model::PointMm::new(b.x0_mm, b.y0_mm),
                args.size as f64 / b.size_mm,
                args.size,
                args.size,
                64,
            )
        };
        let img = neural(&r.track)?;
        let sim = maobi::pipeline::similarity(&r.reference, &img)?;
        (r.report.csim, r.report.ssim, r.report.iou) = (sim.csim, sim.ssim, sim.iou);
        if let Some(states) = &r.executed_states {
            // The executed path through the same generator.
            let executed = brush_model::Track { strokes: vec![brush_model::Stroke { points: states.clone() }] };
            let ex = neural(&executed)?;
            r.report.executed = Some(maobi::pipeline::similarity(&r.reference, &ex)?);
            r.report.agreement = Some(maobi::pipeline::similarity(&img, &ex)?);
            r.executed = Some(ex);
        }
        r.report.model = "b-bsmg";
        r.render = img;
    }
    Ok(())
}

/// One character's line (and its refinement's) on stdout.
fn print_char(r: &CharReport) {
    // The executed figure (what the robot would write) is the headline.
    let executed = match (r.executed, r.agreement) {
        (Some(e), Some(a)) => format!(
            "executed CSIM {:.4}  SSIM {:.4}  IoU {:.4}  (planned CSIM {:.4}, planned vs executed {:.4})",
            e.csim, e.ssim, e.iou, r.csim, a.csim
        ),
        _ => format!("planned CSIM {:.4}  SSIM {:.4}  IoU {:.4}", r.csim, r.ssim, r.iou),
    };
    println!(
        "{} ({} via {}, {}): {executed}{}  strokes {}{}  points {}  {:.1} ms",
        r.char,
        r.source,
        r.method,
        r.model,
        r.chamfer_pct.map_or(String::new(), |c| format!("  chamfer {c:.2}%")),
        r.strokes_found,
        r.strokes_expected.map_or(String::new(), |e| format!("/{e}")),
        r.points,
        r.millis
    );
    if let Some(rf) = &r.refine {
        let fig = |s: Option<maobi::pipeline::Similarity>| s.map_or("-".into(), |s| format!("{:.4}", s.csim));
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
    let sheet = args.sheet.as_deref().map(parse_sheet).transpose()?;
    let layout = match &sheet {
        Some(sh) => Some(layout_on_sheet(sh, n, flow, args.per_line, args.margin_mm, args.char_mm)?),
        None => None,
    };
    match &layout {
        Some(l) => check_sheet_px(l, args.size)?,
        None => check_sheet_size(n, args.size, args.per_line.unwrap_or(4), args.rows)?,
    }
    Ok((sheet, layout))
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
    let mean = |f: fn(&CharReport) -> f64| reports.iter().map(|r| f(r)).sum::<f64>() / reports.len() as f64;
    json!({
        "text": chars.iter().collect::<String>(),
        "char_mm": char_mm,
        "brush": profile.name,
        "model": args.model.name(),
        "mean": {"csim": mean(|r| r.csim), "ssim": mean(|r| r.ssim), "iou": mean(|r| r.iou)},
        "executed_mean": {
            "csim": mean(|r| r.executed.map_or(f64::NAN, |s| s.csim)),
            "ssim": mean(|r| r.executed.map_or(f64::NAN, |s| s.ssim)),
            "iou": mean(|r| r.executed.map_or(f64::NAN, |s| s.iou)),
        },
        "agreement_mean": {"csim": mean(|r| r.agreement.map_or(f64::NAN, |s| s.csim))},
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

/// Refuses a layout whose sheet image would exceed the largest image side, before any work.
/// The sheet's size in pixels does not depend on the box size in mm.
fn check_sheet_size(n: usize, size: u32, per_line: usize, rows: bool) -> Result<()> {
    if n < 2 {
        return Ok(());
    }
    let px_per_mm = size as f64; // a 1 mm box: scale-free
    let boxes = layout(n, 1.0, per_line, rows);
    let w = boxes.iter().map(|b| b.x0_mm + b.size_mm).fold(0.0, f64::max) + 0.1;
    let h = boxes.iter().map(|b| b.y0_mm + b.size_mm).fold(0.0, f64::max) + 0.1;
    let (wp, hp) = ((w * px_per_mm).ceil(), (h * px_per_mm).ceil());
    let max = bezier_raster::coverage::MAX_SIDE as f64;
    if wp > max || hp > max {
        bail!(
            "--size {size} with --per-line {per_line}: the sheet of {n} characters would be {wp}×{hp} px, over the {max} px limit of an image side; lower --size or change --per-line"
        );
    }
    Ok(())
}

/// Character boxes on the paper: columns right to left (or rows left to right), a gap of a
/// tenth of the box between characters and around the sheet.
fn layout(n: usize, char_mm: f64, per_line: usize, rows: bool) -> Vec<CharBox> {
    let per_line = per_line.clamp(1, n.max(1));
    let gap = 0.1 * char_mm;
    let step = char_mm + gap;
    let lines = n.div_ceil(per_line);
    (0..n)
        .map(|i| {
            let (line, pos) = (i / per_line, i % per_line);
            let (x, y) = if rows { (pos, line) } else { (lines - 1 - line, pos) };
            CharBox { x0_mm: gap + x as f64 * step, y0_mm: gap + y as f64 * step, size_mm: char_mm }
        })
        .collect()
}

/// The layout without `--sheet`: the old automatic one (a gap of a tenth of the box around and
/// between the characters), the sheet just large enough for it.
fn auto_layout(n: usize, char_mm: f64, per_line: usize, rows: bool) -> Layout {
    let boxes = layout(n, char_mm, per_line, rows);
    let gap = 0.1 * char_mm;
    let w = boxes.iter().map(|b| b.x0_mm + b.size_mm).fold(0.0, f64::max) + gap;
    let h = boxes.iter().map(|b| b.y0_mm + b.size_mm).fold(0.0, f64::max) + gap;
    let per = per_line.clamp(1, n.max(1));
    Layout {
        sheet: Sheet { name: "automatic".into(), width_mm: w, height_mm: h },
        boxes,
        char_mm,
        per_line: per,
        lines: n.div_ceil(per),
        margin_mm: gap,
    }
}

/// Refuses a sheet whose image would exceed the largest image side.
fn check_sheet_px(l: &Layout, size: u32) -> Result<()> {
    let ppm = size as f64 / l.char_mm;
    let (wp, hp) = ((l.sheet.width_mm * ppm).ceil(), (l.sheet.height_mm * ppm).ceil());
    let max = bezier_raster::coverage::MAX_SIDE as f64;
    if wp > max || hp > max {
        bail!(
            "--size {size} on the {} sheet with {:.1} mm characters: the sheet image would be {wp}×{hp} px, over the {max} px limit of an image side; lower --size",
            l.sheet.name,
            l.char_mm
        );
    }
    Ok(())
}

/// Whether the brush's width range covers the glyphs at the chosen size: the size where it
/// does (`trajectory::auto_char_mm`) and the share of points whose width had to be clamped.
fn brush_fit(reports: &[&CharReport], char_mm: f64, brush_mm: f64) -> serde_json::Value {
    let points: usize = reports.iter().map(|r| r.points).sum();
    let (low, high): (usize, usize) = reports.iter().fold((0, 0), |(l, h), r| (l + r.clamped_low, h + r.clamped_high));
    let share = |n: usize| if points == 0 { 0.0 } else { n as f64 / points as f64 };
    // At the automatic size about a fifth of the points lie beyond each end of the range by
    // construction (it maps the 20th–80th percentile widths onto it), so only a size well off
    // the brush's, or far more clamping than that, is worth a word.
    let note = if share(low) > 0.25 || char_mm < brush_mm / 1.15 {
        format!(
            "at {char_mm:.1} mm the glyphs' strokes are thinner than the brush can make at {:.0}% of the points (its width range suits about {brush_mm:.0} mm characters): give a larger sheet, fewer characters or a smaller brush",
            100.0 * share(low)
        )
    } else if share(high) > 0.25 || char_mm > brush_mm * 1.15 {
        format!(
            "at {char_mm:.1} mm the glyphs' strokes are wider than the brush can make at {:.0}% of the points (its width range suits about {brush_mm:.0} mm characters): give --char-mm or a larger brush",
            100.0 * share(high)
        )
    } else {
        "the brush's width range covers the glyphs at this size".into()
    };
    json!({
        "brush_char_mm": brush_mm,
        "char_mm": char_mm,
        "points": points,
        "clamped_thin": low,
        "clamped_wide": high,
        "covered": !note.starts_with("at "),
        "note": note,
    })
}

fn sheet_image(
    results: &[CharResult],
    profile: &BrushProfile,
    model: ModelKind,
    lay: &Layout,
    size: u32,
) -> Result<bezier_raster::Coverage> {
    let mut all = Track::default();
    for r in results {
        all.strokes.extend(r.track.strokes.iter().cloned());
    }
    let px_per_mm = size as f64 / lay.char_mm;
    let (wp, hp) = ((lay.sheet.width_mm * px_per_mm).ceil() as u32, (lay.sheet.height_mm * px_per_mm).ceil() as u32);
    Ok(bezier_raster::render_track(
        &all,
        profile,
        model.model(),
        Extrapolation::Refuse,
        brush_model::PointMm::new(0.0, 0.0),
        px_per_mm,
        wp,
        hp,
    )?)
}

/// One character's files in `dir` (created by the first write, under the output gate).
fn write_outputs(dir: &Path, r: &CharResult, profile: &BrushProfile, sheet: Option<&Layout>) -> Result<()> {
    write_atomic(&dir.join("render.png"), &r.render.encode_png()?)?;
    write_atomic(&dir.join("reference.png"), &r.reference.encode_png()?)?;
    write_atomic(&dir.join("overlay.png"), &overlay_png(&r.reference, &r.render)?)?;
    if let Some(ex) = &r.executed {
        write_atomic(&dir.join("executed.png"), &ex.encode_png()?)?;
        let row = maobi::pipeline::side_by_side(&[&r.reference, &r.render, ex]);
        write_atomic(&dir.join("side-by-side.png"), &row.encode_png()?)?;
    }
    let mut track = json!({
        "char": r.report.char,
        "char_box_mm": [r.char_box.x0_mm, r.char_box.y0_mm, r.char_box.size_mm],
        "brush": profile,
        "strokes": r.track.strokes,
    });
    if let Some(l) = sheet {
        // Where this character sits: on the --sheet, in paper mm.
        track["sheet_mm"] = json!([l.sheet.width_mm, l.sheet.height_mm]);
    }
    write_atomic(&dir.join("track.json"), serde_json::to_string_pretty(&track)?.as_bytes())?;
    write_atomic(&dir.join("report.json"), serde_json::to_string_pretty(&r.report)?.as_bytes())?;
    if let Some(rf) = &r.report.refine {
        let series = |f: fn(&track_refine::LossTerms) -> f64| -> Vec<(f64, f64)> {
            rf.curve.iter().enumerate().map(|(i, l)| (i as f64, f(l))).collect()
        };
        let png = maobi::plot::loss_png(&[("total", series(|l| l.total)), ("image", series(|l| l.image))])?;
        write_atomic(&dir.join("refine.png"), &png)?;
    }
    Ok(())
}
