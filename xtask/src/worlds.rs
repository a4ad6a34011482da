//! `cargo xtask worlds`: the executed figure under worlds that disagree with the model. Each
//! character is planned and its program executed as `robot send` sends it (the pipeline's
//! executed path), then inked by each world (`worlds::World`) instead of the forward model and
//! scored against the glyph and against the plan; the model's own executed figure beside them.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use bezier_raster::Coverage;
use brush_model::BrushProfile;
use pipeline::{BoxRule, CharResult, Similarity, WriteOptions, prepare, similarity, write_placed};
use rayon::prelude::*;
use serde::Serialize;
use trajectory::embedded_glyph;
use worlds::{World, ink};

use crate::io::{char_bar, write_atomic};
use crate::skeleton_counts::read_set;

const HELP: &str = "\
cargo xtask worlds [--chars TEXT | --set FILE|embedded [--lines A-B]] [--world SPEC]...
                   [--refine] [--size PX] [--brush NAME] [--contact-mm MM] [--threads N]
                   [--json OUT] [--summary OUT] [--images DIR]

Plans each character (medians, auto char box), executes its program as `robot send` sends it,
inks the executed path with each world instead of the forward model, and scores that ink
against the glyph (CSIM, SSIM, IoU) and against the plan (agreement). The model's own figures
are listed first as `model (as planned)`.

  --chars TEXT      the characters (embedded glyph data)
  --set FILE        characters one per line, `#` comments (fixtures/hanzi/heldout-2000.txt);
                    `embedded` is the frequency subset (the tuning set)
  --lines A-B       only the set's lines A to B (1-based, inclusive)
  --world SPEC      a world (worlds::World::parse: model, mismatch, pressure:MM, trail:R,
                    width:F, length:F, lag:MM, spread:MM, light, joined by commas); repeatable;
                    default: pressure:0.05, pressure:1, trail:0.3, mismatch
  --refine          also refine each track (track_refine defaults) and score the refined one
  --size PX         side of the images the figures are taken at (default 512)
  --brush NAME      a built-in brush (default pen1)
  --contact-mm MM   plan with the brush's hairs following from MM (the profile's contact depth;
                    0 plans as before the contact depth, gliding at 0.01 mm)
  --threads N       characters in flight (default 2)
  --json OUT        where to write the figures (default target/worlds.json)
  --summary OUT     also the means alone, without the per-character figures (the committed
                    results under fixtures/worlds/)
  --images DIR      a labelled picture per character: glyph | plan | the model's executed ink |
                    each world's ink over the glyph (black both, red glyph only, blue ink only)
";

/// Scores of one ink against the glyph and the plan.
#[derive(Clone, Copy, Debug, Serialize)]
struct Scored {
    executed: Similarity,
    agreement: Similarity,
}

/// One character under every world, for one track (as built, or refined).
#[derive(Clone, Debug, Serialize)]
struct Judged {
    plan: Similarity,
    /// The model's own executed ink first, then each world's.
    worlds: Vec<Scored>,
}

#[derive(Clone, Debug, Serialize)]
struct CharFigures {
    char: String,
    char_mm: f64,
    unrefined: Judged,
    refined: Option<Judged>,
}

/// Means and worst over the characters, per world.
#[derive(Clone, Debug, Serialize)]
struct WorldSummary {
    world: String,
    description: String,
    executed_csim: f64,
    executed_ssim: f64,
    executed_iou: f64,
    worst_executed_csim: f64,
    agreement_csim: f64,
    worst_agreement_csim: f64,
}

#[derive(Serialize)]
struct Report {
    command: String,
    chars: String,
    brush: String,
    contact_h_mm: f64,
    glide_h_mm: f64,
    size: u32,
    unrefined: Vec<WorldSummary>,
    refined: Option<Vec<WorldSummary>>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    per_char: Vec<CharFigures>,
}

