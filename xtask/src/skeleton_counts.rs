//! `cargo xtask skeleton-counts`: how often the skeleton method finds as many strokes as
//! hanzi-writer's medians, on a named character set, for the default skeleton rules and any
//! variants of them (a sweep computes each glyph's skeleton once and runs every variant on it).

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use rayon::prelude::*;
use serde::Serialize;
use trajectory::{DEFAULT_ANALYSIS_PX, GraphOptions, Skeleton, embedded_chars, embedded_glyph, glyph_from_hanzi_dir};

use crate::io::{char_bar, write_atomic};

const HELP: &str = "\
cargo xtask skeleton-counts [--hanzi-data DIR] [--set FILE|embedded] [--lines A-B]
                            [--opts K=V,K=V]... [--px N] [--json OUT] [--wrong] [--oracle]

Counts the strokes the skeleton method finds (Method::Skeleton at the analysis raster) against
the medians' count, per character, and prints the share that is right.

  --hanzi-data DIR  an unpacked hanzi-writer-data package (files <char>.json); without it the
                    embedded subset is used
  --set FILE        characters, one per line, `#` comments (e.g. fixtures/hanzi/heldout-2000.txt);
                    `embedded` (the default) is the embedded subset
  --lines A-B       only the set's characters A to B (1-based, inclusive), e.g. 1-1000
  --opts K=V,...    a variant of the skeleton rules (GraphOptions::set keys: spur_factor,
                    corner_spur_factor, merge_factor, straight_min_deg, corner_deg,
                    split_box_corners, loose_end_em, corner_spur_away_deg, corner_reach,
                    hook_widths, hook_ratio, covered_max_widths, learned_pairing,
                    learned_corners, ...);
                    repeat for a sweep; the defaults are always measured first
  --px N            analysis raster side (default the pipeline's, 512)
  --json OUT        where to write the figures (default target/skeleton-counts.json)
  --wrong           also list the characters each variant gets wrong (found/expected)
  --oracle          also measure the defaults with junctions paired and corners split as the
                    glyph's own medians say (how far better decisions could go; it needs the
                    answer)
";

#[derive(Serialize)]
struct Variant {
    opts: String,
    right: usize,
    too_few: usize,
    too_many: usize,
    pct_right: f64,
    /// `char found/expected` for each wrong character.
    wrong: Vec<String>,
}

#[derive(Serialize)]
struct Report {
    set: String,
    lines: Option<(usize, usize)>,
    glyphs: String,
    analysis_px: u32,
    chars: usize,
    variants: Vec<Variant>,
}

pub(crate) fn read_set(spec: &str) -> Result<Vec<char>> {
    if spec == "embedded" {
        return Ok(embedded_chars());
    }
    let text = std::fs::read_to_string(spec).with_context(|| format!("--set {spec}"))?;
    let chars: Vec<char> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .filter_map(|l| l.chars().next())
        .collect();
    if chars.is_empty() {
        bail!("--set {spec}: no characters (one per line, `#` comments)");
    }
    Ok(chars)
}

fn parse_opts(spec: &str) -> Result<GraphOptions> {
    let mut o = GraphOptions::default();
    for kv in spec.split(',').filter(|s| !s.is_empty()) {
        let (k, v) = kv.split_once('=').with_context(|| format!("--opts {spec}: `{kv}` is not KEY=VALUE"))?;
        let v: f64 = v.trim().parse().with_context(|| format!("--opts {spec}: `{v}` is not a number"))?;
        o.set(k.trim(), v).map_err(|e| anyhow::anyhow!("--opts {spec}: {e}"))?;
    }
    Ok(o)
}

