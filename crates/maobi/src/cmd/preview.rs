//! `maobi preview`: one self-contained HTML file that plays the writing program over the sheet
//! (the brush moving in time, footprints appearing), with plots of h, α and speed, the robot
//! check's verdict and the ink dips. No network: the data and the script are inline.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use brush_model::{BrushProfile, Extrapolation, ForwardModel, Track, TrackPoint};
use pipeline::{Grid, SheetTrack, parse_sheet};
use robot_io::{
    PaperFrame, RobotConfig, TaggedEntry, TraceEntry, TrackFile, build_program_chars, level_frame_in_front,
    trace_to_states,
};
use serde_json::{Value, json};

use crate::common::{check_output_file, write_atomic};

/// Arguments of `maobi preview`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// `track.json` from `maobi write` (one character or a whole sheet).
    track: PathBuf,
    /// The paper to show: A4, WxH or paper.json (default: the track's sheet, or the box around
    /// its strokes).
    #[arg(long)]
    sheet: Option<String>,
    /// `paper.json` for the robot check (default: a level sheet in front of the AUBO-i5).
    #[arg(long)]
    paper: Option<PathBuf>,
    /// `robot.json` (speeds, ink station); defaults when omitted.
    #[arg(long)]
    robot: Option<PathBuf>,
    /// Output HTML file.
    #[arg(short, long)]
    output: PathBuf,
    /// Replace the output file if it exists (without it, an existing file is refused).
    #[arg(long)]
    force: bool,
}

/// What the preview shows.
pub struct PreviewInput<'a> {
    /// Title.
    pub title: String,
    /// Sheet `[w, h]`, mm.
    pub sheet_mm: [f64; 2],
    /// Grid under each box.
    pub grid: Grid,
    /// Character boxes `[x0, y0, size]`, mm.
    pub boxes: Vec<[f64; 3]>,
    /// Each stroke's character, when known.
    pub stroke_chars: Option<Vec<usize>>,
    /// The brush.
    pub brush: &'a BrushProfile,
    /// The strokes.
    pub track: Track,
}

/// Runs the command.
pub fn run(a: Args) -> Result<()> {
    let name = a.track.display().to_string();
    let text = std::fs::read_to_string(&a.track).with_context(|| format!("{name}: cannot read"))?;
    let v: Value = serde_json::from_str(&text).with_context(|| format!("{name}: not JSON"))?;
    let tf = TrackFile::load(&a.track)?;
    let track = tf.track();
    if track.point_count() == 0 {
        bail!("{name}: the track has no points");
    }
    let nums = |key: &str, n: usize| -> Result<Option<Vec<f64>>> {
        match v.get(key) {
            None | Some(Value::Null) => Ok(None),
            Some(x) => {
                let out: Vec<f64> = serde_json::from_value(x.clone())
                    .with_context(|| format!("{name}: field `{key}` must be a list of {n} numbers"))?;
                if out.len() != n || out.iter().any(|x| !x.is_finite()) {
                    bail!("{name}: field `{key}` must be a list of {n} finite numbers");
                }
                Ok(Some(out))
            }
        }
    };
    let mut boxes = Vec::new();
    if let Some(chars) = v.get("chars").and_then(Value::as_array) {
        for c in chars {
            let b: [f64; 3] = serde_json::from_value(c["char_box_mm"].clone())
                .with_context(|| format!("{name}: chars[].char_box_mm must be [x0, y0, size]"))?;
            boxes.push(b);
        }
    } else if let Some(b) = nums("char_box_mm", 3)? {
        boxes.push([b[0], b[1], b[2]]);
    }
    let stroke_chars: Option<Vec<usize>> = match v.get("stroke_chars") {
        None | Some(Value::Null) => None,
        Some(x) => Some(
            serde_json::from_value(x.clone())
                .with_context(|| format!("{name}: field `stroke_chars` must be a list of character indices"))?,
        ),
    };
    let grid: Grid = match v.get("grid") {
        None | Some(Value::Null) => Grid::None,
        Some(x) => serde_json::from_value(x.clone()).with_context(|| format!("{name}: field `grid`"))?,
    };
    let sheet_mm = if let Some(s) = &a.sheet {
        let s = parse_sheet(s).with_context(|| format!("--sheet {s}"))?;
        [s.width_mm, s.height_mm]
    } else if let Some(s) = nums("sheet_mm", 2)? {
        [s[0], s[1]]
    } else {
        // The box around the strokes and the character boxes, with a margin.
        let (mut w, mut h) = (0.0f64, 0.0f64);
        for p in track.points() {
            w = w.max(p.x_mm);
            h = h.max(p.y_mm);
        }
        for b in &boxes {
            w = w.max(b[0] + b[2]);
            h = h.max(b[1] + b[2]);
        }
        [w + 10.0, h + 10.0]
    };
    if !(sheet_mm.iter().all(|v| v.is_finite() && *v > 0.0 && *v <= pipeline::MAX_SHEET_MM)) {
        bail!("{name}: the sheet {:?} mm is not a usable size", sheet_mm);
    }
    let frame = a.paper.as_deref().map(PaperFrame::load).transpose()?;
    let cfg = a.robot.as_deref().map(RobotConfig::load).transpose()?;
    let input = PreviewInput {
        title: tf.char.clone().unwrap_or_else(|| "track".into()),
        sheet_mm,
        grid,
        boxes,
        stroke_chars,
        brush: &tf.brush,
        track,
    };
    let html = preview_html(&input, frame.as_ref(), cfg.as_ref())?;
    check_output_file("-o", &a.output, a.force)?;
    write_atomic(&a.output, html.as_bytes())?;
    println!("preview of {} strokes written to {}", input.track.strokes.len(), a.output.display());
    Ok(())
}

