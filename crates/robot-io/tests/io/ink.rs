//! The ink station and its reload rule: dips only between strokes, at the rule's points, carried
//! by the simulator's execution and by the Lua, URScript and G-code exports.

// Poses written as a teach pendant shows them: rx = 3.14 rad (the tool flipped), not π.
#![allow(clippy::approx_constant, reason = "3.14 rad is a pendant-style rx, deliberately not π")]

use brush_model::{Stroke, Track, TrackPoint};
use robot_io::{
    DWELL_SINK_MM, InkStation, Move, PaperFrame, Reload, RobotConfig, build_program, build_program_chars, dip_plan,
    execute_program, execute_program_tagged, trace_to_states,
};

use crate::common::pen1;

/// The fixture's paper (300 × 300 mm, level, origin at base (0.3, 0.25, 0.05)).
fn paper() -> PaperFrame {
    PaperFrame::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/robot/paper.json")).unwrap()
}

/// `strokes` horizontal strokes of 21 points 0.5 mm apart (10 mm pressed each), one per row.
fn rows(strokes: usize) -> Track {
    Track {
        strokes: (0..strokes)
            .map(|k| Stroke {
                points: (0..21)
                    .map(|i| TrackPoint {
                        x_mm: 40.0 + 0.5 * i as f64,
                        y_mm: 40.0 + 10.0 * k as f64,
                        h_mm: 12.0,
                        alpha_rad: 0.0,
                        beta_rad: 0.0,
                    })
                    .collect(),
            })
            .collect(),
    }
}

fn station(reload: Reload) -> InkStation {
    // Beside the fixture's sheet (paper x = 330 mm), the pot's surface 20 mm above the paper.
    InkStation {
        pose: [0.63, 0.10, 0.07, std::f64::consts::PI, 0.0, 0.0],
        depth_mm: 25.0,
        dwell_s: 0.5,
        reload,
        paper_mm: Some([330.0, 150.0]),
    }
}

fn cfg(reload: Reload) -> RobotConfig {
    RobotConfig { ink: Some(station(reload)), ..RobotConfig::default() }
}

#[test]
fn reload_rules_pick_stroke_boundaries() {
    let t = rows(6);
    let plan = |r: Reload, chars: Option<&[usize]>| dip_plan(&t, chars, &station(r)).unwrap();
    assert_eq!(plan(Reload::EveryStrokes(2), None), [true, false, true, false, true, false]);
    // 10 mm per stroke, a load lasts 25 mm: two strokes per load.
    assert_eq!(plan(Reload::EveryMm(25.0), None), [true, false, true, false, true, false]);
    assert_eq!(plan(Reload::EveryMm(30.0), None), [true, false, false, true, false, false]);
    // A load shorter than one stroke: a dip before every stroke, never inside one.
    assert_eq!(plan(Reload::EveryMm(3.0), None), [true; 6]);
    let chars = [0, 0, 0, 1, 1, 2];
    assert_eq!(plan(Reload::BeforeEachChar, Some(&chars)), [true, false, false, true, false, true]);
    // Without the character boundaries that rule is refused, naming what is missing.
    let e = dip_plan(&t, None, &station(Reload::BeforeEachChar)).unwrap_err().to_string();
    assert!(e.contains("before_each_char") && e.contains("stroke_chars"), "{e}");
    let e = dip_plan(&t, Some(&[0, 1]), &station(Reload::BeforeEachChar)).unwrap_err().to_string();
    assert!(e.contains("2 entries for 6 strokes"), "{e}");
}

