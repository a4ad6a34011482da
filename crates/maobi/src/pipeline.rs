//! Character pipeline: glyph → centre lines → track → render → scores.

use std::time::Instant;

use anyhow::{Context, Result};
use bezier_raster::{Coverage, ModelKind, render_stamps, render_track, sweep_stamps};
use brush_model::{BrushProfile, Extrapolation, PointMm, Track, TrackPoint};
use robot_io::frame::PaperFrame;
use robot_io::program::{RobotConfig, build_program};
use serde::Serialize;
use stroke_metrics::GrayRef;
pub use track_refine::RefineOptions;
use track_refine::{LossTerms, Target};
use trajectory::{
    CharBox, Glyph, Method, Registration, Sizing, StrokeFit, StrokePath, TrackOptions, build_track, centre_lines,
    centre_lines_from_template, chamfer_pct, raster::render_glyph,
};

/// Analysis raster for widths and skeletons, px per em box.
pub const ANALYSIS_PX: u32 = trajectory::DEFAULT_ANALYSIS_PX;

/// Options of [`write_char`].
#[derive(Clone, Copy, Debug)]
pub struct WriteOptions {
    /// Centre-line method; `None` picks medians when the source has them.
    pub method: Option<Method>,
    /// Stroke model for rendering.
    pub model: ModelKind,
    /// Side of the render and reference images, px.
    pub size: u32,
    /// Constant tilt, radians.
    pub alpha_rad: f64,
    /// Track point spacing, mm.
    pub spacing_mm: f64,
    /// Also score the plan with footprints sized freely from the glyph ([`CharReport::free_widths`]).
    pub free_widths: bool,
    /// Also run the track as a robot program (default paper frame and `robot.json`, the
    /// simulator's motion) and score what it writes.
    pub execute: bool,
    /// Refine the built track by gradient descent against the glyph (`track_refine`); `None`
    /// leaves the track as built.
    pub refine: Option<RefineOptions>,
}

impl Default for WriteOptions {
    fn default() -> Self {
        Self {
            method: None,
            model: ModelKind::Bsm,
            size: 512,
            alpha_rad: 0.0,
            spacing_mm: trajectory::DEFAULT_SPACING_MM,
            free_widths: true,
            execute: true,
            refine: None,
        }
    }
}

/// CSIM, SSIM and IoU of a render against its reference.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct Similarity {
    /// Cosine similarity.
    pub csim: f64,
    /// Structural similarity.
    pub ssim: f64,
    /// Intersection over union at 0.5.
    pub iou: f64,
}

/// Scores `render` against `reference` (same size).
pub fn similarity(reference: &Coverage, render: &Coverage) -> Result<Similarity> {
    let g = gray;
    Ok(Similarity {
        csim: stroke_metrics::csim(g(reference), g(render))?,
        ssim: stroke_metrics::ssim(g(reference), g(render))?,
        iou: stroke_metrics::iou(g(reference), g(render))?,
    })
}

/// Wraps a coverage image for the metrics crate.
pub fn gray(c: &Coverage) -> GrayRef<'_> {
    GrayRef::new(c.data(), c.width() as usize, c.height() as usize)
        .expect("coverage buffers have width × height values")
}

/// A glyph with its centre lines, ready to be placed.
#[derive(Clone)]
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
/// When the method cannot be used on this source, or the glyph is blank.
pub fn prepare(glyph: Glyph, method: Option<Method>) -> Result<Prepared> {
    prepare_with_template(glyph, method, None)
}

/// Finds the centre lines of a glyph, registering `template` (a glyph of the same character
/// with stroke medians: embedded or from a hanzi-writer-data folder) onto it for
/// [`Method::Template`]. `method: None` picks the source's own medians when it has them, else
/// the template when one is given, else a skeleton.
///
/// # Errors
/// [`Method::Template`] on a glyph without medians and no `template` (nothing to register),
/// a method that cannot be used on this source, or a blank glyph.
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
        let Some(t) = template else {
            anyhow::bail!(
                "{ch:?}: the template method needs the character's stroke data, and {ch:?} has none here (expected it in the embedded set or in a hanzi-writer-data folder)"
            );
        };
        let reg = centre_lines_from_template(t, &glyph, ANALYSIS_PX).with_context(|| format!("{ch:?}"))?;
        let template = Some(TemplateReport::of(&reg));
        return Ok(Prepared { glyph, method, paths: reg.paths, template });
    }
    let paths = centre_lines(&glyph, method, ANALYSIS_PX).with_context(|| format!("{ch:?}"))?;
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

