//! A sheet of paper and the characters laid out on it: paper sizes (`A4`, `WxH`, `paper.json`),
//! margins, columns right to left or rows left to right, the character size from the paper and
//! the count, and the sheet-level `track.json` (see docs/sheet.md).

use std::path::Path;

use bezier_raster::{Coverage, ModelKind};
use brush_model::{BrushProfile, Extrapolation, Stroke, Track};
use serde::{Deserialize, Serialize};
use thiserror::Error;
use trajectory::CharBox;

use crate::{CharReport, CharResult, Mark};

/// Why a sheet could not be understood or laid out. The messages never name a command-line
/// flag: the caller adds the flag or field the value came from.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum SheetError {
    /// A paper.json could not be read.
    #[error("reading the paper file")]
    Paper {
        /// The path given.
        spec: String,
        /// Why.
        #[source]
        source: robot_io::RobotError,
    },
    /// Neither a named size, `WxH` nor a paper.json.
    #[error(
        "expected a paper size (A0–A6, B3–B5, optionally A4L or A4-landscape), WxH in mm (e.g. 180x680) or a paper.json file, not `{spec}`"
    )]
    Unknown {
        /// What was given.
        spec: String,
    },
    /// A side outside the accepted range.
    #[error("the {side} {value_mm} mm is outside 10..={MAX_SHEET_MM} mm")]
    Side {
        /// What was given.
        spec: String,
        /// `width` or `height`.
        side: &'static str,
        /// The side, mm.
        value_mm: f64,
    },
    /// Nothing to lay out.
    #[error("no characters to lay out")]
    NoChars,
    /// The margin leaves no room on the sheet.
    #[error("a margin of {margin_mm} mm leaves no room on the {sheet} sheet ({width_mm}×{height_mm} mm)")]
    NoRoom {
        /// The margin, mm.
        margin_mm: f64,
        /// The sheet's name.
        sheet: String,
        /// Its width, mm.
        width_mm: f64,
        /// Its height, mm.
        height_mm: f64,
    },
    /// The characters do not fit at the asked size.
    #[error(
        "{char_mm} mm characters: {n} in {lines} {} of {per_line} need {need_w_mm:.0}×{need_h_mm:.0} mm; the {sheet} sheet leaves {usable_w_mm:.0}×{usable_h_mm:.0} mm inside a {margin_mm} mm margin (at most {fit_mm:.1} mm per character)",
        if *flow == Flow::Columns { "column(s)" } else { "row(s)" }
    )]
    DoesNotFit {
        /// The asked side, mm.
        char_mm: f64,
        /// Characters.
        n: usize,
        /// Columns (or rows).
        lines: usize,
        /// Characters per line.
        per_line: usize,
        /// Columns or rows.
        flow: Flow,
        /// Needed width, mm.
        need_w_mm: f64,
        /// Needed height, mm.
        need_h_mm: f64,
        /// The sheet's name.
        sheet: String,
        /// Usable width inside the margins, mm.
        usable_w_mm: f64,
        /// Usable height inside the margins, mm.
        usable_h_mm: f64,
        /// The margin, mm.
        margin_mm: f64,
        /// The largest side that fits, mm.
        fit_mm: f64,
    },
    /// The sheet's image would exceed the largest image side.
    #[error(
        "the sheet image would be {width_px}×{height_px} px ({width_mm:.0}×{height_mm:.0} mm at {px_per_mm:.2} px/mm), over the {max_px} px limit of an image side"
    )]
    ImageTooLarge {
        /// Width, px.
        width_px: f64,
        /// Height, px.
        height_px: f64,
        /// Sheet width, mm.
        width_mm: f64,
        /// Sheet height, mm.
        height_mm: f64,
        /// Scale, px per mm.
        px_per_mm: f64,
        /// The limit, px.
        max_px: u32,
    },
}

/// The gap between characters (and between the block and the margins' inside edge is none), as a
/// fraction of the character size.
pub const GAP_FRACTION: f64 = 0.1;

/// The largest sheet side accepted, mm (a 2 m scroll).
pub const MAX_SHEET_MM: f64 = 2000.0;