/// Runs the task with its arguments (after `worlds`).
pub fn run(args: &[String]) -> Result<()> {
    let mut chars: Option<Vec<char>> = None;
    let mut set: Option<String> = None;
    let mut lines: Option<(usize, usize)> = None;
    let mut specs: Vec<String> = Vec::new();
    let mut refine = false;
    let mut size = 512u32;
    let mut brush = "pen1".to_string();
    let mut contact: Option<f64> = None;
    let mut threads = 2usize;
    let mut json = PathBuf::from("target/worlds.json");
    let mut images: Option<PathBuf> = None;
    let mut summary: Option<PathBuf> = None;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().with_context(|| format!("{a} needs a value"));
        match a.as_str() {
            "--help" | "-h" => {
                print!("{HELP}");
                return Ok(());
            }
            "--chars" => chars = Some(val()?.chars().filter(|c| !c.is_whitespace()).collect()),
            "--set" => set = Some(val()?.clone()),
            "--lines" => lines = Some(crate::io::parse_lines(val()?)?),
            "--world" => specs.push(val()?.clone()),
            "--refine" => refine = true,
            "--size" => size = val()?.parse().context("--size")?,
            "--brush" => brush = val()?.clone(),
            "--contact-mm" => contact = Some(val()?.parse().context("--contact-mm")?),
            "--threads" => threads = val()?.parse().context("--threads")?,
            "--json" => json = PathBuf::from(val()?),
            "--images" => images = Some(PathBuf::from(val()?)),
            "--summary" => summary = Some(PathBuf::from(val()?)),
            other => bail!("unknown argument `{other}`\n\n{HELP}"),
        }
    }
    let mut chars = match (chars, &set) {
        (Some(c), None) => c,
        (None, Some(s)) => read_set(s)?,
        _ => bail!("give --chars TEXT or --set FILE\n\n{HELP}"),
    };
    if let Some((x, y)) = lines {
        if set.is_none() || y > chars.len() {
            bail!("--lines {x}-{y}: needs --set with at least {y} characters");
        }
        chars = chars[x - 1..y].to_vec();
    }
    if chars.is_empty() || !(16..=4096).contains(&size) || threads == 0 {
        bail!("worlds: no characters, or --size outside 16..=4096, or --threads 0");
    }
    if specs.is_empty() {
        specs = ["pressure:0.05", "pressure:1", "trail:0.3", "mismatch"].map(String::from).to_vec();
    }
    let worlds: Vec<World> = specs.iter().map(|s| World::parse(s)).collect::<Result<_, _>>()?;
    let mut profile = BrushProfile::builtin(&brush)?;
    if let Some(c) = contact {
        profile.hairs.contact_h_mm = c;
        profile.validate("--contact-mm")?;
    }
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    let pb = char_bar(chars.len(), "worlds");
    let per_char: Vec<CharFigures> = pool.install(|| {
        chars
            .par_iter()
            .map(|&c| {
                let r = judge_char(c, &profile, &worlds, &specs, size, refine, images.as_deref());
                pb.inc(1);
                r.with_context(|| format!("{c}"))
            })
            .collect::<Result<_>>()
    })?;
    pb.finish_and_clear();
    let mut names = vec!["model (as planned)".to_string()];
    names.extend(specs.iter().cloned());
    let mut descriptions = vec!["the forward model with the brush's own hairs".to_string()];
    descriptions.extend(worlds.iter().map(World::describe));
    let unrefined = summarise(&names, &descriptions, per_char.iter().map(|c| &c.unrefined));
    let refined = refine.then(|| summarise(&names, &descriptions, per_char.iter().filter_map(|c| c.refined.as_ref())));
    let text: String = chars.iter().collect();
    println!(
        "{} characters, {brush} (hairs follow from {} mm; glides at {} mm), {size}²",
        chars.len(),
        profile.hairs.contact_h_mm,
        trajectory::glide_h_mm(&profile)
    );
    print_table("unrefined", &unrefined);
    if let Some(r) = &refined {
        print_table("refined", r);
    }
    let report = Report {
        command: std::iter::once("cargo xtask worlds".to_string())
            .chain(args.iter().cloned())
            .collect::<Vec<_>>()
            .join(" "),
        chars: text,
        brush,
        contact_h_mm: profile.hairs.contact_h_mm,
        glide_h_mm: trajectory::glide_h_mm(&profile),
        size,
        unrefined,
        refined,
        per_char,
    };
    write_atomic(&json, (serde_json::to_string_pretty(&report)? + "\n").as_bytes())?;
    eprintln!("wrote {}", json.display());
    if let Some(path) = summary {
        let means = Report { per_char: Vec::new(), ..report };
        write_atomic(&path, (serde_json::to_string_pretty(&means)? + "\n").as_bytes())?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

fn print_table(what: &str, rows: &[WorldSummary]) {
    println!("{what}:");
    println!(
        "  {:<28} {:>9} {:>9} {:>9} {:>10} {:>9} {:>10}",
        "world", "exec CSIM", "exec IoU", "worst", "agreement", "worst", "exec SSIM"
    );
    for r in rows {
        println!(
            "  {:<28} {:>9.4} {:>9.4} {:>9.4} {:>10.4} {:>9.4} {:>10.4}",
            r.world,
            r.executed_csim,
            r.executed_iou,
            r.worst_executed_csim,
            r.agreement_csim,
            r.worst_agreement_csim,
            r.executed_ssim
        );
    }
}

fn summarise<'a>(
    names: &[String],
    descriptions: &[String],
    judged: impl Iterator<Item = &'a Judged>,
) -> Vec<WorldSummary> {
    let judged: Vec<&Judged> = judged.collect();
    let n = judged.len().max(1) as f64;
    names
        .iter()
        .zip(descriptions)
        .enumerate()
        .map(|(k, (name, description))| {
            let s: Vec<&Scored> = judged.iter().map(|j| &j.worlds[k]).collect();
            let mean = |f: &dyn Fn(&Scored) -> f64| s.iter().map(|x| f(x)).sum::<f64>() / n;
            let worst = |f: &dyn Fn(&Scored) -> f64| s.iter().map(|x| f(x)).fold(f64::INFINITY, f64::min);
            WorldSummary {
                world: name.clone(),
                description: description.clone(),
                executed_csim: mean(&|x| x.executed.csim),
                executed_ssim: mean(&|x| x.executed.ssim),
                executed_iou: mean(&|x| x.executed.iou),
                worst_executed_csim: worst(&|x| x.executed.csim),
                agreement_csim: mean(&|x| x.agreement.csim),
                worst_agreement_csim: worst(&|x| x.agreement.csim),
            }
        })
        .collect()
}

