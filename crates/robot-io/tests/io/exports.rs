//! Exported programs carry only checked lines (issue 26): a hostile title stays inside the
//! first comment of every format, each export reads back as the checked program, a tampered
//! text is refused by the parse-back check, and a number that would print as something else
//! (a speed of 1e-300 as `0.000000`) refuses the export.

use robot_io::{
    DhParams, ExportTarget as Target, GcodeStatement, InkStation, MAX_COMMENT_CHARS, Move, PointTimes, Program,
    ProgramTiming, ReadMove, Reload, RobotConfig, RobotError, aubo_lua, build_program, comment_text, compact_program,
    gcode, gcode_merge, point_times, read_gcode, read_lua, read_urscript, time_program, urscript, verify_gcode,
    verify_lua, verify_urscript,
};

use crate::common::{paper, pen1, small_track};

/// A pot beside the sheet, dipped before every stroke, with a dwell.
fn inked() -> RobotConfig {
    RobotConfig {
        limits: robot_io::Limits { max_step_mm: 16.0, ..Default::default() },
        ink: Some(InkStation {
            pose: [0.63, 0.10, 0.07, std::f64::consts::PI, 0.0, 0.0],
            depth_mm: 25.0,
            dwell_s: 0.5,
            reload: Reload::EveryStrokes(1),
            paper_mm: Some([330.0, 150.0]),
        }),
        ..RobotConfig::default()
    }
}

fn program(cfg: &RobotConfig) -> Program {
    build_program(&small_track(), &pen1(), &paper(), cfg).unwrap().0
}

/// The timing of `p` on the nominal arm (the exports take only its speeds).
fn timing(p: &Program, cfg: &RobotConfig) -> ProgramTiming {
    time_program(p, &DhParams::AUBO_I5, cfg).unwrap()
}

/// When the timed strokes of the small track's program reach its points.
fn times(cfg: &RobotConfig) -> PointTimes {
    let p = program(cfg);
    point_times(&p, &timing(&p, cfg)).unwrap()
}

/// The three exports of the small track (with dips) under `title`.
fn exports(title: &str) -> [(Target, String); 3] {
    let cfg = inked();
    let p = program(&cfg);
    [
        (Target::Lua, aubo_lua(&p, title).unwrap()),
        (Target::UrScript, urscript(&p, &timing(&p, &cfg), &cfg, title).unwrap()),
        (Target::Gcode, gcode(&small_track(), &times(&cfg), &cfg, title).unwrap().0),
    ]
}

/// Statements of an export as read back: moves (arm) or G-code statements.
fn statements(target: Target, text: &str) -> usize {
    match target {
        Target::Lua => read_lua(text).unwrap().moves.len(),
        Target::UrScript => read_urscript(text).unwrap().moves.len(),
        Target::Gcode => read_gcode(text).unwrap().len(),
    }
}

fn verify(target: Target, text: &str) -> Result<(), RobotError> {
    let cfg = inked();
    match target {
        Target::Lua => verify_lua(text, &program(&cfg)),
        Target::UrScript => {
            let p = program(&cfg);
            verify_urscript(text, &p, &timing(&p, &cfg), &cfg)
        }
        Target::Gcode => verify_gcode(text, &small_track(), None, &times(&cfg), &cfg),
    }
}

