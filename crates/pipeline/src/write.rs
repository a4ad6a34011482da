//! One character written: the track built from its centre lines in a char box, its render,
//! the robot program run as the controller would, and the scores of both against the glyph.

use std::time::Instant;

use bezier_raster::{Coverage, ModelKind, Stamp, render_stamps, sweep_stamps, track_stamps};
use brush_model::{BrushProfile, Extrapolation, PointMm, Track, TrackPoint};
use robot_io::{PaperFrame, RobotConfig, build_program};
use serde::Serialize;
use track_refine::{LossTerms, RefineOptions, Target};
use trajectory::{CharBox, Glyph, Method, Sizing, TrackOptions, build_track, chamfer_pct, render_glyph};

use crate::{Error, Prepared, Result, TemplateReport};

/// Options of [`write_char`].
#[derive(Clone)]
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
    /// Also score the plan with footprints sized freely from the glyph ([`PlanReport::free_widths`]):
    /// a diagnostic (a second track and render), off by default.
    pub free_widths: bool,
    /// Also run the track as a robot program (default paper frame and `robot.json`, the
    /// simulator's motion) and score what it writes.
    pub execute: bool,
    /// How the program is executed for the executed figure (default: as `robot send` sends it,
    /// [`Execution::PathBuffer`]).
    pub execution: Execution,
    /// Keep the executed program as it ran ([`CharResult::executed_run`], a few MB a
    /// character), so that a preview of the same program plays it rather than running it again
    /// ([`crate::run_sheet_with`]); off by default.
    pub keep_run: bool,
    /// Refine the built track by gradient descent against the glyph (`track_refine`); `None`
    /// leaves the track as built.
    pub refine: Option<RefineOptions>,
    /// The generator refinement takes its gradients from when [`WriteOptions::refine`] asks for
    /// [`track_refine::Gradients::Generator`] (the caller loads it once and shares it).
    #[cfg(feature = "generator")]
    pub generator: Option<std::sync::Arc<track_refine::GenModel>>,
}

impl std::fmt::Debug for WriteOptions {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut d = f.debug_struct("WriteOptions");
        d.field("method", &self.method)
            .field("model", &self.model)
            .field("size", &self.size)
            .field("alpha_rad", &self.alpha_rad)
            .field("spacing_mm", &self.spacing_mm)
            .field("free_widths", &self.free_widths)
            .field("execute", &self.execute)
            .field("execution", &self.execution)
            .field("keep_run", &self.keep_run)
            .field("refine", &self.refine);
        #[cfg(feature = "generator")]
        d.field("generator", &self.generator.as_ref().map(|_| "a generator"));
        d.finish()
    }
}

