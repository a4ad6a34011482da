//! Timed strokes: each pressed stroke of a [`Program`] as a time-parameterised joint
//! trajectory, sampled at a fixed interval (the waypoints of a path buffer).
//!
//! A stroke's pressed path (the first point, which the descent reaches, then every pressed
//! point) is parameterised by its length `s` (TCP travel, a turn counting [`TURN_LENGTH_M`] per
//! radian). Its joints come from inverse kinematics on one branch, each point seeded by the one
//! before (refined to 1e-9), with the joint limits and the distance from singularities
//! checked. The speed `ṡ(s)` is then the largest that keeps, at every point:
//!
//! - the TCP speed within `write_speed_m_s`, the depth rate within
//!   `timing.max_depth_rate_mm_s`, every joint speed within `joint_speed_rad_s`;
//! - the TCP's path acceleration (along and across the path: the slowing at sharp turns)
//!   within `write_acc_m_s2`, and every joint acceleration `q′·s̈ + q″·ṡ²` within
//!   `joint_acc_rad_s2`;
//!
//! found by a forward and a backward pass over the discretised path (time-optimal for these
//! constraints on that discretisation: the numerical-integration form of TOPP), the brush
//! stopping where the path turns back (more than 90°), so a waypoint lies on the turning point. The joints are
//! interpolated linearly between the points, so a change of direction at a point is crossed
//! within one waypoint interval `dt`: the speed there is also bounded so that the waypoints'
//! acceleration (`v·Δ/dt`) and joint jerk (`v·Δq′/dt²`) stay within `write_acc_m_s2`,
//! `joint_acc_rad_s2` and `timing.joint_jerk_rad_s3`. For the jerk along the path the speed in
//! time is then averaged over a window of `T = write_acc / timing.write_jerk` (a moving average
//! turns the bang-bang acceleration into ramps, `|s⃛| ≤ write_jerk`), after each point's speed
//! limit was spread around it (growing by `1 / 2T` per metre), so the average stays within it. The figures of the result (speeds, accelerations, jerks) are
//! measured on the waypoints themselves, so they hold whatever the scheme.

#![allow(clippy::needless_range_loop, reason = "one joint index runs through several arrays at once")]

use nalgebra::{Isometry3, Matrix6, Vector3, Vector6};
use serde::Serialize;

use crate::RobotError;
use crate::kinematics::{Chain, DhParams, JOINT_LIMIT_RAD};
use crate::pose::Pose;
use crate::program::{Move, Program, RobotConfig, StrokeProgram};

/// How far a path buffer's first waypoint may lie from the arm's joints when the buffer is
/// moved, rad: the runner and the Lua script check it before `movePathBuffer`, and the
/// simulator refuses a buffer that does not start where the arm is.
pub const PATH_START_TOLERANCE_RAD: f64 = 5e-3;

/// How much path length a turn of the tool counts for, m per rad: a turn in place has a
/// length, so it has a speed and a duration.
pub const TURN_LENGTH_M: f64 = 0.01;
/// The longest piece of path between two points of the discretisation, m: longer segments
/// are split (the joints are interpolated linearly within a piece).
pub const MAX_PIECE_M: f64 = 5e-4;
/// Points closer than this (path length, m) are merged.
pub const MERGE_M: f64 = 1e-7;
/// The largest joint step between two neighbouring points of the discretisation, rad: more
/// is a change of branch (a wrist flip), refused.
pub const BRANCH_STEP_RAD: f64 = 0.05;
/// Most waypoints one timed stroke may have (at the default 10 ms interval, 1000 s).
pub const MAX_STROKE_WAYPOINTS: usize = 100_000;
/// How far the forward kinematics of a timed stroke's waypoints may lie from the commanded
/// path, m.
pub const PATH_TOLERANCE_M: f64 = 1e-4;
/// How far the tool orientation of a waypoint may turn from the commanded path, rad.
pub const PATH_TOLERANCE_RAD: f64 = 1e-3;

/// One pressed stroke, timed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TimedStroke {
    /// The stroke's index in the track.
    pub stroke: usize,
    /// The interval between waypoints, s.
    pub interval_s: f64,
    /// Joint waypoints, rad, one per interval: the first at the stroke's first point at rest,
    /// the last at its last point at rest.
    #[serde(skip)]
    pub joints: Vec<[f64; 6]>,
    /// The commanded TCP pose at each waypoint (on the path, where the time law puts it).
    #[serde(skip)]
    pub poses: Vec<Pose>,
    /// Duration, s.
    pub duration_s: f64,
    /// The time-optimal duration under the speed and acceleration limits alone (no jerk
    /// limit), s: the reference the timing is measured against.
    pub reference_s: f64,
    /// Largest TCP speed, m/s.
    pub peak_speed_m_s: f64,
    /// Largest TCP acceleration, m/s².
    pub peak_acc_m_s2: f64,
    /// Largest rate of change of the press depth, mm/s.
    pub peak_depth_rate_mm_s: f64,
    /// Largest speed of each joint, rad/s.
    pub peak_joint_speed_rad_s: [f64; 6],
    /// Largest joint acceleration (any joint), rad/s².
    pub peak_joint_acc_rad_s2: f64,
    /// Largest joint jerk (any joint), rad/s³.
    pub peak_joint_jerk_rad_s3: f64,
    /// Smallest singular value of the Jacobian along the stroke.
    pub min_singular_value: f64,
    /// Largest distance between the forward kinematics of a waypoint and the commanded path, m.
    pub path_error_m: f64,
    /// Largest turn between the tool at a waypoint and the commanded path, rad.
    pub path_error_rad: f64,
}