/// A sheet of paper, mm.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sheet {
    /// How it was named (`A4`, `210x297`, the paper.json path).
    pub name: String,
    /// Width (paper x), mm.
    pub width_mm: f64,
    /// Height (paper y), mm.
    pub height_mm: f64,
}

/// ISO 216 A and B sizes, portrait, mm.
const NAMED: &[(&str, f64, f64)] = &[
    ("A0", 841.0, 1189.0),
    ("A1", 594.0, 841.0),
    ("A2", 420.0, 594.0),
    ("A3", 297.0, 420.0),
    ("A4", 210.0, 297.0),
    ("A5", 148.0, 210.0),
    ("A6", 105.0, 148.0),
    ("B3", 353.0, 500.0),
    ("B4", 250.0, 353.0),
    ("B5", 176.0, 250.0),
];

/// Parses `--sheet`: a named size (`A0`–`A6`, `B3`–`B5`, portrait; add `-landscape` or `L`, e.g.
/// `A4L`), `WxH` in mm (`180x680` for a couplet strip), or a `paper.json` file (its `size_mm`,
/// or the touched points' bounding box).
///
/// # Errors
/// [`SheetError::Unknown`], [`SheetError::Side`] or [`SheetError::Paper`] saying what was
/// expected.
///
/// # Examples
/// ```
/// let a4l = pipeline::parse_sheet("A4L")?;
/// assert_eq!((a4l.width_mm, a4l.height_mm), (297.0, 210.0));
/// # Ok::<(), pipeline::SheetError>(())
/// ```
pub fn parse_sheet(spec: &str) -> Result<Sheet, SheetError> {
    let s = spec.trim();
    if s.to_ascii_lowercase().ends_with(".json") || Path::new(s).is_file() {
        let frame = robot_io::PaperFrame::load(Path::new(s))
            .map_err(|source| SheetError::Paper { spec: s.to_string(), source })?;
        let b = frame.bounds_mm;
        return checked(Sheet { name: s.to_string(), width_mm: b[2] - b[0], height_mm: b[3] - b[1] }, spec);
    }
    let up = s.to_ascii_uppercase();
    let (base, landscape) = if let Some(b) = up.strip_suffix("-LANDSCAPE") {
        (b.to_string(), true)
    } else if up.len() == 3 && up.ends_with('L') {
        (up[..2].to_string(), true)
    } else {
        (up.clone(), false)
    };
    if let Some(&(n, w, h)) = NAMED.iter().find(|(n, ..)| *n == base) {
        let (w, h) = if landscape { (h, w) } else { (w, h) };
        return Ok(Sheet {
            name: if landscape { format!("{n} landscape") } else { n.to_string() },
            width_mm: w,
            height_mm: h,
        });
    }
    if let Some((a, b)) = s.split_once(['x', 'X', '×']) {
        let num = |t: &str| t.trim().trim_end_matches("mm").trim().parse::<f64>().ok();
        if let (Some(w), Some(h)) = (num(a), num(b)) {
            return checked(Sheet { name: s.to_string(), width_mm: w, height_mm: h }, spec);
        }
    }
    Err(SheetError::Unknown { spec: spec.to_string() })
}

fn checked(sheet: Sheet, spec: &str) -> Result<Sheet, SheetError> {
    for (side, value_mm) in [("width", sheet.width_mm), ("height", sheet.height_mm)] {
        if !(value_mm.is_finite() && (10.0..=MAX_SHEET_MM).contains(&value_mm)) {
            return Err(SheetError::Side { spec: spec.to_string(), side, value_mm });
        }
    }
    Ok(sheet)
}

/// How characters are placed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Flow {
    /// Columns top to bottom, the first column on the right (traditional).
    Columns,
    /// Rows left to right, the first row on top.
    Rows,
}

/// The grid drawn under each character in the preview only (never written by the robot).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Grid {
    /// No grid.
    None,
    /// 米字格: the box, its midlines and diagonals.
    Mi,
    /// 田字格: the box and its midlines.
    Tian,
}

impl std::str::FromStr for Grid {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "none" => Ok(Grid::None),
            "mi" | "米" | "米字格" => Ok(Grid::Mi),
            "tian" | "田" | "田字格" => Ok(Grid::Tian),
            _ => Err(format!("`{s}`: expected none, mi (米字格) or tian (田字格)")),
        }
    }
}