impl Default for WriteOptions {
    fn default() -> Self {
        Self {
            method: None,
            model: ModelKind::Bsm,
            size: 512,
            alpha_rad: 0.0,
            spacing_mm: trajectory::DEFAULT_SPACING_MM,
            free_widths: false,
            execute: true,
            execution: Execution::default(),
            keep_run: false,
            refine: None,
            #[cfg(feature = "generator")]
            generator: None,
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
    let (a, b) = (reference.as_gray(), render.as_gray());
    Ok(Similarity {
        csim: stroke_metrics::csim(a, b)?,
        ssim: stroke_metrics::ssim(a, b)?,
        iou: stroke_metrics::iou(a, b)?,
    })
}

/// Everything `maobi write` reports for one character (its `report.json`), grouped: what the
/// plan scores ([`PlanReport`]), what the executed program scores, how far the two agree, the
/// brush, and the time taken. Every field is described in `docs/outputs.md`.
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
    /// Char box side, mm.
    pub char_mm: f64,
    /// The plan (the track as built, rendered through the forward model) against the glyph.
    pub plan: PlanReport,
    /// What the robot would write (the program executed as the simulator moves, through the
    /// forward model) against the glyph: the headline figure (null when not executed).
    pub executed: Option<Similarity>,
    /// The plan's render against the executed render (how far the plan can be trusted; null when
    /// not executed).
    pub agreement: Option<Similarity>,
    /// The brush and how well its width range covers the glyph at this size.
    pub brush: BrushReport,
    /// Wall times, ms.
    pub timing_ms: TimingMs,
    /// Before/after figures of the refinement (when [`WriteOptions::refine`] is set); the
    /// figures above are then those of the refined track (or of the built one if the refined
    /// track was rejected).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refine: Option<RefineReport>,
    /// What template registration found (`--from template` on a font or image glyph).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub template: Option<TemplateReport>,
}

/// The plan's figures in a [`CharReport`]: the track as built, rendered, against the glyph.
#[derive(Clone, Debug, Serialize)]
pub struct PlanReport {
    /// Render vs reference: cosine similarity.
    pub csim: f64,
    /// Render vs reference: structural similarity.
    pub ssim: f64,
    /// Render vs reference: intersection over union at 0.5.
    pub iou: f64,
    /// Symmetric chamfer distance of the track to the medians, % of the em box (null without
    /// medians).
    pub chamfer_pct: Option<f64>,
    /// Strokes in the source (null without medians or a template).
    pub strokes_expected: Option<usize>,
    /// Strokes in the track.
    pub strokes_found: usize,
    /// Track points.
    pub points: usize,
    /// The plan's scores with every footprint sized freely from the glyph's width (h unclamped,
    /// extrapolating beyond the brush's calibrated range). Not a bound: clamping can score higher
    /// on some characters (an overshooting free width costs more than a clamped one). Null unless
    /// asked for ([`WriteOptions::free_widths`]).
    pub free_widths: Option<Similarity>,
}

impl PlanReport {
    /// CSIM, SSIM and IoU of the plan.
    pub fn similarity(&self) -> Similarity {
        Similarity { csim: self.csim, ssim: self.ssim, iou: self.iou }
    }

    fn set_similarity(&mut self, s: Similarity) {
        (self.csim, self.ssim, self.iou) = (s.csim, s.ssim, s.iou);
    }
}

/// The brush in a [`CharReport`]: which one, and at how many track points the glyph asked for a
/// width it cannot make (its press depth h clamped to the calibrated range).
#[derive(Clone, Debug, Serialize)]
pub struct BrushReport {
    /// The brush profile's name (`pen1`, or the name in a profile file).
    pub name: String,
    /// Track points whose glyph width was below what the brush can make.
    pub clamped_low_points: usize,
    /// Track points whose glyph width was above what the brush can make.
    pub clamped_high_points: usize,
}

/// Wall times in a [`CharReport`], ms.
#[derive(Clone, Debug, Serialize)]
pub struct TimingMs {
    /// Building the track, rendering the plan and scoring it, ms.
    pub plan: f64,
    /// The refinement (null without one), ms.
    pub refine: Option<f64>,
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
    /// Wall time of the refinement itself, ms (`time_ms` in JSON).
    #[serde(rename = "time_ms")]
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
    /// The program behind [`CharResult::executed_states`] as it ran (with
    /// [`WriteOptions::keep_run`] and [`Execution::PathBuffer`]).
    pub executed_run: Option<ExecutedRun>,
}

/// A program as the simulator's arm ran it, as `robot send` sends it ([`Execution::PathBuffer`]),
/// kept with the configuration it was built and timed with: what [`crate::run_sheet_with`]
/// plays when it builds the same program, rather than timing and running it again.
#[derive(Clone, Debug)]
pub struct ExecutedRun {
    pub(crate) program: robot_io::Program,
    pub(crate) cfg: RobotConfig,
    pub(crate) timing: robot_io::ProgramTiming,
    pub(crate) trace: Vec<robot_io::TaggedEntry>,
}

impl ExecutedRun {
    /// Builds `program`'s run on the nominal AUBO-i5 (each pressed stroke one path buffer on its
    /// timing with `cfg`, the other moves on the controller's time law).
    pub(crate) fn run(program: robot_io::Program, cfg: &RobotConfig) -> Result<Self, robot_io::RobotError> {
        use robot_io::sim::{SendMotion, execute_as_sent_tagged};
        let kin = robot_io::DhParams::AUBO_I5;
        let timing = robot_io::time_program(&program, &kin, cfg)?;
        let trace = execute_as_sent_tagged(&program, &kin, SendMotion::PathBuffer(&timing))?;
        Ok(Self { program, cfg: cfg.clone(), timing, trace })
    }