/// Every pressed stroke of a program, timed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ProgramTiming {
    /// The strokes (those with at least two distinct points), in writing order.
    pub strokes: Vec<TimedStroke>,
    /// The total pressed (writing) time, s.
    pub writing_s: f64,
    /// The reference durations' total, s.
    pub reference_s: f64,
    /// Largest speed of each joint over all strokes, rad/s.
    pub peak_joint_speed_rad_s: [f64; 6],
}

/// The pressed path of a stroke: the descent's target (the first point), then every pressed
/// point.
pub fn pressed_path(st: &StrokeProgram) -> Vec<Pose> {
    st.approach
        .last()
        .into_iter()
        .chain(&st.press)
        .filter_map(|m| match m {
            Move::Line { pose, .. } => Some(*pose),
            _ => None,
        })
        .collect()
}

/// Times every pressed stroke of `program` with the arm `kin` (the controller's parameters
/// before sending; [`DhParams::AUBO_I5`] for a check without a controller) and checks it
/// against `cfg.limits`.
///
/// # Examples
/// ```
/// # use robot_io::brush_model::{BrushProfile, Stroke, Track, TrackPoint};
/// # use robot_io::{level_frame_in_front, DhParams, RobotConfig, build_program};
/// # use robot_io::time_program;
/// let profile = BrushProfile::builtin("pen1").unwrap();
/// let pt = |x: f64| TrackPoint { x_mm: x, y_mm: 60.0, h_mm: 3.0, alpha_rad: 0.0, beta_rad: 0.0 };
/// let track = Track { strokes: vec![Stroke { points: (0..40).map(|i| pt(30.0 + f64::from(i))).collect() }] };
/// let frame = level_frame_in_front([50.0, 60.0], [0.0, 0.0, 210.0, 297.0]);
/// let cfg = RobotConfig::default();
/// let (program, _) = build_program(&track, &profile, &frame, &cfg).unwrap();
/// let timing = time_program(&program, &DhParams::AUBO_I5, &cfg).unwrap();
/// // 39 mm at 20 mm/s and no more, with the ramps.
/// assert!(timing.writing_s > 39.0 / 20.0 && timing.strokes[0].peak_speed_m_s <= 0.02 + 1e-9);
/// ```
///
/// # Errors
/// [`RobotError::Unsafe`] naming the stroke (and point) when a pressed pose is unreachable,
/// the branch changes (a joint would jump more than [`BRANCH_STEP_RAD`] between neighbouring
/// points), the arm comes closer to a singularity than `limits.min_singular_value`, or a
/// measured speed, acceleration or jerk exceeds its limit (`limits.max_linear_speed_m_s`,
/// `max_linear_acc_m_s2`, `max_joint_speed_rad_s`, `max_joint_acc_rad_s2`,
/// `max_joint_jerk_rad_s3`), or the waypoints leave the path by more than
/// [`PATH_TOLERANCE_M`] / [`PATH_TOLERANCE_RAD`].
pub fn time_program(program: &Program, kin: &DhParams, cfg: &RobotConfig) -> Result<ProgramTiming, RobotError> {
    time_program_from(program, kin, cfg, None)
}

/// [`time_program`] with the first stroke's inverse kinematics seeded by `seed` (rad: the
/// joints the arm reaches the start pose with, so the waypoints keep its branch).
///
/// # Errors
/// As [`time_program`].
pub fn time_program_from(
    program: &Program,
    kin: &DhParams,
    cfg: &RobotConfig,
    seed: Option<&[f64; 6]>,
) -> Result<ProgramTiming, RobotError> {
    let tcp = program.tcp();
    let mut strokes = Vec::new();
    let mut seed: Option<[f64; 6]> = seed.copied();
    for st in &program.strokes {
        let path = pressed_path(st);
        let depths: Vec<f64> = path.iter().map(|p| program.depth_mm(p.position())).collect();
        if let Some(t) = time_stroke_within_limits(st.index, &path, &depths, kin, &tcp, seed.as_ref(), cfg)? {
            seed = t.joints.last().copied();
            strokes.push(t);
        }
    }
    let mut peak = [0.0f64; 6];
    for t in &strokes {
        for j in 0..6 {
            peak[j] = peak[j].max(t.peak_joint_speed_rad_s[j]);
        }
    }
    Ok(ProgramTiming {
        writing_s: strokes.iter().map(|t| t.duration_s).sum(),
        reference_s: strokes.iter().map(|t| t.reference_s).sum(),
        peak_joint_speed_rad_s: peak,
        strokes,
    })
}

/// How many times a stroke is timed again, uniformly slower, when a measured figure of its
/// waypoints exceeds a limit: the per-point bounds of [`time_stroke`] hold for the planned
/// speed profile, and its moving average and the stops can still push a measured peak over.
const RETIMES: usize = 4;

/// The slowest a stroke is retimed to, as a fraction of its planned speeds: a stroke that
/// needs more than this is over its limits by more than the timing's approximations, and is
/// refused rather than written at a crawl (a brush held nearly still spreads ink).
const MIN_RETIME_SCALE: f64 = 0.5;

/// [`time_stroke`], then checked against the limits; while a speed, acceleration or jerk
/// exceeds its limit, timed again with every planned rate scaled in time (speeds by `f`,
/// accelerations by `f²`, jerks by `f³`, `f` from the worst excess), at most [`RETIMES`] times
/// and down to [`MIN_RETIME_SCALE`] of the planned speeds; beyond that it is refused. A stroke
/// within the limits at once is timed exactly as [`time_stroke`] times it.
fn time_stroke_within_limits(
    stroke: usize,
    poses: &[Pose],
    depths: &[f64],
    kin: &DhParams,
    tcp: &Isometry3<f64>,
    seed: Option<&[f64; 6]>,
    cfg: &RobotConfig,
) -> Result<Option<TimedStroke>, RobotError> {
    let mut planned = cfg.clone();
    let (mut attempt, mut scale) = (0, 1.0);
    loop {
        let Some(t) = time_stroke(stroke, poses, depths, kin, tcp, seed, &planned)? else {
            return Ok(None);
        };
        let excess = limit_excess(&t, cfg);
        let f = 0.97 / excess;
        if excess <= 1.0 || attempt == RETIMES || scale * f < MIN_RETIME_SCALE {
            check_stroke(&t, cfg)?;
            return Ok(Some(t));
        }
        attempt += 1;
        scale *= f;
        planned.write_speed_m_s *= f;
        planned.joint_speed_rad_s *= f;
        planned.timing.max_depth_rate_mm_s *= f;
        planned.write_acc_m_s2 *= f * f;
        planned.joint_acc_rad_s2 *= f * f;
        planned.timing.write_jerk_m_s3 *= f * f * f;
        planned.timing.joint_jerk_rad_s3 *= f * f * f;
    }
}

