//! The preview page: one self-contained HTML file that plays a track's program over its sheet
//! (the brush moving in time, footprints appearing), with plots of h, α and speed, the robot
//! check's verdict and the ink dips. No network: the data and the script are inline. What it
//! plays comes from the pipeline ([`pipeline::run_sheet`], [`pipeline::run_footprints`]); this
//! module only lays it out. `maobi preview` and `maobi write` write it.

use std::path::Path;

use brush_model::{BrushProfile, Track};
use pipeline::{ExecutedRun, Grid, RunSample, SheetTrack};
use robot_io::PaperFrame;
use robot_io::RobotConfig;
use robot_io::{TrackFile, level_frame_in_front};
use serde::{Deserialize, Serialize};

use crate::{FigureError, Result};

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

/// The preview of a sheet track (what `maobi write` writes beside the sheet); `ran`: the run
/// of the same program already made, if any ([`preview_html`]).
pub fn sheet_preview(
    t: &SheetTrack,
    frame: Option<&PaperFrame>,
    cfg: Option<&RobotConfig>,
    ran: Option<&ExecutedRun>,
) -> Result<String> {
    let input = PreviewInput {
        title: t.char.clone(),
        sheet_mm: t.sheet_mm,
        grid: t.grid,
        boxes: t.chars.iter().map(|c| c.char_box_mm).collect(),
        stroke_chars: Some(t.stroke_chars.clone()),
        brush: &t.brush,
        track: Track { strokes: t.strokes.clone() },
    };
    preview_html(&input, frame, cfg, ran)
}

/// A preview page made from a `track.json` file ([`track_preview`]).
#[derive(Clone, Debug)]
pub struct TrackPreview {
    /// The page.
    pub html: String,
    /// The strokes it plays.
    pub strokes: usize,
}

/// What a sheet's `track.json` adds for the preview to what [`TrackFile`] reads.
#[derive(Deserialize)]
struct SheetFields {
    #[serde(default)]
    chars: Option<Vec<CharBoxField>>,
    #[serde(default)]
    grid: Option<Grid>,
}

/// A sheet character's box.
#[derive(Deserialize)]
struct CharBoxField {
    char_box_mm: [f64; 3],
}

/// The preview of a `track.json` as `maobi write` writes it (a character's or a sheet's), on
/// the sheet `sheet_mm` (`[w, h]` mm; default: the file's sheet, else the box around its
/// strokes and character boxes with a 10 mm margin), checked on `frame` and `cfg` as
/// [`preview_html`] does.
///
/// # Errors
/// [`FigureError::Read`] when the file cannot be read, [`FigureError::Track`] when it is not a
/// valid track, [`FigureError::TrackFile`] when it has no points or gives no usable sheet size;
/// and the errors of [`preview_html`].
///
/// # Examples
/// ```no_run
/// let page = figures::track_preview(std::path::Path::new("out/track.json"), None, None, None)?;
/// std::fs::write("preview.html", page.html)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn track_preview(
    path: &Path,
    sheet_mm: Option<[f64; 2]>,
    frame: Option<&PaperFrame>,
    cfg: Option<&RobotConfig>,
) -> Result<TrackPreview> {
    let refused = |what: String| FigureError::TrackFile { path: path.to_path_buf(), what };
    let bytes = pipeline::read_bounded(path, robot_io::MAX_FILE_BYTES, "a track file maobi writes")?;
    let text = String::from_utf8(bytes).map_err(|_| refused("not UTF-8 text".into()))?;
    let tf = TrackFile::from_json(&text, &path.display().to_string())?;
    let extra: SheetFields = serde_json::from_str(&text)
        .map_err(|e| refused(format!("chars[].char_box_mm must be [x0, y0, size] and grid a grid name ({e})")))?;
    let track = tf.track();
    if track.point_count() == 0 {
        return Err(refused("the track has no points".into()));
    }
    let boxes: Vec<[f64; 3]> = match (extra.chars, tf.char_box_mm) {
        (Some(chars), _) => chars.iter().map(|c| c.char_box_mm).collect(),
        (None, b) => b.into_iter().collect(),
    };
    let sheet_mm = sheet_mm.or(tf.sheet_mm).unwrap_or_else(|| {
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
    });
    if !(sheet_mm.iter().all(|v| v.is_finite() && *v > 0.0 && *v <= pipeline::MAX_SHEET_MM)) {
        return Err(refused(format!("the sheet {sheet_mm:?} mm is not a usable size")));
    }
    let input = PreviewInput {
        title: tf.char.clone().unwrap_or_else(|| "track".into()),
        sheet_mm,
        grid: extra.grid.unwrap_or(Grid::None),
        boxes,
        stroke_chars: tf.stroke_chars.clone(),
        brush: &tf.brush,
        track,
    };
    let html = preview_html(&input, frame, cfg, None)?;
    Ok(TrackPreview { html, strokes: input.track.strokes.len() })
}

