//! `maobi.robot.check` and `maobi.robot.export`: the checked robot program of a track, as
//! `maobi robot check --json` and `maobi robot export` build it.

use pyo3::prelude::*;
use robot_io::aubo::Motion;
use robot_io::{
    ArmKinematics, DhParams, ExportFormat, PaperFile, PaperFrame, Plan, Program, RobotConfig, TrackFile,
    build_program_chars,
};

use crate::arrays::{input_path, json_to_py};
use crate::errors::value_err;
use crate::write::Track;
use crate::{MaobiError, guarded, lib_err};

/// A dict argument as JSON text (through the `json` module), or `None` when `obj` is a path.
fn dict_json(obj: &Bound<'_, PyAny>) -> PyResult<Option<String>> {
    if obj.is_instance_of::<pyo3::types::PyDict>() {
        let text: String = obj.py().import("json")?.call_method1("dumps", (obj,))?.extract()?;
        return Ok(Some(text));
    }
    Ok(None)
}

/// `paper=`: a `paper.json` path or its content as a dict.
fn paper_arg(obj: &Bound<'_, PyAny>) -> PyResult<PaperFrame> {
    match dict_json(obj)? {
        Some(text) => {
            let file: PaperFile = serde_json::from_str(&text)
                .map_err(|e| value_err(format!("paper: not a paper.json (touch_points, size_mm): {e}")))?;
            PaperFrame::fit(&file).map_err(|e| value_err(format!("paper: {}", crate::errors::chain(&e))))
        }
        None => PaperFrame::load(&input_path(obj, "paper")?).map_err(|e| lib_err("paper", e)),
    }
}

/// `robot=`: `None` (the defaults), a `robot.json` path or its content as a dict (missing
/// fields take the defaults).
fn robot_arg(obj: Option<&Bound<'_, PyAny>>) -> PyResult<RobotConfig> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(RobotConfig::default());
    };
    match dict_json(obj)? {
        Some(text) => {
            let c: RobotConfig =
                serde_json::from_str(&text).map_err(|e| value_err(format!("robot: not a robot.json: {e}")))?;
            c.validate().map_err(|e| value_err(format!("robot: {}", crate::errors::chain(&e))))?;
            Ok(c)
        }
        None => RobotConfig::load(&input_path(obj, "robot")?).map_err(|e| lib_err("robot", e)),
    }
}

/// `track=`: a `maobi.Track` or a `track.json` path.
fn track_arg(obj: &Bound<'_, PyAny>) -> PyResult<TrackFile> {
    if let Ok(t) = obj.cast::<Track>() {
        return Ok(t.get().file.clone());
    }
    TrackFile::load(&input_path(obj, "track")?).map_err(|e| lib_err("track", e))
}

/// The checked program, as `maobi robot` builds it.
fn program(t: &TrackFile, frame: &PaperFrame, cfg: &RobotConfig) -> PyResult<(Program, robot_io::CheckReport)> {
    build_program_chars(&t.track(), t.stroke_chars.as_deref(), &t.brush, frame, cfg)
        .map_err(|e| MaobiError::new_err(format!("the program fails the check: {}", crate::errors::chain(&e))))
}

/// The safety report of a track's robot program, as `maobi robot check --json` prints it: the
/// program is built through the safety envelope (reach, press depth, speeds, paper bounds) and
/// timed on the nominal AUBO-i5 (`timing`). `track`: a `maobi.Track` or a `track.json` path;
/// `paper`: a `paper.json` path or dict; `robot`: a `robot.json` path or dict (defaults when
/// `None`). Raises `MaobiError` when the program fails the check.
#[pyfunction]
#[pyo3(signature = (track, paper, robot = None))]
pub(crate) fn robot_check<'py>(
    py: Python<'py>,
    track: &Bound<'py, PyAny>,
    paper: &Bound<'py, PyAny>,
    robot: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let t = track_arg(track)?;
    let frame = paper_arg(paper)?;
    let cfg = robot_arg(robot)?;
    let v = guarded(py, "robot.check", move || {
        let (program, report) = program(&t, &frame, &cfg)?;
        let timing = robot_io::time_program(&program, &DhParams::AUBO_I5, &cfg)
            .map_err(|e| MaobiError::new_err(format!("the program cannot be timed: {}", crate::errors::chain(&e))))?;
        let mut v = serde_json::to_value(&report).map_err(|e| lib_err("report", e))?;
        v["timing"] = serde_json::to_value(&timing).map_err(|e| lib_err("timing", e))?;
        Ok(v)
    })?;
    json_to_py(py, &v)
}

