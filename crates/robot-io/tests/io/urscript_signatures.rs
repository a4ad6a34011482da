//! The URScript maobi writes, checked against UR's published signatures
//! (`tests/golden/urscript_signatures.json`, transcribed from UR's Script Manual): every call's
//! function exists, its arguments come in the manual's order (positional first, then named, no
//! name twice, none missing), and each value is plausible in the parameter's unit (metres, not
//! millimetres; m/s, not mm/s; the register in the range UR reserves for RTDE clients).

use robot_io::brush_model::{BrushProfile, Stroke, Track, TrackPoint};
use robot_io::{DhParams, RobotConfig, build_program, level_frame_in_front, time_program, urscript};
use serde_json::Value;

fn signatures() -> Value {
    let text = include_str!("../golden/urscript_signatures.json");
    serde_json::from_str(text).unwrap()
}

/// The top-level arguments of a call's argument list (commas inside brackets kept).
fn split_args(s: &str) -> Vec<&str> {
    let (mut out, mut depth, mut start) = (Vec::new(), 0i32, 0);
    for (i, c) in s.char_indices() {
        match c {
            '[' | '(' => depth += 1,
            ']' | ')' => depth -= 1,
            ',' if depth == 0 => {
                out.push(s[start..i].trim());
                start = i + 1;
            }
            _ => {}
        }
    }
    if !s[start..].trim().is_empty() {
        out.push(s[start..].trim());
    }
    out
}

fn numbers(list: &str) -> Option<Vec<f64>> {
    list.split(',').map(|x| x.trim().parse().ok()).collect()
}

/// Whether `value` is plausible for `unit`.
fn plausible(unit: &str, value: &str) -> Result<(), String> {
    let num = || value.parse::<f64>().map_err(|_| format!("{value:?} is not a number"));
    let within = |lo: f64, hi: f64| -> Result<(), String> {
        let v = num()?;
        if v > lo && v <= hi { Ok(()) } else { Err(format!("{v} is not in ({lo}, {hi}] {unit}")) }
    };
    match unit {
        "pose" | "joints_or_pose" => {
            if let Some(inner) = value.strip_prefix("p[").and_then(|v| v.strip_suffix(']')) {
                let v = numbers(inner).ok_or(format!("{value:?}: not six numbers"))?;
                let reach = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                let turn = (v[3] * v[3] + v[4] * v[4] + v[5] * v[5]).sqrt();
                if v.len() != 6 || reach > 1.5 || turn > std::f64::consts::PI + 1e-6 {
                    return Err(format!("{value:?}: not a pose in m and a rotation vector in rad"));
                }
                Ok(())
            } else if unit == "joints_or_pose" && value.starts_with('[') {
                let v = numbers(&value[1..value.len() - 1]).ok_or(format!("{value:?}: not six numbers"))?;
                if v.len() == 6 && v.iter().all(|q| q.abs() <= 2.0 * std::f64::consts::PI) {
                    Ok(())
                } else {
                    Err(format!("{value:?}: not six joint angles in rad"))
                }
            } else {
                Err(format!("{value:?}: not a pose"))
            }
        }
        // A blend radius in metres: a millimetre value would be metres long.
        "m" => {
            let v = num()?;
            if (0.0..=0.1).contains(&v) { Ok(()) } else { Err(format!("{v} m is not a blend radius in metres")) }
        }
        "s" => (num()? == 0.0).then_some(()).ok_or(format!("t={value}: maobi times nothing by t")),
        "m_s" => within(0.0, 3.2),
        "m_s2" | "rad_s2" => within(0.0, 40.0),
        "rad_s" => within(0.0, 3.2),
        "rtde_register" => {
            let r: usize = value.parse().map_err(|_| format!("{value:?}: not an address"))?;
            (24..=47).contains(&r).then_some(()).ok_or(format!("register {r} is not one UR reserves for RTDE clients"))
        }
        "int32" => value.parse::<i32>().map(|_| ()).map_err(|_| format!("{value:?}: not an int32")),
        _ => Err(format!("unknown unit {unit}")),
    }
}

