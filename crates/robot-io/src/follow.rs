//! Following an arm against what was commanded: where a reported TCP pose may be (finite,
//! within reach, near the program, on the commanded path or at its end, within tolerances), and
//! how long commanded motion should take. Shared by the controllers that drive arms (AUBO, UR):
//! none of them acts on a pose it has not checked here.

use nalgebra::{Point3, Vector3};

use crate::RobotError;
use crate::pose::Pose;
use crate::program::{Move, Program, StrokeProgram};

/// How far a reported TCP position may lie from the commanded one (or from the commanded path
/// after a fault, widened by the moves' blend radius), m: 5 mm. Far above a controller's
/// repeatability (±0.02–0.05 mm for the AUBO-i5) and the simulator's (exact), far below the
/// 80 mm "believed" offsets it exists to catch.
pub const POSE_TOLERANCE_M: f64 = 0.005;
/// How far a reported tool orientation may turn from the commanded one, rad (about 2.9°).
pub const ORIENTATION_TOLERANCE_RAD: f64 = 0.05;
/// Farthest a reported TCP may lie from the robot base, m: beyond the AUBO-i5's reach
/// (0.886 m) and the UR5e's (0.85 m) plus a brush.
pub const MAX_REACH_M: f64 = 1.2;
/// How far outside the box of the program's commanded positions a reported TCP may lie once
/// the arm is at the start pose, m.
pub const NEIGHBOURHOOD_M: f64 = 0.1;
/// One move sent to the controller, as the checks need it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sent {
    /// Where it ends (`None`: a joint move whose TCP pose is not known).
    pub(crate) target: Option<Pose>,
    /// A joint move: its TCP path is not a line.
    pub(crate) joint: bool,
    /// Its largest joint travel, rad (joint moves; `None`: not known).
    pub(crate) joint_travel_rad: Option<f64>,
    /// Speed (m/s or rad/s) and acceleration.
    pub(crate) v: f64,
    pub(crate) a: f64,
    /// Blend radius, m.
    pub(crate) blend_m: f64,
    /// The move's own duration, s, where it is known (a path buffer's timing).
    pub(crate) fixed_s: Option<f64>,
}

impl Sent {
    pub(crate) fn of(m: &Move) -> Sent {
        match *m {
            Move::Joint { a, v, .. } => {
                Sent { target: None, joint: true, joint_travel_rad: None, v, a, blend_m: 0.0, fixed_s: None }
            }
            Move::JointPose { pose, a, v } => {
                Sent { target: Some(pose), joint: true, joint_travel_rad: None, v, a, blend_m: 0.0, fixed_s: None }
            }
            Move::Line { pose, a, v, blend_m } => {
                Sent { target: Some(pose), joint: false, joint_travel_rad: None, v, a, blend_m, fixed_s: None }
            }
        }
    }
}

/// What was commanded since the arm was last seen idle where expected.
#[derive(Clone, Debug, Default)]
pub(crate) struct Commanded {
    /// The pose the arm was seen at then (`None` before the run).
    pub(crate) from: Option<Pose>,
    /// The moves sent since, in order (a move whose answer was lost included).
    pub(crate) sent: Vec<Sent>,
}

impl Commanded {
    /// The last commanded pose: the last move's target, or where the arm was seen.
    pub(crate) fn last_pose(&self) -> Option<Pose> {
        match self.sent.last() {
            Some(s) => s.target,
            None => self.from,
        }
    }

    /// Seconds the controller needs for the moves sent: per move, the path length (or a turn
    /// in place at the speed per 0.1 m, as the simulator runs it) at the commanded speed times
    /// the speed fraction, plus the time a trapezoidal profile loses ramping up and down at the
    /// commanded acceleration (v / a); a joint move of unknown travel counts 2π rad.
    pub(crate) fn duration_s(&self, speed_fraction: f64) -> f64 {
        let mut at = self.from;
        let mut total = 0.0;
        for s in &self.sent {
            if let Some(d) = s.fixed_s {
                total += d;
                at = s.target;
                continue;
            }
            let v = (s.v * speed_fraction).max(1e-9);
            let path = if s.joint {
                s.joint_travel_rad.unwrap_or(std::f64::consts::TAU)
            } else {
                match (at, s.target) {
                    (Some(a), Some(b)) => {
                        let turn = a.to_iso().rotation.angle_to(&b.to_iso().rotation);
                        distance_m(&a, &b).max(0.1 * turn)
                    }
                    _ => MAX_REACH_M * 2.0,
                }
            };
            total += path / v + v / s.a.max(1e-9);
            at = s.target;
        }
        total
    }
}

