//! Program exporters: AUBO ARCS Lua script, Universal Robots URScript, and G-code for 3-axis
//! brush plotters.

use brush_model::Track;

use crate::program::{DWELL_SINK_MM, Move, Program, RobotConfig, dip_plan};

fn f(v: f64) -> String {
    let s = format!("{v:.6}");
    if s == "-0.000000" { "0.000000".into() } else { s }
}

fn list(v: &[f64]) -> String {
    v.iter().map(|x| f(*x)).collect::<Vec<_>>().join(", ")
}

/// An ARCS Lua script (`return function(api) ... end`) that sets the tool offset and speed
/// fraction and runs every move.
pub fn aubo_lua(program: &Program, title: &str) -> String {
    let mut s = String::new();
    s.push_str(&format!(
        "-- maobi writing program: {title}\n-- {} strokes, {} moves. Generated; do not edit by hand.\n",
        program.strokes.len(),
        program.move_count()
    ));
    s.push_str("return function(api)\n");
    s.push_str("  local robot_name = api:getRobotNames()[1]\n");
    s.push_str("  local robot = api:getRobotInterface(robot_name)\n");
    s.push_str(&format!("  robot:getRobotConfig():setTcpOffset({{0, 0, {}, 0, 0, 0}})\n", f(program.tcp_offset_m)));
    s.push_str("  local mc = robot:getMotionControl()\n");
    s.push_str(&format!("  mc:setSpeedFraction({})\n", f(program.speed_fraction)));
    let emit = |s: &mut String, m: &Move| match m {
        Move::Joint { q, a, v } => {
            s.push_str(&format!("  mc:moveJoint({{{}}}, {}, {}, 0, 0)\n", list(q), f(*a), f(*v)))
        }
        Move::JointPose { pose, a, v } => {
            // The controller solves the joints from where the arm is, and refuses to move when
            // it cannot.
            s.push_str(&format!(
                "  local q, ret = robot:getRobotAlgorithm():inverseKinematics(robot:getRobotState():getJointPositions(), {{{}}})\n",
                list(&pose.0)
            ));
            s.push_str("  if ret ~= 0 then error(\"maobi: the controller cannot reach the first pose\") end\n");
            s.push_str(&format!("  mc:moveJoint(q, {}, {}, 0, 0)\n", f(*a), f(*v)))
        }
        Move::Line { pose, a, v, blend_m } => {
            s.push_str(&format!("  mc:moveLine({{{}}}, {}, {}, {}, 0)\n", list(&pose.0), f(*a), f(*v), f(*blend_m)))
        }
    };
    emit(&mut s, &program.start);
    for st in &program.strokes {
        if !st.dip.is_empty() {
            s.push_str(&format!("  -- ink dip before stroke {}\n", st.index + 1));
            for m in &st.dip {
                emit(&mut s, m);
            }
        }
        s.push_str(&format!("  -- stroke {}\n", st.index + 1));
        for m in st.moves().skip(st.dip.len()) {
            emit(&mut s, m);
        }
    }
    s.push_str("end\n");
    s
}

/// A URScript program: `movel(p[x, y, z, rx, ry, rz], a, v, r=blend)` with rotation vectors.
pub fn urscript(program: &Program, title: &str) -> String {
    let mut s = format!("# maobi writing program: {title}\ndef maobi_write():\n");
    s.push_str(&format!("  set_tcp(p[0, 0, {}, 0, 0, 0])\n", f(program.tcp_offset_m)));
    let emit = |s: &mut String, m: &Move| match m {
        Move::Joint { q, a, v } => s.push_str(&format!("  movej([{}], a={}, v={})\n", list(q), f(*a), f(*v))),
        // A pose target: the UR controller solves the joints.
        Move::JointPose { pose, a, v } => s.push_str(&format!(
            "  movej(p[{}, {}], a={}, v={})\n",
            list(&pose.position()),
            list(&pose.rotation_vector()),
            f(*a),
            f(*v)
        )),
        Move::Line { pose, a, v, blend_m } => {
            let p = pose.position();
            let r = pose.rotation_vector();
            s.push_str(&format!(
                "  movel(p[{}, {}], a={}, v={}, r={})\n",
                list(&p),
                list(&r),
                f(*a),
                f(*v),
                f(*blend_m)
            ));
        }
    };
    emit(&mut s, &program.start);
    for st in &program.strokes {
        if !st.dip.is_empty() {
            s.push_str(&format!("  # ink dip before stroke {}\n", st.index + 1));
            for m in &st.dip {
                emit(&mut s, m);
            }
        }
        s.push_str(&format!("  # stroke {}\n", st.index + 1));
        for m in st.moves().skip(st.dip.len()) {
            emit(&mut s, m);
        }
    }
    s.push_str("end\nmaobi_write()\n");
    s
}