#[test]
fn hostile_titles_stay_inside_the_first_comment() {
    let plain = exports("t");
    let long = format!("{}\nG1 Z-40 F3000", "十".repeat(5000));
    let titles = [
        "十\nG1 Z-40 F3000",
        "十\r\n\r\nos.execute('x')",
        "a\rG1 Z-40 F3000",
        "a\u{2028}G1 Z-40\u{2029}b",
        "a\u{85}G1 Z-40",
        "a\u{0}b\u{1b}[2Jc\u{7f}",
        "a\u{b}b\u{c}c\td",
        "; G1 Z-40 F3000",
        "(G1 Z-40) %",
        "--[[ os.exit() ]]",
        "]] os.exit() --[[",
        "--[==[\nos.exit()\n]==]",
        "# movel(p[0, 0, 0, 0, 0, 0])",
        "\"'`\\\" ; os.exit() --",
        "\u{202e}0-Z 1G\u{2066}",
        long.as_str(),
    ];
    for title in titles {
        for ((target, text), (_, base)) in exports(title).iter().zip(&plain) {
            let what = format!("{target:?} for {title:?}");
            assert!(verify(*target, text).is_ok(), "{what}");
            // One line for the title, whatever it holds; the rest is the plain title's program.
            assert_eq!(text.split('\n').count(), base.split('\n').count(), "{what}");
            let (first, rest) = text.split_once('\n').unwrap();
            assert_eq!(rest, base.split_once('\n').unwrap().1, "{what}");
            assert_eq!(statements(*target, text), statements(*target, base), "{what}");
            let marker = match target {
                Target::Lua => "-- maobi writing program: ",
                Target::UrScript => "# maobi writing program: ",
                Target::Gcode => "; maobi writing program: ",
            };
            let kept = first.strip_prefix(marker).unwrap();
            assert_eq!(kept, comment_text(title, *target), "{what}");
            assert!(kept.chars().count() <= MAX_COMMENT_CHARS * 10 + 1, "{what}");
            let special: &[char] = match target {
                Target::Lua => &['[', ']', '\'', '"'],
                Target::UrScript => &['#', '\'', '"'],
                Target::Gcode => &[';', '(', ')', '%'],
            };
            assert!(!kept.contains(special), "{what}: {kept}");
            assert!(!text.contains(['\r', '\u{85}', '\u{2028}', '\u{2029}', '\u{0}', '\u{202e}']), "{what}");
        }
    }
}

#[test]
fn exports_read_back_as_the_checked_program() {
    let cfg = inked();
    let p = program(&cfg);
    let lua = read_lua(&aubo_lua(&p, "十").unwrap()).unwrap();
    let ur = read_urscript(&urscript(&p, &timing(&p, &cfg), &cfg, "十").unwrap()).unwrap();
    // URScript: the pressed moves compacted (stroke 1's (60, 61) lies on its neighbours' line),
    // each a process move.
    let compact = compact_program(&p, &cfg);
    let moves =
        |r: &robot_io::ReadProgram| r.moves.iter().filter(|(_, m)| !matches!(m, ReadMove::Progress { .. })).count();
    assert_eq!((moves(&lua), moves(&ur)), (p.move_count(), compact.move_count()));
    // The count of finished strokes after each lift, from 0.
    let progress: Vec<usize> = ur
        .moves
        .iter()
        .filter_map(|(_, m)| if let ReadMove::Progress { strokes } = m { Some(*strokes) } else { None })
        .collect();
    assert_eq!(progress, (0..=p.strokes.len()).collect::<Vec<_>>());
    assert!(compact.move_count() < p.move_count());
    let process = ur.moves.iter().filter(|(_, m)| matches!(m, ReadMove::Process { .. })).count();
    assert_eq!(process, compact.strokes.iter().map(|s| s.press.len()).sum::<usize>());
    assert_eq!(lua.speed_fraction, Some(p.speed_fraction));
    assert_eq!(lua.tcp_offset_m, p.tcp_offset_m);
    // Lua carries the poses as the program has them, to the bit here.
    let Move::Line { pose, v, .. } = p.strokes[1].press[1] else { panic!() };
    let n = 1 + p.strokes[0].moves().count() + p.strokes[1].dip.len() + p.strokes[1].approach.len() + 1;
    let lua_moves: Vec<ReadMove> =
        lua.moves.iter().map(|(_, m)| *m).filter(|m| !matches!(m, ReadMove::Progress { .. })).collect();
    let ReadMove::Line { target, v: read_v, .. } = lua_moves[n] else { panic!("{:?}", lua_moves[n]) };
    for k in 0..6 {
        assert!((target[k] - pose.0[k]).abs() <= 1e-9 * pose.0[k].abs().max(1e-3), "{target:?} {pose:?}");
    }
    assert_eq!(read_v, v);
    // The first move: a joint move to a pose the controller solves, in both languages.
    let Move::JointPose { pose: start, .. } = p.start else { panic!("{:?}", p.start) };
    let near = |t: [f64; 6]| t.iter().zip(start.0).all(|(r, w)| (r - w).abs() <= 1e-8);
    assert!(matches!(lua_moves[0], ReadMove::JointPose { target, .. } if near(target)), "{:?}", lua_moves[0]);
    assert!(matches!(ur.moves[1].1, ReadMove::JointPose { .. }), "{:?}", ur.moves[1]);
    // Joints given by the program (no longer built, still exported) read back too.
    let joints = Program { start: Move::Joint { q: [0.1, -0.2, 1.5, 0.3, 1.2, 0.0], a: 1.0, v: 0.5 }, ..p.clone() };
    let lua_q = read_lua(&aubo_lua(&joints, "q").unwrap()).unwrap();
    assert!(matches!(lua_q.moves[1].1, ReadMove::Joint { q, .. } if q[2] == 1.5), "{:?}", lua_q.moves[1]);
    let ur_q = read_urscript(&urscript(&joints, &timing(&joints, &cfg), &cfg, "q").unwrap()).unwrap();
    assert!(matches!(ur_q.moves[1].1, ReadMove::Joint { v, .. } if v == 0.5), "{:?}", ur_q.moves[1]);
    // A program whose start differs from the text's is refused.
    let e = verify_lua(&aubo_lua(&joints, "q").unwrap(), &p).unwrap_err().to_string();
    assert!(e.contains("line 11"), "{e}");
    let g = read_gcode(&gcode(&small_track(), &times(&cfg), &cfg, "十").unwrap().0).unwrap();
    let pressed =
        g.iter().filter(|(_, s)| matches!(s, GcodeStatement::Move { rapid: false, x_mm: Some(_), .. })).count();
    // Per stroke the descent and the merged moves: (60, 61) of stroke 1 and (55, 55) of
    // stroke 2 lie on their neighbours' lines and are left out.
    let merged: usize = small_track()
        .strokes
        .iter()
        .map(|st| gcode_merge(&st.points.iter().map(|p| [p.x_mm, p.y_mm, -p.h_mm]).collect::<Vec<_>>()).len())
        .sum();
    assert_eq!((pressed, merged), (small_track().point_count() - 2, small_track().point_count() - 2));
    assert_eq!(g.first().map(|s| s.1), Some(GcodeStatement::Millimetres));
    assert_eq!(g.last().map(|s| s.1), Some(GcodeStatement::End));
}