/// A level sheet in front of the AUBO-i5, its centre at base (0.45, 0.05, 0.05) m (as
/// `maobi write` places a character for its executed figure).
fn level_frame(sheet_mm: [f64; 2]) -> PaperFrame {
    level_frame_in_front([sheet_mm[0] / 2.0, sheet_mm[1] / 2.0], [0.0, 0.0, sheet_mm[0], sheet_mm[1]])
}

/// The safe program's verdict: what it holds and how long it takes.
fn verdict(run: &pipeline::SheetRun, cfg: &RobotConfig, where_: &str) -> String {
    let report = &run.report;
    // Ink is off unless the robot configuration names an ink pot: say so, not "0 dips".
    let dips = if cfg.ink.is_none() {
        "ink dipping off (no \"ink\" in robot.json: see fixtures/robot/robot-ink.json)".to_string()
    } else {
        format!("{} ink dip(s)", report.dips)
    };
    // One time: the program as the simulator runs it (what the timeline plays).
    let run_s = run.samples.last().map_or(0.0, |x| x.t_s);
    format!(
        "safe ({where_}): {} strokes, {} points, {} moves, {dips}; deepest press {:.2} mm; {run_s:.1} s to write, {:.1} s of it on the paper (the strokes' timing; the longest stroke {:.1} s)",
        report.strokes,
        report.points,
        report.moves,
        report.max_press_mm,
        run.timing.writing_s,
        run.timing.strokes.iter().map(|t| t.duration_s).fold(0.0, f64::max)
    )
}

fn r2(v: f64) -> f64 {
    (v * 100.0).round() / 100.0
}

/// Builds the preview HTML: the program is checked with `paper` (default: a level sheet in front
/// of the arm) and `robot.json` (default settings) and executed as the simulator would
/// ([`pipeline::run_sheet`]); the footprints come from the forward model over the executed path,
/// each at the time the brush reaches it ([`pipeline::run_footprints`]). A refused program is
/// previewed from the planned track (timed at the write speed) with the refusal as the verdict.
/// `ran`: a run already made ([`pipeline::run_sheet_with`]: played only when it is the run of
/// the program built here, as `maobi write` keeps it for one character).
///
/// # Errors
/// When the page's data cannot be written as JSON.
///
/// # Examples
/// ```
/// use brush_model::{BrushProfile, Stroke, Track, TrackPoint};
///
/// let pen1 = BrushProfile::builtin("pen1")?;
/// // A 20 mm stroke pressed 12 mm across an 80 mm sheet.
/// let p = |x: f64| TrackPoint { x_mm: x, y_mm: 40.0, h_mm: 12.0, alpha_rad: 0.0, beta_rad: 0.0 };
/// let input = figures::PreviewInput {
///     title: "一".into(),
///     sheet_mm: [80.0, 80.0],
///     grid: pipeline::Grid::None,
///     boxes: vec![[10.0, 10.0, 60.0]],
///     stroke_chars: None,
///     brush: &pen1,
///     track: Track { strokes: vec![Stroke { points: (0..=20).map(|i| p(30.0 + f64::from(i))).collect() }] },
/// };
/// let page = figures::preview_html(&input, None, None, None)?;
/// assert!(page.starts_with("<!DOCTYPE html>") && page.contains("safe (on a level sheet"));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn preview_html(
    input: &PreviewInput<'_>,
    paper: Option<&PaperFrame>,
    cfg: Option<&RobotConfig>,
    ran: Option<&ExecutedRun>,
) -> Result<String> {
    let default_cfg = RobotConfig::default();
    let cfg = cfg.unwrap_or(&default_cfg);
    let level = level_frame(input.sheet_mm);
    let frame = paper.unwrap_or(&level);
    let where_ = if paper.is_some() { "on the given paper.json" } else { "on a level sheet in front of the AUBO-i5" };
    // Checked and timed as `robot check` does it (the nominal i5, the simulator's arm) and
    // played as `robot send` sends it: the timeline's pressed time is the timing's. A timing
    // beyond a limit is a refusal like the check's.
    let (samples, footprints, verdict, safe, dips, strokes_s) =
        match pipeline::run_sheet_with(&input.track, input.stroke_chars.as_deref(), input.brush, frame, cfg, ran) {
            Ok(run) => {
                let v = verdict(&run, cfg, where_);
                let spans = run.strokes_s.iter().map(|s| [r2(s[0]), r2(s[1])]).collect();
                (run.samples, run.footprints, v, true, run.report.dips, spans)
            }
            // The planned track, pen-down paths at the write speed, a second of travel between.
            Err(e) => {
                let samples = pipeline::planned_samples(&input.track, cfg.write_speed_m_s);
                let footprints = pipeline::run_footprints(&samples, input.brush, frame);
                (samples, footprints, format!("refused ({where_}): {e}"), false, 0, Vec::new())
            }
        };
    let mut feet: Vec<f64> = Vec::new();
    for f in footprints {
        feet.push(r2(f.t_s));
        for p in f.outline {
            feet.push(r2(p.x_mm));
            feet.push(r2(p.y_mm));
        }
    }
    let path = path_data(&samples);
    let dip_spans = dip_spans(&samples);
    let data = PageData {
        boxes: &input.boxes,
        brush: &input.brush.name,
        dip_spans: dip_spans.iter().map(|d| [r2(d[0]), r2(d[1])]).collect(),
        dips,
        duration_s: samples.last().map_or(0.0, |s| s.t_s),
        feet,
        grid: input.grid,
        path,
        safe,
        sheet_mm: input.sheet_mm,
        strokes_s,
        title: &input.title,
        verdict,
    };
    // No `<` at all inside the inline JSON (`\u003c` is the same string to JSON): `</script`
    // would end the element and `<!--` would change how the browser reads the rest of it.
    let data = serde_json::to_string(&data)?.replace('<', "\\u003c");
    Ok(fill(TEMPLATE, &html_escape(&input.title), &data))
}