    /// Whether this is the run of `program` built and timed with `cfg`.
    pub(crate) fn is_of(&self, program: &robot_io::Program, cfg: &RobotConfig) -> bool {
        self.program == *program && self.cfg == *cfg
    }
}

/// The paper frame `maobi write` runs its program on: a level sheet
/// ([`robot_io::level_frame_in_front`]) with the char box's centre in front of the AUBO-i5
/// at base (0.45, 0.05, 0.05) m, usable one box size around the box.
pub fn level_frame_for(b: &CharBox) -> PaperFrame {
    robot_io::level_frame_in_front(
        [b.x0_mm + b.size_mm / 2.0, b.y0_mm + b.size_mm / 2.0],
        [b.x0_mm - b.size_mm, b.y0_mm - b.size_mm, b.x0_mm + 2.0 * b.size_mm, b.y0_mm + 2.0 * b.size_mm],
    )
}

/// Builds the robot program of a track (checked like `maobi robot check`) and executes it as
/// `robot send` sends it and the simulator runs it ([`Execution::PathBuffer`]: each pressed
/// stroke one path buffer on its timing); returns the executed brush states on the paper.
///
/// # Errors
/// The check's error when the program fails it; the timing's when a stroke cannot be timed
/// within the limits.
pub fn execute_track(
    track: &Track,
    profile: &BrushProfile,
    frame: &PaperFrame,
    cfg: &RobotConfig,
) -> Result<Vec<TrackPoint>, robot_io::RobotError> {
    execute_track_with(track, profile, frame, cfg, Execution::default())
}

/// How a program is executed for an executed figure.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Execution {
    /// [`robot_io::execute_program`]: every move at its commanded speed, straight
    /// between the points, no ramps and no blends (no controller moves so; kept to measure
    /// what the time law changes).
    Plain,
    /// As `robot send` sends it by default and the simulator server runs it: each pressed
    /// stroke as one path buffer of its timed waypoints, the other moves on the trapezoidal
    /// time law ([`robot_io::sim::execute_as_sent`]). The figure `maobi write` reports.
    #[default]
    PathBuffer,
    /// As `robot send --motion moves` sends it: the program compacted
    /// ([`robot_io::compact_program`]) and run with its blends rounded, on the time law.
    Moves,
}

impl Execution {
    /// Every kind, in the order the CLI lists them.
    pub const ALL: [Execution; 3] = [Execution::PathBuffer, Execution::Moves, Execution::Plain];

    /// The CLI name: `path-buffer`, `moves` or `plain`.
    pub fn name(self) -> &'static str {
        match self {
            Execution::Plain => "plain",
            Execution::PathBuffer => "path-buffer",
            Execution::Moves => "moves",
        }
    }
}

impl std::str::FromStr for Execution {
    type Err = String;

    /// Parses [`Execution::name`].
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        Execution::ALL
            .into_iter()
            .find(|e| e.name() == s)
            .ok_or_else(|| format!("expected path-buffer, moves or plain, got `{s}`"))
    }
}

/// [`execute_track`] executed as `how` says (the AUBO-i5's nominal kinematics, the simulator's
/// arm; timing with `cfg`).
///
/// # Errors
/// The check's error when the program fails it; the timing's when a stroke cannot be timed
/// within the limits.
pub fn execute_track_with(
    track: &Track,
    profile: &BrushProfile,
    frame: &PaperFrame,
    cfg: &RobotConfig,
    how: Execution,
) -> Result<Vec<TrackPoint>, robot_io::RobotError> {
    Ok(execute_run(track, profile, frame, cfg, how)?.0)
}