/// The factor by which a stroke's time scale must shrink for its measured peaks to meet the
/// limits (1 or less when they do): the worst over [`limit_figures`] of each ratio to its
/// limit, taken to the root of the figure's order (speed ratio, √ acceleration ratio, ∛ jerk
/// ratio).
fn limit_excess(t: &TimedStroke, cfg: &RobotConfig) -> f64 {
    limit_figures(t, cfg)
        .into_iter()
        .map(|f| {
            let r = f.value / f.max;
            match f.order {
                1 => r,
                2 => r.sqrt(),
                _ => r.cbrt(),
            }
        })
        .fold(0.0, f64::max)
}

/// One measured figure of a timed stroke beside its limit.
struct LimitFigure {
    what: &'static str,
    value: f64,
    max: f64,
    field: &'static str,
    unit: &'static str,
    /// How the figure scales with the stroke's time: 1 for a speed, 2 for an acceleration, 3
    /// for a jerk (retiming by `f` scales it by `f^order`).
    order: u8,
}

/// A timed stroke's measured peaks against the limits, in the order they are checked.
fn limit_figures(t: &TimedStroke, cfg: &RobotConfig) -> [LimitFigure; 5] {
    let l = &cfg.limits;
    let joint_speed = t.peak_joint_speed_rad_s.iter().copied().fold(0.0, f64::max);
    let f = |what, value, max, field, unit, order| LimitFigure { what, value, max, field, unit, order };
    [
        f("TCP speed", t.peak_speed_m_s, l.max_linear_speed_m_s, "max_linear_speed_m_s", "m/s", 1),
        f("TCP acceleration", t.peak_acc_m_s2, l.max_linear_acc_m_s2, "max_linear_acc_m_s2", "m/s²", 2),
        f("joint speed", joint_speed, l.max_joint_speed_rad_s, "max_joint_speed_rad_s", "rad/s", 1),
        f("joint acceleration", t.peak_joint_acc_rad_s2, l.max_joint_acc_rad_s2, "max_joint_acc_rad_s2", "rad/s²", 2),
        f("joint jerk", t.peak_joint_jerk_rad_s3, l.max_joint_jerk_rad_s3, "max_joint_jerk_rad_s3", "rad/s³", 3),
    ]
}

fn unsafe_at(stroke: usize, point: Option<usize>, reason: String) -> RobotError {
    RobotError::Unsafe { stroke: Some(stroke), point, reason }
}

/// Refuses a timed stroke whose measured figures exceed the limits.
fn check_stroke(t: &TimedStroke, cfg: &RobotConfig) -> Result<(), RobotError> {
    for LimitFigure { what, value: v, max, field, unit, .. } in limit_figures(t, cfg) {
        if v > max {
            return Err(unsafe_at(
                t.stroke,
                None,
                format!("the timed stroke's {what} reaches {v:.4} {unit}, beyond limits.{field} = {max} {unit}"),
            ));
        }
    }
    if t.path_error_m > PATH_TOLERANCE_M || t.path_error_rad > PATH_TOLERANCE_RAD {
        return Err(unsafe_at(
            t.stroke,
            None,
            format!(
                "the forward kinematics of the stroke's joint waypoints leave the path by {:.4} mm and {:.5} rad (at most {} mm and {PATH_TOLERANCE_RAD} rad)",
                t.path_error_m * 1e3,
                t.path_error_rad,
                PATH_TOLERANCE_M * 1e3
            ),
        ));
    }
    Ok(())
}

/// The combined length of a move: TCP travel and [`TURN_LENGTH_M`] per radian of turn.
fn piece_len(a: &Isometry3<f64>, b: &Isometry3<f64>) -> f64 {
    let dp = (a.translation.vector - b.translation.vector).norm();
    let dr = a.rotation.angle_to(&b.rotation) * TURN_LENGTH_M;
    dp.hypot(dr)
}

fn lerp_iso(a: &Isometry3<f64>, b: &Isometry3<f64>, f: f64) -> Isometry3<f64> {
    let t = a.translation.vector.lerp(&b.translation.vector, f);
    let r = a.rotation.try_slerp(&b.rotation, f, 1e-12).unwrap_or(if f < 0.5 { a.rotation } else { b.rotation });
    Isometry3::from_parts(t.into(), r)
}

/// The pose error `target − at` (position, then the rotation vector).
fn pose_error(target: &Isometry3<f64>, at: &Isometry3<f64>) -> Vector6<f64> {
    let dp = target.translation.vector - at.translation.vector;
    let dr = (target.rotation * at.rotation.inverse()).scaled_axis();
    Vector6::new(dp.x, dp.y, dp.z, dr.x, dr.y, dr.z)
}

fn jacobian(chain: &Chain, q: &[f64; 6], tcp: &Isometry3<f64>) -> Matrix6<f64> {
    let (base, nudged) = chain.forward_nudged(q, 1e-7, tcp);
    let mut j = Matrix6::zeros();
    for (k, at) in nudged.iter().enumerate() {
        j.set_column(k, &(pose_error(at, &base) / 1e-7));
    }
    j
}

