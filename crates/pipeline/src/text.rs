//! Several characters written together: one box size, laid out on a sheet or automatically.

use brush_model::BrushProfile;
use rayon::prelude::*;
use trajectory::Method;

use crate::sheet::{Flow, Layout, auto_layout};
use crate::{CharResult, Prepared, Result, WriteOptions, searched_placement, searched_splits, write_char};

/// How [`write_text`] sizes and lays out its characters.
#[derive(Clone, Debug, PartialEq)]
pub struct TextOptions {
    /// The layout on a sheet, planned beforehand ([`crate::layout_on_sheet`]); `None`: an
    /// automatic layout ([`auto_layout`]) at `char_mm`.
    pub layout: Option<Layout>,
    /// The char box side without a sheet layout, mm; `None`: the size that suits the brush for
    /// all the glyphs together ([`trajectory::auto_char_mm`]), or the searched size for a
    /// single template character.
    pub char_mm: Option<f64>,
    /// Characters per column (or row) of the automatic layout.
    pub per_line: usize,
    /// Columns right to left, or rows left to right.
    pub flow: Flow,
    /// Whether template tracks ([`Method::Template`]) are placed by search: a single character
    /// without a given size searches its box size and corner splits ([`searched_placement`]),
    /// characters sharing a box size search their splits ([`searched_splits`]). Other methods
    /// are not affected.
    pub search_templates: bool,
    /// With an automatic layout (no `layout`), the margin it is widened to
    /// ([`Layout::widened`]), mm: room for registration marks ([`crate::tuning::MARK_MARGIN_MM`]).
    pub mark_margin_mm: Option<f64>,
}

impl Default for TextOptions {
    fn default() -> Self {
        Self {
            layout: None,
            char_mm: None,
            per_line: 4,
            flow: Flow::Columns,
            search_templates: true,
            mark_margin_mm: None,
        }
    }
}

/// What [`write_text`] wrote.
pub struct WrittenText {
    /// Where the characters sit.
    pub layout: Layout,
    /// One result per character, in writing order.
    pub results: Vec<CharResult>,
    /// The char box side that suits the brush for all the glyphs together, mm (for
    /// [`crate::BrushFit`]).
    pub brush_char_mm: f64,
}

/// Writes prepared characters in one box size ([`write_char`] each, in parallel), laid out by
/// `text`; `on_char` is called as each character is done (for progress).
///
/// # Errors
/// The first character's error, as [`write_char`] and [`searched_placement`] give it.
///
/// # Examples
/// ```
/// use pipeline::{TextOptions, WriteOptions, prepare, write_text};
/// let pen1 = brush_model::BrushProfile::builtin("pen1")?;
/// let chars = ['十', '口'].map(|c| prepare(trajectory::embedded_glyph(c).unwrap(), None).unwrap());
/// let opts = WriteOptions { size: 64, free_widths: false, execute: false, ..WriteOptions::default() };
/// let w = write_text(chars.to_vec(), &pen1, &opts, &TextOptions::default(), &|| {})?;
/// assert_eq!(w.results.len(), 2);
/// assert_eq!(w.layout.boxes[0].size_mm, w.layout.boxes[1].size_mm);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_text(
    prepared: Vec<Prepared>,
    profile: &BrushProfile,
    opts: &WriteOptions,
    text: &TextOptions,
    on_char: &(dyn Fn() + Sync),
) -> Result<WrittenText> {
    let (layout, results, brush_char_mm) = write_text_each(prepared, profile, opts, text, &|_, r| {
        on_char();
        Ok::<_, crate::Error>(r)
    })?;
    Ok(WrittenText { layout, results, brush_char_mm })
}

/// As [`write_text`], but each character's result goes to `each` (with its index) as soon as it
/// is written, and only what `each` returns is kept: a caller that writes a character's files
/// and keeps its report and track writes a long text in bounded memory (the results of the
/// characters in flight, one per thread, and what `each` keeps). Returns the layout, what
/// `each` returned in writing order, and the box side that suits the brush.
///
/// # Errors
/// As [`write_text`] (converted into `E`), and the first error `each` returns.
///
/// # Examples
/// ```
/// use pipeline::{TextOptions, WriteOptions, prepare, write_text_each};
/// let pen1 = brush_model::BrushProfile::builtin("pen1")?;
/// let chars = ['十', '口'].map(|c| prepare(trajectory::embedded_glyph(c).unwrap(), None).unwrap());
/// let opts = WriteOptions { size: 64, free_widths: false, execute: false, ..WriteOptions::default() };
/// // Keep only each character's plan CSIM (a caller would write its images here).
/// let (layout, csim, _) =
///     write_text_each(chars.to_vec(), &pen1, &opts, &TextOptions::default(), &|_, r| {
///         Ok::<_, pipeline::Error>(r.report.plan.csim)
///     })?;
/// assert_eq!((layout.boxes.len(), csim.len()), (2, 2));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_text_each<T: Send, E: From<crate::Error> + Send>(
    prepared: Vec<Prepared>,
    profile: &BrushProfile,
    opts: &WriteOptions,
    text: &TextOptions,
    each: &(dyn Fn(usize, CharResult) -> Result<T, E> + Sync),
) -> Result<(Layout, Vec<T>, f64), E> {
    let all: Vec<_> = prepared.iter().flat_map(|p| p.paths.iter().cloned()).collect();
    let brush_char_mm = trajectory::auto_char_mm(&all, profile, opts.alpha_rad);
    let search = |p: &Prepared| text.search_templates && p.method == Method::Template;
    // One template character on its own: its box size is searched too.
    let single_searched = match (&prepared[..], &text.layout, text.char_mm) {
        ([p], None, None) if search(p) => Some(searched_placement(p, profile, opts).map_err(E::from)?),
        _ => None,
    };
    let layout = match &text.layout {
        Some(l) => l.clone(),
        None => auto_layout(
            prepared.len(),
            text.char_mm.or(single_searched.as_ref().map(|pl| pl.size_mm)).unwrap_or(brush_char_mm),
            text.per_line,
            text.flow,
        ),
    };
    let layout = match (&text.layout, text.mark_margin_mm) {
        (None, Some(m)) => layout.widened(m),
        _ => layout,
    };
    let char_mm = layout.char_mm;
    // Template characters sharing the box size: their corner splits are searched.
    let prepared: Vec<Prepared> = prepared
        .into_par_iter()
        .map(|p| match &single_searched {
            Some(pl) => Ok(p.placed(pl)),
            None if search(&p) => Ok(p.placed(&searched_splits(&p, profile, opts, char_mm)?)),
            None => Ok(p),
        })
        .collect::<Result<_>>()
        .map_err(E::from)?;
    // Each glyph is dropped once its character is written.
    let kept: Vec<T> = prepared
        .into_par_iter()
        .zip(layout.boxes.clone().into_par_iter())
        .enumerate()
        .map(|(i, (p, b))| each(i, write_char(&p, profile, b, opts).map_err(E::from)?))
        .collect::<Result<_, E>>()?;
    Ok((layout, kept, brush_char_mm))
}