/// [`execute_track_with`], and with [`Execution::PathBuffer`] the run itself.
fn execute_run(
    track: &Track,
    profile: &BrushProfile,
    frame: &PaperFrame,
    cfg: &RobotConfig,
    how: Execution,
) -> Result<(Vec<TrackPoint>, Option<ExecutedRun>), robot_io::RobotError> {
    use robot_io::DhParams;
    use robot_io::sim::{SendMotion, execute_as_sent};
    let (program, _) = build_program(track, profile, frame, cfg)?;
    let (trace, run) = match how {
        Execution::Plain => (robot_io::execute_program(&program), None),
        Execution::PathBuffer => {
            let run = ExecutedRun::run(program, cfg)?;
            (run.trace.iter().map(|e| e.entry).collect(), Some(run))
        }
        Execution::Moves => {
            let compact = robot_io::compact_program(&program, cfg);
            (execute_as_sent(&compact, &DhParams::AUBO_I5, SendMotion::Moves)?, None)
        }
    };
    // Depths as executed: a press at the range's end read back a little outside it is the
    // forward model's to take (`brush_model::DEPTH_EDGE_TOLERANCE_MM`).
    Ok((robot_io::trace_to_states(&trace, frame), run))
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
    render_over(&sweep_stamps(states, profile, ex), model, b, size)
}

/// Footprints (paper mm) over a char box onto a `size²` image of the box.
fn render_over(stamps: &[Stamp], model: ModelKind, b: &CharBox, size: u32) -> Coverage {
    render_stamps(stamps, model.model(), PointMm::new(b.x0_mm, b.y0_mm), size as f64 / b.size_mm, size, size)
}

/// Renders a track through the forward model (its hairs as `profile.hairs` describes them: a
/// brush the closed loop fitted trails as fitted) over a char box onto a `size²` image of the
/// box.
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
    Ok(render_over(&track_stamps(track, profile, ex)?, model, b, size))
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
    // The plan (its render beside the glyph's, its scores, the free-width plan when asked) and
    // the executed program depend only on the track: both at once on rayon's pool.
    let plan = || -> Result<_> {
        let (render, reference) = rayon::join(
            || render_char(&built.track, profile, opts.model, Extrapolation::Refuse, &char_box, opts.size),
            || render_glyph(&p.glyph, opts.size),
        );
        let render = render?;
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
        Ok((render, reference, sim, chamfer, millis, free_widths))
    };
    let executed = || {
        opts.execute
            .then(|| execute_and_render(&built.track, profile, opts, &char_box))
            .transpose()
            .map_err(|source| Error::Check { ch: p.glyph.ch.to_string(), source })
    };
    let (plan, executed) = rayon::join(plan, executed);
    let (render, reference, sim, chamfer, millis, free_widths) = plan?;
    let (executed, agreement, executed_img, executed_states, executed_run) = match executed? {
        Some((states, img, run)) => {
            let (executed, agreement) = rayon::join(|| similarity(&reference, &img), || similarity(&render, &img));
            (Some(executed?), Some(agreement?), Some(img), Some(states), run)
        }
        None => (None, None, None, None, None),
    };
    let report = CharReport {
        char: p.glyph.ch.to_string(),
        source: p.glyph.source.kind(),
        method: p.method.name(),
        model: opts.model.name(),
        char_mm: char_box.size_mm,
        plan: PlanReport {
            csim: sim.csim,
            ssim: sim.ssim,
            iou: sim.iou,
            chamfer_pct: chamfer,
            strokes_expected: p.glyph.medians.as_ref().map(Vec::len).or(p.template.as_ref().map(|t| t.strokes)),
            strokes_found: built.track.strokes.len(),
            points: built.track.point_count(),
            free_widths,
        },
        executed,
        agreement,
        brush: BrushReport {
            name: profile.name.clone(),
            clamped_low_points: built.clamped_low,
            clamped_high_points: built.clamped_high,
        },
        timing_ms: TimingMs { plan: millis, refine: None },
        refine: None,
        template: p.template.clone(),
    };
    let mut result = CharResult {
        report,
        track: built.track,
        char_box,
        render,
        reference,
        executed: executed_img,
        executed_states,
        executed_run,
    };
    if let Some(ro) = &opts.refine {
        let target = refine_target(&p.glyph, &result.char_box, ro.analysis_px)?;
        refine_result(&mut result, p, profile, opts, ro, &target)?;
    }
    Ok(result)
}