/// Characters laid out on a sheet.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    /// The sheet.
    pub sheet: Sheet,
    /// One box per character, in writing order.
    pub boxes: Vec<CharBox>,
    /// The character side, mm.
    pub char_mm: f64,
    /// Characters per column (or row).
    pub per_line: usize,
    /// Columns (or rows).
    pub lines: usize,
    /// The margin kept free on every side, mm.
    pub margin_mm: f64,
}

/// The side of `n_along` boxes with gaps between them, in box sides.
fn span(n: usize) -> f64 {
    n as f64 + (n.saturating_sub(1)) as f64 * GAP_FRACTION
}

/// Lays `n` characters out on `sheet` inside `margin_mm`: columns right to left (or rows left to
/// right) with a gap of [`GAP_FRACTION`] of the box between characters, the block centred in the
/// usable area. The box side is `char_mm` when given (refused when the block does not fit), else
/// the largest that fits, over every characters-per-line count (or the given `per_line`).
///
/// # Errors
/// [`SheetError::NoRoom`] when the margins leave no room, [`SheetError::DoesNotFit`] when the
/// characters do not fit at the asked size, [`SheetError::NoChars`] for `n = 0`.
pub fn layout_on_sheet(
    sheet: &Sheet,
    n: usize,
    flow: Flow,
    per_line: Option<usize>,
    margin_mm: f64,
    char_mm: Option<f64>,
) -> Result<Layout, SheetError> {
    if n == 0 {
        return Err(SheetError::NoChars);
    }
    let (uw, uh) = (sheet.width_mm - 2.0 * margin_mm, sheet.height_mm - 2.0 * margin_mm);
    if !(margin_mm.is_finite() && margin_mm >= 0.0) || uw <= 0.0 || uh <= 0.0 {
        return Err(SheetError::NoRoom {
            margin_mm,
            sheet: sheet.name.clone(),
            width_mm: sheet.width_mm,
            height_mm: sheet.height_mm,
        });
    }
    // Along a line (down a column, or along a row) and across lines.
    let (along, across) = match flow {
        Flow::Columns => (uh, uw),
        Flow::Rows => (uw, uh),
    };
    let size_for = |per: usize| {
        let lines = n.div_ceil(per);
        (along / span(per)).min(across / span(lines))
    };
    let per = match per_line {
        Some(p) => p.clamp(1, n),
        None => match char_mm {
            // The fewest lines that fit the asked size (a column as long as the paper allows).
            Some(c) => (1..=n).rev().find(|&p| size_for(p) >= c - 1e-9).unwrap_or(n),
            None => (1..=n).max_by(|&a, &b| size_for(a).total_cmp(&size_for(b)).then(b.cmp(&a))).unwrap_or(n),
        },
    };
    let lines = n.div_ceil(per);
    let fit = size_for(per);
    let size = match char_mm {
        Some(c) if c > fit + 1e-9 => {
            let (need_along, need_across) = (span(per) * c, span(lines) * c);
            let (w, h) = match flow {
                Flow::Columns => (need_across, need_along),
                Flow::Rows => (need_along, need_across),
            };
            return Err(SheetError::DoesNotFit {
                char_mm: c,
                n,
                lines,
                per_line: per,
                flow,
                need_w_mm: w,
                need_h_mm: h,
                sheet: sheet.name.clone(),
                usable_w_mm: uw,
                usable_h_mm: uh,
                margin_mm,
                fit_mm: fit,
            });
        }
        Some(c) => c,
        None => fit,
    };
    let step = size * (1.0 + GAP_FRACTION);
    let (bw, bh) = match flow {
        Flow::Columns => (span(lines) * size, span(per) * size),
        Flow::Rows => (span(per) * size, span(lines) * size),
    };
    let (x0, y0) = (margin_mm + (uw - bw) / 2.0, margin_mm + (uh - bh) / 2.0);
    let boxes = (0..n)
        .map(|i| {
            let (line, pos) = (i / per, i % per);
            let (x, y) = match flow {
                Flow::Columns => (lines - 1 - line, pos),
                Flow::Rows => (pos, line),
            };
            CharBox { x0_mm: x0 + x as f64 * step, y0_mm: y0 + y as f64 * step, size_mm: size }
        })
        .collect();
    Ok(Layout { sheet: sheet.clone(), boxes, char_mm: size, per_line: per, lines, margin_mm })
}