/// Newton steps from `q` (a solution within the inverse's tolerance) until the pose error is
/// below 1e-10 m and rad.
fn refine(chain: &Chain, goal: &Isometry3<f64>, tcp: &Isometry3<f64>, mut q: [f64; 6]) -> [f64; 6] {
    for _ in 0..6 {
        let e = pose_error(goal, &chain.forward(&q, tcp));
        if e.norm() < 1e-10 {
            break;
        }
        let Some(inv) = jacobian(chain, &q, tcp).try_inverse() else { break };
        let step = inv * e;
        for k in 0..6 {
            q[k] += step[k];
        }
    }
    q
}

/// The discretised pressed path: merged, split into pieces of at most [`MAX_PIECE_M`], at
/// least two pieces.
struct Path {
    iso: Vec<Isometry3<f64>>,
    depth_mm: Vec<f64>,
    /// The original point each discretisation point lies after (for messages).
    from: Vec<usize>,
    s: Vec<f64>,
}

fn discretise(poses: &[Pose], depths: &[f64]) -> Option<Path> {
    let mut iso: Vec<Isometry3<f64>> = Vec::new();
    let mut depth_mm = Vec::new();
    let mut from = Vec::new();
    for (i, p) in poses.iter().enumerate() {
        let x = p.to_iso();
        if let Some(last) = iso.last()
            && piece_len(last, &x) < MERGE_M
        {
            continue;
        }
        iso.push(x);
        depth_mm.push(depths[i]);
        from.push(i);
    }
    if iso.len() < 2 {
        return None;
    }
    let mut out = Path { iso: vec![iso[0]], depth_mm: vec![depth_mm[0]], from: vec![from[0]], s: vec![0.0] };
    let single = iso.len() == 2;
    for i in 1..iso.len() {
        let len = piece_len(&iso[i - 1], &iso[i]);
        let n = ((len / MAX_PIECE_M).ceil() as usize).max(if single { 2 } else { 1 });
        let s0 = *out.s.last().expect("one point");
        for k in 1..=n {
            let f = k as f64 / n as f64;
            out.iso.push(if k == n { iso[i] } else { lerp_iso(&iso[i - 1], &iso[i], f) });
            out.depth_mm.push(depth_mm[i - 1] + (depth_mm[i] - depth_mm[i - 1]) * f);
            out.from.push(from[i]);
            out.s.push(s0 + len * f);
        }
    }
    Some(out)
}

impl Path {
    fn len(&self) -> usize {
        self.iso.len()
    }
    fn push(&mut self, (iso, depth_mm, s, from): Target) {
        self.iso.push(iso);
        self.depth_mm.push(depth_mm);
        self.s.push(s);
        self.from.push(from);
    }
}

/// A point of the path: pose, depth (mm), path length (m), original point index.
type Target = (Isometry3<f64>, f64, f64, usize);

/// How many times a piece whose joints move more than [`BRANCH_STEP_RAD`] is halved before
/// the move counts as a change of branch.
const MAX_HALVINGS: usize = 6;

/// Inverse kinematics along a stroke, with its checks.
struct Solver<'a> {
    stroke: usize,
    kin: &'a DhParams,
    chain: &'a Chain,
    tcp: &'a Isometry3<f64>,
    cfg: &'a RobotConfig,
    min_sv: &'a mut f64,
}

impl Solver<'_> {
    /// The joints for `target`, seeded by `seed`, refined, within the joint limits and away
    /// from singularities.
    fn solve(&mut self, target: &Target, seed: Option<&[f64; 6]>) -> Result<[f64; 6], RobotError> {
        let (iso, _, _, from) = *target;
        let at = |reason: String| unsafe_at(self.stroke, Some(from), reason);
        let qi = self
            .kin
            .inverse(&Pose::from_iso(&iso), self.tcp, seed)
            .map(|s| refine(self.chain, &iso, self.tcp, s))
            .ok_or_else(|| at("the pressed pose is not reachable by the arm with this brush orientation".into()))?;
        if let Some(j) = qi.iter().position(|v| v.abs() > JOINT_LIMIT_RAD) {
            return Err(at(format!(
                "joint {} would reach {:.4} rad, beyond its limit ±{JOINT_LIMIT_RAD:.4}",
                j + 1,
                qi[j]
            )));
        }
        let sv = jacobian(self.chain, &qi, self.tcp).singular_values().min();
        *self.min_sv = self.min_sv.min(sv);
        if sv < self.cfg.limits.min_singular_value {
            return Err(at(format!(
                "the arm comes within {sv:.4} of a singularity (the Jacobian's smallest singular value), below limits.min_singular_value = {}",
                self.cfg.limits.min_singular_value
            )));
        }
        Ok(qi)
    }

    /// Solves the piece `prev` → `target` (joints `qp` at `prev`), halving it while the joints
    /// jump, and appends `target` (and any midpoints) to `path` and `q`.
    fn piece(
        &mut self,
        prev: &Target,
        qp: &[f64; 6],
        target: &Target,
        level: usize,
        path: &mut Path,
        q: &mut Vec<[f64; 6]>,
    ) -> Result<(), RobotError> {
        let qi = self.solve(target, Some(qp))?;
        let step = (0..6).map(|j| (qi[j] - qp[j]).abs()).fold(0.0, f64::max);
        if step <= BRANCH_STEP_RAD {
            path.push(*target);
            q.push(qi);
            return Ok(());
        }
        if level >= MAX_HALVINGS {
            return Err(unsafe_at(
                self.stroke,
                Some(target.3),
                format!(
                    "the joints jump {step:.4} rad between neighbouring points ({:.4} mm of path apart): the inverse kinematics changed branch (a wrist flip), beyond {BRANCH_STEP_RAD} rad",
                    (target.2 - prev.2) * 1e3
                ),
            ));
        }
        let mid = (lerp_iso(&prev.0, &target.0, 0.5), 0.5 * (prev.1 + target.1), 0.5 * (prev.2 + target.2), target.3);
        self.piece(prev, qp, &mid, level + 1, path, q)?;
        let qm = *q.last().expect("the midpoint");
        self.piece(&mid, &qm, target, level + 1, path, q)
    }
}