#[test]
fn tampered_exports_are_refused() {
    let [(_, lua), (_, ur), (_, g)] = exports("十");
    let insert_after = |text: &str, prefix: &str, extra: &str| {
        let i = text.find(prefix).unwrap_or_else(|| panic!("{prefix}"));
        let end = i + text[i..].find('\n').unwrap() + 1;
        format!("{}{extra}{}", &text[..end], &text[end..])
    };
    let first_line = |text: &str, prefix: &str| {
        let i = text.find(prefix).unwrap();
        text[i..i + text[i..].find('\n').unwrap()].to_string()
    };
    let lua_line = first_line(&lua, "  moveLine(");
    let ur_line = first_line(&ur, "  movel(");
    let g_line = first_line(&g, "G1 X");
    let cases: Vec<(Target, String, &str)> = vec![
        (Target::Gcode, insert_after(&g, "; maobi", "G1 Z-40.000000 F3000.000000\n"), "line 2"),
        (Target::Gcode, insert_after(&g, "; maobi", "G1 Z-40\n"), "line 2: expected `G21`"),
        (Target::Gcode, insert_after(&g, &g_line, "(G1 Z-40)\n"), "expected `G21`"),
        (Target::Gcode, insert_after(&g, &g_line, &format!("{g_line}\n")), "does not match"),
        (Target::Gcode, g.replacen(&g_line, &g_line.replace(" F", " F1"), 1), "F reads"),
        (Target::Gcode, g.replacen("G21 ; millimetres", "G21 ; (millimetres)", 1), "not inert"),
        (Target::Gcode, g.replacen("\n", "\r\n", 1), "U+000D"),
        (Target::Gcode, format!("{g}G1 Z-40.000000 F1.000000\n"), "nothing after `M2`"),
        (Target::Gcode, g.replace("M2\n", ""), "does not end with `M2`"),
        (Target::Lua, insert_after(&lua, "  setSpeedFraction", "  os.execute(\"x\")\n"), "line 10: expected a move"),
        (Target::Lua, insert_after(&lua, "-- maobi", "--[[\n"), "line 2: a comment that is not inert"),
        (Target::Lua, insert_after(&lua, &lua_line, "  --[[ x ]] os.exit()\n"), "expected a move"),
        (Target::Lua, insert_after(&lua, &lua_line, &format!("{lua_line}\n")), "does not match"),
        (Target::Lua, lua.replacen(", 0.020000, 0.000000, 0)", ", 0.000000, 0.000000, 0)", 1), "the speed reads 0"),
        (Target::Lua, lua.replacen("setSpeedFraction(1.000000)", "setSpeedFraction(0.000000)", 1), "speed fraction"),
        (Target::Lua, lua.replacen("0.048000", "0.148000", 1), "tool offset"),
        (Target::Lua, format!("{lua}os.exit()\n"), "nothing after the final `end`"),
        (Target::Lua, lua.replacen("  moveLine(", "  moveLine( ", 1), "expected a move"),
        // The progress counts the strokes finished, from 0.
        (
            Target::Lua,
            lua.replacen("setInt32(\"maobi_strokes\", 1)", "setInt32(\"maobi_strokes\", 3)", 1),
            "progress register reads 3",
        ),
        (Target::Lua, lua.replacen("setInt32(\"maobi_strokes\", 1)", "setInt32(\"maobi\", 1)", 1), "expected a move"),
        // AUBO's documented environment, exactly.
        (Target::Lua, lua.replacen("select_robot(1)", "select_robot(2)", 1), "line 4: expected"),
        (Target::Lua, lua.replacen("\n", "\r\n\r\n", 1), "U+000D"),
        (
            Target::Lua,
            lua.replacen("(ret ~= nil and ret ~= 0) then error(", "(ret ~= nil and ret ~= 1) then error(", 1),
            "line 13: expected",
        ),
        (
            Target::Lua,
            lua.replacen(
                "    moveJoint(q, ",
                "    moveJoint({0.000000, 0.000000, 0.000000, 0.000000, 0.000000, 0.000000}, ",
                1,
            ),
            "line 14",
        ),
        (Target::Lua, lua.replacen("  do\n", "", 1), "line 11: expected a move"),
        (Target::UrScript, ur.replacen("  movej(p[", "  movel(p[", 1), "expected a move"),
        (Target::UrScript, insert_after(&ur, &ur_line, "  popup(\"x\")\n"), "`popup` is not in the URScript subset"),
        // UR's order is `t` before `r`: the other way round is refused.
        (
            Target::UrScript,
            ur.replacen(&ur_line, &ur_line.replace(", t=0, r=", ", r=").replace(")", ", t=0)"), 1),
            "expected a move",
        ),
        // The progress register and its count are the plan's.
        (
            Target::UrScript,
            ur.replacen("write_output_integer_register(24, 1)", "write_output_integer_register(24, 2)", 1),
            "progress register reads 2",
        ),
        (
            Target::UrScript,
            ur.replacen("write_output_integer_register(24, 1)", "write_output_integer_register(23, 1)", 1),
            "expected a move",
        ),
        (Target::UrScript, insert_after(&ur, &ur_line, &format!("{ur_line}\n")), "does not match"),
        (Target::UrScript, ur.replacen(&ur_line, &ur_line.replace("r=0.000000", "r=0.100000"), 1), "blend radius"),
        (Target::UrScript, ur.replacen("movel(p[0.", "movel(p[1.", 1), "x reads"),
        (Target::UrScript, insert_after(&ur, "def maobi_program", "  # x\u{2028}movel(p[0])\n"), "U+2028"),
        (Target::UrScript, format!("{ur}maobi_program()\n"), "nothing after `end`"),
        (Target::UrScript, ur.replace("def maobi_program():", "def other():"), "`def maobi_program():`"),
    ];
    for (target, text, needle) in cases {
        let e = verify(target, &text).expect_err(needle);
        assert!(matches!(e, RobotError::Unsafe { .. }), "{e}");
        let msg = e.to_string();
        assert!(msg.contains(needle) && msg.contains(target.name()), "{target:?} {needle}: {msg}");
    }
}

