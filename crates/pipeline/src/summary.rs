//! `summary.json`: what a written text says as a whole (docs/outputs.md).

use serde::Serialize;

use crate::{BrushChoice, BrushFit, CharReport, Flow, Layout, ReportMeans, SimilarityMeans};

/// A written text's `summary.json` (docs/outputs.md): the text, the sheet, the means, whether
/// the brush suits the size, and every character's report.
///
/// # Examples
/// ```no_run
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use pipeline::{Flow, TextOptions, TextSummary, WriteOptions, prepare, write_text};
/// use trajectory::embedded_glyph;
/// let pen1 = brush_model::BrushProfile::builtin("pen1")?;
/// let prepared = vec![prepare(embedded_glyph('十')?, None)?, prepare(embedded_glyph('口')?, None)?];
/// let text = TextOptions::default();
/// let w = write_text(prepared, &pen1, &WriteOptions::default(), &text, &|| {})?;
/// let reports: Vec<_> = w.results.iter().map(|r| &r.report).collect();
/// let s = TextSummary::new(&reports, &w.layout, Flow::Columns, &pen1.name, "bsm", w.brush_char_mm);
/// println!("{}", serde_json::to_string_pretty(&s)?);
/// # Ok(())
/// # }
/// ```
#[derive(Clone, Debug, Serialize)]
pub struct TextSummary<'a> {
    /// The characters, in order.
    pub text: String,
    /// The char box side, mm.
    pub char_mm: f64,
    /// The brush's name.
    pub brush: &'a str,
    /// The stroke model's name.
    pub model: &'a str,
    /// The plans against their glyphs, means over every character.
    pub plan_mean: Figures,
    /// What the robot would write against the glyph: means over every character, `null`
    /// figures unless every character was executed.
    pub executed_mean: Figures<Option<f64>>,
    /// The plan against the executed render, as `executed_mean`.
    pub agreement_mean: Agreement,
    /// The sheet and how the characters are laid out on it.
    pub sheet: SheetSummary<'a>,
    /// Whether the brush's width range covers the glyphs at this size.
    pub brush_fit: BrushFit,
    /// `--brush auto`'s choice (`null` when the brush was named).
    pub brush_choice: Option<&'a BrushChoice>,
    /// Every character's report.
    pub chars: Vec<&'a CharReport>,
}

/// Mean CSIM, SSIM and IoU.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Figures<T = f64> {
    /// Cosine similarity.
    pub csim: T,
    /// Structural similarity.
    pub ssim: T,
    /// Intersection over union.
    pub iou: T,
}

/// The plan's mean CSIM against the executed render (`None` unless every character was
/// executed).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Agreement {
    /// Cosine similarity.
    pub csim: Option<f64>,
}

/// The sheet of a [`TextSummary`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SheetSummary<'a> {
    /// Its name (`A4`, `180x680`, …).
    pub name: &'a str,
    /// Width and height, mm.
    pub size_mm: [f64; 2],
    /// The margin kept free on every side, mm.
    pub margin_mm: f64,
    /// Columns right to left, or rows.
    pub flow: Flow,
    /// Characters per column (or row).
    pub per_line: usize,
    /// Columns (or rows).
    pub lines: usize,
}

impl<'a> TextSummary<'a> {
    /// The summary of `reports` written on `layout` in `flow` with the brush `brush` and the
    /// stroke model `model`; `brush_char_mm` is the box side the brush suits
    /// ([`crate::WrittenText::brush_char_mm`]). [`TextSummary::brush_choice`] starts `None`.
    ///
    /// # Panics
    /// When `reports` is empty.
    pub fn new(
        reports: &[&'a CharReport],
        layout: &'a Layout,
        flow: Flow,
        brush: &'a str,
        model: &'a str,
        brush_char_mm: f64,
    ) -> Self {
        let m = ReportMeans::of(reports.iter().copied());
        // Executed figures are means over every character (null unless all were executed).
        let all = |s: Option<SimilarityMeans>| s.filter(|s| s.count == m.count);
        let (ex, ag) = (all(m.executed), all(m.agreement));
        let sheet = &layout.sheet;
        TextSummary {
            text: reports.iter().map(|r| r.char.as_str()).collect(),
            char_mm: layout.char_mm,
            brush,
            model,
            plan_mean: Figures { csim: m.plan.csim, ssim: m.plan.ssim, iou: m.plan.iou },
            executed_mean: Figures { csim: ex.map(|s| s.csim), ssim: ex.map(|s| s.ssim), iou: ex.map(|s| s.iou) },
            agreement_mean: Agreement { csim: ag.map(|s| s.csim) },
            sheet: SheetSummary {
                name: &sheet.name,
                size_mm: [sheet.width_mm, sheet.height_mm],
                margin_mm: layout.margin_mm,
                flow,
                per_line: layout.per_line,
                lines: layout.lines,
            },
            brush_fit: BrushFit::of(reports, layout.char_mm, brush_char_mm),
            brush_choice: None,
            chars: reports.to_vec(),
        }
    }
}
