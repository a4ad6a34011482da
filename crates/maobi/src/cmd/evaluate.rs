//! `maobi evaluate`: the write pipeline over many characters, in parallel, with mean scores.

use anyhow::{Context, Result, bail};
use bezier_raster::ModelKind;
use pipeline::{
    BoxRule, CharReport, GlyphInput, RefineMeans, ReportMeans, SimilarityMeans, WriteOptions, write_placed,
};
use rayon::prelude::*;
use serde_json::json;
use trajectory::{GlyphError, Method, embedded_chars};

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
    let mut summary = summary_json(&means);
    if !args.font.is_empty() {
        summary["uncovered"] = json!({"count": uncovered.chars().count(), "chars": uncovered});
    }
    if let Some(r) = &means.refine {
        summary["refine"] = refine_json(r);
    }
    if args.json {
        print_json(
            &json!({"method": method_name(&reports), "model": args.model.name(), "brush": profile.name, "summary": summary, "chars": reports}),
        )?;
    } else {
        crate::outln!(
            "{} characters, {} via {}, brush {} (plan: the track as built; executed: its program as the simulator runs it; scores against the glyph):",
            reports.len(),
            args.model.name(),
            method_name(&reports),
            profile.name
        )?;
        print_table(&reports, &summary)?;
    }
    Ok(())
}

/// `text` padded to five terminal columns (a CJK character takes two).
fn column(text: &str) -> String {
    let width: usize = text.chars().map(|c| if c as u32 >= 0x1100 { 2 } else { 1 }).sum();
    format!("{text}{}", " ".repeat(5usize.saturating_sub(width)))
}

/// The per-character table, the means last, then what the summary adds (free widths, fonts'
/// uncovered characters, refinement).
fn print_table(reports: &[CharReport], summary: &serde_json::Value) -> Result<()> {
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
        line(
            &column(&r.char),
            strokes,
            Some(p.csim),
            [ex.map(|e| e.csim), ex.map(|e| e.ssim), ex.map(|e| e.iou)],
            r.agreement.map(|a| a.csim),
            p.chamfer_pct,
            r.timing_ms.plan,
        )?;
    }
    let g = |v: &serde_json::Value| v.as_f64();
    let ex = &summary["executed"];
    let strokes = summary["strokes_match_fraction"].as_f64().map_or("-".to_string(), |f| format!("{:.0}%", 100.0 * f));
    line(
        &column("mean"),
        strokes,
        g(&summary["csim"]),
        [g(&ex["csim"]), g(&ex["ssim"]), g(&ex["iou"])],
        g(&summary["agreement"]["csim"]),
        g(&summary["chamfer_pct"]),
        g(&summary["millis_mean"]).unwrap_or(f64::NAN),
    )?;
    if let Some(w) = g(&ex["csim_min"]) {
        crate::outln!(
            "worst executed CSIM {w:.4}; plan SSIM {} and IoU {} (means)",
            f4(g(&summary["ssim"])),
            f4(g(&summary["iou"]))
        )?;
    }
    let fw = &summary["free_widths"];
    if let Some(c) = g(&fw["csim"]) {
        crate::outln!("plan with footprints sized freely from the glyph (not a bound): CSIM {c:.4} (mean)")?;
    }
    if let Some(n) = summary["uncovered"]["count"].as_u64().filter(|n| *n > 0) {
        crate::outln!("not in the font: {n} ({})", summary["uncovered"]["chars"].as_str().unwrap_or(""))?;
    }
    if let Some(rf) = summary.get("refine") {
        crate::outln!(
            "refined {} ({} rejected): executed CSIM {} → {}, {:.0} ms each on average",
            rf["count"],
            rf["rejected"],
            f4(g(&rf["executed_before"]["csim"])),
            f4(g(&rf["executed_after"]["csim"])),
            g(&rf["millis_mean"]).unwrap_or(f64::NAN)
        )?;
    }
    Ok(())
}

/// The summary's means and counts over the character reports ([`ReportMeans`]).
fn summary_json(m: &ReportMeans) -> serde_json::Value {
    let sim = |s: Option<SimilarityMeans>| {
        s.map_or(
            serde_json::Value::Null,
            |s| json!({"csim": s.csim, "ssim": s.ssim, "iou": s.iou, "csim_min": s.csim_min}),
        )
    };
    let fw = m.free_widths.map_or(serde_json::Value::Null, |u| json!({"csim": u.csim, "ssim": u.ssim, "iou": u.iou}));
    json!({
        "count": m.count,
        "csim": m.plan.csim,
        "ssim": m.plan.ssim,
        "iou": m.plan.iou,
        "chamfer_pct": m.chamfer_pct,
        "strokes_match_fraction": m.strokes_match_fraction,
        "millis_mean": m.plan_millis,
        "executed": sim(m.executed),
        "agreement": sim(m.agreement),
        // The plan with footprints sized freely from the glyph (not a bound: see CharReport).
        "free_widths": fw,
    })
}

/// The refinement's before/after means.
fn refine_json(rf: &RefineMeans) -> serde_json::Value {
    let sim = |s: Option<SimilarityMeans>| {
        s.map_or(serde_json::Value::Null, |s| json!({"csim": s.csim, "ssim": s.ssim, "iou": s.iou}))
    };
    json!({
        "count": rf.count,
        "rejected": rf.rejected,
        "executed_before": sim(rf.executed_before),
        "executed_after": sim(rf.executed_after),
        "planned_before": sim(Some(rf.planned_before)),
        "planned_after": sim(Some(rf.planned_after)),
        "millis_mean": rf.millis_mean,
        "millis_max": rf.millis_max,
    })
}

/// The method the reports used: one name, or the names joined by `+` when they differ.
fn method_name(reports: &[CharReport]) -> String {
    let mut names: Vec<&str> = reports.iter().map(|r| r.method).collect();
    names.sort_unstable();
    names.dedup();
    names.join("+")
}

/// Whether a glyph error says the fonts do not cover the character.
fn is_uncovered(e: &anyhow::Error) -> bool {
    matches!(e.downcast_ref::<pipeline::Error>(), Some(pipeline::Error::Glyph(GlyphError::Unknown { .. })))
}

/// The images of `--images DIR`: files `<char>.png|jpg|jpeg`, one character per name, sorted.
fn image_files(dir: &std::path::Path) -> Result<Vec<(char, std::path::PathBuf)>> {
    let entries =
        std::fs::read_dir(dir).with_context(|| format!("--images {}: cannot read the folder", dir.display()))?;
    let mut out = Vec::new();
    for e in entries {
        let path = e.with_context(|| format!("--images {}", dir.display()))?.path();
        let ext = path.extension().and_then(|x| x.to_str()).map(str::to_ascii_lowercase);
        if !matches!(ext.as_deref(), Some("png" | "jpg" | "jpeg")) {
            continue;
        }
        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or_default();
        let mut cs = stem.chars();
        match (cs.next(), cs.next()) {
            (Some(c), None) => out.push((c, path)),
            _ => bail!("{}: expected an image named after its one character (e.g. 永.png)", path.display()),
        }
    }
    out.sort();
    out.dedup_by(|a, b| a.0 == b.0);
    if out.is_empty() {
        bail!("--images {}: no <char>.png, .jpg or .jpeg files", dir.display());
    }
    Ok(out)
}

/// The characters to evaluate and where their glyphs come from (`--font`, `--images`, a
/// hanzi-writer-data folder or the embedded set), checked against each other.
fn chars_and_input(args: &Args) -> Result<(Vec<char>, GlyphInput)> {
    let image_files = match &args.images {
        Some(dir) => image_files(dir)?,
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