/// The preview of a sheet track (what `maobi write` writes beside the sheet).
pub fn sheet_preview(t: &SheetTrack, frame: Option<&PaperFrame>, cfg: Option<&RobotConfig>) -> Result<String> {
    let input = PreviewInput {
        title: t.char.clone(),
        sheet_mm: t.sheet_mm,
        grid: t.grid,
        boxes: t.chars.iter().map(|c| c.char_box_mm).collect(),
        stroke_chars: Some(t.stroke_chars.clone()),
        brush: &t.brush,
        track: Track { strokes: t.strokes.clone() },
    };
    preview_html(&input, frame, cfg)
}

/// A level sheet in front of the AUBO-i5, its centre at base (0.45, 0.05, 0.05) m (as
/// `maobi write` places a character for its executed figure).
fn level_frame(sheet_mm: [f64; 2]) -> PaperFrame {
    level_frame_in_front([sheet_mm[0] / 2.0, sheet_mm[1] / 2.0], [0.0, 0.0, sheet_mm[0], sheet_mm[1]])
}

fn r2(v: f64) -> f64 {
    (v * 100.0).round() / 100.0
}

/// A timed sample of the executed path: time, paper x, y, depth h, tilt α, and whether it belongs
/// to an ink dip.
struct Sample {
    t: f64,
    p: TrackPoint,
    dip: bool,
}

/// The program's samples as `robot send` runs it on the simulator
/// ([`robot_io::sim::execute_as_sent_tagged`]: each pressed stroke one path buffer on its
/// timing, the other moves on the controller's time law), tagged with whether each move is part
/// of an ink dip. The first joint move from the controller's home pose is left out: the timeline
/// starts (t = 0) with the brush at the safe height above the first stroke.
fn execute_tagged(tagged: &[TaggedEntry], frame: &PaperFrame) -> Vec<Sample> {
    let start = tagged.iter().take_while(|e| e.stroke.is_none()).count();
    let t0 = if start > 0 { tagged[start - 1].entry.t_s } else { 0.0 };
    let (entries, dips): (Vec<TraceEntry>, Vec<bool>) = tagged[start..].iter().map(|e| (e.entry, e.dip)).unzip();
    let states = trace_to_states(&entries, frame);
    entries.iter().zip(states).zip(dips).map(|((e, p), dip)| Sample { t: e.t_s - t0, p, dip }).collect()
}

