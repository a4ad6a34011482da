//! `maobi evaluate`: the write pipeline over many characters, in parallel, with mean scores.

use anyhow::{Context, Result, bail};
use bezier_raster::ModelKind;
use pipeline::{BoxRule, CharReport, GlyphInput, ReportMeans, WriteOptions, write_placed};
use rayon::prelude::*;
use serde_json::json;
use trajectory::{Method, embedded_chars};

use crate::common::{BrushArg, check_range, load_brush, parse_method, parse_model, print_json, progress};
use crate::common::{MAX_CHAR_MM, MIN_CHAR_MM, PlacementArg, RefineArgs, glyph_input, prepare_char};
use crate::generator::committed_gen_model;

/// Arguments of `maobi evaluate`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Characters to evaluate (default: the whole embedded set).
    #[arg(long)]
    chars: Option<String>,
    /// Only the first N characters.
    #[arg(long)]
    limit: Option<usize>,
    /// Centre-line method (default: medians for stroke data; template for --font or --images).
    #[arg(long = "from", value_parser = parse_method())]
    method: Option<Method>,
    #[command(flatten)]
    brush: BrushArg,
    /// Stroke model that draws the footprints.
    #[arg(long, default_value = "bsm", value_parser = parse_model())]
    model: ModelKind,
    /// Image side, px.
    #[arg(long, default_value_t = 512)]
    size: u32,
    /// Char box side, mm (default: chosen per character from its widths).
    #[arg(long)]
    char_mm: Option<f64>,
    /// Read characters from a hanzi-writer-data folder (`<char>.json` files) instead of the
    /// embedded set; `--chars` then names them (e.g. characters outside the embedded set).
    #[arg(long)]
    hanzi_data: Option<std::path::PathBuf>,
    /// Evaluate a font's glyphs: TTF, OTF, TTC/OTC, WOFF or WOFF2 files or folders of them
    /// (repeatable; the first file covering a character is used). Stroke templates come from
    /// the embedded set or --hanzi-data. Characters the fonts do not cover are skipped and
    /// counted.
    #[arg(long, group = "style", value_name = "FILE|DIR")]
    font: Vec<std::path::PathBuf>,
    /// Face of a font collection (TTC/OTC) given to --font, from 0.
    #[arg(long, requires = "font")]
    font_index: Option<u32>,
    /// Evaluate photos or scans of characters: a folder of images named `<char>.png`,
    /// `<char>.jpg` or `<char>.jpeg` (one character each, dark ink on light paper).
    #[arg(long, group = "style", value_name = "DIR")]
    images: Option<std::path::PathBuf>,
    /// Constant tilt α, degrees.
    #[arg(long, default_value_t = 0.0)]
    alpha: f64,
    /// Print every character's report (the fields docs/outputs.md lists for report.json) and
    /// the means as JSON instead of the table.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    placement: PlacementArg,
    #[command(flatten)]
    refine: RefineArgs,
}

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    check_range("--size", args.size, 64, 4096, "px")?;
    if let Some(mm) = args.char_mm {
        check_range("--char-mm", mm, MIN_CHAR_MM, MAX_CHAR_MM, "mm")?;
    }
    if args.limit == Some(0) {
        bail!("--limit 0: expected at least 1 character");
    }
    let profile = load_brush(&args.brush.brush)?;
    let (chars, input) = chars_and_input(&args)?;
    let alpha_rad = args.alpha.to_radians();
    let refine = args.refine.options()?;
    let generator = match refine {
        Some(r) if r.gradients == track_refine::Gradients::Generator => Some(committed_gen_model()?),
        _ => None,
    };
    let opts = WriteOptions {
        model: args.model,
        size: args.size,
        free_widths: true,
        alpha_rad,
        refine,
        generator,
        ..WriteOptions::default()
    };
    let pb = progress(chars.len() as u64, "evaluate");
    // `None`: a font that does not cover the character (skipped and counted).
    let reports: Vec<Option<CharReport>> = chars
        .par_iter()
        .map(|&c| {
            let p = match prepare_char(&input, c, args.method, true) {
                Err(e) if !args.font.is_empty() && is_uncovered(&e) => {
                    pb.inc(1);
                    return Ok(None);
                }
                r => r?,
            };
            let rule = match args.char_mm {
                _ if args.placement.search() && p.method == Method::Template => BoxRule::Search(args.char_mm),
                Some(mm) => BoxRule::Fixed(mm),
                None => BoxRule::Auto,
            };
            let r = write_placed(&p, &profile, &opts, rule)?;
            pb.inc(1);
            Ok(Some(r.report))
        })
        .collect::<Result<_>>()?;
    let uncovered: String = chars.iter().zip(&reports).filter(|(_, r)| r.is_none()).map(|(c, _)| *c).collect();
    let reports: Vec<CharReport> = reports.into_iter().flatten().collect();
    if reports.is_empty() {
        bail!("--font covers none of the {} characters asked for", chars.len());
    }
    pb.finish_and_clear();
    let means = ReportMeans::of(&reports);
    let uncovered = (!args.font.is_empty()).then_some(uncovered.as_str());
    if args.json {
        let mut summary = serde_json::to_value(&means)?;
        if let Some(u) = uncovered {
            summary["uncovered"] = json!({"count": u.chars().count(), "chars": u});
        }
        let method = pipeline::methods_used(&reports);
        print_json(
            &json!({"method": method, "model": args.model.name(), "brush": profile.name, "summary": summary, "chars": reports}),
        )?;
    } else {
        crate::outln!(
            "{} characters, {} via {}, brush {} (plan: the track as built; executed: its program as the simulator runs it; scores against the glyph):",
            reports.len(),
            args.model.name(),
            pipeline::methods_used(&reports),
            profile.name
        )?;
        print_table(&reports, &means, uncovered)?;
    }
    Ok(())
}