/// The program text of a track, as `maobi robot export` writes it: `format` is `"urscript"`
/// (UR `movep` moves), `"gcode"` (timed feeds) or `"aubo-lua"` (ARCS Lua: path buffers of joint
/// waypoints, which need the arm's own `kinematics` file from `maobi robot kinematics` or
/// `accept_nominal_kinematics=True`; or `motion="moves"`: compacted, blended moves). Every
/// program is the checked one (`check`); `kinematics` also times URScript and G-code.
#[pyfunction]
#[pyo3(signature = (track, paper, format = "urscript", robot = None, *, kinematics = None, motion = "path-buffer", accept_nominal_kinematics = false))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn robot_export<'py>(
    py: Python<'py>,
    track: &Bound<'py, PyAny>,
    paper: &Bound<'py, PyAny>,
    format: &str,
    robot: Option<&Bound<'py, PyAny>>,
    kinematics: Option<&Bound<'py, PyAny>>,
    motion: &str,
    accept_nominal_kinematics: bool,
) -> PyResult<String> {
    let lua = match format {
        "aubo-lua" => true,
        "urscript" | "gcode" => false,
        other => {
            return Err(value_err(format!("format={other:?}: expected \"urscript\", \"gcode\" or \"aubo-lua\"")));
        }
    };
    let by_moves = match motion {
        "moves" => true,
        "path-buffer" => false,
        other => return Err(value_err(format!("motion={other:?}: expected \"path-buffer\" or \"moves\""))),
    };
    if by_moves && !lua {
        return Err(value_err(
            "motion=\"moves\" applies to format=\"aubo-lua\" (URScript writes process moves, G-code merged moves)",
        ));
    }
    let t = track_arg(track)?;
    let frame = paper_arg(paper)?;
    let cfg = robot_arg(robot)?;
    let arm = match kinematics.filter(|k| !k.is_none()) {
        Some(k) => Some(ArmKinematics::load(&input_path(k, "kinematics")?).map_err(|e| lib_err("kinematics", e))?),
        None => None,
    };
    if lua && !by_moves && arm.is_none() && !accept_nominal_kinematics {
        return Err(value_err(
            "format=\"aubo-lua\" writes joint waypoints, which need the arm's own kinematics: give kinematics= (a file \
             from `maobi robot kinematics`), or accept_nominal_kinematics=True (the script then stops before moving an \
             arm whose controller reports other parameters), or motion=\"moves\"",
        ));
    }
    let format = match format {
        "aubo-lua" if by_moves => ExportFormat::AuboLua(Motion::Moves),
        "aubo-lua" => ExportFormat::AuboLua(Motion::PathBuffer),
        "urscript" => ExportFormat::UrScript,
        _ => ExportFormat::Gcode,
    };
    let (text, warnings) = guarded(py, "robot.export", move || {
        let (program, _) = program(&t, &frame, &cfg)?;
        let (track, title) = (t.track(), t.title());
        let plan = Plan {
            program: &program,
            config: &cfg,
            track: &track,
            stroke_chars: t.stroke_chars.as_deref(),
            title: &title,
        };
        let kin = arm.as_ref().map_or(DhParams::AUBO_I5, |k| k.kinematics);
        let e = robot_io::export_program(&plan, format, &kin)
            .map_err(|e| MaobiError::new_err(format!("export: {}", crate::errors::chain(&e))))?;
        Ok((e.text, e.warnings.iter().map(|w| w.to_string()).collect::<Vec<String>>()))
    })?;
    // What `maobi robot export` prints as warnings on stderr.
    let category = py.get_type::<pyo3::exceptions::PyUserWarning>();
    for w in warnings {
        let msg = std::ffi::CString::new(w.replace('\0', " ")).expect("no NUL");
        PyErr::warn(py, &category, &msg, 1)?;
    }
    Ok(text)
}