/// What `write` runs for its executed figure: the track's program on [`level_frame_for`] the
/// char box with the default `robot.json`, executed as [`WriteOptions::execution`] says
/// ([`execute_track_with`]), rendered like the plan
/// ([`render_states`]). Returns the executed states, their render and the run when
/// [`WriteOptions::keep_run`] asks for it.
fn execute_and_render(
    track: &Track,
    profile: &BrushProfile,
    opts: &WriteOptions,
    char_box: &CharBox,
) -> Result<Executed, robot_io::RobotError> {
    let (states, run) =
        execute_run(track, profile, &level_frame_for(char_box), &RobotConfig::default(), opts.execution)?;
    let stamps = sweep_stamps(&states, profile, Extrapolation::Refuse);
    let img = render_over(&stamps, opts.model, char_box, opts.size);
    Ok((states, img, run.filter(|_| opts.keep_run)))
}

/// The executed states, their render and the run kept ([`execute_and_render`]).
type Executed = (Vec<TrackPoint>, Coverage, Option<ExecutedRun>);

/// The glyph raster a track is refined against: the em box (the char box on the paper) at
/// `px²`.
///
/// # Errors
/// [`Error::Refine`] when `px` or the box make no usable target.
pub fn refine_target(glyph: &Glyph, char_box: &CharBox, px: u32) -> Result<Target> {
    let img = render_glyph(glyph, px);
    Target::new(px, px, img.data().to_vec(), PointMm::new(char_box.x0_mm, char_box.y0_mm), char_box.size_mm / px as f64)
        .map_err(|source| Error::Refine { ch: glyph.ch, source })
}