/// Where a reported pose must be.
pub(crate) enum Expect<'c> {
    /// Before the run: anywhere within reach.
    Reach,
    /// Idle after the commanded moves: at their end.
    At(Pose),
    /// After a fault: anywhere along what was commanded since the arm was last seen.
    Along(&'c Commanded),
}

pub(crate) fn distance_m(a: &Pose, b: &Pose) -> f64 {
    let (p, q) = (a.position(), b.position());
    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
}

pub(crate) fn turn_rad(a: &Pose, b: &Pose) -> f64 {
    a.to_iso().rotation.angle_to(&b.to_iso().rotation)
}

/// A number for a message: 4 decimals, or scientific when huge.
pub(crate) fn num(x: f64) -> String {
    if x.is_finite() && x.abs() < 1e6 { format!("{x:.4}") } else { format!("{x:e}") }
}

/// A pose (or joints) for a message.
pub(crate) fn show(v: &[f64]) -> String {
    format!("[{}]", v.iter().map(|&x| num(x)).collect::<Vec<_>>().join(", "))
}

/// The box of every position the program commands (m), for the neighbourhood check.
pub(crate) fn program_box(program: &Program) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let moves = std::iter::once(&program.start).chain(program.strokes.iter().flat_map(StrokeProgram::moves));
    for m in moves {
        if let Move::Line { pose, .. } | Move::JointPose { pose, .. } = m {
            for k in 0..3 {
                lo[k] = lo[k].min(pose.0[k]);
                hi[k] = hi[k].max(pose.0[k]);
            }
        }
    }
    (lo, hi)
}

/// Distance from `p` to the segment `a`–`b` and the parameter of the nearest point.
pub(crate) fn to_segment(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>) -> (f64, f64) {
    let ab: Vector3<f64> = b - a;
    let len2 = ab.norm_squared();
    let t = if len2 > 0.0 { ((p - a).dot(&ab) / len2).clamp(0.0, 1.0) } else { 0.0 };
    ((p - (a + ab * t)).norm(), t)
}

/// Checks a reported TCP pose: finite, within [`MAX_REACH_M`] of the base, within
/// [`NEIGHBOURHOOD_M`] of the program's box (`near`, once the program has started), and where
/// `expect` says. The error names the pose reported, the pose expected and the distance.
pub(crate) fn check_pose(
    here: &Pose,
    expect: &Expect<'_>,
    near: Option<&([f64; 3], [f64; 3])>,
    when: &str,
) -> Result<(), RobotError> {
    check_pose_from(here, expect, near, when, "getTcpPose")
}