/// Everything `maobi write` reports for one character.
#[derive(Clone, Debug, Serialize)]
pub struct CharReport {
    /// The character.
    pub char: String,
    /// Glyph source kind.
    pub source: &'static str,
    /// `medians`, `skeleton` or `template`.
    pub method: &'static str,
    /// Stroke model.
    pub model: &'static str,
    /// Render vs reference.
    pub csim: f64,
    /// Render vs reference.
    pub ssim: f64,
    /// Render vs reference.
    pub iou: f64,
    /// Symmetric chamfer distance of the track to the medians, % of the em box (null without
    /// medians).
    pub chamfer_pct: Option<f64>,
    /// Strokes in the source (null without medians).
    pub strokes_expected: Option<usize>,
    /// Strokes in the track.
    pub strokes_found: usize,
    /// Track points.
    pub points: usize,
    /// Wall time of track building, rendering and scoring, ms.
    pub millis: f64,
    /// Char box side, mm.
    pub char_mm: f64,
    /// Points whose glyph width was below / above what the brush can make (h clamped).
    pub clamped_low: usize,
    /// See `clamped_low`.
    pub clamped_high: usize,
    /// The plan's scores with every footprint sized freely from the glyph's width (h unclamped,
    /// extrapolating beyond the brush's calibrated range). Not a bound: clamping can score higher
    /// on some characters (an overshooting free width costs more than a clamped one).
    pub free_widths: Option<Similarity>,
    /// What the robot would write (the program executed as the simulator moves, through the
    /// forward model) against the glyph: the headline figure.
    pub executed: Option<Similarity>,
    /// The plan's render against the executed render (how far the plan can be trusted).
    pub agreement: Option<Similarity>,
    /// Before/after figures of the refinement (when [`WriteOptions::refine`] is set); the
    /// figures above are then those of the refined track (or of the built one if the refined
    /// track was rejected).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refine: Option<RefineReport>,
    /// What template registration found (`--from template` on a font or image glyph).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub template: Option<TemplateReport>,
}

/// What refinement did to one character.
#[derive(Clone, Debug, Serialize)]
pub struct RefineReport {
    /// The options used.
    pub options: RefineOptions,
    /// The built track's render vs the glyph.
    pub planned_before: Similarity,
    /// The refined track's render vs the glyph.
    pub planned_after: Similarity,
    /// What the built track's program writes vs the glyph (when executing).
    pub executed_before: Option<Similarity>,
    /// What the refined track's program writes vs the glyph (when executing).
    pub executed_after: Option<Similarity>,
    /// The loss before each step and after the last.
    pub curve: Vec<LossTerms>,
    /// Variables refined.
    pub variables: usize,
    /// Footprints in the image term.
    pub footprints: usize,
    /// Wall time of the refinement itself, ms.
    pub millis: f64,
    /// Why the refined track was not used (it failed `robot check`), if it was not.
    pub rejected: Option<String>,
}

/// One written character.
pub struct CharResult {
    /// The report.
    pub report: CharReport,
    /// The track on the paper.
    pub track: Track,
    /// Where the character sits.
    pub char_box: CharBox,
    /// The render, `size²`, em box on the whole image.
    pub render: Coverage,
    /// The reference glyph at the same scale.
    pub reference: Coverage,
    /// What the executed program writes, same framing (when [`WriteOptions::execute`]).
    pub executed: Option<Coverage>,
    /// The executed brush states on the paper (when [`WriteOptions::execute`]).
    pub executed_states: Option<Vec<TrackPoint>>,
}