/// The data the page's script plays, written straight to JSON (its keys in the order the page
/// has always had them: sorted).
#[derive(Serialize)]
struct PageData<'a> {
    boxes: &'a [[f64; 3]],
    brush: &'a str,
    dip_spans: Vec<[f64; 2]>,
    dips: usize,
    duration_s: f64,
    feet: Vec<f64>,
    grid: Grid,
    path: Vec<f64>,
    safe: bool,
    sheet_mm: [f64; 2],
    strokes_s: Vec<[f64; 2]>,
    title: &'a str,
    verdict: String,
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

/// The samples thinned for the animation and plots (at most ~8000): t, x, y, h, α (degrees),
/// speed (mm/s) and dip (0/1) each.
fn path_data(samples: &[RunSample]) -> Vec<f64> {
    // Thin the samples for the animation and plots (at most ~8000).
    let step = samples.len().div_ceil(8000).max(1);
    let mut path: Vec<f64> = Vec::new();
    let mut prev: Option<&RunSample> = None;
    for (k, s) in samples.iter().enumerate() {
        if k % step != 0 && k + 1 != samples.len() {
            continue;
        }
        let speed = prev.map_or(0.0, |q| {
            let dt = s.t_s - q.t_s;
            let d = ((s.point.x_mm - q.point.x_mm).powi(2)
                + (s.point.y_mm - q.point.y_mm).powi(2)
                + (s.point.h_mm - q.point.h_mm).powi(2))
            .sqrt();
            if dt > 1e-9 { d / dt } else { 0.0 }
        });
        path.extend([
            (s.t_s * 1000.0).round() / 1000.0,
            r2(s.point.x_mm),
            r2(s.point.y_mm),
            r2(s.point.h_mm),
            (s.point.alpha_rad.to_degrees() * 100.0).round() / 100.0,
            r2(speed),
            if s.dip { 1.0 } else { 0.0 },
        ]);
        prev = Some(s);
    }
    path
}

/// The ink dips' intervals, s.
fn dip_spans(samples: &[RunSample]) -> Vec<[f64; 2]> {
    let mut dip_spans: Vec<[f64; 2]> = Vec::new();
    let mut was_dip = false;
    for x in samples {
        match (x.dip, was_dip) {
            (true, false) => dip_spans.push([x.t_s, x.t_s]),
            (true, true) => {
                if let Some(last) = dip_spans.last_mut() {
                    last[1] = x.t_s;
                }
            }
            _ => {}
        }
        was_dip = x.dip;
    }
    dip_spans
}

const TEMPLATE: &str = include_str!("preview.html");