#[test]
fn numbers_that_would_print_as_something_else_refuse_the_export() {
    let cfg = inked();
    let base = program(&cfg);
    fn slow_line(p: &mut Program, v_m_s: f64) {
        if let Move::Line { v, .. } = &mut p.strokes[0].press[0] {
            *v = v_m_s;
        }
    }
    // URScript has no speed fraction, and its process speeds come from the timing, at most
    // the program's speed (an infinite one bounds nothing).
    type Change = fn(&mut Program);
    let arm: [(Change, &str, bool); 4] = [
        (|p| p.speed_fraction = 1e-300, "the speed fraction reads 0 where it is 1e-300", false),
        (|p| slow_line(p, 1e-300), "the speed reads 0 where it is 1e-300", true),
        (|p| p.tcp_offset_m = f64::NAN, "expected `  setTcpOffset", true),
        (|p| slow_line(p, f64::INFINITY), "expected a move", false),
    ];
    let t = timing(&base, &cfg);
    for (change, needle, ur_refuses) in arm {
        let mut p = base.clone();
        change(&mut p);
        let e = aubo_lua(&p, "t").unwrap_err().to_string();
        assert!(e.contains(needle), "{e}");
        assert_eq!(urscript(&p, &t, &cfg, "t").is_err(), ur_refuses, "{needle}");
    }
    // A write speed of 1e-9 m/s prints in full and reads back as itself.
    let mut p = base.clone();
    slow_line(&mut p, 1e-9);
    let lua = aubo_lua(&p, "t").unwrap();
    assert!(lua.contains(", 0.000000001, 0.000500, 0)"), "{lua}");
    assert!(urscript(&p, &t, &cfg, "t").unwrap().contains(", a=0.300000, v=0.000000001, r="));
    // G-code (strokes not timed: fed at the write speed): a feed rate that prints as 0, and
    // one that prints in full.
    let untimed = PointTimes { strokes: vec![None, None] };
    for (write, ok) in [(1e-300, false), (1e-9, true), (f64::NAN, false)] {
        let c = RobotConfig { write_speed_m_s: write, ..cfg.clone() };
        match gcode(&small_track(), &untimed, &c, "t") {
            Ok((g, _)) => assert!(ok && g.contains(" F0.000060\n"), "{write:e}: {g}"),
            Err(e) => assert!(!ok && e.to_string().contains("G-code"), "{write:e}: {e}"),
        }
    }
}