/// G-code for a 3-axis brush plotter working in paper millimetres: X, Y on the paper, Z = −H
/// (Z 0 where the tip touches, positive up), feed rates from the configured speeds. Tilt α and
/// direction β cannot be expressed and are ignored; the returned warnings say so. Ink dips
/// (robot.json `ink` with `paper_mm`) go to the pot, down `depth_mm` below the paper plane,
/// soak (sink `DWELL_SINK_MM` further over `dwell_s`, as the arm programs do) and back up,
/// before the strokes the reload rule picks.
pub fn gcode(track: &Track, cfg: &RobotConfig, title: &str) -> (String, Vec<String>) {
    gcode_chars(track, None, cfg, title)
}

/// [`gcode`] with the track's character boundaries (`stroke_chars`, for the reload rule
/// `before_each_char`).
pub fn gcode_chars(
    track: &Track,
    stroke_chars: Option<&[usize]>,
    cfg: &RobotConfig,
    title: &str,
) -> (String, Vec<String>) {
    let mut warnings = Vec::new();
    let station = cfg.station();
    let dips = match (&station, station.and_then(|s| s.paper_mm)) {
        (Some(st), Some(_)) => match dip_plan(track, stroke_chars, st) {
            Ok(d) => d,
            Err(e) => {
                warnings.push(format!("no ink dips in the G-code: {e}"));
                vec![false; track.strokes.len()]
            }
        },
        (Some(_), None) => {
            warnings.push(
                "robot.json ink.paper_mm (where the plotter finds the ink, paper mm) is not set: the G-code has no ink dips"
                    .into(),
            );
            vec![false; track.strokes.len()]
        }
        _ => vec![false; track.strokes.len()],
    };
    if track.points().any(|p| p.alpha_rad.abs() > 1e-9) {
        warnings.push("G-code has no tilt axis: α is ignored".to_string());
    }
    warnings.push("G-code has no brush rotation axis: β is ignored".to_string());
    let write_f = cfg.write_speed_m_s * 60_000.0;
    let travel_f = cfg.travel_speed_m_s * 60_000.0;
    let mut s = format!("; maobi writing program: {title}\nG21 ; millimetres\nG90 ; absolute\n");
    s.push_str(&format!("G0 Z{}\n", f(cfg.lift_mm)));
    for (i, st) in track.strokes.iter().enumerate() {
        let Some(first) = st.points.first() else { continue };
        if let (true, Some(st)) = (dips[i], station) {
            let [x, y] = st.paper_mm.unwrap_or([0.0, 0.0]);
            s.push_str(&format!("; ink dip before stroke {}\n", i + 1));
            s.push_str(&format!("G0 X{} Y{} F{}\n", f(x), f(y), f(travel_f)));
            s.push_str(&format!("G1 Z{} F{}\n", f(-st.depth_mm), f(travel_f * 0.5)));
            if st.dwell_s > 0.0 {
                let soak_f = DWELL_SINK_MM / st.dwell_s * 60.0;
                s.push_str(&format!(
                    "G1 Z{} F{} ; dwell {} s\n",
                    f(-st.depth_mm - DWELL_SINK_MM),
                    f(soak_f),
                    st.dwell_s
                ));
            }
            s.push_str(&format!("G0 Z{}\n", f(cfg.lift_mm)));
        }
        s.push_str(&format!("; stroke {}\n", i + 1));
        s.push_str(&format!("G0 X{} Y{} F{}\n", f(first.x_mm), f(first.y_mm), f(travel_f)));
        for p in &st.points {
            s.push_str(&format!("G1 X{} Y{} Z{} F{}\n", f(p.x_mm), f(p.y_mm), f(-p.h_mm), f(write_f)));
        }
        s.push_str(&format!("G0 Z{}\n", f(cfg.lift_mm)));
    }
    s.push_str("M2\n");
    (s, warnings)
}
