//! Where a character goes: its char box side (from its widths, fixed, or searched) and, for
//! template tracks, which strokes keep their corners split.

use bezier_raster::Coverage;
use brush_model::{BrushProfile, Extrapolation, Track};
use robot_io::{RobotConfig, build_program};
use trajectory::{CharBox, Sizing, StrokePath, TrackOptions, build_track, render_glyph};

use crate::write::{level_frame_for, render_char};
use crate::{CharResult, Prepared, Result, WriteOptions, write_char};

/// How [`write_placed`] sizes a character's box.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum BoxRule {
    /// From the glyph's stroke widths and the brush ([`trajectory::auto_char_mm`]).
    #[default]
    Auto,
    /// A given side, mm.
    Fixed(f64),
    /// [`searched_placement`]: the best of a few sizes and corner splits by the plan's CSIM;
    /// with a side given, only the splits are searched ([`searched_splits`]).
    Search(Option<f64>),
}

/// Places a prepared character by `rule` in a char box at the paper's origin and writes it
/// ([`write_char`]): what `maobi evaluate`, the gates and the style tables run per character.
///
/// # Errors
/// As [`write_char`] and [`searched_placement`].
///
/// # Examples
/// ```
/// use pipeline::{BoxRule, WriteOptions, prepare, write_placed};
/// let pen1 = brush_model::BrushProfile::builtin("pen1")?;
/// let p = prepare(trajectory::embedded_glyph('十')?, None)?;
/// let opts = WriteOptions { size: 64, free_widths: false, execute: false, ..WriteOptions::default() };
/// let r = write_placed(&p, &pen1, &opts, BoxRule::Auto)?;
/// assert!(r.report.plan.csim > 0.5, "{}", r.report.plan.csim);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_placed(p: &Prepared, profile: &BrushProfile, opts: &WriteOptions, rule: BoxRule) -> Result<CharResult> {
    let at = |size_mm| CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm };
    match rule {
        BoxRule::Auto => write_char(p, profile, at(trajectory::auto_char_mm(&p.paths, profile, opts.alpha_rad)), opts),
        BoxRule::Fixed(mm) => write_char(p, profile, at(mm), opts),
        BoxRule::Search(size) => {
            let pl = match size {
                Some(mm) => searched_splits(p, profile, opts, mm)?,
                None => searched_placement(p, profile, opts)?,
            };
            write_char(&p.placed(&pl), profile, at(pl.size_mm), opts)
        }
    }
}

/// The char box sizes [`searched_placement`] tries, as multiples of the automatic size
/// ([`trajectory::auto_char_mm`]), the automatic one first (it wins ties). Chosen on tuning
/// fonts only; the measurements are in docs/trajectory.md, "Template registration".
pub const CHAR_BOX_SEARCH_SCALES: [f64; 6] = [1.0, 0.8, 0.9, 1.1, 1.2, 1.35];

/// Side (px) of the plan renders [`searched_placement`] compares. Hand-set (half the scoring
/// raster, for time).
pub const CHAR_BOX_SEARCH_PX: u32 = 256;

/// What [`searched_placement`] chose for one character.
#[derive(Clone, Debug, PartialEq)]
pub struct Placement {
    /// Char box side, mm.
    pub size_mm: f64,
    /// Per stroke (in the paths' order): whether it keeps its pieces split at its corners
    /// (false: written in one piece, see [`with_splits`]).
    pub split: Vec<bool>,
}

/// The centre lines with the corners of the strokes whose `split` is false removed:
/// [`trajectory::build_track`] then writes such a stroke in one piece, without lifting at its
/// 折 (the knob the line runs out to stays in the line). A stroke past the end of `split` keeps
/// its corners.
pub fn with_splits(paths: &[StrokePath], split: &[bool]) -> Vec<StrokePath> {
    paths
        .iter()
        .enumerate()
        .map(|(i, p)| {
            if split.get(i).copied().unwrap_or(true) {
                p.clone()
            } else {
                StrokePath { corners: Vec::new(), ..p.clone() }
            }
        })
        .collect()
}

/// The char box side and the corner splits for one character chosen by trying. First the plan
/// (brush sizing, as [`write_char`] builds it with `opts`' tilt, spacing and stroke model) is
/// built and rendered at each of [`CHAR_BOX_SEARCH_SCALES`] times the automatic size, with
/// every stroke split at its corners and with every stroke in one piece, and the choice whose
/// render is most like the glyph (CSIM at [`CHAR_BOX_SEARCH_PX`]²) is taken; then, at that
/// size, each stroke with corners in turn is tried the other way and kept so when the CSIM
/// rises (one greedy pass). Why both knobs matter is in docs/trajectory.md, "Template
/// registration". Ties keep the automatic size with split corners; the result's program
/// passes `robot check` (otherwise the best whole-character choice that does, or the
/// automatic one: the caller's own check then reports why). Costs twelve plan renders plus one
/// per stroke with corners.
///
/// # Errors
/// When the profile refuses a track or the images cannot be scored.
pub fn searched_placement(p: &Prepared, profile: &BrushProfile, opts: &WriteOptions) -> Result<Placement> {
    let auto = trajectory::auto_char_mm(&p.paths, profile, opts.alpha_rad);
    let sizes: Vec<f64> = CHAR_BOX_SEARCH_SCALES.iter().map(|s| auto * s).collect();
    search_placement(p, profile, opts, &sizes)
}

/// The corner splits for one character at a given char box side (mm), chosen as in
/// [`searched_placement`] with the size fixed (two plans, every stroke split or every stroke
/// in one piece, then the greedy pass per stroke): what `maobi write` uses where several
/// characters share one box size on a sheet.
///
/// # Errors
/// When the profile refuses a track or the images cannot be scored.
pub fn searched_splits(p: &Prepared, profile: &BrushProfile, opts: &WriteOptions, size_mm: f64) -> Result<Placement> {
    search_placement(p, profile, opts, &[size_mm])
}