/// [`check_pose`] naming `source` (`getTcpPose`, `actual_TCP_pose`) as what reported the pose.
pub(crate) fn check_pose_from(
    here: &Pose,
    expect: &Expect<'_>,
    near: Option<&([f64; 3], [f64; 3])>,
    when: &str,
    source: &str,
) -> Result<(), RobotError> {
    let bad =
        |why: String| Err(RobotError::UnexpectedState(format!("{when}: {source} reported {}, {why}", show(&here.0))));
    if !here.0.iter().all(|x| x.is_finite()) {
        return bad("which is not a finite pose".into());
    }
    let p = Point3::from(here.position());
    let reach = p.coords.norm();
    if reach > MAX_REACH_M {
        // (The norm of 1e300 overflows: then the largest coordinate says it.)
        let far = if reach.is_finite() { format!("{reach:.3}") } else { num(p.coords.amax()) };
        return bad(format!("{far} m from the robot base: outside the workspace (at most {MAX_REACH_M} m)"));
    }
    if let Some((lo, hi)) = near {
        let out = (0..3).map(|k| (lo[k] - p[k]).max(p[k] - hi[k]).max(0.0)).fold(0.0, |s: f64, d| s + d * d).sqrt();
        if out > NEIGHBOURHOOD_M {
            return bad(format!(
                "{:.0} mm outside the box of this program's poses [{}]–[{}] (at most {:.0} mm)",
                out * 1e3,
                show(lo),
                show(hi),
                NEIGHBOURHOOD_M * 1e3
            ));
        }
    }
    let tol_mm = POSE_TOLERANCE_M * 1e3;
    match expect {
        Expect::Reach => Ok(()),
        Expect::At(want) => {
            let d = distance_m(here, want);
            if d > POSE_TOLERANCE_M {
                return bad(format!(
                    "{:.1} mm from the commanded pose {} (tolerance {tol_mm:.1} mm)",
                    d * 1e3,
                    show(&want.0)
                ));
            }
            let turn = turn_rad(here, want);
            if turn > ORIENTATION_TOLERANCE_RAD {
                return bad(format!(
                    "its orientation {turn:.3} rad ({:.1}°) from the commanded pose {} (tolerance {ORIENTATION_TOLERANCE_RAD} rad)",
                    turn.to_degrees(),
                    show(&want.0)
                ));
            }
            Ok(())
        }
        Expect::Along(c) => {
            let Some(from) = c.from else { return Ok(()) };
            if c.sent.iter().any(|s| s.joint || s.target.is_none()) {
                // A joint move's TCP path is not a line: within reach is all that is known.
                return Ok(());
            }
            let poses: Vec<Pose> = std::iter::once(from).chain(c.sent.iter().filter_map(|s| s.target)).collect();
            let blends: Vec<f64> = std::iter::once(0.0).chain(c.sent.iter().map(|s| s.blend_m)).collect();
            let mut nearest = f64::INFINITY;
            // The least turn from the commanded orientation where the position is within
            // tolerance.
            let mut least_turn = f64::INFINITY;
            for i in 0..poses.len() {
                let (a, b) = (poses[i], poses[(i + 1).min(poses.len() - 1)]);
                let (pa, pb) = (Point3::from(a.position()), Point3::from(b.position()));
                let (d, t) = to_segment(&p, &pa, &pb);
                nearest = nearest.min(d);
                let blend = blends[i].max(blends[(i + 1).min(poses.len() - 1)]);
                if d > POSE_TOLERANCE_M + blend {
                    continue;
                }
                let (ra, rb) = (a.to_iso().rotation, b.to_iso().rotation);
                let rot = here.to_iso().rotation;
                // Along a line the orientation is where the position is; turning in place, any.
                let ts: Vec<f64> =
                    if (pb - pa).norm() < 1e-6 { (0..=16).map(|k| k as f64 / 16.0).collect() } else { vec![t] };
                let turned = ts
                    .iter()
                    .map(|&t| rot.angle_to(&ra.try_slerp(&rb, t, 1e-9).unwrap_or(if t < 0.5 { ra } else { rb })))
                    .fold(f64::INFINITY, f64::min);
                if turned <= ORIENTATION_TOLERANCE_RAD {
                    return Ok(());
                }
                least_turn = least_turn.min(turned);
            }
            let last = poses.last().copied().unwrap_or(from);
            if least_turn.is_finite() {
                return bad(format!(
                    "at a point of the commanded path ({} move(s) from {} to {}) but with its orientation {least_turn:.3} rad ({:.1}°) from the commanded one there (tolerance {ORIENTATION_TOLERANCE_RAD} rad)",
                    c.sent.len(),
                    show(&from.0),
                    show(&last.0),
                    least_turn.to_degrees()
                ));
            }
            bad(format!(
                "{:.1} mm from the nearest point of the commanded path ({} move(s) from {} to {}; tolerance {tol_mm:.1} mm and {ORIENTATION_TOLERANCE_RAD} rad)",
                nearest * 1e3,
                c.sent.len(),
                show(&from.0),
                show(&last.0)
            ))
        }
    }
}

/// What a lift from `depth_mm` (below the paper; negative above it) to `lift_mm` above it did,
/// in words.
pub(crate) fn lift_words(depth_mm: f64, lift_mm: f64) -> String {
    let from = if depth_mm >= 0.0 {
        format!("{depth_mm:.1} mm below the paper")
    } else {
        format!("{:.1} mm above the paper", -depth_mm)
    };
    format!("brush lifted from {from} to the safe height ({lift_mm:.1} mm above it)")
}