/// Refines a written character's track against `target` (its glyph, or the closed loop's
/// shifted glyph) and replaces the result's track, renders and figures by the refined ones,
/// keeping the built track's figures as "before"; every figure is scored against the glyph.
/// A refined track that fails the robot check is not used (the report says why).
pub(crate) fn refine_result(
    r: &mut CharResult,
    p: &Prepared,
    profile: &BrushProfile,
    opts: &WriteOptions,
    ro: &RefineOptions,
    target: &Target,
) -> Result<()> {
    let refined = match ro.gradients {
        track_refine::Gradients::Analytic => track_refine::refine(&r.track, profile, target, ro),
        #[cfg(feature = "generator")]
        track_refine::Gradients::Generator => {
            let g = opts.generator.clone().ok_or(Error::NoGenerator)?;
            track_refine::refine_with_generator(&r.track, profile, target, ro, g)
        }
        #[cfg(not(feature = "generator"))]
        track_refine::Gradients::Generator => return Err(Error::NoGenerator),
    }
    .map_err(|source| Error::Refine { ch: p.glyph.ch, source })?;
    let render = render_char(&refined.track, profile, opts.model, Extrapolation::Refuse, &r.char_box, opts.size)?;
    let planned_after = similarity(&r.reference, &render)?;
    let planned_before = r.report.plan.similarity();
    let mut rejected = None;
    let mut executed_after = None;
    let mut executed = None;
    if opts.execute {
        match execute_and_render(&refined.track, profile, opts, &r.char_box) {
            Ok((states, img, run)) => {
                executed_after = Some(similarity(&r.reference, &img)?);
                executed = Some((img, states, run));
            }
            Err(e) => rejected = Some(format!("the refined track fails `robot check`: {e}")),
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
        r.report.plan.set_similarity(planned_after);
        r.report.plan.points = refined.track.point_count();
        if let Some((img, states, run)) = executed {
            r.report.executed = executed_after;
            r.report.agreement = Some(similarity(&render, &img)?);
            r.executed = Some(img);
            r.executed_states = Some(states);
            r.executed_run = run;
        }
        if let Some(m) = p.glyph.medians.as_ref() {
            r.report.plan.chamfer_pct = Some(chamfer_pct(&refined.track, &r.char_box, m));
        }
        r.track = refined.track;
        r.render = render;
    }
    r.report.timing_ms.refine = Some(report.millis);
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

impl CharResult {
    /// The character's `track.json`: its brush, its strokes on the paper, its box and, when it
    /// was laid out on a sheet, the sheet's size (`[width, height]` mm).
    pub fn track_file(&self, profile: &BrushProfile, sheet_mm: Option<[f64; 2]>) -> robot_io::TrackFile {
        let b = self.char_box;
        robot_io::TrackFile {
            char: Some(self.report.char.clone()),
            char_box_mm: Some([b.x0_mm, b.y0_mm, b.size_mm]),
            sheet_mm,
            brush: profile.clone(),
            strokes: self.track.strokes.clone(),
            stroke_chars: None,
        }
    }
}

/// Renders every result again through a B-BSMG generator trained for `profile` and scores
/// those images instead (the plan, and the executed path when there is one); `size_px` is the
/// side of each character's images.
///
/// # Errors
/// [`Error::GeneratorBrush`] when the generator was trained for another brush;
/// [`Error::Generator`] or [`Error::Metrics`] when rendering or scoring fails.
#[cfg(feature = "generator")]
pub fn rerender_with_generator(
    results: &mut [CharResult],
    g: &neural_gen::Generator,
    profile: &BrushProfile,
    size_px: u32,
) -> Result<()> {
    if g.config.profile.model != profile.model || g.config.profile.ranges != profile.ranges {
        return Err(Error::GeneratorBrush { trained: g.config.profile.name.clone(), brush: profile.name.clone() });
    }
    for r in results.iter_mut() {
        let b = r.char_box;
        let neural = |t: &Track| {
            neural_gen::render_track(
                g,
                t,
                PointMm::new(b.x0_mm, b.y0_mm),
                size_px as f64 / b.size_mm,
                size_px,
                size_px,
                64,
            )
        };
        let img = neural(&r.track)?;
        let sim = similarity(&r.reference, &img)?;
        r.report.plan.set_similarity(sim);
        if let Some(states) = &r.executed_states {
            // The executed path through the same generator.
            let executed = Track { strokes: vec![brush_model::Stroke { points: states.clone() }] };
            let ex = neural(&executed)?;
            r.report.executed = Some(similarity(&r.reference, &ex)?);
            r.report.agreement = Some(similarity(&img, &ex)?);
            r.executed = Some(ex);
        }
        r.report.model = "b-bsmg";
        r.render = img;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn execution_names_round_trip_and_a_bad_one_is_named() {
        for e in Execution::ALL {
            assert_eq!(e.name().parse::<Execution>(), Ok(e));
        }
        assert_eq!("fast".parse::<Execution>(), Err("expected path-buffer, moves or plain, got `fast`".to_string()));
    }

    /// `字`'s roof is pressed at pen1's shallowest calibrated depth; executed as sent, its depths
    /// come back up to 1e-5 mm shallower (joints interpolated between solved poses) and must
    /// still leave their footprints: plan and execution agree (the gate's worst was 0.984).
    /// pen2's shallowest depth (7.333… mm) is not a whole number of nanometres and is kept too.
    #[test]
    fn presses_at_the_shallowest_depth_are_executed_without_gaps() {
        for (ch, brush, size_mm) in [('字', "pen1", None), ('十', "pen2", Some(60.0))] {
            let profile = BrushProfile::builtin(brush).unwrap();
            let p = crate::prepare(trajectory::embedded_glyph(ch).unwrap(), Some(Method::Medians)).unwrap();
            let opts = WriteOptions { size: 128, free_widths: false, ..WriteOptions::default() };
            let size_mm = size_mm.unwrap_or_else(|| trajectory::auto_char_mm(&p.paths, &profile, 0.0));
            let r = write_char(&p, &profile, CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm }, &opts).unwrap();
            let states = r.executed_states.as_ref().unwrap();
            let min = profile.ranges.h_mm.min;
            let at_min = states.iter().filter(|s| (s.h_mm - min).abs() < 1e-3).count();
            assert!(at_min > 10, "{ch}: {at_min} executed depths at {min} mm: the case is not exercised");
            let agreement = r.report.agreement.unwrap().csim;
            assert!(agreement > 0.999, "{ch} with {brush}: plan vs executed CSIM {agreement}");
        }
    }

    #[test]
    fn the_executed_figure_is_the_program_as_sent_unless_asked_otherwise() {
        let pen1 = BrushProfile::builtin("pen1").unwrap();
        let p = crate::prepare(trajectory::embedded_glyph('十').unwrap(), None).unwrap();
        let b = CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm: 60.0 };
        let opts = WriteOptions { size: 64, free_widths: false, ..WriteOptions::default() };
        assert_eq!(opts.execution, Execution::PathBuffer);
        let r = write_char(&p, &pen1, b, &opts).unwrap();
        let (frame, cfg) = (level_frame_for(&b), RobotConfig::default());
        let as_sent = execute_track_with(&r.track, &pen1, &frame, &cfg, Execution::PathBuffer).unwrap();
        let plain = execute_track_with(&r.track, &pen1, &frame, &cfg, Execution::Plain).unwrap();
        // The path buffers are sampled on their timing, the plain executor at its speeds: not
        // the same samples.
        assert_ne!(as_sent, plain);
        assert_eq!(r.executed_states.as_ref(), Some(&as_sent));
        let plain_opts = WriteOptions { execution: Execution::Plain, ..opts };
        let r = write_char(&p, &pen1, b, &plain_opts).unwrap();
        assert_eq!(r.executed_states.as_ref(), Some(&plain));
    }

    /// A brush fitted to trail otherwise (the closed loop fits `hairs.trail_reach` into the
    /// profile) is the one the plan, the executed path and the refined track are rendered with.
    #[test]
    fn the_plan_is_rendered_with_the_profiles_trail() {
        let pen1 = BrushProfile::builtin("pen1").unwrap();
        let mut short = pen1.clone();
        short.hairs.trail_reach = 0.3;
        // 心's hook and dots curve: where the tip trails decides which way their footprints point.
        let p = crate::prepare(trajectory::embedded_glyph('心').unwrap(), Some(Method::Medians)).unwrap();
        let b = CharBox { x0_mm: 0.0, y0_mm: 0.0, size_mm: 120.0 };
        let base = WriteOptions { size: 96, free_widths: false, ..WriteOptions::default() };
        let r5 = write_char(&p, &pen1, b, &base).unwrap();
        let opts = WriteOptions { refine: Some(RefineOptions { iterations: 2, ..RefineOptions::default() }), ..base };
        let r3 = write_char(&p, &short, b, &opts).unwrap();
        let by = |profile: &BrushProfile, t: &Track| {
            render_char(t, profile, opts.model, Extrapolation::Refuse, &b, 96).unwrap()
        };
        // The refined track's render is the one kept, through the fitted reach.
        assert!(r3.report.refine.as_ref().unwrap().rejected.is_none());
        assert_eq!(r3.render.data(), by(&short, &r3.track).data());
        assert_ne!(r3.render.data(), by(&pen1, &r3.track).data());
        let stamps = sweep_stamps(r3.executed_states.as_ref().unwrap(), &short, Extrapolation::Refuse);
        let executed = render_over(&stamps, opts.model, &b, 96);
        assert_eq!(r3.executed.as_ref().unwrap().data(), executed.data());
        // The nominal brush trails as the forward model's own.
        assert_eq!(r5.render.data(), by(&pen1, &r5.track).data());
        // The track carries the brush as it was written with.
        assert_eq!(r3.track_file(&short, None).brush.hairs.trail_reach, 0.3);
    }
}