/// The paper frame `maobi write` runs its program on: a level sheet
/// ([`robot_io::exec::level_frame_in_front`]) with the char box's centre in front of the AUBO-i5
/// at base (0.45, 0.05, 0.05) m, usable one box size around the box.
pub fn level_frame_for(b: &CharBox) -> PaperFrame {
    robot_io::exec::level_frame_in_front(
        [b.x0_mm + b.size_mm / 2.0, b.y0_mm + b.size_mm / 2.0],
        [b.x0_mm - b.size_mm, b.y0_mm - b.size_mm, b.x0_mm + 2.0 * b.size_mm, b.y0_mm + 2.0 * b.size_mm],
    )
}

/// Builds the robot program of a track (checked like `maobi robot check`) and executes it as the
/// simulator does; returns the executed brush states on the paper.
///
/// # Errors
/// When the program fails the safety check.
pub fn execute_track(
    track: &Track,
    profile: &BrushProfile,
    frame: &PaperFrame,
    cfg: &RobotConfig,
) -> Result<Vec<TrackPoint>> {
    let (program, _) = build_program(track, profile, frame, cfg).context("the track fails `robot check`")?;
    let trace = robot_io::exec::execute_program(&program);
    Ok(robot_io::exec::trace_to_states(&trace, frame))
}

/// Renders brush states (an executed path) through the forward model over a char box onto a
/// `size²` image of the box.
pub fn render_states(
    states: &[TrackPoint],
    profile: &BrushProfile,
    model: ModelKind,
    ex: Extrapolation,
    b: &CharBox,
    size: u32,
) -> Coverage {
    let stamps = sweep_stamps(states, profile, ex);
    render_stamps(&stamps, model.model(), PointMm::new(b.x0_mm, b.y0_mm), size as f64 / b.size_mm, size, size)
}

/// Renders a track over a char box onto a `size²` image of the box.
///
/// # Errors
/// When the profile refuses a point.
pub fn render_char(
    track: &Track,
    profile: &BrushProfile,
    model: ModelKind,
    ex: Extrapolation,
    b: &CharBox,
    size: u32,
) -> Result<Coverage> {
    Ok(render_track(
        track,
        profile,
        model.model(),
        ex,
        PointMm::new(b.x0_mm, b.y0_mm),
        size as f64 / b.size_mm,
        size,
        size,
    )?)
}

/// Builds, renders and scores one prepared character placed at `char_box`.
///
/// # Errors
/// When the profile refuses the track or the images cannot be scored.
pub fn write_char(p: &Prepared, profile: &BrushProfile, char_box: CharBox, opts: &WriteOptions) -> Result<CharResult> {
    let t0 = Instant::now();
    let topts =
        TrackOptions { char_box, spacing_mm: opts.spacing_mm, alpha_rad: opts.alpha_rad, sizing: Sizing::Brush };
    let built = build_track(&p.paths, profile, &topts)?;
    let render = render_char(&built.track, profile, opts.model, Extrapolation::Refuse, &char_box, opts.size)?;
    let reference = render_glyph(&p.glyph, opts.size);
    let sim = similarity(&reference, &render)?;
    let chamfer = p.glyph.medians.as_ref().map(|m| chamfer_pct(&built.track, &char_box, m));
    let millis = t0.elapsed().as_secs_f64() * 1e3;
    let free_widths = if opts.free_widths {
        let free = build_track(&p.paths, profile, &TrackOptions { sizing: Sizing::Unconstrained, ..topts })?;
        let img = render_char(&free.track, profile, opts.model, Extrapolation::Allow, &char_box, opts.size)?;
        Some(similarity(&reference, &img)?)
    } else {
        None
    };
    let (executed, agreement, executed_img, executed_states) = if opts.execute {
        let (states, img) = execute_and_render(&built.track, profile, opts, &char_box)
            .with_context(|| format!("{}: executing the plan", p.glyph.ch))?;
        (Some(similarity(&reference, &img)?), Some(similarity(&render, &img)?), Some(img), Some(states))
    } else {
        (None, None, None, None)
    };
    let report = CharReport {
        char: p.glyph.ch.to_string(),
        source: p.glyph.source.kind(),
        method: p.method.name(),
        model: opts.model.name(),
        csim: sim.csim,
        ssim: sim.ssim,
        iou: sim.iou,
        chamfer_pct: chamfer,
        strokes_expected: p.glyph.medians.as_ref().map(Vec::len).or(p.template.as_ref().map(|t| t.strokes)),
        strokes_found: built.track.strokes.len(),
        points: built.track.point_count(),
        millis,
        char_mm: char_box.size_mm,
        clamped_low: built.clamped_low,
        clamped_high: built.clamped_high,
        free_widths,
        executed,
        agreement,
        refine: None,
        template: p.template.clone(),
    };
    let mut result =
        CharResult { report, track: built.track, char_box, render, reference, executed: executed_img, executed_states };
    if let Some(ro) = &opts.refine {
        refine_result(&mut result, p, profile, opts, ro)?;
    }
    Ok(result)
}

