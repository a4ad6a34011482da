//! One entry to every exporter: a plan written in the format asked for, with what it holds in
//! words.

use crate::RobotError;
use crate::aubo::Motion;
use crate::controller::Plan;
use crate::kinematics::DhParams;
use crate::program::{check_blends, compact_program};
use crate::timing::time_program;

use super::{aubo_lua, aubo_lua_path_buffer, gcode_chars, point_times, urscript};

/// A program format [`export_program`] writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExportFormat {
    /// An AUBO ARCS Lua script: with [`Motion::PathBuffer`] each pressed stroke one path buffer
    /// of joint waypoints on its timing ([`aubo_lua_path_buffer`]); with [`Motion::Moves`] a
    /// `moveLine` per point of the compacted program ([`compact_program`], its blends checked by
    /// [`check_blends`], then [`aubo_lua`]).
    AuboLua(Motion),
    /// A URScript program ([`urscript`]) on the program's timing.
    UrScript,
    /// G-code for a 3-axis brush plotter ([`gcode_chars`]) fed at the program's timing.
    Gcode,
}

/// A program written by [`export_program`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Exported {
    /// The program's text, read back and compared with the plan by its exporter.
    pub text: String,
    /// What it holds, in words: `"120 moves"`, or for path buffers `"3 path buffers, 9 motion
    /// calls"`.
    pub summary: String,
    /// What the exporter warns of (G-code: settings a plotter cannot follow as configured).
    pub warnings: Vec<String>,
}

/// Writes `plan` as `format`. `kin`: the arm's kinematics (modified DH) the path buffers' joints
/// are computed on and the URScript and G-code speeds are timed on (neither of those exports a
/// joint, so the nominal AUBO-i5 serves where no other arm is known).
///
/// # Examples
/// ```
/// use robot_io::brush_model::{Stroke, Track, TrackPoint};
/// use robot_io::aubo::Motion;
/// use robot_io::{DhParams, ExportFormat, Plan, RobotConfig, build_program, export_program, level_frame_in_front};
/// let pt = |x: f64| TrackPoint { x_mm: x, y_mm: 60.0, h_mm: 3.0, alpha_rad: 0.0, beta_rad: 0.0 };
/// let track = Track { strokes: vec![Stroke { points: (0..=20).map(|i| pt(30.0 + f64::from(i))).collect() }] };
/// let frame = level_frame_in_front([50.0, 60.0], [0.0, 0.0, 210.0, 297.0]);
/// let profile = robot_io::brush_model::BrushProfile::builtin("pen1").unwrap();
/// let cfg = RobotConfig::default();
/// let (program, _) = build_program(&track, &profile, &frame, &cfg).unwrap();
/// let plan = Plan { program: &program, config: &cfg, track: &track, stroke_chars: None, title: "一" };
/// let lua = export_program(&plan, ExportFormat::AuboLua(Motion::PathBuffer), &DhParams::AUBO_I5).unwrap();
/// assert_eq!(lua.summary, format!("1 path buffers, {} motion calls", lua.text.lines().filter(|l| l.trim_start().starts_with("move")).count()));
/// let g = export_program(&plan, ExportFormat::Gcode, &DhParams::AUBO_I5).unwrap();
/// assert!(g.text.starts_with("; maobi writing program: 一\n") && g.summary.ends_with(" moves"));
/// ```
///
/// # Errors
/// As the format's exporter, the timing ([`time_program`]) and, for [`Motion::Moves`],
/// [`check_blends`].
pub fn export_program(plan: &Plan<'_>, format: ExportFormat, kin: &DhParams) -> Result<Exported, RobotError> {
    let (program, cfg) = (plan.program, plan.config);
    let counted =
        |text: String, moves: usize| Exported { text, summary: format!("{moves} moves"), warnings: Vec::new() };
    Ok(match format {
        ExportFormat::AuboLua(Motion::Moves) => {
            let compact = compact_program(program, cfg);
            check_blends(&compact)?;
            counted(aubo_lua(&compact, plan.title)?, compact.move_count())
        }
        ExportFormat::AuboLua(Motion::PathBuffer) => {
            let text = aubo_lua_path_buffer(program, kin, cfg, plan.title)?;
            let buffers = text.matches("movePathBuffer(name)").count();
            let calls = text.lines().filter(|l| l.trim_start().starts_with("move")).count();
            Exported { summary: format!("{buffers} path buffers, {calls} motion calls"), text, warnings: Vec::new() }
        }
        ExportFormat::UrScript => {
            let timing = time_program(program, kin, cfg)?;
            let text = urscript(program, &timing, cfg, plan.title)?;
            let moves = text.lines().filter(|l| l.starts_with("  move")).count();
            counted(text, moves)
        }
        ExportFormat::Gcode => {
            let timing = time_program(program, kin, cfg)?;
            let times = point_times(program, &timing)?;
            let (text, warnings) = gcode_chars(plan.track, plan.stroke_chars, &times, cfg, plan.title)?;
            let moves = text.lines().filter(|l| l.starts_with("G0") || l.starts_with("G1")).count();
            Exported { warnings, ..counted(text, moves) }
        }
    })
}