#[test]
fn tampered_path_buffer_lua_is_refused() {
    use robot_io::{aubo_lua_path_buffer, verify_lua_path_buffer};
    let cfg = inked();
    let p = program(&cfg);
    let kin = DhParams::AUBO_I5;
    let lua = aubo_lua_path_buffer(&p, &kin, &cfg, "十").unwrap();
    verify_lua_path_buffer(&lua, &p, &kin, &cfg).unwrap();
    let read = read_lua(&lua).unwrap();
    // The parameters as printed: within 1e-9 relative (the script's check allows 1e-6).
    let k = read.kinematics.unwrap();
    let rows = [(k.a_m, kin.a_m), (k.alpha_rad, kin.alpha_rad), (k.d_m, kin.d_m), (k.theta_rad, kin.theta_rad)];
    for (r, w) in rows {
        assert!(r.iter().zip(w).all(|(r, w)| (r - w).abs() <= 1e-9 * w.abs()), "{r:?} {w:?}");
    }
    assert_eq!(read.path_buffers.len(), p.strokes.len());
    let t = timing(&p, &cfg);
    for (b, t) in read.path_buffers.iter().zip(&t.strokes) {
        assert_eq!((b.size, b.waypoints.len(), b.interval_s), (t.joints.len(), t.joints.len(), 0.01));
        assert_eq!(b.name, format!("maobi_stroke_{}", t.stroke + 1));
    }
    // A move-per-point check of a path-buffer text, and the reverse, are refused.
    let e = verify_lua(&lua, &p).unwrap_err().to_string();
    assert!(e.contains("checks the controller's kinematics where the plan does not"), "{e}");
    let e = verify_lua_path_buffer(&aubo_lua(&p, "十").unwrap(), &p, &kin, &cfg).unwrap_err().to_string();
    assert!(e.contains("does not check the controller's kinematics"), "{e}");
    // Another arm's parameters: its own program, which this text is not.
    let longer = DhParams { a_m: [0.0, 0.0, 0.41, 0.376, 0.0, 0.0], ..kin };
    let e = verify_lua_path_buffer(&lua, &p, &longer, &cfg).unwrap_err().to_string();
    assert!(e.contains("the kinematics checked: a[2] reads 0.408 where it is 0.41"), "{e}");
    let bad = DhParams { d_m: [f64::NAN, 0.1215, 0.0, 0.0, 0.1025, 0.094], ..kin };
    let e = aubo_lua_path_buffer(&p, &bad, &cfg, "十").unwrap_err().to_string();
    assert!(e.contains("the arm's kinematics: d[0]"), "{e}");
    let waypoint = lua.lines().find(|l| l.starts_with("      {")).unwrap();
    let mut changed: Vec<String> = waypoint.split(", ").map(String::from).collect();
    changed[1] = "1.000000".into();
    let q0 = lua.lines().find(|l| l.starts_with("    local q0 = {")).unwrap();
    let want = lua.lines().find(|l| l.starts_with("    local want = {")).unwrap();
    let eval = lua.lines().find(|l| l.starts_with("    pathBufferEval(")).unwrap();
    // The start solved near the first waypoint; the form that asks the arm's joints instead.
    let ik = lua.lines().find(|l| l.contains("inverseKinematics(")).unwrap();
    let (start, near_end) = (ik.find("inverseKinematics(").unwrap() + 18, ik.find("}, {").unwrap());
    let from_arm = format!("{}getJointPositions(){}", &ik[..start], &ik[near_end + 1..]);
    let kin_block_start = lua.find("  do\n    local want").unwrap();
    let kin_block_end = lua.find("  setTcpOffset").unwrap();
    let cases: Vec<(String, &str)> = vec![
        (lua.replacen(waypoint, &changed.join(", "), 1), "waypoint 0, joint 2 reads 1"),
        (lua.replacen(waypoint, &format!("{waypoint}\n{waypoint}"), 1), "more waypoints than the"),
        (lua.replacen(q0, &q0.replacen("{", "{1.000000, ", 1), 1), "expected `    local q0"),
        (lua.replacen(q0, &q0.replace("local q0 = {", "local q0 = {1"), 1), "the first waypoint checked, joint 1"),
        (lua.replacen(want, &want.replacen("0.408000", "0.428000", 1), 1), "a[2] reads 0.428"),
        (lua.replacen(eval, &eval.replacen("3.000000", "30.000000", 1), 1), "the joint acceleration limit"),
        (lua.replacen("<= 0.000001)", "<= 0.100000)", 1), "expected `        if type(got[i])"),
        (lua.replacen("if polls > 500 then", "if polls > 5000000 then", 1), "expected `      if polls > 500"),
        (lua.replacen("<= 0.005000)", "<= 6.000000)", 1), "expected `      if type(q) ~= \"table\""),
        (lua.replacen("    pathBufferFree(name)\n", "", 1), "expected `    pathBufferFree(name)`"),
        (lua.replacen("maobi_stroke_1\"", "maobi_stroke_2\"", 1), "named `maobi_stroke_2`"),
        (lua.replacen(ik, &ik.replacen("inverseKinematics({", "inverseKinematics({1", 1), 1), "solved near, joint 1"),
        (lua.replacen(ik, &from_arm, 1), "solved near other joints than the plan's"),
        (
            format!("{}{}", &lua[..kin_block_start], &lua[kin_block_end..]),
            "does not check the controller's kinematics first",
        ),
    ];
    for (text, needle) in cases {
        assert_ne!(text, lua, "{needle}");
        let e = verify_lua_path_buffer(&text, &p, &kin, &cfg).expect_err(needle).to_string();
        assert!(e.contains(needle), "{needle}: {e}");
    }
}