/// One character: planned (and refined), executed, inked by each world, scored.
fn judge_char(
    c: char,
    profile: &BrushProfile,
    worlds: &[World],
    specs: &[String],
    size: u32,
    refine: bool,
    images: Option<&std::path::Path>,
) -> Result<CharFigures> {
    let p = prepare(embedded_glyph(c)?, None)?;
    let opts = WriteOptions { size, free_widths: false, ..WriteOptions::default() };
    let built = write_placed(&p, profile, &opts, BoxRule::Auto)?;
    let (unrefined, inks) = judge(&built, profile, worlds)?;
    if let Some(dir) = images {
        strip(dir, c, "unrefined", &built, specs, &inks)?;
    }
    let refined = if refine {
        let ro = Some(pipeline::RefineOptions::default());
        let r = write_placed(&p, profile, &WriteOptions { refine: ro, ..opts }, BoxRule::Auto)?;
        let (j, inks) = judge(&r, profile, worlds)?;
        if let Some(dir) = images {
            strip(dir, c, "refined", &r, specs, &inks)?;
        }
        Some(j)
    } else {
        None
    };
    Ok(CharFigures { char: c.to_string(), char_mm: built.char_box.size_mm, unrefined, refined })
}

/// The figures of one written character under the model and each world, and each world's ink.
fn judge(r: &CharResult, profile: &BrushProfile, worlds: &[World]) -> Result<(Judged, Vec<Coverage>)> {
    let states = r.executed_states.as_ref().context("not executed")?;
    let b = r.char_box;
    let (Some(executed), Some(agreement)) = (r.report.executed, r.report.agreement) else {
        bail!("not executed");
    };
    let mut scored = vec![Scored { executed, agreement }];
    let mut inks = Vec::new();
    for w in worlds {
        let img = ink(&w.stamps(states, profile), b.x0_mm, b.y0_mm, b.size_mm, r.render.width());
        scored.push(Scored { executed: similarity(&r.reference, &img)?, agreement: similarity(&r.render, &img)? });
        inks.push(img);
    }
    Ok((Judged { plan: r.report.plan.similarity(), worlds: scored }, inks))
}

