//! A glyph and its centre lines: the first step of the pipeline.

use serde::Serialize;
use trajectory::{Glyph, Method, Registration, StrokeFit, StrokePath, centre_lines, centre_lines_from_template};

use crate::{Error, Result};

/// Analysis raster for widths and skeletons, px per em box.
pub const ANALYSIS_PX: u32 = trajectory::DEFAULT_ANALYSIS_PX;

/// A glyph with its centre lines, ready to be placed.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// The glyph.
    pub glyph: Glyph,
    /// The method used.
    pub method: Method,
    /// Its centre lines with half-widths.
    pub paths: Vec<StrokePath>,
    /// What registration found when the centre lines came from a stroke template registered
    /// onto a font or image glyph ([`prepare_with_template`]); `None` otherwise.
    pub template: Option<TemplateReport>,
}

/// Finds the centre lines of a glyph with `method` (`None`: the source's medians when it has
/// them, otherwise a skeleton).
///
/// # Errors
/// [`Error::CentreLines`] when the method cannot be used on this source or the glyph is blank.
///
/// # Examples
/// ```
/// let p = pipeline::prepare(trajectory::embedded_glyph('十')?, None)?;
/// assert_eq!(p.paths.len(), 2);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn prepare(glyph: Glyph, method: Option<Method>) -> Result<Prepared> {
    prepare_with_template(glyph, method, None)
}

/// Finds the centre lines of a glyph, registering `template` (a glyph of the same character
/// with stroke medians: embedded or from a hanzi-writer-data folder) onto it for
/// [`Method::Template`]. `method: None` picks the source's own medians when it has them, else
/// the template when one is given, else a skeleton.
///
/// # Errors
/// [`Error::NoTemplate`] for [`Method::Template`] on a glyph without medians and no
/// `template`; [`Error::CentreLines`] for a method that cannot be used on this source or a
/// blank glyph.
pub fn prepare_with_template(glyph: Glyph, method: Option<Method>, template: Option<&Glyph>) -> Result<Prepared> {
    let own_medians = glyph.medians.is_some();
    let method = method.unwrap_or(if own_medians {
        Method::Medians
    } else if template.is_some() {
        Method::Template
    } else {
        Method::Skeleton
    });
    let ch = glyph.ch;
    if method == Method::Template && !own_medians {
        let t = template.ok_or(Error::NoTemplate(ch))?;
        let reg =
            centre_lines_from_template(t, &glyph, ANALYSIS_PX).map_err(|source| Error::CentreLines { ch, source })?;
        let template = Some(TemplateReport::of(&reg));
        return Ok(Prepared { glyph, method, paths: reg.paths, template });
    }
    let paths = centre_lines(&glyph, method, ANALYSIS_PX).map_err(|source| Error::CentreLines { ch, source })?;
    Ok(Prepared { glyph, method, paths, template: None })
}

/// What template registration found for one character, as `report.json` shows it.
#[derive(Clone, Debug, Serialize)]
pub struct TemplateReport {
    /// Strokes of the template (the strokes expected).
    pub strokes: usize,
    /// Strokes (from 1, in writing order) that found no ink under them: kept where the
    /// template put them, not snapped.
    pub missing: Vec<usize>,
    /// Pairs of strokes (from 1) that landed on one target stroke.
    pub doubled: Vec<[usize; 2]>,
    /// Whether every stroke found its own ink (the stroke count holds on the target).
    pub strokes_ok: bool,
    /// Share (0..1) of the target's ink that no registered stroke explains: a stroke the
    /// template lacks, or another form of the character.
    pub uncovered_ink: f64,
    /// Per stroke, in writing order.
    pub fits: Vec<StrokeFit>,
}

impl TemplateReport {
    /// The report of a registration.
    pub fn of(r: &Registration) -> Self {
        Self {
            strokes: r.strokes.len(),
            missing: r.missing().into_iter().map(|i| i + 1).collect(),
            doubled: r.strokes.iter().enumerate().filter_map(|(i, s)| s.doubled_with.map(|j| [i + 1, j + 1])).collect(),
            strokes_ok: r.strokes_ok(),
            uncovered_ink: r.uncovered_ink,
            fits: r.strokes.clone(),
        }
    }
}