/// The times the URScript speeds and G-code feeds come from: each stroke starts at 0 and
/// reaches its last point when its timing ends, never faster between two points than the
/// timed stroke's peak speed; a timing of another program is refused.
#[test]
fn point_times_follow_the_timed_strokes() {
    let cfg = inked();
    let p = program(&cfg);
    let t = timing(&p, &cfg);
    let times = point_times(&p, &t).unwrap();
    assert_eq!(times.strokes.len(), 2);
    for (st, ts) in p.strokes.iter().zip(&t.strokes) {
        let at = times.strokes[st.index].as_ref().unwrap();
        let path = robot_io::pressed_path(st);
        assert_eq!(at.len(), path.len());
        assert_eq!(at[0], 0.0);
        // The last point is first reached within one waypoint interval of the end, at rest.
        assert!((ts.duration_s - at[at.len() - 1]).abs() <= ts.interval_s + 1e-9, "{at:?} {}", ts.duration_s);
        for (k, w) in at.windows(2).enumerate() {
            let d =
                (nalgebra::Vector3::from(path[k + 1].position()) - nalgebra::Vector3::from(path[k].position())).norm();
            assert!(w[1] > w[0] && d / (w[1] - w[0]) <= ts.peak_speed_m_s * (1.0 + 1e-6), "point {k}: {w:?}, {d} m");
        }
    }
    // The timing of the track moved 1 mm is not this program's.
    let mut moved = small_track();
    moved.strokes.iter_mut().flat_map(|s| s.points.iter_mut()).for_each(|q| q.x_mm += 1.0);
    let other = build_program(&moved, &pen1(), &paper(), &cfg).unwrap().0;
    let e = point_times(&p, &timing(&other, &cfg)).unwrap_err().to_string();
    assert!(e.contains("does not lie on the stroke's pressed path"), "{e}");
}