#[cfg(test)]
mod tests {
    use super::*;
    use brush_model::{Stroke, TrackPoint};

    /// The JSON between the page's data element tags.
    fn data_of(page: &str) -> serde_json::Value {
        let start = page.find(r#"id="data">"#).unwrap() + r#"id="data">"#.len();
        let end = start + page[start..].find("</script>").unwrap();
        serde_json::from_str(&page[start..end]).unwrap()
    }

    fn input<'a>(brush: &'a BrushProfile, title: &str, h_mm: f64) -> PreviewInput<'a> {
        let p = |x: f64| TrackPoint { x_mm: x, y_mm: 40.0, h_mm, alpha_rad: 0.0, beta_rad: 0.0 };
        PreviewInput {
            title: title.into(),
            sheet_mm: [80.0, 80.0],
            grid: Grid::None,
            boxes: vec![[10.0, 10.0, 60.0]],
            stroke_chars: Some(vec![0]),
            brush,
            track: Track { strokes: vec![Stroke { points: (0..=20).map(|i| p(30.0 + f64::from(i))).collect() }] },
        }
    }

    #[test]
    fn the_page_plays_the_run_with_its_footprints_and_escapes_the_title() {
        let pen1 = BrushProfile::builtin("pen1").unwrap();
        let page = preview_html(&input(&pen1, "</script><b>", 12.0), None, None, None).unwrap();
        // The title is text in the head and a string in the data, never markup.
        assert!(page.contains("maobi preview: &lt;/script&gt;&lt;b&gt;"));
        let data = data_of(&page);
        assert_eq!(data["title"], "</script><b>");
        assert_eq!(data["safe"], true);
        assert!(data["verdict"].as_str().unwrap().starts_with("safe (on a level sheet in front of the AUBO-i5)"));
        // Every footprint is a time and six points; the path is seven numbers a sample.
        let feet = data["feet"].as_array().unwrap();
        assert!(!feet.is_empty() && feet.len() % 13 == 0);
        assert_eq!(data["path"].as_array().unwrap().len() % 7, 0);
        assert_eq!(data["strokes_s"].as_array().unwrap().len(), 1);
    }

    #[test]
    fn a_refused_program_is_previewed_from_its_plan_with_the_refusal() {
        let pen1 = BrushProfile::builtin("pen1").unwrap();
        // 500 mm of press: far beyond what the robot check lets through.
        let page = preview_html(&input(&pen1, "deep", 500.0), None, None, None).unwrap();
        let data = data_of(&page);
        assert_eq!(data["safe"], false);
        assert!(data["verdict"].as_str().unwrap().starts_with("refused"));
        assert!(!data["path"].as_array().unwrap().is_empty());
    }

    #[test]
    fn a_track_file_is_previewed_on_its_sheet_or_the_box_around_it() {
        let pen1 = BrushProfile::builtin("pen1").unwrap();
        let i = input(&pen1, "一", 1.0);
        let file = |sheet_mm: Option<[f64; 2]>, strokes| TrackFile {
            char: Some("一".into()),
            char_box_mm: Some([10.0, 10.0, 60.0]),
            sheet_mm,
            brush: pen1.clone(),
            strokes,
            stroke_chars: None,
        };
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("track.json");
        let save = |t: &TrackFile| std::fs::write(&path, serde_json::to_string(t).unwrap()).unwrap();
        save(&file(None, i.track.strokes.clone()));
        let page = track_preview(&path, None, None, None).unwrap();
        assert_eq!(page.strokes, 1);
        // No sheet: the box around the strokes and the char box, 10 mm beyond.
        assert_eq!(data_of(&page.html)["sheet_mm"], serde_json::json!([80.0, 80.0]));
        save(&file(Some([210.0, 297.0]), i.track.strokes.clone()));
        let page = track_preview(&path, None, None, None).unwrap();
        assert_eq!(data_of(&page.html)["sheet_mm"], serde_json::json!([210.0, 297.0]));
        let page = track_preview(&path, Some([100.0, 100.0]), None, None).unwrap();
        assert_eq!(data_of(&page.html)["sheet_mm"], serde_json::json!([100.0, 100.0]));
        save(&file(None, vec![]));
        let e = track_preview(&path, None, None, None).unwrap_err().to_string();
        assert!(e.contains("track.json") && e.contains("no points"), "{e}");
        let e = track_preview(&dir.path().join("none.json"), None, None, None).unwrap_err();
        assert!(matches!(e, FigureError::Read(_)), "{e}");
    }
}