/// One character of a sheet track: where it sits and which strokes are its own.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SheetChar {
    /// The character.
    pub char: String,
    /// `[x0, y0, size]`, mm.
    pub char_box_mm: [f64; 3],
    /// Its strokes in the sheet's `strokes`: `[first, end)`.
    pub strokes: [usize; 2],
}

/// The sheet-level `track.json`: the whole sheet in paper mm, one stroke after another, each a
/// pen-down path (the program lifts the brush and travels between strokes). `robot check`,
/// `export` and `send` read `brush` and `strokes` (and `char` as the title); the rest is for the
/// preview and for reload rules that need the character boundaries.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SheetTrack {
    /// Title: the text.
    pub char: String,
    /// `"sheet"`.
    pub kind: String,
    /// The sheet.
    pub sheet: Sheet,
    /// `[width, height]`, mm.
    pub sheet_mm: [f64; 2],
    /// Margin, mm.
    pub margin_mm: f64,
    /// Columns or rows.
    pub flow: Flow,
    /// Grid drawn in the preview only.
    pub grid: Grid,
    /// Character side, mm.
    pub char_mm: f64,
    /// A square over the whole sheet (`[0, 0, max(w, h)]`), so `robot render-trace` frames the
    /// sheet as it frames one character.
    pub char_box_mm: [f64; 3],
    /// The characters and their stroke ranges.
    pub chars: Vec<SheetChar>,
    /// For each stroke, the index of its character in `chars`.
    pub stroke_chars: Vec<usize>,
    /// The brush profile.
    pub brush: BrushProfile,
    /// Every stroke of the sheet in writing order: the registration marks' strokes first (see
    /// `mark_strokes`), then the characters'.
    pub strokes: Vec<Stroke>,
    /// The registration marks written first ([`crate::registration_marks`]); empty without.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub marks: Vec<Mark>,
    /// How many of `strokes`, from the first, write the marks (two per mark).
    #[serde(default)]
    pub mark_strokes: usize,
}

impl SheetTrack {
    /// Joins characters' tracks (already placed on the paper) into one sheet track.
    pub fn new(
        layout: &Layout,
        flow: Flow,
        grid: Grid,
        chars: &[(String, CharBox, &[Stroke])],
        brush: &BrushProfile,
    ) -> Self {
        let mut strokes = Vec::new();
        let mut stroke_chars = Vec::new();
        let mut out = Vec::new();
        for (i, (c, b, s)) in chars.iter().enumerate() {
            let first = strokes.len();
            strokes.extend(s.iter().cloned());
            stroke_chars.extend(std::iter::repeat_n(i, s.len()));
            out.push(SheetChar {
                char: c.clone(),
                char_box_mm: [b.x0_mm, b.y0_mm, b.size_mm],
                strokes: [first, strokes.len()],
            });
        }
        let (w, h) = (layout.sheet.width_mm, layout.sheet.height_mm);
        SheetTrack {
            char: chars.iter().map(|c| c.0.as_str()).collect(),
            kind: "sheet".into(),
            sheet: layout.sheet.clone(),
            sheet_mm: [w, h],
            margin_mm: layout.margin_mm,
            flow,
            grid,
            char_mm: layout.char_mm,
            char_box_mm: [0.0, 0.0, w.max(h)],
            chars: out,
            stroke_chars,
            brush: brush.clone(),
            strokes,
            marks: Vec::new(),
            mark_strokes: 0,
        }
    }

    /// The same sheet with `marks` written first: their strokes ([`crate::mark_strokes`]) go
    /// before the characters' (counted as the first character's in `stroke_chars`, so a reload
    /// rule per character treats them as part of it) and every character's stroke range moves
    /// on by their count.
    pub fn with_marks(mut self, marks: &[Mark], brush: &BrushProfile) -> Self {
        let strokes = crate::mark_strokes(marks, brush);
        let n = strokes.len();
        for c in &mut self.chars {
            c.strokes = [c.strokes[0] + n, c.strokes[1] + n];
        }
        let mut sc = vec![0; n];
        sc.append(&mut self.stroke_chars);
        self.stroke_chars = sc;
        let mut all = strokes;
        all.append(&mut self.strokes);
        self.strokes = all;
        self.marks.extend_from_slice(marks);
        self.mark_strokes += n;
        self
    }
}