/// The char box sizes [`searched_placement`] tries, as multiples of the automatic size
/// ([`trajectory::auto_char_mm`]), the automatic one first (it wins ties). Tuning fonts only
/// (LXGW WenKai Bold, Zhi Mang Xing; embedded characters 1–40, executed CSIM per character at
/// 0.8, 0.9, 1, 1.1, 1.2 and 1.35 times the automatic size): the best of all six scored 0.924
/// and 0.832 against 0.918 and 0.823 for the automatic size alone; no single factor beat it on
/// both fonts (docs/trajectory.md, "Template registration").
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
/// rises (one greedy pass). A brush's footprint is long for its width (pen1: 14 to 25 mm long
/// for 4.4 to 8 mm wide), so a smaller box gives wider marks but leaves short strokes and pieces
/// too short for a full press, and a larger one the reverse; a piece starts thin (its
/// footprints' tails must stay behind its start), so a brush font's joined strokes come out
/// fuller in one piece, where a kaishu 折 needs its lift. Which wins depends on the character
/// and the stroke. Ties keep the automatic size with split corners; the result's program
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
    Ok((stroke_metrics::csim(gray(reference), gray(&img))?, built.track))
}

impl Prepared {
    /// The same centre lines with the corner splits of `placement` applied ([`with_splits`]).
    pub fn placed(&self, placement: &Placement) -> Prepared {
        Prepared { paths: with_splits(&self.paths, &placement.split), ..self.clone() }
    }
}

/// What `write` runs for its executed figure: the track's program on [`level_frame_for`] the
/// char box with the default `robot.json` ([`execute_track`]), rendered like the plan
/// ([`render_states`]). Returns the executed states and their render.
fn execute_and_render(
    track: &Track,
    profile: &BrushProfile,
    opts: &WriteOptions,
    char_box: &CharBox,
) -> Result<(Vec<TrackPoint>, Coverage)> {
    let states = execute_track(track, profile, &level_frame_for(char_box), &RobotConfig::default())?;
    let img = render_states(&states, profile, opts.model, Extrapolation::Refuse, char_box, opts.size);
    Ok((states, img))
}

/// The glyph raster a track is refined against: the em box (the char box on the paper) at
/// `px²`.
pub fn refine_target(glyph: &Glyph, char_box: &CharBox, px: u32) -> Result<Target> {
    let img = render_glyph(glyph, px);
    Ok(Target::new(
        px,
        px,
        img.data().to_vec(),
        PointMm::new(char_box.x0_mm, char_box.y0_mm),
        char_box.size_mm / px as f64,
    )?)
}

/// The committed pen1 generator prepared for refinement (`--gradients generator`), loaded once.
fn committed_gen_model() -> Result<std::sync::Arc<track_refine::GenModel>> {
    static CELL: std::sync::OnceLock<Result<std::sync::Arc<track_refine::GenModel>, String>> =
        std::sync::OnceLock::new();
    CELL.get_or_init(|| {
        let g = crate::generator::load_generator(None).map_err(|e| format!("{e:#}"))?;
        track_refine::GenModel::new(&g).map(std::sync::Arc::new).map_err(|e| e.to_string())
    })
    .clone()
    .map_err(|e| anyhow::anyhow!("the committed generator: {e}"))
}