/// The time law's inputs at each point of the path.
struct Limits1 {
    v_write: f64,
    a_write: f64,
    qd: f64,
    qdd: f64,
    depth_rate: f64,
    qddd: f64,
}

/// Forward and backward passes: the largest speed at each point within `vlim` and the
/// acceleration bounds. `qs[i]`, `xs`… are per segment (i → i+1), `qss[i]`, `xss` per point.
fn passes(vlim: &[f64], ds: &[f64], qs: &[[f64; 6]], qss: &[[f64; 6]], lim: &Limits1) -> Vec<f64> {
    let n = vlim.len();
    let accel = |v: f64, seg: usize, at: usize| -> f64 {
        let mut u = lim.a_write;
        for j in 0..6 {
            let room = lim.qdd - qss[at][j].abs() * v * v;
            if qs[seg][j].abs() > 1e-12 {
                u = u.min(room.max(0.0) / qs[seg][j].abs());
            }
        }
        u
    };
    let mut v = vlim.to_vec();
    v[0] = 0.0;
    v[n - 1] = 0.0;
    for i in 0..n - 1 {
        let u = accel(v[i], i, i);
        v[i + 1] = v[i + 1].min((v[i] * v[i] + 2.0 * u * ds[i]).sqrt());
    }
    for i in (0..n - 1).rev() {
        let u = accel(v[i + 1], i, i + 1);
        v[i] = v[i].min((v[i + 1] * v[i + 1] + 2.0 * u * ds[i]).sqrt());
    }
    v
}

/// The times at the points for speeds `v` (constant acceleration within each segment).
fn times(v: &[f64], ds: &[f64]) -> Vec<f64> {
    let mut t = vec![0.0; v.len()];
    for i in 0..ds.len() {
        let dt = if v[i] + v[i + 1] > 0.0 { 2.0 * ds[i] / (v[i] + v[i + 1]) } else { 0.0 };
        t[i + 1] = t[i] + dt;
    }
    t
}

/// `s` at time `at` for the time law (`t`, `v` at the points).
fn s_at(at: f64, t: &[f64], v: &[f64], s: &[f64]) -> f64 {
    let n = t.len();
    if at >= t[n - 1] {
        return s[n - 1];
    }
    let i = t.partition_point(|&x| x <= at).saturating_sub(1).min(n - 2);
    let dt = t[i + 1] - t[i];
    if dt <= 0.0 {
        return s[i];
    }
    let u = (v[i + 1] - v[i]) / dt;
    let tau = at - t[i];
    (s[i] + v[i] * tau + 0.5 * u * tau * tau).min(s[i + 1])
}

/// A turn of the path's direction at a point beyond which the brush stops there (the change
/// of the unit direction: √2 is 90°).
const STOP_TURN: f64 = std::f64::consts::SQRT_2;

/// One piece of a stroke's path between stops, timed from rest to rest.
struct Piece<'a> {
    vlim: &'a [f64],
    ds: &'a [f64],
    qs: &'a [[f64; 6]],
    qss: &'a [[f64; 6]],
    /// Path length at its points, m (absolute).
    s: &'a [f64],
}

impl Piece<'_> {
    /// The path length at each waypoint (`dt` apart; the first and last at the ends, at rest)
    /// and the reference duration (time-optimal without the jerk limit), s.
    fn time(&self, lim: &Limits1, dt: f64, window: usize) -> (Vec<f64>, f64) {
        if self.vlim.len() == 2 {
            // One segment from rest to rest (a stop just before the stroke's end, or two stops
            // one point apart): the passes need a point inside it to reach any speed, or the
            // segment would take no time and its waypoints jump across it.
            let mid = |a: &[f64; 6], b: &[f64; 6]| -> [f64; 6] { std::array::from_fn(|j| 0.5 * (a[j] + b[j])) };
            let vlim = [self.vlim[0], self.vlim[0].max(self.vlim[1]), self.vlim[1]];
            let ds = [0.5 * self.ds[0]; 2];
            let qs = [self.qs[0]; 2];
            let qss = [self.qss[0], mid(&self.qss[0], &self.qss[1]), self.qss[1]];
            let s = [self.s[0], 0.5 * (self.s[0] + self.s[1]), self.s[1]];
            return Piece { vlim: &vlim, ds: &ds, qs: &qs, qss: &qss, s: &s }.time(lim, dt, window);
        }
        let n = self.vlim.len();
        let v_ref = passes(self.vlim, self.ds, self.qs, self.qss, lim);
        let reference = times(&v_ref, self.ds)[n - 1];
        // The jerk limit: a limit at one point holds, growing by 1 / (2 T) per metre of path,
        // around it; the path is timed within those, then the speed averaged over T.
        let slope = 0.5 / (window as f64 * dt);
        let mut eroded = self.vlim.to_vec();
        for i in 1..n {
            eroded[i] = eroded[i].min(eroded[i - 1] + self.ds[i - 1] * slope);
        }
        for i in (0..n - 1).rev() {
            eroded[i] = eroded[i].min(eroded[i + 1] + self.ds[i] * slope);
        }
        let v = passes(&eroded, self.ds, self.qs, self.qss, lim);
        let t = times(&v, self.ds);
        let total = t[n - 1];
        let (s0, s_end) = (self.s[0], self.s[n - 1]);
        // A piece too slow to sample is refused by the caller (its waypoint count).
        let steps = if total.is_finite() { (total / dt).ceil().clamp(1.0, MAX_STROKE_WAYPOINTS as f64) } else { 1.0 };
        let steps = steps as usize;
        let at: Vec<f64> = (0..=steps).map(|k| s_at(k as f64 * dt, &t, &v, self.s)).collect();
        if !total.is_finite() || total > MAX_STROKE_WAYPOINTS as f64 * dt {
            return (vec![s0; MAX_STROKE_WAYPOINTS + 2], reference);
        }
        // Mean speed over each interval, averaged over the window (zeros before and after).
        let mean: Vec<f64> = at.windows(2).map(|w| (w[1] - w[0]) / dt).collect();
        let len = mean.len() + window - 1;
        let mut out = Vec::with_capacity(len + 1);
        out.push(s0);
        let (mut acc, mut run) = (0.0, s0);
        for k in 0..len {
            if k < mean.len() {
                acc += mean[k];
            }
            if k >= window {
                acc -= mean[k - window];
            }
            run += acc / window as f64 * dt;
            out.push(run.min(s_end));
        }
        *out.last_mut().expect("samples") = s_end;
        (out, reference)
    }
}