/// The layout without a sheet: `n` boxes of side `char_mm`, `per_line` to a column (or row), a
/// gap of [`GAP_FRACTION`] of the box around and between them, on an `automatic` sheet just
/// large enough for them.
pub fn auto_layout(n: usize, char_mm: f64, per_line: usize, flow: Flow) -> Layout {
    let per = per_line.clamp(1, n.max(1));
    let gap = GAP_FRACTION * char_mm;
    let step = char_mm + gap;
    let lines = n.div_ceil(per);
    let boxes: Vec<CharBox> = (0..n)
        .map(|i| {
            let (line, pos) = (i / per, i % per);
            let (x, y) = match flow {
                Flow::Rows => (pos, line),
                Flow::Columns => (lines - 1 - line, pos),
            };
            CharBox { x0_mm: gap + x as f64 * step, y0_mm: gap + y as f64 * step, size_mm: char_mm }
        })
        .collect();
    let w = boxes.iter().map(|b| b.x0_mm + b.size_mm).fold(0.0, f64::max) + gap;
    let h = boxes.iter().map(|b| b.y0_mm + b.size_mm).fold(0.0, f64::max) + gap;
    Layout {
        sheet: Sheet { name: "automatic".into(), width_mm: w, height_mm: h },
        boxes,
        char_mm,
        per_line: per,
        lines,
        margin_mm: gap,
    }
}

impl Layout {
    /// The same layout with at least `margin_mm` free around its boxes: the sheet grows and the
    /// boxes move in by the difference (room for registration marks on an automatic layout).
    pub fn widened(&self, margin_mm: f64) -> Layout {
        let d = (margin_mm - self.margin_mm).max(0.0);
        let mut l = self.clone();
        for b in &mut l.boxes {
            b.x0_mm += d;
            b.y0_mm += d;
        }
        l.sheet.width_mm += 2.0 * d;
        l.sheet.height_mm += 2.0 * d;
        l.margin_mm += d;
        l
    }

    /// The sheet image's size in px when each character's image is `size_px` wide.
    pub fn image_px(&self, size_px: u32) -> (f64, f64) {
        let ppm = size_px as f64 / self.char_mm;
        ((self.sheet.width_mm * ppm).ceil(), (self.sheet.height_mm * ppm).ceil())
    }

    /// Refuses a layout whose sheet image ([`sheet_image`]) at `size_px` per character would
    /// exceed the largest image side ([`bezier_raster::MAX_SIDE`]); the size in px
    /// does not depend on the box side in mm, so this can run before the glyphs are known.
    ///
    /// # Errors
    /// [`SheetError::ImageTooLarge`].
    pub fn check_image_size(&self, size_px: u32) -> Result<(), SheetError> {
        let (width_px, height_px) = self.image_px(size_px);
        let max_px = bezier_raster::MAX_SIDE;
        if width_px > max_px as f64 || height_px > max_px as f64 {
            return Err(SheetError::ImageTooLarge {
                width_px,
                height_px,
                width_mm: self.sheet.width_mm,
                height_mm: self.sheet.height_mm,
                px_per_mm: size_px as f64 / self.char_mm,
                max_px,
            });
        }
        Ok(())
    }
}

/// Every written character's track on one image of the whole sheet, at the scale of the
/// characters' own images (`size_px` per char box side), the footprints through the forward
/// model with `profile`'s hairs.
///
/// # Errors
/// When the profile refuses a press (it accepted them when the characters were written).
pub fn sheet_image(
    results: &[CharResult],
    profile: &BrushProfile,
    model: ModelKind,
    layout: &Layout,
    size_px: u32,
) -> Result<Coverage, brush_model::ProfileError> {
    let tracks: Vec<&Track> = results.iter().map(|r| &r.track).collect();
    sheet_image_of(&tracks, profile, model, layout, size_px)
}

