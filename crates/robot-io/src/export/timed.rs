//! When a timed stroke reaches each point of its pressed path: the times the URScript tool
//! speeds and the G-code feed rates are made from.

use nalgebra::Isometry3;

use crate::RobotError;
use crate::pose::Pose;
use crate::program::{Program, StrokeProgram};
use crate::timing::{ProgramTiming, TURN_LENGTH_M, TimedStroke, pressed_path};

/// How far a waypoint of a timed stroke may lie from its pressed path, m: the waypoints are
/// interpolated on the path, where the timing merged points closer than
/// [`crate::timing::MERGE_M`] (1e-7 m), so only that and rounding separate them.
const ON_PATH_M: f64 = 2e-7;
/// As [`ON_PATH_M`], for the tool orientation, rad (1e-7 m of path is 1e-5 rad of turn).
const ON_PATH_RAD: f64 = 2e-5;
/// How far back along the path (m) a waypoint may seem to lie from the one before (the
/// merged points again); a waypoint farther back lies on a later piece.
const BACK_M: f64 = 1e-6;

/// For each stroke of a track (by its index in the track), the time (s, from the start of its
/// timed stroke) at which the brush first reaches each of its points; `None` for a stroke that
/// was not timed (fewer than two distinct points).
#[derive(Clone, Debug, PartialEq)]
pub struct PointTimes {
    /// Per track stroke: the times at its points, s.
    pub strokes: Vec<Option<Vec<f64>>>,
}

/// The times at which the timed strokes of `timing` (the timing of `program`) reach each
/// point of their pressed paths (the first point, which the descent reaches, and every pressed
/// point: one per track point).
///
/// # Errors
/// [`RobotError::Unsafe`] naming the stroke when a timed stroke does not belong to `program`
/// (a waypoint off the stroke's pressed path, or the path not reached to its end).
pub fn point_times(program: &Program, timing: &ProgramTiming) -> Result<PointTimes, RobotError> {
    let n = program.strokes.iter().map(|s| s.index + 1).max().unwrap_or(0);
    let mut strokes = vec![None; n];
    for st in &program.strokes {
        if let Some(t) = timing.strokes.iter().find(|t| t.stroke == st.index) {
            strokes[st.index] = Some(stroke_point_times(st, t)?);
        }
    }
    Ok(PointTimes { strokes })
}

/// The combined length of a piece of path, as the timing measures it: TCP travel and
/// [`TURN_LENGTH_M`] per radian of turn.
fn piece_len(a: &Isometry3<f64>, b: &Isometry3<f64>) -> f64 {
    let dp = (a.translation.vector - b.translation.vector).norm();
    dp.hypot(a.rotation.angle_to(&b.rotation) * TURN_LENGTH_M)
}

/// Where `w` lies on the piece `a → b` (the fraction, 0 to 1), if it lies on it.
fn on_piece(a: &Isometry3<f64>, b: &Isometry3<f64>, w: &Isometry3<f64>) -> Option<f64> {
    let ab = b.translation.vector - a.translation.vector;
    let turn = a.rotation.angle_to(&b.rotation);
    let f = if ab.norm() > ON_PATH_M {
        (w.translation.vector - a.translation.vector).dot(&ab) / ab.norm_squared()
    } else if turn > ON_PATH_RAD {
        a.rotation.angle_to(&w.rotation) / turn
    } else {
        0.0
    };
    if !(-1e-9..=1.0 + 1e-9).contains(&f) {
        return None;
    }
    let f = f.clamp(0.0, 1.0);
    let p = a.translation.vector.lerp(&b.translation.vector, f);
    let r = a.rotation.try_slerp(&b.rotation, f, 1e-12).unwrap_or(a.rotation);
    ((w.translation.vector - p).norm() <= ON_PATH_M && r.angle_to(&w.rotation) <= ON_PATH_RAD).then_some(f)
}

/// The times at which timed stroke `t` first reaches each point of `st`'s pressed path, s.
fn stroke_point_times(st: &StrokeProgram, t: &TimedStroke) -> Result<Vec<f64>, RobotError> {
    let refuse = |reason: String| RobotError::Unsafe { stroke: Some(st.index), point: None, reason };
    let path: Vec<Isometry3<f64>> = pressed_path(st).iter().map(Pose::to_iso).collect();
    let mut at_point = vec![0.0; path.len()];
    for i in 1..path.len() {
        at_point[i] = at_point[i - 1] + piece_len(&path[i - 1], &path[i]);
    }
    // The path length at each waypoint: each lies on a piece at or after the last one's, no
    // earlier along the path.
    let mut s_wp = Vec::with_capacity(t.poses.len());
    let (mut piece, mut last_s) = (0usize, 0.0f64);
    for (k, w) in t.poses.iter().enumerate() {
        let w = w.to_iso();
        loop {
            if piece + 1 >= path.len() {
                return Err(refuse(format!(
                    "waypoint {k} of the timed stroke does not lie on the stroke's pressed path: the timing is not this program's"
                )));
            }
            let len = at_point[piece + 1] - at_point[piece];
            if let Some(f) = on_piece(&path[piece], &path[piece + 1], &w) {
                let s = at_point[piece] + f * len;
                if s >= last_s - BACK_M {
                    last_s = s.max(last_s);
                    break;
                }
            }
            piece += 1;
        }
        s_wp.push(last_s);
    }
    let end = at_point[path.len() - 1];
    if s_wp.last().is_none_or(|&s| (s - end).abs() > BACK_M) {
        return Err(refuse("the timed stroke does not reach the end of the stroke's pressed path".into()));
    }
    // The first time the waypoints reach each point's path length (linear between waypoints).
    let dt = t.interval_s;
    let mut out = Vec::with_capacity(path.len());
    let mut k = 0;
    for &s in &at_point {
        while k < s_wp.len() && s_wp[k] < s - BACK_M {
            k += 1;
        }
        let k = k.min(s_wp.len() - 1);
        let time = if k == 0 || s_wp[k] <= s_wp[k - 1] {
            k as f64 * dt
        } else {
            let f = ((s - s_wp[k - 1]) / (s_wp[k] - s_wp[k - 1])).clamp(0.0, 1.0);
            (k as f64 - 1.0 + f) * dt
        };
        out.push(time);
    }
    Ok(out)
}