/// The search of [`searched_placement`] over the char box sides `sizes_mm` (the first wins
/// ties, and is returned with split corners when no candidate passes `robot check`).
fn search_placement(p: &Prepared, profile: &BrushProfile, opts: &WriteOptions, sizes_mm: &[f64]) -> Result<Placement> {
    let reference = render_glyph(&p.glyph, CHAR_BOX_SEARCH_PX);
    let n = p.paths.len();
    let plan = |size_mm: f64, split: &[bool]| plan_score(p, &reference, profile, opts, size_mm, split);
    let passes = |size_mm: f64, track: &Track| {
        let b = CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm };
        build_program(track, profile, &level_frame_for(&b), &RobotConfig::default()).is_ok()
    };
    let mut tried: Vec<(f64, Placement, Track)> = Vec::with_capacity(2 * sizes_mm.len());
    for whole in [true, false] {
        for &size_mm in sizes_mm {
            let pl = Placement { size_mm, split: vec![whole; n] };
            let (csim, track) = plan(pl.size_mm, &pl.split)?;
            tried.push((csim, pl, track));
        }
    }
    // Best first; a stable sort keeps the first size with split corners ahead on ties.
    tried.sort_by(|a, b| b.0.total_cmp(&a.0));
    let Some((best_csim, start, _)) = tried.iter().find(|(_, pl, t)| passes(pl.size_mm, t)).cloned() else {
        return Ok(Placement { size_mm: sizes_mm[0], split: vec![true; n] });
    };
    // Per stroke, one greedy pass.
    let (mut pl, mut best) = (start.clone(), best_csim);
    let mut track = None;
    for i in (0..n).filter(|&i| !p.paths[i].corners.is_empty()) {
        pl.split[i] = !pl.split[i];
        let (csim, t) = plan(pl.size_mm, &pl.split)?;
        if csim > best + 1e-12 {
            (best, track) = (csim, Some(t));
        } else {
            pl.split[i] = !pl.split[i];
        }
    }
    Ok(match track {
        Some(t) if !passes(pl.size_mm, &t) => start,
        _ => pl,
    })
}

/// The plan's CSIM against `reference` (the glyph at [`CHAR_BOX_SEARCH_PX`]²) and its track,
/// for the centre lines split as `split` ([`with_splits`]) in a char box of side `size_mm` at
/// the origin: what [`searched_placement`] compares.
fn plan_score(
    p: &Prepared,
    reference: &Coverage,
    profile: &BrushProfile,
    opts: &WriteOptions,
    size_mm: f64,
    split: &[bool],
) -> Result<(f64, Track)> {
    let char_box = CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm };
    let topts =
        TrackOptions { char_box, spacing_mm: opts.spacing_mm, alpha_rad: opts.alpha_rad, sizing: Sizing::Brush };
    let built = build_track(&with_splits(&p.paths, split), profile, &topts)?;
    let img = render_char(&built.track, profile, opts.model, Extrapolation::Refuse, &char_box, CHAR_BOX_SEARCH_PX)?;
    Ok((stroke_metrics::csim(reference.as_gray(), img.as_gray())?, built.track))
}

impl Prepared {
    /// The same centre lines with the corner splits of `placement` applied ([`with_splits`]).
    pub fn placed(&self, placement: &Placement) -> Prepared {
        Prepared { paths: with_splits(&self.paths, &placement.split), ..self.clone() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::prepare;

    #[test]
    fn the_searched_placement_scores_at_least_every_whole_character_candidate() {
        let pen = BrushProfile::builtin("pen1").unwrap();
        // 口 has corners (the split matters), 永 a hook.
        for c in ['永', '口'] {
            let p = prepare(trajectory::embedded_glyph(c).unwrap(), None).unwrap();
            assert!(p.paths.iter().any(|q| !q.corners.is_empty()), "{c}");
            let auto = trajectory::auto_char_mm(&p.paths, &pen, 0.0);
            let pl = searched_placement(&p, &pen, &WriteOptions::default()).unwrap();
            assert_eq!(pl.split.len(), p.paths.len());
            assert!(
                CHAR_BOX_SEARCH_SCALES.iter().any(|s| (auto * s - pl.size_mm).abs() < 1e-9),
                "{c}: {pl:?} of {auto}"
            );
            let reference = render_glyph(&p.glyph, CHAR_BOX_SEARCH_PX);
            let opts = WriteOptions::default();
            let score =
                |size_mm: f64, split: &[bool]| plan_score(&p, &reference, &pen, &opts, size_mm, split).unwrap().0;
            let got = score(pl.size_mm, &pl.split);
            let n = p.paths.len();
            let best_whole = CHAR_BOX_SEARCH_SCALES
                .iter()
                .flat_map(|s| [score(auto * s, &vec![true; n]), score(auto * s, &vec![false; n])])
                .fold(0.0, f64::max);
            assert!(got >= best_whole - 1e-12, "{c}: {pl:?} scores {got} < {best_whole}");
        }
        // Strokes marked false lose their corners, the others keep them.
        let p = prepare(trajectory::embedded_glyph('口').unwrap(), None).unwrap();
        let split: Vec<bool> = (0..p.paths.len()).map(|i| i % 2 == 0).collect();
        for ((a, b), s) in with_splits(&p.paths, &split).iter().zip(&p.paths).zip(&split) {
            assert_eq!(a.corners.is_empty(), !s || b.corners.is_empty());
            assert_eq!(a.points, b.points);
        }
    }
}
