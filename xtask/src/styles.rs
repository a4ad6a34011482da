//! `cargo xtask styles`: how well maobi writes in a font's style, per method (skeleton,
//! template), on the font's glyphs and optionally on synthetic scans of them.
//!
//! For every character that both the font and the stroke data (embedded or `--hanzi-data`)
//! have: centre lines by the method, a track built and rendered as `maobi evaluate` does
//! (`maobi::pipeline::write_char`, pen1 nominal, B-BSM, 512²; the char box and corner splits by
//! default the best of a few by the plan's CSIM, `--char-box auto` the automatic size alone),
//! scored against the
//! font glyph. "Strokes right" compares the stroke count with the template's; for the template
//! method (whose count is the template's by construction) a character counts as right only when
//! every stroke found ink under it and no two strokes landed on one.

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

use anyhow::{Context, Result, bail};
use brush_model::BrushProfile;
use pipeline::{BoxRule, GlyphInput, WriteOptions, prepare_with_template, write_placed};
use rayon::prelude::*;
use serde::Serialize;
use trajectory::{Glyph, GlyphError, Method};
use trajectory::{ScanOptions, decode_gray, embedded_chars, synth_scan};

use crate::io::write_atomic;

const HELP: &str = "\
cargo xtask styles --font F [--font F2 ...] [--hanzi-data DIR] [--chars STR | --chars-file FILE]
                   [--skip N] [--take N] [--methods skeleton,template] [--scan] [--execute]
                   [--free-widths] [--char-box search|auto] [--size PX] [--json OUT]

  --font F       a TrueType/OpenType file (a .ttc: its first font) or a folder of them; given
                 several times, each character comes from the first file that has it
  --hanzi-data   stroke data (unpacked hanzi-writer-data); default: the embedded data
  --chars        the characters (default: the embedded subset in frequency order); @FILE or
  --chars-file   read them from a file (whitespace and lines starting with # ignored)
  --skip/--take  a slice of that list (e.g. tune on --take 100, report on --skip 100)
  --scan         also score each method on a synthetic scan of the font glyph (seeded per char)
  --execute      score the executed program like `maobi evaluate` (slower); default: the plan
  --free-widths  also score the plan with widths unconstrained (the brush's range not applied)
  --char-box R   each character's box: search (default: the best of a few sizes around the
                 automatic one, each stroke split at its corners or written in one piece, by
                 the plan's CSIM; pipeline::searched_placement) or auto
                 (trajectory::auto_char_mm alone, corners split, as `maobi evaluate` does)
  --json OUT     write every character's row and the summary
";

#[derive(Clone, Debug, Serialize)]
struct Row {
    font: String,
    char: String,
    method: &'static str,
    scan: bool,
    strokes_expected: usize,
    strokes_found: usize,
    strokes_ok: bool,
    missing: Vec<usize>,
    doubled: Vec<usize>,
    /// Template method: share of the glyph's ink no registered stroke explains.
    uncovered_ink: Option<f64>,
    csim: f64,
    ssim: f64,
    iou: f64,
    /// Share of the glyph's ink (coverage sum) the scored render leaves out.
    missing_ink: f64,
    /// Ink the scored render puts outside the glyph, as a share of the glyph's ink.
    extra_ink: f64,
    /// Share of the track's pressed points whose width the brush had to clamp up / down.
    clamped_low_pct: f64,
    /// See `clamped_low_pct`.
    clamped_high_pct: f64,
    /// CSIM of the plan with widths unconstrained (`--free-widths`).
    free_csim: Option<f64>,
    /// Char box side, mm.
    char_mm: f64,
}

#[derive(Clone, Debug, Serialize)]
struct Summary {
    font: String,
    method: &'static str,
    scan: bool,
    chars: usize,
    /// Characters that could not be written or scored (not in `chars` or the means).
    failed: usize,
    strokes_right_pct: f64,
    mean_csim: f64,
    worst_csim: f64,
    mean_iou: f64,
    mean_missing_ink: f64,
    mean_extra_ink: f64,
    mean_free_csim: Option<f64>,
}

/// How `styles` sizes each character's box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum CharBoxRule {
    /// `trajectory::auto_char_mm` (the glyph's typical widths onto the brush's width range).
    Auto,
    /// `pipeline::searched_placement` (the best of a few sizes and of the strokes split
    /// at their corners or not, by the plan's CSIM).
    Search,
}

/// One method on one target glyph: centre lines, track, render, scores.
#[allow(clippy::too_many_arguments)]
fn score(
    font: &str,
    template: &Glyph,
    target: Glyph,
    method: Method,
    scan: bool,
    pen: &BrushProfile,
    opts: &WriteOptions,
    char_box: CharBoxRule,
) -> Result<Row> {
    let expected = template.medians.as_ref().map_or(0, Vec::len);
    let p = prepare_with_template(target, Some(method), Some(template))?;
    // The template report counts strokes from 1; the rows from 0.
    let t = p.template.as_ref();
    let missing: Vec<usize> = t.map_or(Vec::new(), |t| t.missing.iter().map(|i| i - 1).collect());
    let doubled: Vec<usize> = t.map_or(Vec::new(), |t| t.doubled.iter().map(|d| d[0] - 1).collect());
    let fits_ok = t.is_none_or(|t| t.strokes_ok);
    let uncovered_ink = t.map(|t| t.uncovered_ink);
    let rule = match char_box {
        CharBoxRule::Auto => BoxRule::Auto,
        CharBoxRule::Search => BoxRule::Search(None),
    };
    let res = write_placed(&p, pen, opts, rule)?;
    let (missing_ink, extra_ink) = ink_balance(&res.reference, res.executed.as_ref().unwrap_or(&res.render));
    let r = res.report;
    let sim = r.executed.map_or((r.plan.csim, r.plan.ssim, r.plan.iou), |e| (e.csim, e.ssim, e.iou));
    let pct = |k: usize| 100.0 * k as f64 / r.plan.points.max(1) as f64;
    Ok(Row {
        font: font.to_string(),
        char: r.char,
        method: method.name(),
        scan,
        strokes_expected: expected,
        strokes_found: r.plan.strokes_found,
        strokes_ok: fits_ok && r.plan.strokes_found == expected,
        missing,
        doubled,
        uncovered_ink,
        csim: sim.0,
        ssim: sim.1,
        iou: sim.2,
        missing_ink,
        extra_ink,
        clamped_low_pct: pct(r.brush.clamped_low_points),
        clamped_high_pct: pct(r.brush.clamped_high_points),
        free_csim: r.plan.free_widths.map(|f| f.csim),
        char_mm: r.char_mm,
    })
}

/// The ink `render` leaves out of `reference` and the ink it puts outside, each as a share of
/// the reference's ink (coverage sums, same size images).
fn ink_balance(reference: &bezier_raster::Coverage, render: &bezier_raster::Coverage) -> (f64, f64) {
    let (mut g, mut miss, mut extra) = (0.0f64, 0.0f64, 0.0f64);
    for (&a, &b) in reference.data().iter().zip(render.data()) {
        let (a, b) = (a as f64, b as f64);
        g += a;
        miss += (a - b).max(0.0);
        extra += (b - a).max(0.0);
    }
    if g <= 0.0 { (0.0, 0.0) } else { (miss / g, extra / g) }
}

/// A stable per-character seed for the synthetic scan.
fn seed_of(c: char) -> u64 {
    0x9E37_79B9 ^ (c as u64).wrapping_mul(0x1000_0000_01B3)
}

/// Runs `cargo xtask styles`.
pub fn run(args: &[String]) -> Result<()> {
    let mut fonts = Vec::new();
    let (mut hanzi, mut chars, mut skip, mut take, mut json) = (None, None, 0usize, usize::MAX, None);
    let mut methods = vec![Method::Skeleton, Method::Template];
    let (mut do_scan, mut execute, mut size, mut free) = (false, false, 512u32, false);
    let mut char_box = CharBoxRule::Search;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().with_context(|| format!("{a} needs a value\n\n{HELP}"));
        match a.as_str() {
            "--font" => fonts.push(PathBuf::from(val()?)),
            "--hanzi-data" => hanzi = Some(PathBuf::from(val()?)),
            "--chars" => {
                let v = val()?;
                chars = Some(match v.strip_prefix('@') {
                    Some(f) => std::fs::read_to_string(f).with_context(|| f.to_string())?,
                    None => v.clone(),
                });
            }
            "--chars-file" => {
                let f = val()?;
                chars = Some(std::fs::read_to_string(f).with_context(|| f.to_string())?);
            }
            "--skip" => skip = val()?.parse().context("--skip")?,
            "--take" => take = val()?.parse().context("--take")?,
            "--methods" => {
                methods =
                    val()?.split(',').map(|m| m.parse::<Method>().map_err(anyhow::Error::msg)).collect::<Result<_>>()?
            }
            "--scan" => do_scan = true,
            "--execute" => execute = true,
            "--free-widths" => free = true,
            "--char-box" => {
                char_box = match val()?.as_str() {
                    "auto" => CharBoxRule::Auto,
                    "search" => CharBoxRule::Search,
                    other => bail!("--char-box: expected auto or search, got `{other}`\n\n{HELP}"),
                }
            }
            "--size" => size = val()?.parse().context("--size")?,
            "--json" => json = Some(PathBuf::from(val()?)),
            "--help" | "-h" => {
                print!("{HELP}");
                return Ok(());
            }
            other => bail!("unknown argument `{other}`\n\n{HELP}"),
        }
    }
    if fonts.is_empty() {
        bail!("--font is required\n\n{HELP}");
    }
    // The fonts (files or folders, the first covering a character wins) and the stroke templates
    // (embedded, or --hanzi-data), as `maobi evaluate --font` reads them.
    let input = GlyphInput::fonts(&fonts, None, hanzi.clone())?;
    let font_name = fonts.iter().map(|f| f.display().to_string()).collect::<Vec<_>>().join("+");
    let list: Vec<char> = match &chars {
        Some(s) => s
            .lines()
            .filter(|l| !l.trim_start().starts_with('#'))
            .flat_map(|l| l.chars())
            .filter(|c| !c.is_whitespace())
            .collect(),
        None => embedded_chars(),
    };
    let list: Vec<char> = list.into_iter().skip(skip).take(take).collect();
    let pen = BrushProfile::builtin("pen1")?;
    let opts = WriteOptions { size, free_widths: free, execute, ..WriteOptions::default() };
    // The characters both sources have.
    let jobs: Vec<(char, Glyph, Glyph)> = list
        .iter()
        .filter_map(|&c| match input.load(c) {
            Ok((g, Some(t))) => Some(Ok((c, t, g))),
            Ok((_, None)) | Err(pipeline::Error::Glyph(GlyphError::Unknown { .. })) => None,
            Err(e) => Some(Err(e.into())),
        })
        .collect::<Result<_>>()?;
    eprintln!(
        "styles: {} of {} characters in both the font ({}) and the stroke data; methods {}{}",
        jobs.len(),
        list.len(),
        font_name,
        methods.iter().map(|m| m.name()).collect::<Vec<_>>().join(", "),
        if do_scan { ", font glyphs and synthetic scans" } else { "" }
    );
    let done = AtomicUsize::new(0);
    let total = jobs.len();
    let results: Vec<std::result::Result<Row, (&'static str, bool)>> = jobs
        .par_iter()
        .map(|(c, t, g)| {
            let mut out = Vec::new();
            let mut targets = vec![(g.clone(), false)];
            if do_scan {
                let bytes = synth_scan(g, &ScanOptions::seeded(seed_of(*c)))?;
                let gray = decode_gray(&bytes)?;
                targets.push((trajectory::glyph_from_gray(*c, &format!("scan of {c}"), &gray)?, true));
            }
            for (target, scan) in targets {
                for &m in &methods {
                    // A character that fails (e.g. its program fails the robot check) is reported and
                    // counted, not allowed to stop the run.
                    match score(&font_name, t, target.clone(), m, scan, &pen, &opts, char_box) {
                        Ok(row) => out.push(Ok(row)),
                        Err(e) => {
                            eprintln!(
                                "styles: {c} ({}, {}) failed: {e:#}",
                                m.name(),
                                if scan { "scan" } else { "font" }
                            );
                            out.push(Err((m.name(), scan)));
                        }
                    }
                }
            }
            let k = done.fetch_add(1, Ordering::Relaxed) + 1;
            if k % 10 == 0 || k == total {
                eprintln!("styles: {k}/{total}");
            }
            Ok(out)
        })
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .flatten()
        .collect();
    let failures: Vec<(&'static str, bool)> = results.iter().filter_map(|r| r.as_ref().err().copied()).collect();
    let rows: Vec<Row> = results.into_iter().filter_map(|r| r.ok()).collect();
    let mut summaries = Vec::new();
    for scan in if do_scan { vec![false, true] } else { vec![false] } {
        for &m in &methods {
            let r: Vec<&Row> = rows.iter().filter(|r| r.method == m.name() && r.scan == scan).collect();
            if r.is_empty() {
                continue;
            }
            let n = r.len() as f64;
            summaries.push(Summary {
                font: font_name.clone(),
                method: m.name(),
                scan,
                chars: r.len(),
                failed: failures.iter().filter(|f| **f == (m.name(), scan)).count(),
                strokes_right_pct: 100.0 * r.iter().filter(|x| x.strokes_ok).count() as f64 / n,
                mean_csim: r.iter().map(|x| x.csim).sum::<f64>() / n,
                worst_csim: r.iter().map(|x| x.csim).fold(f64::INFINITY, f64::min),
                mean_iou: r.iter().map(|x| x.iou).sum::<f64>() / n,
                mean_missing_ink: r.iter().map(|x| x.missing_ink).sum::<f64>() / n,
                mean_extra_ink: r.iter().map(|x| x.extra_ink).sum::<f64>() / n,
                mean_free_csim: free.then(|| r.iter().filter_map(|x| x.free_csim).sum::<f64>() / n),
            });
        }
    }
    println!(
        "| font | target | method | chars | strokes right | mean CSIM | worst CSIM | mean IoU | ink missing | ink outside |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for s in &summaries {
        println!(
            "| {} | {} | {} | {} | {:.1} % | {:.3} | {:.3} | {:.3} | {:.1} % | {:.1} % |{}",
            s.font,
            if s.scan { "synthetic scan" } else { "font glyph" },
            s.method,
            if s.failed > 0 { format!("{} (+{} failed)", s.chars, s.failed) } else { s.chars.to_string() },
            s.strokes_right_pct,
            s.mean_csim,
            s.worst_csim,
            s.mean_iou,
            100.0 * s.mean_missing_ink,
            100.0 * s.mean_extra_ink,
            s.mean_free_csim.map_or(String::new(), |f| format!(" free widths CSIM {f:.3}"))
        );
    }
    if let Some(path) = json {
        let doc = serde_json::json!({
            "fonts": fonts, "hanzi_data": hanzi, "skip": skip, "take": take, "size": size,
            "char_box": format!("{char_box:?}").to_lowercase(),
            "scored": if execute { "executed" } else { "planned" }, "summary": summaries, "chars": rows,
        });
        write_atomic(&path, serde_json::to_string_pretty(&doc)?.as_bytes())?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bad arguments are refused with a message naming the argument, and no JSON is written.
    #[test]
    fn bad_input_names_the_argument_and_writes_nothing() {
        let json = std::env::temp_dir().join(format!("maobi-styles-{}.json", std::process::id()));
        let font = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/fonts/ukai-subset.ttf");
        let (j, f) = (json.to_str().unwrap(), font.to_str().unwrap());
        let err = |v: &[&str]| format!("{:#}", run(&v.iter().map(|s| s.to_string()).collect::<Vec<_>>()).unwrap_err());
        assert!(err(&["--json", j]).contains("--font is required"));
        assert!(
            err(&["--font", f, "--char-box", "best", "--json", j])
                .contains("--char-box: expected auto or search, got `best`")
        );
        assert!(err(&["--font", f, "--size", "big", "--json", j]).starts_with("--size"));
        assert!(err(&["--font", f, "--methods", "ink", "--json", j]).contains("ink"));
        assert!(err(&["--font", f, "--bogus"]).contains("unknown argument `--bogus`"));
        assert!(err(&["--font", f, "--json"]).contains("--json needs a value"));
        assert!(!json.exists());
    }

    #[test]
    fn ink_balance_counts_missed_and_outside_ink_against_the_reference() {
        let (mut g, mut r) = (bezier_raster::Coverage::new(4, 1), bezier_raster::Coverage::new(4, 1));
        g.data_mut().copy_from_slice(&[1.0, 1.0, 0.5, 0.0]);
        r.data_mut().copy_from_slice(&[1.0, 0.0, 1.0, 0.25]);
        let (miss, extra) = ink_balance(&g, &r);
        assert!((miss - 1.0 / 2.5).abs() < 1e-9 && (extra - 0.75 / 2.5).abs() < 1e-9, "{miss} {extra}");
        assert_eq!(ink_balance(&r, &r), (0.0, 0.0));
    }
}