/// Refines a written character's track against its glyph and replaces the result's track,
/// renders and figures by the refined ones, keeping the built track's figures as "before".
/// A refined track that fails the robot check is not used (the report says why).
fn refine_result(
    r: &mut CharResult,
    p: &Prepared,
    profile: &BrushProfile,
    opts: &WriteOptions,
    ro: &RefineOptions,
) -> Result<()> {
    let target = refine_target(&p.glyph, &r.char_box, ro.analysis_px)?;
    let refined = match ro.gradients {
        track_refine::Gradients::Analytic => track_refine::refine(&r.track, profile, &target, ro),
        track_refine::Gradients::Generator => {
            track_refine::refine_with_generator(&r.track, profile, &target, ro, committed_gen_model()?)
        }
    }
    .with_context(|| format!("{}: refining the track", p.glyph.ch))?;
    let render = render_char(&refined.track, profile, opts.model, Extrapolation::Refuse, &r.char_box, opts.size)?;
    let planned_after = similarity(&r.reference, &render)?;
    let planned_before = Similarity { csim: r.report.csim, ssim: r.report.ssim, iou: r.report.iou };
    let mut rejected = None;
    let mut executed_after = None;
    let mut executed = None;
    if opts.execute {
        match execute_and_render(&refined.track, profile, opts, &r.char_box) {
            Ok((states, img)) => {
                executed_after = Some(similarity(&r.reference, &img)?);
                executed = Some((img, states));
            }
            Err(e) => rejected = Some(format!("{e:#}")),
        }
    } else if let Err(e) =
        build_program(&refined.track, profile, &level_frame_for(&r.char_box), &RobotConfig::default())
    {
        rejected = Some(format!("the refined track fails `robot check`: {e}"));
    }
    let report = RefineReport {
        options: *ro,
        planned_before,
        planned_after,
        executed_before: r.report.executed,
        executed_after,
        curve: refined.curve,
        variables: refined.variables,
        footprints: refined.footprints,
        millis: refined.millis,
        rejected: rejected.clone(),
    };
    if rejected.is_none() {
        (r.report.csim, r.report.ssim, r.report.iou) = (planned_after.csim, planned_after.ssim, planned_after.iou);
        r.report.points = refined.track.point_count();
        if let Some((img, states)) = executed {
            r.report.executed = executed_after;
            r.report.agreement = Some(similarity(&render, &img)?);
            r.executed = Some(img);
            r.executed_states = Some(states);
        }
        if let Some(m) = p.glyph.medians.as_ref() {
            r.report.chamfer_pct = Some(chamfer_pct(&refined.track, &r.char_box, m));
        }
        r.track = refined.track;
        r.render = render;
    }
    r.report.refine = Some(report);
    Ok(())
}

/// Images of one height side by side, left to right, with a 4 px white gap between them (for
/// reference | plan | executed).
pub fn side_by_side(images: &[&Coverage]) -> Coverage {
    let gap = 4u32;
    let h = images.iter().map(|c| c.height()).max().unwrap_or(0);
    let w = images.iter().map(|c| c.width()).sum::<u32>() + gap * images.len().saturating_sub(1) as u32;
    let mut out = Coverage::new(w, h);
    let mut x0 = 0usize;
    let ow = w as usize;
    for c in images {
        let cw = c.width() as usize;
        for y in 0..c.height() as usize {
            out.data_mut()[y * ow + x0..y * ow + x0 + cw].copy_from_slice(&c.data()[y * cw..(y + 1) * cw]);
        }
        x0 += cw + gap as usize;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_searched_placement_scores_at_least_every_whole_character_candidate() {
        let pen = BrushProfile::builtin("pen1").unwrap();
        // 口 has corners (the split matters), 永 a hook.
        for c in ['永', '口'] {
            let p = prepare(trajectory::glyph::embedded(c).unwrap(), None).unwrap();
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
        let p = prepare(trajectory::glyph::embedded('口').unwrap(), None).unwrap();
        let split: Vec<bool> = (0..p.paths.len()).map(|i| i % 2 == 0).collect();
        for ((a, b), s) in with_splits(&p.paths, &split).iter().zip(&p.paths).zip(&split) {
            assert_eq!(a.corners.is_empty(), !s || b.corners.is_empty());
            assert_eq!(a.points, b.points);
        }
    }
}