/// As [`sheet_image`] from the characters' tracks alone.
///
/// # Errors
/// When the profile refuses a press.
pub fn sheet_image_of(
    tracks: &[&Track],
    profile: &BrushProfile,
    model: ModelKind,
    layout: &Layout,
    size_px: u32,
) -> Result<Coverage, brush_model::ProfileError> {
    let mut all = Track::default();
    for t in tracks {
        all.strokes.extend(t.strokes.iter().cloned());
    }
    let px_per_mm = size_px as f64 / layout.char_mm;
    let (wp, hp) = layout.image_px(size_px);
    let stamps = bezier_raster::track_stamps(&all, profile, Extrapolation::Refuse)?;
    Ok(bezier_raster::render_stamps(
        &stamps,
        model.model(),
        brush_model::PointMm::new(0.0, 0.0),
        px_per_mm,
        wp as u32,
        hp as u32,
    ))
}

/// `sheet.png`: every character's track ([`sheet_image_of`]) and the registration marks the
/// robot writes before them (`marks`: the first strokes of the sheet's track, as the preview and
/// the exports show them), at the characters' image scale (`size_px` per char box). The marks
/// lie in the margin, apart from the characters; their ink is joined to the characters' as a
/// union.
///
/// # Errors
/// When the profile refuses a press of a character or of a mark.
pub fn sheet_image_with_marks(
    tracks: &[&Track],
    marks: &[brush_model::Stroke],
    profile: &BrushProfile,
    model: ModelKind,
    layout: &Layout,
    size_px: u32,
) -> Result<Coverage, brush_model::ProfileError> {
    let mut img = sheet_image_of(tracks, profile, model, layout, size_px)?;
    if marks.is_empty() {
        return Ok(img);
    }
    let marks = Track { strokes: marks.to_vec() };
    let (wp, hp) = layout.image_px(size_px);
    let stamps = bezier_raster::track_stamps(&marks, profile, Extrapolation::Refuse)?;
    let m = bezier_raster::render_stamps(
        &stamps,
        model.model(),
        brush_model::PointMm::new(0.0, 0.0),
        size_px as f64 / layout.char_mm,
        wp as u32,
        hp as u32,
    );
    for (a, &b) in img.data_mut().iter_mut().zip(m.data()) {
        *a = 1.0 - (1.0 - *a) * (1.0 - b);
    }
    Ok(img)
}

/// Share of track points beyond one end of the brush's width range above which
/// [`BrushFit::of`] says the brush does not suit the size. At the automatic size about a fifth
/// of the points lie beyond each end by construction (it maps the 20th–80th percentile widths
/// onto the range), so only clearly more is worth a word. Hand-set, not tuned.
pub const BRUSH_FIT_CLAMPED_SHARE: f64 = 0.25;

/// How far (as a factor) the char box may be from the size that suits the brush before
/// [`BrushFit::of`] says the brush does not suit it. Hand-set, not tuned.
pub const BRUSH_FIT_SIZE_FACTOR: f64 = 1.15;

/// Whether the brush's width range covers the glyphs at the chosen size, as `summary.json`
/// reports it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BrushFit {
    /// The char box side that suits the brush ([`trajectory::auto_char_mm`] of all glyphs), mm.
    pub brush_char_mm: f64,
    /// The chosen char box side, mm.
    pub char_mm: f64,
    /// Track points written.
    pub points: usize,
    /// Points whose glyph width was below what the brush can make.
    pub clamped_thin: usize,
    /// Points whose glyph width was above what the brush can make.
    pub clamped_wide: usize,
    /// Whether the brush suits the size.
    pub covered: bool,
    /// The verdict in one sentence.
    pub note: String,
    /// Which way the brush misses, if it does.
    #[serde(skip)]
    pub miss: Option<BrushMiss>,
}

/// Which way a brush misses the glyphs' widths ([`BrushFit::miss`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BrushMiss {
    /// The strokes are thinner than the brush can make: larger characters or a smaller brush.
    TooWide,
    /// The strokes are wider than the brush can make: smaller characters or a larger brush.
    TooNarrow,
}

