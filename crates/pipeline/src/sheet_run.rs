//! A sheet's execution: its program built and checked as `robot check` does it, timed and run
//! on the simulator's arm as `robot send` sends it ([`run_sheet`]), and the footprints the brush
//! leaves along what ran, each at the time the brush reaches it ([`run_footprints`], the forward
//! model with the profile's hairs). `maobi write`'s preview and `maobi preview` play what these
//! return.

use brush_model::{BrushProfile, Extrapolation, ForwardModel, PointMm, Track, TrackPoint};
use robot_io::DhParams;
use robot_io::PaperFrame;
use robot_io::sim::{SendMotion, execute_as_sent_tagged};
use robot_io::{CheckReport, RobotConfig, build_program_chars};
use robot_io::{ProgramTiming, RobotError, TaggedEntry, TraceEntry, TraceKind, trace_to_states};

/// One timed sample of the executed path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunSample {
    /// Time from the start of the run (the brush at the safe height above the first stroke), s.
    pub t_s: f64,
    /// The brush state, paper mm and rad.
    pub point: TrackPoint,
    /// Whether it belongs to an ink dip.
    pub dip: bool,
}

/// A sheet's program as the simulator's arm runs it.
#[derive(Clone, Debug)]
pub struct SheetRun {
    /// The robot check's report (strokes, points, moves, dips, deepest press).
    pub report: CheckReport,
    /// The program's timing (each stroke's path buffer).
    pub timing: ProgramTiming,
    /// The executed path, timed; the first joint move from the controller's home pose is left
    /// out.
    pub samples: Vec<RunSample>,
    /// When each stroke's path buffer runs, `[start, end]` s on the samples' clock.
    pub strokes_s: Vec<[f64; 2]>,
}

/// A footprint left along a run: when the brush reaches it and its outline (the upper and
/// the lower Bézier's first three control points, paper mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimedFootprint {
    /// Time on the run's clock, s.
    pub t_s: f64,
    /// Upper curve's points 0–2, then the lower curve's points 0–2.
    pub outline: [PointMm; 6],
}

/// Builds `track`'s program on `frame` with `cfg` (strokes tagged with their characters by
/// `stroke_chars`), checks it, times it on the nominal AUBO-i5 and runs it on the simulator's
/// arm as `robot send` sends it (each pressed stroke one path buffer on its timing, the other
/// moves on the controller's time law).
///
/// # Errors
/// The robot check's or the timing's [`RobotError`]: the program refused.
///
/// # Examples
/// ```
/// use pipeline::run_sheet;
/// use brush_model::{BrushProfile, Stroke, Track, TrackPoint};
///
/// let pen1 = BrushProfile::builtin("pen1")?;
/// // A 20 mm stroke pressed 12 mm, a point every millimetre.
/// let p = |x: f64| TrackPoint { x_mm: x, y_mm: 40.0, h_mm: 12.0, alpha_rad: 0.0, beta_rad: 0.0 };
/// let track = Track { strokes: vec![Stroke { points: (0..=20).map(|i| p(30.0 + i as f64)).collect() }] };
/// let frame = robot_io::level_frame_in_front([40.0, 40.0], [0.0, 0.0, 80.0, 80.0]);
/// let run = run_sheet(&track, None, &pen1, &frame, &robot_io::RobotConfig::default())?;
/// assert_eq!(run.strokes_s.len(), 1);
/// assert!(run.samples.iter().any(|s| s.point.h_mm > 0.0));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn run_sheet(
    track: &Track,
    stroke_chars: Option<&[usize]>,
    brush: &BrushProfile,
    frame: &PaperFrame,
    cfg: &RobotConfig,
) -> Result<SheetRun, RobotError> {
    let (program, report) = build_program_chars(track, stroke_chars, brush, frame, cfg)?;
    let kin = DhParams::AUBO_I5;
    let timing = robot_io::time_program(&program, &kin, cfg)?;
    let tagged = execute_as_sent_tagged(&program, &kin, SendMotion::PathBuffer(&timing))?;
    let samples = timed_samples(&tagged, frame);
    // The timeline starts where the start move ends, as in `timed_samples`.
    let t0 = tagged.iter().take_while(|e| e.stroke.is_none()).last().map_or(0.0, |e| e.entry.t_s);
    let mut strokes_s: Vec<[f64; 2]> = Vec::new();
    let mut current = None;
    for e in tagged.iter().filter(|e| e.entry.kind == TraceKind::PathBuffer) {
        let at = e.entry.t_s - t0;
        match strokes_s.last_mut() {
            Some(span) if current == e.stroke => span[1] = at,
            _ => {
                strokes_s.push([at, at]);
                current = e.stroke;
            }
        }
    }
    Ok(SheetRun { report, timing, samples, strokes_s })
}