#[test]
fn export_program_writes_each_format_as_its_exporter_does() {
    use robot_io::aubo::Motion;
    use robot_io::{ExportFormat, Plan, aubo_lua_path_buffer, check_blends, export_program, gcode_chars};
    let cfg = inked();
    let (p, track) = (program(&cfg), small_track());
    let plan = Plan { program: &p, config: &cfg, track: &track, stroke_chars: None, title: "二" };
    let kin = DhParams::AUBO_I5;
    let export = |f| export_program(&plan, f, &kin).unwrap();
    // Moves: the compacted program, its blends checked.
    let compact = compact_program(&p, &cfg);
    check_blends(&compact).unwrap();
    let moves = export(ExportFormat::AuboLua(Motion::Moves));
    assert_eq!(moves.text, aubo_lua(&compact, "二").unwrap());
    assert_eq!(moves.summary, format!("{} moves", compact.move_count()));
    let buffers = export(ExportFormat::AuboLua(Motion::PathBuffer));
    assert_eq!(buffers.text, aubo_lua_path_buffer(&p, &kin, &cfg, "二").unwrap());
    let calls = buffers.text.lines().filter(|l| l.trim_start().starts_with("move")).count();
    assert_eq!(buffers.summary, format!("{} path buffers, {calls} motion calls", p.strokes.len()));
    let ur = export(ExportFormat::UrScript);
    assert_eq!(ur.text, urscript(&p, &timing(&p, &cfg), &cfg, "二").unwrap());
    let ur_moves =
        read_urscript(&ur.text).unwrap().moves.iter().filter(|(_, m)| !matches!(m, ReadMove::Progress { .. })).count();
    assert_eq!(ur.summary, format!("{ur_moves} moves"));
    let g = export(ExportFormat::Gcode);
    let (text, warnings) = gcode_chars(&track, None, &times(&cfg), &cfg, "二").unwrap();
    assert_eq!((&g.text, &g.warnings), (&text, &warnings));
    let g_moves = read_gcode(&text).unwrap().iter().filter(|(_, s)| matches!(s, GcodeStatement::Move { .. })).count();
    assert_eq!(g.summary, format!("{g_moves} moves"));
    // The speeds are timed on the arm given.
    let ur5e = time_program(&p, &DhParams::UR5E, &cfg).unwrap();
    let other = export_program(&plan, ExportFormat::UrScript, &DhParams::UR5E).unwrap();
    assert_eq!(other.text, urscript(&p, &ur5e, &cfg, "二").unwrap());
}