/// Runs the task with its arguments (after `skeleton-counts`).
pub fn run(args: &[String]) -> Result<()> {
    let mut hanzi: Option<PathBuf> = None;
    let mut set = "embedded".to_string();
    let mut lines: Option<(usize, usize)> = None;
    let mut variants: Vec<String> = vec![String::new()];
    let mut px = DEFAULT_ANALYSIS_PX;
    let mut json = PathBuf::from("target/skeleton-counts.json");
    let mut list_wrong = false;
    let mut oracle = false;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().with_context(|| format!("{a} needs a value"));
        match a.as_str() {
            "--help" | "-h" => {
                print!("{HELP}");
                return Ok(());
            }
            "--hanzi-data" => hanzi = Some(PathBuf::from(val()?)),
            "--set" => set = val()?.clone(),
            "--lines" => lines = Some(crate::io::parse_lines(val()?)?),
            "--opts" => variants.push(val()?.clone()),
            "--px" => px = val()?.parse().context("--px")?,
            "--json" => json = PathBuf::from(val()?),
            "--wrong" => list_wrong = true,
            "--oracle" => oracle = true,
            other => bail!("unknown argument `{other}`\n\n{HELP}"),
        }
    }
    let opts: Vec<GraphOptions> = variants.iter().map(|v| parse_opts(v)).collect::<Result<_>>()?;
    if oracle {
        variants.push("pairing and corners by the medians (oracle)".into());
    }
    let mut chars = read_set(&set)?;
    if let Some((x, y)) = lines {
        if y > chars.len() {
            bail!("--lines {x}-{y}: the set has {} characters", chars.len());
        }
        chars = chars[x - 1..y].to_vec();
    }
    let load = |c: char| match &hanzi {
        Some(dir) => glyph_from_hanzi_dir(dir, c),
        None => embedded_glyph(c),
    };
    let pb = char_bar(chars.len(), "skeletons");
    // Per character: the medians' count and each variant's count.
    let counts: Vec<(char, usize, Vec<usize>)> = chars
        .par_iter()
        .map(|&c| -> Result<(char, usize, Vec<usize>)> {
            let g = load(c).with_context(|| format!("{c}"))?;
            let expected = g.medians.as_ref().map(Vec::len).with_context(|| format!("{c}: no medians"))?;
            let medians = g.medians.as_deref().unwrap_or_default();
            let found = match Skeleton::of(&g, px) {
                Some(s) => {
                    let mut f: Vec<usize> = opts.iter().map(|o| s.strokes(o).len()).collect();
                    if oracle {
                        f.push(s.strokes_paired_by_medians(&opts[0], medians).len());
                    }
                    f
                }
                None => vec![0; variants.len()],
            };
            pb.inc(1);
            Ok((c, expected, found))
        })
        .collect::<Result<_>>()?;
    pb.finish_and_clear();
    let n = counts.len();
    let mut out = Vec::new();
    for (k, v) in variants.iter().enumerate() {
        let (mut right, mut few, mut many, mut wrong) = (0, 0, 0, Vec::new());
        for (c, e, f) in &counts {
            match f[k].cmp(e) {
                std::cmp::Ordering::Equal => right += 1,
                std::cmp::Ordering::Less => few += 1,
                std::cmp::Ordering::Greater => many += 1,
            }
            if f[k] != *e {
                wrong.push(format!("{c} {}/{e}", f[k]));
            }
        }
        let pct = |x: usize| 100.0 * x as f64 / n.max(1) as f64;
        let name = if v.is_empty() { "defaults" } else { v.as_str() };
        println!(
            "{name}: {right}/{n} right ({:.1} %), too few {:.1} %, too many {:.1} %",
            pct(right),
            pct(few),
            pct(many)
        );
        if list_wrong {
            println!("  wrong: {}", wrong.join("  "));
        }
        out.push(Variant {
            opts: name.to_string(),
            right,
            too_few: few,
            too_many: many,
            pct_right: (pct(right) * 10.0).round() / 10.0,
            wrong,
        });
    }
    let report = Report {
        set,
        lines,
        glyphs: hanzi.as_ref().map_or("embedded".into(), |d| d.display().to_string()),
        analysis_px: px,
        chars: n,
        variants: out,
    };
    write_atomic(&json, serde_json::to_string_pretty(&report)?.as_bytes())?;
    eprintln!("wrote {}", json.display());
    Ok(())
}