/// The tagged trace as timed samples in paper coordinates, from the end of the first joint
/// move (t = 0 with the brush at the safe height above the first stroke).
fn timed_samples(tagged: &[TaggedEntry], frame: &PaperFrame) -> Vec<RunSample> {
    let start = tagged.iter().take_while(|e| e.stroke.is_none()).count();
    let t0 = if start > 0 { tagged[start - 1].entry.t_s } else { 0.0 };
    let (entries, dips): (Vec<TraceEntry>, Vec<bool>) = tagged[start..].iter().map(|e| (e.entry, e.dip)).unzip();
    let states = trace_to_states(&entries, frame);
    entries.iter().zip(states).zip(dips).map(|((e, point), dip)| RunSample { t_s: e.t_s - t0, point, dip }).collect()
}

/// The footprints the brush leaves along `samples` (on `frame`'s paper, ink dips left out):
/// the forward model ([`ForwardModel::sweep`], the profile's hairs) over each contact (a run of
/// pressed samples, with one sample of lift before and after so the model sees it begin and
/// end), each stamp timed by the nearest sample along the contact. A press the profile refuses
/// leaves none.
pub fn run_footprints(samples: &[RunSample], brush: &BrushProfile, frame: &PaperFrame) -> Vec<TimedFootprint> {
    let model = ForwardModel::default();
    let mut feet = Vec::new();
    let mut i = 0;
    while i < samples.len() {
        let s = &samples[i];
        if s.point.h_mm <= 0.0 || s.dip || !frame.contains(s.point.x_mm, s.point.y_mm) {
            i += 1;
            continue;
        }
        let start = i;
        while i < samples.len() && samples[i].point.h_mm > 0.0 && !samples[i].dip {
            i += 1;
        }
        let (a, b) = (start.saturating_sub(1), (i + 1).min(samples.len()));
        let run: Vec<TrackPoint> = samples[a..b].iter().map(|s| s.point).collect();
        let sweep = model.sweep(brush, &run, Extrapolation::Refuse);
        let mut j = 0usize;
        for st in &sweep.stamps {
            // Advance along the run to the nearest sample (stamps are in path order).
            let d = |k: usize| (run[k].x_mm - st.x_mm).hypot(run[k].y_mm - st.y_mm);
            let mut best = j;
            for k in j..(j + 64).min(run.len()) {
                if d(k) < d(best) {
                    best = k;
                }
            }
            j = best;
            let Ok(fp) = brush.predict_oriented(&st.press(), Extrapolation::Refuse) else { continue };
            let o = fp.outline(st.anchor(), st.beta_rad);
            let (u, l) = (&o.upper.points, &o.lower.points);
            feet.push(TimedFootprint { t_s: samples[a + j].t_s, outline: [u[0], u[1], u[2], l[0], l[1], l[2]] });
        }
    }
    feet
}

/// The planned track as timed samples, for a program that was refused: each stroke's points at
/// `speed_m_s` along it, a second of travel between strokes.
pub fn planned_samples(track: &Track, speed_m_s: f64) -> Vec<RunSample> {
    let mut out = Vec::new();
    let mut t_s = 0.0;
    for st in &track.strokes {
        let mut prev: Option<&TrackPoint> = None;
        for p in &st.points {
            if let Some(q) = prev {
                t_s += (p.x_mm - q.x_mm).hypot(p.y_mm - q.y_mm) / (speed_m_s * 1000.0);
            }
            out.push(RunSample { t_s, point: *p, dip: false });
            prev = Some(p);
        }
        t_s += 1.0;
    }
    out
}

/// A recorded trace (a simulator's `--trace`, an arm's samples) on `frame`'s paper, rendered
/// through the forward model over `char_box` onto a `size_px²` image, as [`crate::render_states`]
/// renders `maobi write`'s executed path. Returns the image and the brush states the trace
/// holds.
pub fn render_trace(
    trace: &[TraceEntry],
    frame: &PaperFrame,
    brush: &BrushProfile,
    model: bezier_raster::ModelKind,
    char_box: &trajectory::CharBox,
    size_px: u32,
) -> (bezier_raster::Coverage, Vec<TrackPoint>) {
    let states = trace_to_states(trace, frame);
    let img = crate::render_states(&states, brush, model, Extrapolation::Refuse, char_box, size_px);
    (img, states)
}