impl BrushFit {
    /// The verdict for characters written at `char_mm` whose widths suit `brush_char_mm`
    /// ([`BRUSH_FIT_CLAMPED_SHARE`], [`BRUSH_FIT_SIZE_FACTOR`]).
    pub fn of(reports: &[&CharReport], char_mm: f64, brush_char_mm: f64) -> Self {
        let points: usize = reports.iter().map(|r| r.plan.points).sum();
        let (low, high): (usize, usize) =
            reports.iter().fold((0, 0), |(l, h), r| (l + r.brush.clamped_low_points, h + r.brush.clamped_high_points));
        let share = |n: usize| if points == 0 { 0.0 } else { n as f64 / points as f64 };
        let (k, f) = (BRUSH_FIT_CLAMPED_SHARE, BRUSH_FIT_SIZE_FACTOR);
        let (miss, note) = if share(low) > k || char_mm < brush_char_mm / f {
            (
                Some(BrushMiss::TooWide),
                format!(
                    "at {char_mm:.1} mm the glyphs' strokes are thinner than the brush can make at {:.0}% of the points (its width range suits about {brush_char_mm:.0} mm characters)",
                    100.0 * share(low)
                ),
            )
        } else if share(high) > k || char_mm > brush_char_mm * f {
            (
                Some(BrushMiss::TooNarrow),
                format!(
                    "at {char_mm:.1} mm the glyphs' strokes are wider than the brush can make at {:.0}% of the points (its width range suits about {brush_char_mm:.0} mm characters)",
                    100.0 * share(high)
                ),
            )
        } else {
            (None, "the brush's width range covers the glyphs at this size".into())
        };
        BrushFit {
            brush_char_mm,
            char_mm,
            points,
            clamped_thin: low,
            clamped_wide: high,
            covered: miss.is_none(),
            note,
            miss,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn named_and_custom_sizes() {
        let a4 = parse_sheet("A4").unwrap();
        assert_eq!((a4.width_mm, a4.height_mm), (210.0, 297.0));
        let l = parse_sheet("a4l").unwrap();
        assert_eq!((l.width_mm, l.height_mm), (297.0, 210.0));
        let c = parse_sheet("180x680").unwrap();
        assert_eq!((c.width_mm, c.height_mm), (180.0, 680.0));
        for bad in ["A9", "x", "0x100", "100x1e9", "-5x10"] {
            let e = parse_sheet(bad).unwrap_err();
            assert!(matches!(e, SheetError::Unknown { .. } | SheetError::Side { .. }), "{bad}: {e}");
            assert!(e.to_string().contains("expected") || e.to_string().contains("outside"), "{bad}: {e}");
        }
    }

    #[test]
    fn four_characters_fill_an_a4_sheet_in_columns_right_to_left() {
        let a4 = parse_sheet("A4").unwrap();
        let l = layout_on_sheet(&a4, 4, Flow::Columns, None, 15.0, None).unwrap();
        // Two columns of two on portrait A4: the width limits (180 mm for 2.1 boxes).
        assert_eq!((l.per_line, l.lines), (2, 2));
        assert!((l.char_mm - 180.0 / 2.1).abs() < 1e-9, "{}", l.char_mm);
        // The first column is on the right; everything inside the margins.
        assert!(l.boxes[0].x0_mm > l.boxes[2].x0_mm);
        assert!(l.boxes[1].y0_mm > l.boxes[0].y0_mm);
        for b in &l.boxes {
            assert!(b.x0_mm >= 15.0 - 1e-9 && b.x0_mm + b.size_mm <= 195.0 + 1e-9);
            assert!(b.y0_mm >= 15.0 - 1e-9 && b.y0_mm + b.size_mm <= 282.0 + 1e-9);
        }
        // A couplet: one column of seven.
        let strip = parse_sheet("180x680").unwrap();
        let c = layout_on_sheet(&strip, 7, Flow::Columns, None, 10.0, None).unwrap();
        assert_eq!(c.lines, 1);
        // An asked size that does not fit is refused with the numbers.
        let e = layout_on_sheet(&a4, 4, Flow::Columns, None, 15.0, Some(130.0)).unwrap_err();
        assert!(matches!(e, SheetError::DoesNotFit { fit_mm, per_line: 4, .. } if fit_mm < 130.0), "{e}");
        let e = e.to_string();
        assert!(e.contains("130 mm characters") && e.contains("A4"), "{e}");
        let ok = layout_on_sheet(&a4, 4, Flow::Rows, None, 15.0, Some(40.0)).unwrap();
        assert_eq!(ok.char_mm, 40.0);
        assert_eq!(ok.lines, 1);
    }
}
