//! `maobi preview`: one self-contained HTML file that plays the writing program over the sheet
//! (the brush moving in time, footprints appearing), with plots of h, α and speed, the robot
//! check's verdict and the ink dips. No network: the data and the script are inline.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use pipeline::{Grid, parse_sheet};
use robot_io::PaperFrame;
use robot_io::RobotConfig;
use robot_io::TrackFile;
use serde_json::Value;

use figures::{PreviewInput, preview_html};

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
    let html = preview_html(&input, frame.as_ref(), cfg.as_ref(), None)?;
    check_output_file("-o", &a.output, a.force)?;
    write_atomic(&a.output, html.as_bytes())?;
    println!("preview of {} strokes written to {}", input.track.strokes.len(), a.output.display());
    Ok(())
}