/// The speed bound at each point of a stroke's path, m/s: the write speed, each joint's speed
/// and the depth rate over the neighbouring pieces (`qs`, `hs`: rates per metre), and at the
/// inner points the path's curvature and kink (`xs`: directions) and the joints' acceleration
/// and jerk (`qss`) within one interval `dt`.
fn speed_limits(
    lim: &Limits1,
    dt: f64,
    ds: &[f64],
    xs: &[Vector3<f64>],
    qs: &[[f64; 6]],
    hs: &[f64],
    qss: &[[f64; 6]],
) -> Vec<f64> {
    let n = qss.len();
    let mut vlim = vec![lim.v_write; n];
    for i in 0..n {
        let segs = [i.checked_sub(1), (i < n - 1).then_some(i)];
        for seg in segs.into_iter().flatten() {
            for j in 0..6 {
                if qs[seg][j].abs() > 0.0 {
                    vlim[i] = vlim[i].min(lim.qd / qs[seg][j].abs());
                }
            }
            if hs[seg].abs() > 0.0 {
                vlim[i] = vlim[i].min(lim.depth_rate / hs[seg].abs());
            }
        }
        if i == 0 || i == n - 1 {
            continue;
        }
        // The joints are interpolated linearly between the points, so a change of direction
        // at a point (`dx` of the path, `dq` of a joint's rate per metre) falls within one
        // interval of the waypoints: an acceleration v·dx/dt (v·dq/dt), and for the joints a
        // jerk v·dq/dt². The bounds keep those within the limits.
        let m = 0.5 * (ds[i - 1] + ds[i]);
        let dx = (xs[i] - xs[i - 1]).norm();
        if dx > 0.0 {
            // The path's curvature dx/m, and its kink crossed within one interval.
            vlim[i] = vlim[i].min((lim.a_write * m / dx).sqrt()).min(lim.a_write * dt / dx);
        }
        for j in 0..6 {
            let dq = (qs[i][j] - qs[i - 1][j]).abs();
            if dq > 0.0 {
                vlim[i] = vlim[i].min(lim.qdd * dt / dq).min(lim.qddd * dt * dt / dq);
            }
        }
        for j in 0..6 {
            if qss[i][j].abs() > 0.0 {
                vlim[i] = vlim[i].min((lim.qdd / qss[i][j].abs()).sqrt());
            }
        }
    }
    vlim
}

/// The peaks of a timed stroke's waypoints, by finite differences over `dt`.
struct Peaks {
    v: f64,
    a: f64,
    h: f64,
    qd: [f64; 6],
    qdd: f64,
    qddd: f64,
}

impl Peaks {
    fn of(poses: &[Pose], depth_mm: &[f64], joints: &[[f64; 6]], dt: f64) -> Peaks {
        let m = joints.len();
        let pos: Vec<Vector3<f64>> = poses.iter().map(|p| Vector3::from(p.position())).collect();
        let mut peak_v = 0.0f64;
        let mut peak_a = 0.0f64;
        let mut peak_h = 0.0f64;
        let mut peak_qd = [0.0f64; 6];
        let (mut peak_qdd, mut peak_qddd) = (0.0f64, 0.0f64);
        for k in 1..m {
            peak_v = peak_v.max((pos[k] - pos[k - 1]).norm() / dt);
            peak_h = peak_h.max((depth_mm[k] - depth_mm[k - 1]).abs() / dt);
            for j in 0..6 {
                peak_qd[j] = peak_qd[j].max((joints[k][j] - joints[k - 1][j]).abs() / dt);
            }
            if k >= 2 {
                peak_a = peak_a.max((pos[k] - 2.0 * pos[k - 1] + pos[k - 2]).norm() / (dt * dt));
                for j in 0..6 {
                    let a = joints[k][j] - 2.0 * joints[k - 1][j] + joints[k - 2][j];
                    peak_qdd = peak_qdd.max(a.abs() / (dt * dt));
                }
            }
            if k >= 3 {
                for j in 0..6 {
                    let jk = joints[k][j] - 3.0 * joints[k - 1][j] + 3.0 * joints[k - 2][j] - joints[k - 3][j];
                    peak_qddd = peak_qddd.max(jk.abs() / (dt * dt * dt));
                }
            }
        }
        Peaks { v: peak_v, a: peak_a, h: peak_h, qd: peak_qd, qdd: peak_qdd, qddd: peak_qddd }
    }
}