#[test]
fn the_tagged_execution_is_the_plain_one_with_its_dips_and_strokes_marked() {
    let t = rows(4);
    let f = paper();
    let (prog, _) = build_program_chars(&t, Some(&[0, 0, 1, 1]), &pen1(), &f, &cfg(Reload::BeforeEachChar)).unwrap();
    let plain = execute_program(&prog);
    let tagged = execute_program_tagged(&prog);
    // The same samples in the same order.
    assert_eq!(tagged.iter().map(|e| e.entry).collect::<Vec<_>>(), plain);
    // The first move (from home) comes first and is untagged; then strokes 0..4 in order.
    let start = tagged.iter().take_while(|e| e.stroke.is_none()).count();
    assert!(start > 0 && tagged[..start].iter().all(|e| !e.dip));
    let strokes: Vec<usize> = tagged[start..].iter().map(|e| e.stroke.expect("a stroke's sample")).collect();
    assert!(strokes.windows(2).all(|w| w[1] == w[0] || w[1] == w[0] + 1));
    assert_eq!((strokes[0], strokes[strokes.len() - 1]), (0, 3));
    // Dip samples: only before the strokes that dip (0 and 2), each stroke's dip before its
    // other moves, and every sample in the pot is one of them.
    let mut dipping: Vec<usize> = tagged.iter().filter(|e| e.dip).filter_map(|e| e.stroke).collect();
    dipping.dedup();
    assert_eq!(dipping, [0, 2]);
    for k in [0, 2] {
        let own: Vec<bool> = tagged.iter().filter(|e| e.stroke == Some(k)).map(|e| e.dip).collect();
        let first_non_dip = own.iter().position(|d| !d).unwrap();
        assert!(first_non_dip > 0 && own[first_non_dip..].iter().all(|d| !d), "stroke {k}");
    }
    let states = trace_to_states(&plain, &f);
    for (e, s) in tagged.iter().zip(&states) {
        if s.x_mm > 300.0 && s.h_mm > 0.0 {
            assert!(e.dip, "a sample in the pot not tagged as a dip: {s:?}");
        }
    }
}

#[test]
fn the_program_dips_between_strokes_and_the_simulator_goes_to_the_ink() {
    let t = rows(4);
    let f = paper();
    let (prog, report) =
        build_program_chars(&t, Some(&[0, 0, 1, 1]), &pen1(), &f, &cfg(Reload::BeforeEachChar)).unwrap();
    assert_eq!(report.dips, 2);
    let dipped: Vec<bool> = prog.strokes.iter().map(|s| !s.dip.is_empty()).collect();
    assert_eq!(dipped, [true, false, true, false]);
    // above → down → soak (dwell) → above; the soak lasts dwell_s at its speed.
    let d = &prog.strokes[0].dip;
    assert_eq!(d.len(), 4);
    let Move::Line { v, .. } = d[2] else { panic!("line") };
    assert!((DWELL_SINK_MM / 1000.0 / v - 0.5).abs() < 1e-9);
    // Dips are whole moves between strokes: the moves of a stroke are dip, approach, press, lift.
    for st in &prog.strokes {
        let all: Vec<_> = st.moves().collect();
        assert_eq!(all.len(), st.dip.len() + st.approach.len() + st.press.len() + 1);
    }
    // Executed: the brush reaches 25 + 1 mm into the pot beside the sheet, twice, each time
    // between a lift and the next stroke's approach, and never lower over the sheet than the track.
    let trace = execute_program(&prog);
    let states = trace_to_states(&trace, &f);
    let in_pot: Vec<usize> = (0..states.len()).filter(|&i| states[i].x_mm > 300.0 && states[i].h_mm > 0.0).collect();
    assert!(!in_pot.is_empty());
    let deepest = in_pot.iter().map(|&i| states[i].h_mm).fold(0.0, f64::max);
    // The pot's surface is 20 mm above the paper: 25 + 1 mm below it is 6 mm below the paper plane.
    assert!((deepest - 6.0).abs() < 1e-6, "{deepest}");
    let visits = in_pot.windows(2).filter(|w| w[1] != w[0] + 1).count() + 1;
    assert_eq!(visits, 2);
    for s in states.iter().filter(|s| s.x_mm <= 300.0) {
        assert!(s.h_mm <= 12.0 + 1e-6);
    }
    // The dwell takes time: the soak move alone lasts 0.5 s.
    let t_pot: f64 = trace
        .windows(2)
        .filter(|w| f.to_paper(w[1].pose.position())[2] > 5.0 && f.to_paper(w[1].pose.position())[0] > 300.0)
        .map(|w| w[1].t_s - w[0].t_s)
        .sum();
    assert!(t_pot > 2.0 * 0.5, "{t_pot}");
    // Without the boundaries, the plain builder refuses before_each_char.
    assert!(build_program(&t, &pen1(), &f, &cfg(Reload::BeforeEachChar)).is_err());
}