/// `DIR/<char>-<what>.png`: glyph | plan | the model's executed ink | each world's ink over the
/// glyph, labelled.
fn strip(
    dir: &std::path::Path,
    c: char,
    what: &str,
    r: &CharResult,
    specs: &[String],
    inks: &[Coverage],
) -> Result<()> {
    let executed = r.executed.as_ref().context("not executed")?;
    let mut panels: Vec<(String, image::RgbImage)> = vec![
        ("glyph".into(), gray_rgb(&r.reference)),
        ("plan".into(), gray_rgb(&r.render)),
        ("model (executed)".into(), overlay(&r.reference, executed)?),
    ];
    for (s, img) in specs.iter().zip(inks) {
        panels.push((s.clone(), overlay(&r.reference, img)?));
    }
    let panels: Vec<(&str, &image::RgbImage)> = panels.iter().map(|(l, img)| (l.as_str(), img)).collect();
    let png = figures::labelled_row_rgb_png(&panels)?;
    write_atomic(&dir.join(format!("{c}-{what}.png")), &png)
}

fn gray_rgb(c: &Coverage) -> image::RgbImage {
    let g = c.to_gray8();
    image::RgbImage::from_fn(c.width(), c.height(), |x, y| {
        let v = g[(y * c.width() + x) as usize];
        image::Rgb([v, v, v])
    })
}

fn overlay(reference: &Coverage, ink: &Coverage) -> Result<image::RgbImage> {
    let png = bezier_raster::overlay_png(reference, ink)?;
    Ok(image::load_from_memory(&png)?.to_rgb8())
}

/// The worlds the gate judges the gate characters under.
pub const GATE_WORLDS: [&str; 4] = ["pressure:0.05", "pressure:1", "trail:0.3", "mismatch"];

/// One world's means over characters, for the gate: (name, executed CSIM, executed IoU,
/// agreement CSIM, worst agreement CSIM).
pub type GateRow = (String, f64, f64, f64, f64);

/// `chars` planned with pen1 at `size`², executed as sent and inked by the forward model (the
/// first row, `model`) and each world of `specs`: their means over the characters.
///
/// # Errors
/// When a world is not one, or a character cannot be written.
pub fn gate_rows(chars: &str, specs: &[&str], size: u32) -> Result<Vec<GateRow>> {
    let pen1 = BrushProfile::builtin("pen1")?;
    let worlds: Vec<World> = specs.iter().map(|s| World::parse(s)).collect::<Result<_, _>>()?;
    let judged: Vec<Judged> = chars
        .chars()
        .collect::<Vec<_>>()
        .par_iter()
        .map(|&c| {
            let p = prepare(embedded_glyph(c)?, None)?;
            let opts = WriteOptions { size, free_widths: false, ..WriteOptions::default() };
            let r = write_placed(&p, &pen1, &opts, BoxRule::Auto)?;
            Ok(judge(&r, &pen1, &worlds)?.0)
        })
        .collect::<Result<_>>()?;
    let mut names = vec!["model".to_string()];
    names.extend(specs.iter().map(|s| s.to_string()));
    Ok(summarise(&names, &names, judged.iter())
        .into_iter()
        .map(|r| (r.world, r.executed_csim, r.executed_iou, r.agreement_csim, r.worst_agreement_csim))
        .collect())
}