/// [`RobotError::RunStopped`] after a controller stopped a run (`stop`: what the stop did, in
/// words) and then lifted the brush (`Ok`: what the lift did and where the arm was seen after
/// it) or did not (`Err`: why, in words).
pub(crate) fn run_stopped(
    cause: RobotError,
    completed: usize,
    total: usize,
    stop: String,
    lift: Result<(String, Pose), String>,
) -> RobotError {
    let (lifted, words, at) = match lift {
        Ok((w, pose)) => (true, format!("{stop}; {w}"), Some(Box::new(crate::controller::Position::Tcp(pose)))),
        Err(why) => (false, format!("{stop}; {why}"), None),
    };
    RobotError::RunStopped { cause: Box::new(cause), completed, total, reconnects: 0, lifted, lift: words, at }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(pose: [f64; 6], v: f64, blend_m: f64) -> Sent {
        Sent { target: Some(Pose(pose)), joint: false, joint_travel_rad: None, v, a: 1.0, blend_m, fixed_s: None }
    }

    #[test]
    fn the_expected_duration_counts_path_speed_and_ramps() {
        let from = Pose([0.4, 0.0, 0.1, std::f64::consts::PI, 0.0, 0.0]);
        let c =
            Commanded { from: Some(from), sent: vec![line([0.5, 0.0, 0.1, std::f64::consts::PI, 0.0, 0.0], 0.1, 0.0)] };
        // 0.1 m at 0.1 m/s, plus v / a = 0.1 s; at half speed 2 s plus 0.05 s.
        assert!((c.duration_s(1.0) - 1.1).abs() < 1e-9, "{}", c.duration_s(1.0));
        assert!((c.duration_s(0.5) - 2.05).abs() < 1e-9, "{}", c.duration_s(0.5));
        // A joint move of unknown travel counts a full turn at its speed.
        let j = Commanded { from: None, sent: vec![Sent { joint: true, target: None, ..line([0.0; 6], 0.5, 0.0) }] };
        assert!((j.duration_s(1.0) - (std::f64::consts::TAU / 0.5 + 0.5)).abs() < 1e-9);
    }

    #[test]
    fn reported_poses_are_checked_against_what_was_commanded() {
        let pi = std::f64::consts::PI;
        let a = [0.4, 0.0, 0.1, pi, 0.0, 0.0];
        let b = [0.5, 0.0, 0.1, pi, 0.0, 0.0];
        // A path a → b with a 1 mm blend at b, then a turn in place at b.
        let turned = [0.5, 0.0, 0.1, pi, 0.0, 0.5];
        let c = Commanded { from: Some(Pose(a)), sent: vec![line(b, 0.1, 0.001), line(turned, 0.1, 0.0)] };
        let at = |x: [f64; 6]| Pose(x);
        let near = ([0.4, 0.0, 0.1], [0.5, 0.0, 0.1]);
        // (case, reported, expectation, error needle; None: accepted)
        let cases: Vec<(&str, [f64; 6], Expect<'_>, Option<&str>)> = vec![
            ("at the target", b, Expect::At(at(b)), None),
            ("4.9 mm off", [0.5, 0.0049, 0.1, pi, 0.0, 0.0], Expect::At(at(b)), None),
            ("5.1 mm off", [0.5, 0.0051, 0.1, pi, 0.0, 0.0], Expect::At(at(b)), Some("5.1 mm from the commanded pose")),
            ("turned 0.1 rad", [0.5, 0.0, 0.1, pi, 0.0, 0.1], Expect::At(at(b)), Some("orientation 0.100 rad")),
            ("mid-path", [0.45, 0.003, 0.1, pi, 0.0, 0.0], Expect::Along(&c), None),
            ("mid-path, 5.4 mm off within the blend", [0.5, 0.0054, 0.1, pi, 0.0, 0.0], Expect::Along(&c), None),
            (
                "mid-path, 7 mm off",
                [0.45, 0.007, 0.1, pi, 0.0, 0.0],
                Expect::Along(&c),
                Some("7.0 mm from the nearest point"),
            ),
            ("mid-turn", [0.5, 0.0, 0.1, pi, 0.0, 0.25], Expect::Along(&c), None),
            ("turned beyond the turn", [0.5, 0.0, 0.1, pi, 0.0, 0.8], Expect::Along(&c), Some("orientation 0.300 rad")),
            (
                "before the path",
                [0.35, 0.0, 0.1, pi, 0.0, 0.0],
                Expect::Along(&c),
                Some("50.0 mm from the nearest point"),
            ),
            ("out of the neighbourhood", [0.7, 0.0, 0.1, pi, 0.0, 0.0], Expect::Reach, Some("outside the box")),
            ("out of reach", [1.0, 1.0, 0.1, pi, 0.0, 0.0], Expect::Reach, Some("1.418 m from the robot base")),
            ("huge", [1e300, 0.0, 0.0, 0.0, 0.0, 0.0], Expect::Reach, Some("1e300 m from the robot base")),
        ];
        for (case, reported, expect, needle) in cases {
            let r = check_pose(&Pose(reported), &expect, Some(&near), "test");
            match (r, needle) {
                (Ok(()), None) => {}
                (Err(RobotError::UnexpectedState(m)), Some(n)) => assert!(m.contains(n), "{case}: {m}"),
                (r, _) => panic!("{case}: {r:?}"),
            }
        }
    }
}