/// Times one stroke's pressed path (`poses`, with the press depth at each, mm); `None` when it
/// has fewer than two distinct points.
///
/// # Errors
/// As [`time_program`], for this stroke (the limits other than the kinematic ones are checked
/// by [`time_program`]).
pub fn time_stroke(
    stroke: usize,
    poses: &[Pose],
    depths_mm: &[f64],
    kin: &DhParams,
    tcp: &Isometry3<f64>,
    seed: Option<&[f64; 6]>,
    cfg: &RobotConfig,
) -> Result<Option<TimedStroke>, RobotError> {
    let Some(coarse) = discretise(poses, depths_mm) else { return Ok(None) };
    // Joints on one branch, each seeded by the one before; a piece over which they move more
    // than BRANCH_STEP_RAD is halved (up to MAX_HALVINGS times) before it counts as a jump.
    let mut path = Path { iso: Vec::new(), depth_mm: Vec::new(), from: Vec::new(), s: Vec::new() };
    let mut q: Vec<[f64; 6]> = Vec::with_capacity(coarse.iso.len());
    let mut min_sv = f64::INFINITY;
    let chain = kin.chain();
    let mut solver = Solver { stroke, kin, chain: &chain, tcp, cfg, min_sv: &mut min_sv };
    for i in 0..coarse.iso.len() {
        let target = (coarse.iso[i], coarse.depth_mm[i], coarse.s[i], coarse.from[i]);
        match q.last().copied() {
            None => {
                let qi = solver.solve(&target, seed)?;
                path.push(target);
                q.push(qi);
            }
            Some(qp) => {
                let last = path.len() - 1;
                let prev = (path.iso[last], path.depth_mm[last], path.s[last], path.from[last]);
                solver.piece(&prev, &qp, &target, 0, &mut path, &mut q)?;
            }
        }
    }
    let n = path.iso.len();
    let ds: Vec<f64> = path.s.windows(2).map(|w| w[1] - w[0]).collect();
    let qs: Vec<[f64; 6]> = (0..n - 1).map(|i| std::array::from_fn(|j| (q[i + 1][j] - q[i][j]) / ds[i])).collect();
    let xs: Vec<Vector3<f64>> =
        (0..n - 1).map(|i| (path.iso[i + 1].translation.vector - path.iso[i].translation.vector) / ds[i]).collect();
    let hs: Vec<f64> = (0..n - 1).map(|i| (path.depth_mm[i + 1] - path.depth_mm[i]) / ds[i]).collect();
    let mut qss = vec![[0.0; 6]; n];
    for i in 1..n - 1 {
        let m = 0.5 * (ds[i - 1] + ds[i]);
        qss[i] = std::array::from_fn(|j| (qs[i][j] - qs[i - 1][j]) / m);
    }
    let dt = cfg.timing.interval_s;
    let lim = Limits1 {
        v_write: cfg.write_speed_m_s,
        a_write: cfg.write_acc_m_s2,
        qd: cfg.joint_speed_rad_s,
        qdd: cfg.joint_acc_rad_s2,
        depth_rate: cfg.timing.max_depth_rate_mm_s,
        qddd: cfg.timing.joint_jerk_rad_s3,
    };
    let vlim = speed_limits(&lim, dt, &ds, &xs, &qs, &hs, &qss);
    // The brush stops where the path turns back (more than 90°): each piece between stops is
    // timed from rest to rest, so the waypoints reach the turning point itself.
    let mut bounds = vec![0];
    for i in 1..n - 1 {
        if (xs[i] - xs[i - 1]).norm() > STOP_TURN && *bounds.last().expect("one bound") < i {
            bounds.push(i);
        }
    }
    bounds.push(n - 1);
    let window = ((lim.a_write / cfg.timing.write_jerk_m_s3) / dt).round().max(1.0) as usize;
    let mut s_samples: Vec<f64> = vec![0.0];
    let mut reference_s = 0.0;
    for w in bounds.windows(2) {
        let (a, b) = (w[0], w[1]);
        let piece = Piece { vlim: &vlim[a..=b], ds: &ds[a..b], qs: &qs[a..b], qss: &qss[a..=b], s: &path.s[a..=b] };
        let (samples, reference) = piece.time(&lim, dt, window);
        reference_s += reference;
        s_samples.extend(&samples[1..]);
        let total = (s_samples.len() - 1) as f64 * dt;
        let most = MAX_STROKE_WAYPOINTS as f64 * dt;
        if !(total.is_finite() && total <= most) {
            return Err(unsafe_at(
                stroke,
                None,
                format!(
                    "the timed stroke would take more than {MAX_STROKE_WAYPOINTS} waypoints ({most:.0} s at timing.interval_s = {dt} s): the limits slow it too much"
                ),
            ));
        }
    }
    // Waypoints: joints interpolated along s, and the commanded pose there.
    let mut joints = Vec::with_capacity(s_samples.len());
    let mut poses_out = Vec::with_capacity(s_samples.len());
    let mut depth_out = Vec::with_capacity(s_samples.len());
    let (mut err_m, mut err_rad) = (0.0f64, 0.0f64);
    for &sk in &s_samples {
        let i = path.s.partition_point(|&x| x <= sk).saturating_sub(1).min(n - 2);
        let f = ((sk - path.s[i]) / ds[i]).clamp(0.0, 1.0);
        let qk: [f64; 6] = std::array::from_fn(|j| q[i][j] + (q[i + 1][j] - q[i][j]) * f);
        let want = lerp_iso(&path.iso[i], &path.iso[i + 1], f);
        let got = chain.forward(&qk, tcp);
        err_m = err_m.max((got.translation.vector - want.translation.vector).norm());
        err_rad = err_rad.max(got.rotation.angle_to(&want.rotation));
        joints.push(qk);
        poses_out.push(Pose::from_iso(&want));
        depth_out.push(path.depth_mm[i] + (path.depth_mm[i + 1] - path.depth_mm[i]) * f);
    }
    let pk = Peaks::of(&poses_out, &depth_out, &joints, dt);
    Ok(Some(TimedStroke {
        stroke,
        interval_s: dt,
        duration_s: (joints.len() - 1) as f64 * dt,
        reference_s,
        joints,
        poses: poses_out,
        peak_speed_m_s: pk.v,
        peak_acc_m_s2: pk.a,
        peak_depth_rate_mm_s: pk.h,
        peak_joint_speed_rad_s: pk.qd,
        peak_joint_acc_rad_s2: pk.qdd,
        peak_joint_jerk_rad_s3: pk.qddd,
        min_singular_value: min_sv,
        path_error_m: err_m,
        path_error_rad: err_rad,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;

    #[test]
    fn a_moving_average_of_a_bang_bang_profile_keeps_its_length() {
        // Checked through `time_stroke` on a straight line: the last waypoint is the end.
        let tcp = Isometry3::from_parts(nalgebra::Translation3::new(0.0, 0.0, 0.2), UnitQuaternion::identity());
        let a = Pose([0.5, -0.1, 0.1, std::f64::consts::PI, 0.0, 0.0]);
        let b = Pose([0.5, -0.05, 0.1, std::f64::consts::PI, 0.0, 0.0]);
        let cfg = RobotConfig::default();
        let t = time_stroke(0, &[a, b], &[1.0, 1.0], &DhParams::AUBO_I5, &tcp, None, &cfg).unwrap().unwrap();
        let last = t.poses.last().unwrap().position();
        assert!((0..3).all(|k| (last[k] - b.0[k]).abs() < 1e-12), "{last:?}");
        assert!(t.poses[0].position().iter().zip(&a.0).all(|(x, y)| (x - y).abs() < 1e-12));
        // 50 mm at 20 mm/s at most, with ramps: longer than 2.5 s, and the reference shorter.
        assert!(t.duration_s > 2.5 && t.reference_s > 2.5 && t.reference_s <= t.duration_s, "{t:?}");
        assert!(t.peak_speed_m_s <= 0.02 + 1e-9 && t.peak_speed_m_s > 0.019, "{}", t.peak_speed_m_s);
        assert!(t.peak_acc_m_s2 <= 0.3 + 1e-6, "{}", t.peak_acc_m_s2);
    }

    #[test]
    fn a_stop_one_short_segment_before_the_end_is_timed_not_jumped() {
        // 10 mm along y, then 0.25 mm back: the brush stops at the turn, and the last piece is
        // one segment from rest to rest (it once took no time: one waypoint step of 0.25 mm).
        let tcp = Isometry3::from_parts(nalgebra::Translation3::new(0.0, 0.0, 0.2), UnitQuaternion::identity());
        let at = |y: f64| Pose([0.5, y, 0.1, std::f64::consts::PI, 0.0, 0.0]);
        let (a, b, c) = (at(-0.1), at(-0.09), at(-0.09025));
        let cfg = RobotConfig::default();
        let t = time_stroke(0, &[a, b, c], &[1.0; 3], &DhParams::AUBO_I5, &tcp, None, &cfg).unwrap().unwrap();
        let last = t.poses.last().unwrap().position();
        assert!((0..3).all(|k| (last[k] - c.0[k]).abs() < 1e-12), "{last:?}");
        assert!(t.peak_speed_m_s <= cfg.write_speed_m_s + 1e-9, "{}", t.peak_speed_m_s);
        assert!(t.peak_acc_m_s2 <= cfg.write_acc_m_s2 * 1.5, "{}", t.peak_acc_m_s2);
        // The short piece takes several waypoints (0.25 mm from rest to rest).
        let back = t.poses.iter().filter(|p| p.position()[1] < -0.09 - 1e-9 && p.position()[1] > -0.09025 + 1e-9);
        assert!(back.count() >= 2);
        check_stroke(&t, &cfg).unwrap();
    }
    #[test]
    fn a_stroke_over_a_limit_is_timed_again_slower_until_within_it() {
        // Corners of 30–85° in a 10 mm stroke, with the joint jerk limit set to what the timing
        // plans for: the per-point bounds alone overshoot it at some corner; timed again, every
        // stroke is within every limit, and one that was within at once is timed unchanged.
        let tcp = Isometry3::from_parts(nalgebra::Translation3::new(0.0, 0.0, 0.2), UnitQuaternion::identity());
        let mut cfg = RobotConfig::default();
        cfg.limits.max_joint_jerk_rad_s3 = cfg.timing.joint_jerk_rad_s3;
        let (mut over, mut within) = (0, 0);
        for deg in (30..=85).step_by(5) {
            let turn = f64::from(deg).to_radians();
            let at = |x: f64, y: f64| Pose([0.5 + x, -0.1 + y, 0.1, std::f64::consts::PI, 0.0, 0.0]);
            let poses = [at(0.0, 0.0), at(0.0, 0.005), at(0.005 * turn.sin(), 0.005 + 0.005 * turn.cos())];
            let first = time_stroke(0, &poses, &[1.0; 3], &DhParams::AUBO_I5, &tcp, None, &cfg).unwrap().unwrap();
            let t =
                time_stroke_within_limits(0, &poses, &[1.0; 3], &DhParams::AUBO_I5, &tcp, None, &cfg).unwrap().unwrap();
            assert!(limit_excess(&t, &cfg) <= 1.0, "{deg}°: {t:?}");
            check_stroke(&t, &cfg).unwrap();
            if check_stroke(&first, &cfg).is_err() {
                over += 1;
                assert!(t.duration_s > first.duration_s, "{deg}°: slower");
            } else {
                within += 1;
                assert_eq!(t.joints, first.joints, "{deg}°: unchanged");
            }
        }
        assert!(over > 0 && within > 0, "corners over the limit {over}, within {within}: both kinds are needed");
    }
}
