//! Flags and messages that `write` and `evaluate` share: the glyph source, template
//! placement, the refinement, and what to say when a glyph or a sheet is refused.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use pipeline::{GlyphInput, Prepared, SheetError, prepare_loaded};
use trajectory::Method;

/// `--placement search|auto` of `write` and `evaluate`.
#[derive(clap::Args, Debug)]
pub struct PlacementArg {
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
    pub fn search(&self) -> bool {
        self.placement == "search"
    }
}

/// `--refine [--iters N] [--gradients analytic|generator]` of `write` and `evaluate`.
#[derive(clap::Args, Debug)]
pub struct RefineArgs {
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
    pub fn options(&self) -> Result<Option<track_refine::RefineOptions>> {
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
pub fn glyph_input(
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
pub fn prepare_char(input: &GlyphInput, ch: char, method: Option<Method>, quiet: bool) -> Result<Prepared> {
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
pub fn sheet_advice(e: SheetError, spec: &str, margin_mm: f64) -> anyhow::Error {
    let flag = match &e {
        SheetError::NoRoom { .. } => format!("--margin-mm {margin_mm}"),
        SheetError::DoesNotFit { char_mm, .. } => format!("--char-mm {char_mm}"),
        _ => format!("--sheet {spec}"),
    };
    anyhow::Error::new(e).context(flag)
}

/// The smallest character box a flag may ask for, mm.
pub const MIN_CHAR_MM: f64 = 1.0;
/// The largest character box a flag may ask for, mm (a metre: beyond any robot's reach).
pub const MAX_CHAR_MM: f64 = 1000.0;