/// Builds the preview HTML: the program is checked with `paper` (default: a level sheet in front
/// of the arm) and `robot.json` (default settings) and executed as the simulator would; the
/// footprints come from the forward model over the executed path, each at the time the brush
/// reaches it. A refused program is previewed from the planned track (timed at the write speed)
/// with the refusal as the verdict.
///
/// # Errors
/// When the brush profile refuses the track's presses.
pub fn preview_html(input: &PreviewInput<'_>, paper: Option<&PaperFrame>, cfg: Option<&RobotConfig>) -> Result<String> {
    let default_cfg = RobotConfig::default();
    let cfg = cfg.unwrap_or(&default_cfg);
    let level = level_frame(input.sheet_mm);
    let frame = paper.unwrap_or(&level);
    let where_ = if paper.is_some() { "on the given paper.json" } else { "on a level sheet in front of the AUBO-i5" };
    // Checked and timed as `robot check` does it (the nominal i5, the simulator's arm) and
    // played as `robot send` sends it: the timeline's pressed time is the timing's. A timing
    // beyond a limit is a refusal like the check's.
    let built =
        build_program_chars(&input.track, input.stroke_chars.as_deref(), input.brush, frame, cfg).and_then(|(p, r)| {
            let kin = robot_io::DhParams::AUBO_I5;
            let timing = robot_io::time_program(&p, &kin, cfg)?;
            let motion = robot_io::sim::SendMotion::PathBuffer(&timing);
            let tagged = robot_io::sim::execute_as_sent_tagged(&p, &kin, motion)?;
            Ok((r, timing, tagged))
        });
    let (samples, verdict, safe, dips, strokes_s) = match built {
        Ok((report, timing, tagged)) => {
            let s = execute_tagged(&tagged, frame);
            // When each stroke's path buffer runs on the timeline: [start, end], s.
            // (The timeline starts where the start move ends, as in `execute_tagged`.)
            let t0 = tagged.iter().take_while(|e| e.stroke.is_none()).last().map_or(0.0, |e| e.entry.t_s);
            let mut strokes_s: Vec<[f64; 2]> = Vec::new();
            let mut current = None;
            for e in tagged.iter().filter(|e| e.entry.kind == robot_io::TraceKind::PathBuffer) {
                let at = r2(e.entry.t_s - t0);
                match strokes_s.last_mut() {
                    Some(span) if current == e.stroke => span[1] = at,
                    _ => {
                        strokes_s.push([at, at]);
                        current = e.stroke;
                    }
                }
            }
            // Ink is off unless the robot configuration names an ink pot: say so, not "0 dips".
            let dips = if cfg.ink.is_none() {
                "ink dipping off (no \"ink\" in robot.json: see fixtures/robot/robot-ink.json)".to_string()
            } else {
                format!("{} ink dip(s)", report.dips)
            };
            // One time: the program as the simulator runs it (what the timeline plays).
            let run_s = s.last().map_or(0.0, |x| x.t);
            let v = format!(
                "safe ({where_}): {} strokes, {} points, {} moves, {dips}; deepest press {:.2} mm; {run_s:.1} s to write, {:.1} s of it on the paper (the strokes' timing; the longest stroke {:.1} s)",
                report.strokes,
                report.points,
                report.moves,
                report.max_press_mm,
                timing.writing_s,
                timing.strokes.iter().map(|t| t.duration_s).fold(0.0, f64::max)
            );
            (s, v, true, report.dips, strokes_s)
        }
        Err(e) => {
            // The planned track, pen-down paths at the write speed, a second of travel between.
            let mut out = Vec::new();
            let mut t = 0.0;
            for st in &input.track.strokes {
                let mut prev: Option<&TrackPoint> = None;
                for p in &st.points {
                    if let Some(q) = prev {
                        t += (p.x_mm - q.x_mm).hypot(p.y_mm - q.y_mm) / (cfg.write_speed_m_s * 1000.0);
                    }
                    out.push(Sample { t, p: *p, dip: false });
                    prev = Some(p);
                }
                t += 1.0;
            }
            (out, format!("refused ({where_}): {e}"), false, 0, Vec::new())
        }
    };
    // Footprints: the forward model over each contact (a run of pressed samples), each stamp
    // timed by the nearest sample along the run.
    let model = ForwardModel::default();
    let mut feet: Vec<f64> = Vec::new();
    let mut i = 0;
    while i < samples.len() {
        if samples[i].p.h_mm <= 0.0 || samples[i].dip || !frame.contains(samples[i].p.x_mm, samples[i].p.y_mm) {
            i += 1;
            continue;
        }
        let start = i;
        while i < samples.len() && samples[i].p.h_mm > 0.0 && !samples[i].dip {
            i += 1;
        }
        // One sample of lift before and after, so the forward model sees the contact begin and end.
        let (a, b) = (start.saturating_sub(1), (i + 1).min(samples.len()));
        let run: Vec<TrackPoint> = samples[a..b].iter().map(|s| s.p).collect();
        let sweep = model.sweep(input.brush, &run, Extrapolation::Refuse);
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
            let Ok(fp) = input.brush.predict_oriented(&st.press(), Extrapolation::Refuse) else { continue };
            let o = fp.outline(st.anchor(), st.beta_rad);
            feet.push(r2(samples[a + j].t));
            for c in [o.upper, o.lower] {
                for p in &c.points[..3] {
                    feet.push(r2(p.x_mm));
                    feet.push(r2(p.y_mm));
                }
            }
        }
    }
    // Thin the samples for the animation and plots (at most ~8000).
    let step = samples.len().div_ceil(8000).max(1);
    let mut path: Vec<f64> = Vec::new();
    let mut prev: Option<&Sample> = None;
    for (k, s) in samples.iter().enumerate() {
        if k % step != 0 && k + 1 != samples.len() {
            continue;
        }
        let speed = prev.map_or(0.0, |q| {
            let dt = s.t - q.t;
            let d =
                ((s.p.x_mm - q.p.x_mm).powi(2) + (s.p.y_mm - q.p.y_mm).powi(2) + (s.p.h_mm - q.p.h_mm).powi(2)).sqrt();
            if dt > 1e-9 { d / dt } else { 0.0 }
        });
        path.extend([
            (s.t * 1000.0).round() / 1000.0,
            r2(s.p.x_mm),
            r2(s.p.y_mm),
            r2(s.p.h_mm),
            (s.p.alpha_rad.to_degrees() * 100.0).round() / 100.0,
            r2(speed),
            if s.dip { 1.0 } else { 0.0 },
        ]);
        prev = Some(s);
    }
    // Dip intervals.
    let mut dip_spans: Vec<[f64; 2]> = Vec::new();
    let mut was_dip = false;
    for x in &samples {
        match (x.dip, was_dip) {
            (true, false) => dip_spans.push([x.t, x.t]),
            (true, true) => {
                if let Some(last) = dip_spans.last_mut() {
                    last[1] = x.t;
                }
            }
            _ => {}
        }
        was_dip = x.dip;
    }
    let data = json!({
        "title": input.title,
        "sheet_mm": input.sheet_mm,
        "grid": input.grid,
        "boxes": input.boxes,
        "verdict": verdict,
        "safe": safe,
        "dips": dips,
        "dip_spans": dip_spans.iter().map(|d| [r2(d[0]), r2(d[1])]).collect::<Vec<_>>(),
        "strokes_s": strokes_s,
        "duration_s": samples.last().map_or(0.0, |s| s.t),
        "path": path,
        "feet": feet,
        "brush": input.brush.name,
    });
    // No `<` at all inside the inline JSON (`\u003c` is the same string to JSON): `</script`
    // would end the element and `<!--` would change how the browser reads the rest of it.
    let data = serde_json::to_string(&data)?.replace('<', "\\u003c");
    Ok(fill(TEMPLATE, &html_escape(&input.title), &data))
}

/// The template with its two placeholders filled in one pass, so that text put in for one can
/// never be read as the other.
fn fill(template: &str, title: &str, data: &str) -> String {
    let mut out = String::with_capacity(template.len() + title.len() + data.len());
    let mut rest = template;
    while let Some(i) = rest.find("__") {
        out.push_str(&rest[..i]);
        let tail = &rest[i..];
        if let Some(r) = tail.strip_prefix("__TITLE__") {
            out.push_str(title);
            rest = r;
        } else if let Some(r) = tail.strip_prefix("__DATA__") {
            out.push_str(data);
            rest = r;
        } else {
            out.push_str("__");
            rest = &tail[2..];
        }
    }
    out.push_str(rest);
    out
}

fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;").replace('\'', "&#39;")
}

const TEMPLATE: &str = include_str!("preview.html");