#[test]
fn exports_carry_the_dips() {
    let t = rows(4);
    let f = paper();
    let c = cfg(Reload::EveryStrokes(2));
    let (prog, _) = build_program(&t, &pen1(), &f, &c).unwrap();
    let lua = robot_io::aubo_lua(&prog, "t").unwrap();
    let timing = robot_io::time_program(&prog, &robot_io::DhParams::AUBO_I5, &c).unwrap();
    let ur = robot_io::urscript(&prog, &timing, &c, "t").unwrap();
    let times = robot_io::point_times(&prog, &timing).unwrap();
    assert_eq!(lua.matches("-- ink dip before stroke").count(), 2);
    assert!(lua.contains("-- ink dip before stroke 3"));
    assert_eq!(ur.matches("# ink dip before stroke").count(), 2);
    // Each dip is four line moves at the station's position.
    assert_eq!(ur.matches("movel(p[0.630000, 0.100000").count(), 2 * 4 - 2 * 2 + 2 * 2, "{ur}");
    let (g, warnings) = robot_io::gcode(&t, &times, &c, "t").unwrap();
    assert_eq!(g.matches("; ink dip before stroke").count(), 2);
    assert!(g.contains("G0 X330.000000 Y-150.000000") && g.contains("G1 Z-25.000000") && g.contains("; dwell 0.5 s"));
    assert!(!warnings.iter().any(|w| w.contains("ink")), "{warnings:?}");
    // Without paper_mm the plotter cannot find the pot: said, not guessed.
    let mut no_pot = c.clone();
    no_pot.ink.as_mut().unwrap().paper_mm = None;
    let (g, warnings) = robot_io::gcode(&t, &times, &no_pot, "t").unwrap();
    assert!(!g.contains("ink dip"));
    assert!(warnings.iter().any(|w| w.contains("ink.paper_mm")), "{warnings:?}");
}

#[test]
fn ink_settings_are_validated_and_the_example_loads() {
    let mut c = cfg(Reload::EveryMm(0.0));
    assert!(c.validate().unwrap_err().to_string().contains("every_mm"));
    c.ink.as_mut().unwrap().reload = Reload::EveryStrokes(0);
    assert!(c.validate().unwrap_err().to_string().contains("every_strokes"));
    c = cfg(Reload::EveryMm(100.0));
    c.ink.as_mut().unwrap().dwell_s = 1e9;
    assert!(c.validate().unwrap_err().to_string().contains("dwell_s"));
    c = cfg(Reload::EveryMm(100.0));
    c.dip = Some(robot_io::DipStation { pose: [0.63, 0.1, 0.07, 3.14, 0.0, 0.0], depth_mm: 5.0, every_strokes: 1 });
    assert!(c.validate().unwrap_err().to_string().contains("not both"));
    let ex = RobotConfig::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/robot/robot-ink.json"),
    )
    .unwrap();
    assert_eq!(ex.ink.unwrap().reload, Reload::EveryMm(400.0));
    // An unknown reload rule is refused naming it.
    let dir = std::env::temp_dir().join(format!("robot-io-ink-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("robot.json");
    std::fs::write(
        &bad,
        r#"{"ink": {"pose": [0.6, 0.1, 0.07, 3.14, 0, 0], "depth_mm": 5, "reload": {"every_char": 1}}}"#,
    )
    .unwrap();
    let e = chain(&RobotConfig::load(&bad).unwrap_err());
    assert!(e.contains("robot.json") && e.contains("every_char"), "{e}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// The error and its causes, joined as `anyhow` prints them with `{:#}`.
fn chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        s += &format!(": {c}");
        cause = c.source();
    }
    s
}
