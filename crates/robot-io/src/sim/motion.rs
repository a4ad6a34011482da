//! The simulator's motion model: linear and joint moves sampled into trace entries, and a whole
//! program executed without a connection.

use crate::kinematics::{self, DhParams};
use crate::pose::Pose;

use super::{TRACE_STEP_M, TRACE_STEP_RAD, TRACE_STEP_S, TraceEntry, TraceKind};

/// Most trace samples one move records. A move that would need more (a slow move: the samples
/// are at most [`TRACE_STEP_S`] apart) is sampled evenly with this many, further apart in
/// time; normal programs' moves need far fewer and are unaffected.
pub const MAX_SAMPLES_PER_MOVE: usize = 100_000;

/// The sample count for a move: enough for the step limits, at least 1 (also when a limit is
/// not a number), at most [`MAX_SAMPLES_PER_MOVE`].
fn sample_count(steps: f64) -> usize {
    if steps.is_nan() { 1 } else { steps.ceil().clamp(1.0, MAX_SAMPLES_PER_MOVE as f64) as usize }
}

/// Executes a linear move as the simulator does: the TCP position moves in a straight line and
/// the orientation turns by slerp, both at constant speed `v_m_s` along the path (accelerations
/// and blending are not modelled: a stated simplification, see docs/robot.md). Returns the
/// samples after `from` up to and including `to`, at most [`TRACE_STEP_M`] of travel,
/// [`TRACE_STEP_RAD`] of rotation and [`TRACE_STEP_S`] apart, with their times after `t0_s`;
/// never more than [`MAX_SAMPLES_PER_MOVE`] (a slow move's samples are then further apart in
/// time).
pub fn line_motion(from: &Pose, to: &Pose, v_m_s: f64, t0_s: f64) -> Vec<TraceEntry> {
    let (a, b) = (from.to_iso(), to.to_iso());
    let d = (b.translation.vector - a.translation.vector).norm();
    let turn = a.rotation.angle_to(&b.rotation);
    let v = if v_m_s > 0.0 { v_m_s } else { 1.0 };
    // Rotations in place run at an angular speed of v per 0.1 m (a stated choice).
    let duration = (d / v).max(turn * 0.1 / v);
    let n = sample_count((d / TRACE_STEP_M).max(turn / TRACE_STEP_RAD).max(duration / TRACE_STEP_S));
    (1..=n)
        .map(|k| {
            let f = k as f64 / n as f64;
            let pose = if k == n {
                *to
            } else {
                let t = a.translation.vector.lerp(&b.translation.vector, f);
                let r = a.rotation.try_slerp(&b.rotation, f, 1e-12).unwrap_or(if f < 0.5 {
                    a.rotation
                } else {
                    b.rotation
                });
                Pose::from_iso(&nalgebra::Isometry3::from_parts(nalgebra::Translation3::from(t), r))
            };
            TraceEntry { t_s: t0_s + f * duration, kind: TraceKind::Line, pose }
        })
        .collect()
}

/// Executes a joint move: joints interpolated linearly at joint speed `v_rad_s`, the TCP pose by
/// forward kinematics ([`DhParams::AUBO_I5`]), sampled as [`line_motion`] (at most
/// [`MAX_SAMPLES_PER_MOVE`] samples).
pub fn joint_motion(
    from: &[f64; 6],
    to: &[f64; 6],
    v_rad_s: f64,
    tcp: &nalgebra::Isometry3<f64>,
    t0_s: f64,
) -> Vec<TraceEntry> {
    joint_motion_dh(&DhParams::AUBO_I5, from, to, v_rad_s, tcp, t0_s)
}

/// [`joint_motion`] with the arm's parameters `dh`.
pub(super) fn joint_motion_dh(
    dh: &DhParams,
    from: &[f64; 6],
    to: &[f64; 6],
    v_rad_s: f64,
    tcp: &nalgebra::Isometry3<f64>,
    t0_s: f64,
) -> Vec<TraceEntry> {
    let dq = from.iter().zip(to).map(|(a, b)| (b - a).abs()).fold(0.0, f64::max);
    let duration = dq / if v_rad_s > 0.0 { v_rad_s } else { 1.0 };
    let n = sample_count((dq / TRACE_STEP_RAD).max(duration / TRACE_STEP_S));
    (1..=n)
        .map(|k| {
            let f = k as f64 / n as f64;
            let q: [f64; 6] = std::array::from_fn(|j| from[j] + f * (to[j] - from[j]));
            TraceEntry { t_s: t0_s + f * duration, kind: TraceKind::Joint, pose: Pose::from_iso(&dh.forward(&q, tcp)) }
        })
        .collect()
}

/// Executes a whole program without a connection, as the simulator would if it were sent: the
/// first joint move from the simulator's home position, then every move in order. Returns the
/// executed path ([`line_motion`], [`joint_motion`]).
pub fn execute_program(program: &crate::program::Program) -> Vec<TraceEntry> {
    let tcp = program.tcp();
    let mut q = HOME_JOINTS;
    let mut out = Vec::new();
    let mut pose = Pose::from_iso(&kinematics::forward(&q, &tcp));
    let mut t = 0.0;
    let f = program.speed_fraction;
    let mut run = |m: &crate::program::Move, out: &mut Vec<TraceEntry>| {
        let samples = match *m {
            crate::program::Move::Joint { q: q1, v, .. } => {
                let s = joint_motion(&q, &q1, v * f, &tcp, t);
                q = q1;
                s
            }
            crate::program::Move::JointPose { pose: p1, v, .. } => {
                // Solved as the controller would, from the present joints; a checked program's
                // poses are reachable, so the straight line is only a fallback.
                match kinematics::inverse(&p1, &tcp, Some(&q)) {
                    Some(q1) => {
                        let s = joint_motion(&q, &q1, v * f, &tcp, t);
                        q = q1;
                        s
                    }
                    None => line_motion(&pose, &p1, v * f, t),
                }
            }
            crate::program::Move::Line { pose: p1, v, .. } => line_motion(&pose, &p1, v * f, t),
        };
        if let Some(last) = samples.last() {
            pose = last.pose;
            t = last.t_s;
        }
        out.extend(samples);
    };
    run(&program.start, &mut out);
    for m in program.strokes.iter().flat_map(|s| s.moves()) {
        run(m, &mut out);
    }
    out
}

/// The simulator's joint positions at start, rad (controller convention): the tool points
/// straight down with the flange 0.44 m above the base, in front of the arm.
pub const HOME_JOINTS: [f64; 6] = [0.0, -0.3, 1.2, -0.0708, std::f64::consts::FRAC_PI_2, 0.0];