/// Every statement of `script` inside its `def … end` checked against the signatures; the
/// first disagreement, naming the line.
fn check(script: &str, sig: &Value) -> Result<usize, String> {
    let mut calls = 0;
    for (n, line) in script.lines().enumerate() {
        let l = line.trim();
        if !line.starts_with("  ") || l.starts_with('#') {
            continue;
        }
        let at = |why: String| format!("line {}: {why}: {l}", n + 1);
        let open = l.find('(').ok_or_else(|| at("not a call".into()))?;
        let name = &l[..open];
        let args = l[open + 1..].strip_suffix(')').ok_or_else(|| at("not one call".into()))?;
        let f = sig["functions"].get(name).ok_or_else(|| at(format!("`{name}` is not in the table")))?;
        let params: Vec<(&str, bool, &str)> = f["params"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| (p[0].as_str().unwrap(), p[1].is_null(), p[2].as_str().unwrap()))
            .collect();
        let mut given = vec![false; params.len()];
        // The last parameter filled: a named argument must come after it (the manual's order).
        let mut last: Option<usize> = None;
        let mut named = false;
        for (k, a) in split_args(args).into_iter().enumerate() {
            let (i, value) = match a.split_once('=') {
                Some((key, v)) if key.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') => {
                    let i =
                        params.iter().position(|p| p.0 == key).ok_or_else(|| at(format!("`{name}` has no `{key}`")))?;
                    if last.is_some_and(|j| i <= j) {
                        let order: Vec<&str> = params.iter().map(|p| p.0).collect();
                        return Err(at(format!("`{key}` out of the manual's order {order:?}")));
                    }
                    named = true;
                    (i, v)
                }
                _ => {
                    if named {
                        return Err(at("a positional argument after a named one".into()));
                    }
                    if k >= params.len() {
                        return Err(at(format!("more than the {} parameters of `{name}`", params.len())));
                    }
                    (k, a)
                }
            };
            last = Some(i);
            given[i] = true;
            plausible(params[i].2, value).map_err(|e| at(format!("`{}`: {e}", params[i].0)))?;
        }
        if let Some((p, _, _)) = params.iter().zip(&given).find(|((_, req, _), g)| *req && !**g).map(|(p, _)| p) {
            return Err(at(format!("the required `{p}` is missing")));
        }
        calls += 1;
    }
    Ok(calls)
}

fn script() -> String {
    let pt = |x: f64, y: f64| TrackPoint { x_mm: x, y_mm: y, h_mm: 14.0, alpha_rad: 0.0, beta_rad: 0.3 };
    let stroke =
        |y: f64| Stroke { points: (0..=40).map(|i| pt(30.0 + f64::from(i), y + 0.02 * f64::from(i * i))).collect() };
    let track = Track { strokes: vec![stroke(40.0), stroke(70.0)] };
    let frame = level_frame_in_front([60.0, 60.0], [0.0, 0.0, 210.0, 297.0]);
    let cfg = RobotConfig::default();
    let (program, _) = build_program(&track, &BrushProfile::builtin("pen1").unwrap(), &frame, &cfg).unwrap();
    let timing = time_program(&program, &DhParams::UR5E, &cfg).unwrap();
    urscript(&program, &timing, &cfg, "二").unwrap()
}

#[test]
fn the_urscript_maobi_writes_follows_urs_published_signatures() {
    let sig = signatures();
    let ur = script();
    let calls = check(&ur, &sig).unwrap();
    // set_tcp, the progress register 3 times, the start, and the strokes' moves.
    assert!(calls > 10, "{calls} calls");
    for f in ["set_tcp(", "write_output_integer_register(", "movej(", "movel(", "movep("] {
        assert!(ur.contains(f), "{f}");
    }
    // The checker catches what it is for: UR's order (t before r), units, names.
    let line = ur.lines().find(|l| l.starts_with("  movel(")).unwrap().to_string();
    let cases = [
        (line.replace(", t=0, r=", ", r=").replace(')', ", t=0)"), "out of the manual's order"),
        (line.replace("r=0.000000", "r=0.500000"), "not a blend radius in metres"),
        (line.replace("v=0.100000", "v=100.000000"), "not in (0, 3.2]"),
        (line.replace("movel(", "move_l("), "`move_l` is not in the table"),
        (line.replace(", t=0", ", t=2"), "maobi times nothing by t"),
        ("  write_output_integer_register(3, 1)".to_string(), "not one UR reserves"),
        ("  movep(a=0.1)".to_string(), "the required `pose` is missing"),
    ];
    for (bad, needle) in cases {
        let text = ur.replacen(&line, &bad, 1);
        let text = if text == ur { format!("{ur}{bad}\n") } else { text };
        let e = check(&text, &sig).expect_err(needle);
        assert!(e.contains(needle), "{needle}: {e}");
    }
}