/// `text` padded to five terminal columns (a CJK character takes two).
fn column(text: &str) -> String {
    let width: usize = text.chars().map(|c| if c as u32 >= 0x1100 { 2 } else { 1 }).sum();
    format!("{text}{}", " ".repeat(5usize.saturating_sub(width)))
}

/// The per-character table, the means last, then what the means add (free widths, fonts'
/// uncovered characters, refinement).
fn print_table(reports: &[CharReport], m: &ReportMeans, uncovered: Option<&str>) -> Result<()> {
    let f4 = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.4}"));
    let line = |ch: &str,
                strokes: String,
                plan: Option<f64>,
                ex: [Option<f64>; 3],
                ag: Option<f64>,
                chamfer: Option<f64>,
                ms: f64| {
        crate::outln!(
            "{ch}{strokes:>8} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9.1}",
            f4(plan),
            f4(ex[0]),
            f4(ex[1]),
            f4(ex[2]),
            f4(ag),
            chamfer.map_or("-".to_string(), |c| format!("{c:.2}")),
            ms
        )
    };
    crate::outln!(
        "{:<5}{:>8} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}",
        "char",
        "strokes",
        "plan CSIM",
        "exec CSIM",
        "exec SSIM",
        "exec IoU",
        "agreement",
        "chamfer%",
        "ms"
    )?;
    for r in reports {
        let p = &r.plan;
        let strokes = format!("{}{}", p.strokes_found, p.strokes_expected.map_or(String::new(), |e| format!("/{e}")));
        let ex = r.executed;
        let ex = [ex.map(|e| e.csim), ex.map(|e| e.ssim), ex.map(|e| e.iou)];
        line(
            &column(&r.char),
            strokes,
            Some(p.csim),
            ex,
            r.agreement.map(|a| a.csim),
            p.chamfer_pct,
            r.timing_ms.plan,
        )?;
    }
    let strokes = m.strokes_match_fraction.map_or("-".to_string(), |f| format!("{:.0}%", 100.0 * f));
    let ex = m.executed;
    let ex = [ex.map(|e| e.csim), ex.map(|e| e.ssim), ex.map(|e| e.iou)];
    line(&column("mean"), strokes, Some(m.plan.csim), ex, m.agreement.map(|a| a.csim), m.chamfer_pct, m.plan_millis)?;
    if let Some(ex) = m.executed {
        crate::outln!(
            "worst executed CSIM {:.4}; plan SSIM {:.4} and IoU {:.4} (means)",
            ex.csim_min,
            m.plan.ssim,
            m.plan.iou
        )?;
    }
    if let Some(fw) = m.free_widths {
        crate::outln!("plan with footprints sized freely from the glyph (not a bound): CSIM {:.4} (mean)", fw.csim)?;
    }
    if let Some(u) = uncovered.filter(|u| !u.is_empty()) {
        crate::outln!("not in the font: {} ({u})", u.chars().count())?;
    }
    if let Some(rf) = &m.refine {
        crate::outln!(
            "refined {} ({} rejected): executed CSIM {} → {}, {:.0} ms each on average",
            rf.count,
            rf.rejected,
            f4(rf.executed_before.map(|s| s.csim)),
            f4(rf.executed_after.map(|s| s.csim)),
            rf.millis_mean
        )?;
    }
    Ok(())
}

/// Whether a glyph error says the fonts do not cover the character.
fn is_uncovered(e: &anyhow::Error) -> bool {
    e.downcast_ref::<pipeline::Error>().is_some_and(pipeline::Error::is_uncovered)
}

/// The characters to evaluate and where their glyphs come from (`--font`, `--images`, a
/// hanzi-writer-data folder or the embedded set), checked against each other.
fn chars_and_input(args: &Args) -> Result<(Vec<char>, GlyphInput)> {
    let image_files = match &args.images {
        Some(dir) => pipeline::image_folder(dir).context("--images")?,
        None => Vec::new(),
    };
    let mut chars: Vec<char> = match &args.chars {
        Some(s) => s.chars().filter(|c| !c.is_whitespace()).collect(),
        None if args.images.is_some() => image_files.iter().map(|(c, _)| *c).collect(),
        None => embedded_chars(),
    };
    if args.images.is_some() {
        let missing: Vec<char> = chars.iter().filter(|c| !image_files.iter().any(|(f, _)| f == *c)).copied().collect();
        if !missing.is_empty() {
            bail!(
                "--images {}: no image for {} (expected files named <char>.png, .jpg or .jpeg)",
                args.images.as_ref().map(|d| d.display().to_string()).unwrap_or_default(),
                missing.iter().collect::<String>()
            );
        }
    }
    if let Some(n) = args.limit {
        chars.truncate(n);
    }
    if chars.is_empty() {
        bail!("no characters to evaluate");
    }
    let style = !args.font.is_empty() || args.images.is_some();
    if args.hanzi_data.is_some() && args.chars.is_none() && !style {
        bail!("--hanzi-data needs --chars: name the characters to read from it");
    }
    let images = args.images.is_some().then_some(image_files);
    let input = glyph_input(&args.font, args.font_index, images, args.hanzi_data.clone())?;
    Ok((chars, input))
}
