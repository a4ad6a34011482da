//! A sheet's execution: its program built and checked as `robot check` does it, timed and run
//! on the simulator's arm as `robot send` sends it ([`run_sheet`]), and the footprints the brush
//! leaves along what ran, each at the time the brush reaches it ([`run_footprints`], the forward
//! model with the profile's hairs). `maobi write`'s preview and `maobi preview` play what these
//! return.

use brush_model::{BrushProfile, Extrapolation, ForwardModel, PointMm, Track, TrackPoint};
use robot_io::PaperFrame;

use crate::ExecutedRun;
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
    /// The footprints the brush leaves along the samples ([`run_footprints`]).
    pub footprints: Vec<TimedFootprint>,
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
/// moves on the controller's time law); sweeps the footprints the brush leaves along it.
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
/// assert!(!run.footprints.is_empty());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn run_sheet(
    track: &Track,
    stroke_chars: Option<&[usize]>,
    brush: &BrushProfile,
    frame: &PaperFrame,
    cfg: &RobotConfig,
) -> Result<SheetRun, RobotError> {
    run_sheet_with(track, stroke_chars, brush, frame, cfg, None)
}

/// [`run_sheet`], playing `kept` when it is the run of the very program built here with the
/// same `cfg` (what [`crate::write_char`] keeps with [`crate::WriteOptions::keep_run`]: the
/// preview of one character written plays the run its executed figure scored) rather than
/// timing and running it again. The program is always built and checked here (while the kept
/// run's footprints are swept beside it, used only when it is played).
///
/// # Errors
/// As [`run_sheet`].
pub fn run_sheet_with(
    track: &Track,
    stroke_chars: Option<&[usize]>,
    brush: &BrushProfile,
    frame: &PaperFrame,
    cfg: &RobotConfig,
    kept: Option<&ExecutedRun>,
) -> Result<SheetRun, RobotError> {
    let build = || build_program_chars(track, stroke_chars, brush, frame, cfg);
    let played = |k: &ExecutedRun| {
        let samples = timed_samples(&k.trace, frame);
        let footprints = run_footprints(&samples, brush, frame);
        (samples, footprints)
    };
    let ((program, report), ran) = match kept {
        Some(k) => {
            let (built, swept) = rayon::join(build, || played(k));
            let built = built?;
            let ran = k.is_of(&built.0, cfg).then_some((k, swept));
            (built, ran)
        }
        None => (build()?, None),
    };
    let fresh;
    let (run, (samples, footprints)) = match ran {
        Some(ran) => ran,
        None => {
            fresh = ExecutedRun::run(program, cfg)?;
            (&fresh, played(&fresh))
        }
    };
    let tagged = &run.trace[..];
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
    Ok(SheetRun { report, timing: run.timing.clone(), samples, strokes_s, footprints })
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
    use rayon::prelude::*;
    // The contacts first, then each swept on rayon's pool (in order: the same footprints as one
    // pass over them).
    let mut contacts = Vec::new();
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
        contacts.push((start.saturating_sub(1), (i + 1).min(samples.len())));
    }
    let model = ForwardModel::default();
    let contact_feet = |&(a, b): &(usize, usize)| {
        let run: Vec<TrackPoint> = samples[a..b].iter().map(|s| s.point).collect();
        let sweep = model.sweep(brush, &run, Extrapolation::Refuse);
        let mut feet = Vec::with_capacity(sweep.stamps.len());
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
        feet
    };
    let per_contact: Vec<Vec<TimedFootprint>> = contacts.par_iter().map(contact_feet).collect();
    per_contact.concat()
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{WriteOptions, prepare, write_char};
    use trajectory::{CharBox, embedded_glyph};

    /// The run `write_char` keeps is played when the same program is built again (the same
    /// sheet run as timing and running it afresh), and only then.
    #[test]
    fn a_kept_run_is_played_for_its_own_program_only() {
        let pen1 = BrushProfile::builtin("pen1").unwrap();
        let p = prepare(embedded_glyph('十').unwrap(), None).unwrap();
        // The box centred on an 80 mm sheet: the sheet's level frame and the executed figure's
        // frame put the same point in front of the arm, so the programs are the same.
        let b = CharBox { x0_mm: 10.0, y0_mm: 10.0, size_mm: 60.0 };
        let opts = WriteOptions { size: 64, keep_run: true, ..WriteOptions::default() };
        let r = write_char(&p, &pen1, b, &opts).unwrap();
        let kept = r.executed_run.as_ref().expect("kept with keep_run");
        let frame = robot_io::level_frame_in_front([40.0, 40.0], [0.0, 0.0, 80.0, 80.0]);
        let cfg = RobotConfig::default();
        let chars = vec![0; r.track.strokes.len()];
        let run = |k: Option<&ExecutedRun>| run_sheet_with(&r.track, Some(&chars), &pen1, &frame, &cfg, k).unwrap();
        let fresh = run(None);
        let played = run(Some(kept));
        assert_eq!(
            (&played.samples, &played.strokes_s, &played.timing, &played.footprints),
            (&fresh.samples, &fresh.strokes_s, &fresh.timing, &fresh.footprints)
        );
        assert_eq!(played.report, fresh.report);
        // Played, not run again: a run whose clock goes at half speed shows.
        let mut slow = kept.clone();
        slow.trace.iter_mut().for_each(|e| e.entry.t_s *= 2.0);
        assert_ne!(run(Some(&slow)).samples, fresh.samples);
        // A run made with another configuration, or of another program, is not played.
        let mut other_cfg = slow.clone();
        other_cfg.cfg.write_speed_m_s *= 0.5;
        assert_eq!(run(Some(&other_cfg)).samples, fresh.samples);
        let mut other_program = slow;
        other_program.program.strokes.pop();
        assert_eq!(run(Some(&other_program)).samples, fresh.samples);
        // Nothing is kept unless asked.
        let plain = write_char(&p, &pen1, b, &WriteOptions { keep_run: false, ..opts }).unwrap();
        assert!(plain.executed_run.is_none());
        // Keeping it changes no figure.
        assert_eq!(plain.report.executed, r.report.executed);
    }
}
