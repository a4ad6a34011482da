//! `maobi preview`: one self-contained HTML file that plays the writing program over the sheet
//! (the brush moving in time, footprints appearing), with plots of h, α and speed, the robot
//! check's verdict and the ink dips. No network: the data and the script are inline.

use std::path::PathBuf;

use anyhow::{Context, Result};
use figures::track_preview;
use pipeline::parse_sheet;
use robot_io::{PaperFrame, RobotConfig};

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
    let sheet_mm = match &a.sheet {
        Some(s) => {
            let s = parse_sheet(s).with_context(|| format!("--sheet {s}"))?;
            Some([s.width_mm, s.height_mm])
        }
        None => None,
    };
    let frame = a.paper.as_deref().map(PaperFrame::load).transpose()?;
    let cfg = a.robot.as_deref().map(RobotConfig::load).transpose()?;
    let page = track_preview(&a.track, sheet_mm, frame.as_ref(), cfg.as_ref())?;
    check_output_file("-o", &a.output, a.force)?;
    write_atomic(&a.output, page.html.as_bytes())?;
    println!("preview of {} strokes written to {}", page.strokes, a.output.display());
    Ok(())
}
