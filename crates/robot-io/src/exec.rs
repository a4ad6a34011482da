//! The pure motion executor: linear and joint moves sampled into trace entries, a whole program
//! executed without a connection (plain, or each sample tagged with its stroke and whether it is
//! part of an ink dip), the executed path turned back into brush states on the paper, and the
//! level sheet in front of the arm that the pipeline and the preview run programs on. No
//! sockets: the simulator server ([`crate::sim`]) moves its arm with these functions.

use serde::{Deserialize, Serialize};

use crate::frame::PaperFrame;
use crate::kinematics::{self, DhParams};
use crate::pose::Pose;
use crate::program::{Move, Program};

/// One sample of the executed TCP path.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TraceEntry {
    /// Time since execution started, s (at the commanded speeds).
    #[serde(default)]
    pub t_s: f64,
    /// The move this sample belongs to (`moveLine` or `moveJoint`).
    pub kind: TraceKind,
    /// TCP pose at this instant.
    pub pose: Pose,
}

/// Kind of executed move.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TraceKind {
    /// A joint move.
    Joint,
    /// A linear move.
    Line,
    /// A path buffer's joint waypoints (`movePathBuffer`).
    PathBuffer,
}

/// One sample of a program executed by [`execute_program_tagged`], with the part of the program
/// its move belongs to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TaggedEntry {
    /// The sample.
    pub entry: TraceEntry,
    /// Zero-based index of the stroke whose moves this sample belongs to; `None` for the
    /// program's first move (from the home position to above the first stroke).
    pub stroke: Option<usize>,
    /// Whether the move is part of the ink dip before the stroke.
    pub dip: bool,
}

/// Largest TCP travel between two trace samples, m.
pub const TRACE_STEP_M: f64 = 0.2e-3;
/// Largest time between two trace samples, s (unless a move would need more than
/// [`MAX_SAMPLES_PER_MOVE`] samples).
pub const TRACE_STEP_S: f64 = 0.005;
/// Largest tool rotation between two trace samples, rad.
pub const TRACE_STEP_RAD: f64 = 0.5 * std::f64::consts::PI / 180.0;

/// Where [`level_frame_in_front`] puts the centre it is given: base (0.45, 0.05, 0.05) m, in
/// front of the AUBO-i5 within its reach with the tool pointing down.
pub const IN_FRONT_M: [f64; 3] = [0.45, 0.05, 0.05];

/// A level sheet (as [`PaperFrame::level`]) placed so that the paper point `center_mm`
/// (x, y, mm) lies at [`IN_FRONT_M`], with the usable area `bounds_mm` (`[x0, y0, x1, y1]`, mm).
/// The frame `maobi write` and `maobi preview` run a program on when no `paper.json` is given.
///
/// # Examples
/// ```
/// use robot_io::{IN_FRONT_M, level_frame_in_front};
/// // An A4 sheet (210 × 297 mm) whose middle lies in front of the arm.
/// let frame = level_frame_in_front([105.0, 148.5], [0.0, 0.0, 210.0, 297.0]);
/// let [x_mm, y_mm, depth_mm] = frame.to_paper(IN_FRONT_M);
/// assert!((x_mm - 105.0).abs() < 1e-9 && (y_mm - 148.5).abs() < 1e-9 && depth_mm.abs() < 1e-9);
/// assert!(frame.contains(200.0, 290.0) && !frame.contains(220.0, 100.0));
/// ```
pub fn level_frame_in_front(center_mm: [f64; 2], bounds_mm: [f64; 4]) -> PaperFrame {
    let [x_m, y_m, z_m] = IN_FRONT_M;
    let mut f = PaperFrame::level([x_m - center_mm[0] / 1000.0, y_m + center_mm[1] / 1000.0, z_m], [0.0, 0.0]);
    f.bounds_mm = bounds_mm;
    f
}

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
            let pose = if k == n { *to } else { pose_between(&a, &b, f) };
            TraceEntry { t_s: t0_s + f * duration, kind: TraceKind::Line, pose }
        })
        .collect()
}

/// The pose a fraction `f` (0..1) of the way from `a` to `b`: the position on the straight line,
/// the orientation by slerp (the nearer end's for a half turn, where slerp is undefined).
pub(crate) fn pose_between(a: &nalgebra::Isometry3<f64>, b: &nalgebra::Isometry3<f64>, f: f64) -> Pose {
    let t = a.translation.vector.lerp(&b.translation.vector, f);
    let r = a.rotation.try_slerp(&b.rotation, f, 1e-12).unwrap_or(if f < 0.5 { a.rotation } else { b.rotation });
    Pose::from_iso(&nalgebra::Isometry3::from_parts(nalgebra::Translation3::from(t), r))
}

/// Executes a joint move: joints interpolated linearly at joint speed `v_rad_s`, the TCP pose by
/// forward kinematics with the arm's parameters `dh` (the AUBO-i5's: [`DhParams::AUBO_I5`]),
/// sampled as [`line_motion`] (at most [`MAX_SAMPLES_PER_MOVE`] samples).
pub fn joint_motion(
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
/// first joint move from the simulator's home position ([`HOME_JOINTS`]), then every move in
/// order. Returns the executed path ([`line_motion`], [`joint_motion`]).
///
/// # Examples
/// ```
/// use robot_io::brush_model::{BrushProfile, Stroke, Track, TrackPoint};
/// use robot_io::{RobotConfig, build_program, execute_program, level_frame_in_front};
/// let profile = BrushProfile::builtin("pen1").unwrap();
/// let pt = |x: f64| TrackPoint { x_mm: x, y_mm: 60.0, h_mm: 3.0, alpha_rad: 0.0, beta_rad: 0.0 };
/// let track = Track { strokes: vec![Stroke { points: (0..=100).map(|i| pt(30.0 + 0.2 * f64::from(i))).collect() }] };
/// // A level sheet whose surface is at z = 0.05 m in the base frame.
/// let frame = level_frame_in_front([50.0, 60.0], [0.0, 0.0, 210.0, 297.0]);
/// let (program, _) = build_program(&track, &profile, &frame, &RobotConfig::default()).unwrap();
/// let trace = execute_program(&program);
/// assert!(trace.windows(2).all(|w| w[0].t_s <= w[1].t_s));
/// // The brush tip goes 3 mm into the paper and no deeper.
/// let lowest_m = trace.iter().map(|e| e.pose.0[2]).fold(f64::INFINITY, f64::min);
/// assert!((lowest_m - (0.05 - 0.003)).abs() < 1e-6);
/// ```
pub fn execute_program(program: &Program) -> Vec<TraceEntry> {
    let mut out = Vec::new();
    execute_with(program, |samples, _, _| out.extend_from_slice(samples));
    out
}

/// [`execute_program`] with each sample tagged with its stroke and whether its move is part of
/// that stroke's ink dip (the same samples, in the same order).
pub fn execute_program_tagged(program: &Program) -> Vec<TaggedEntry> {
    let mut out = Vec::new();
    execute_with(program, |samples, stroke, dip| {
        out.extend(samples.iter().map(|&entry| TaggedEntry { entry, stroke, dip }));
    });
    out
}

/// Executes `program` move by move, handing each move's samples to `sink` with the move's stroke
/// (`None` for the first move) and whether it is part of the stroke's ink dip.
fn execute_with(program: &Program, mut sink: impl FnMut(&[TraceEntry], Option<usize>, bool)) {
    let tcp = program.tcp();
    let mut q = HOME_JOINTS;
    let mut pose = Pose::from_iso(&kinematics::forward(&q, &tcp));
    let mut t = 0.0;
    let f = program.speed_fraction;
    let mut run = |m: &Move, stroke: Option<usize>, dip: bool| {
        let samples = match *m {
            Move::Joint { q: q1, v, .. } => {
                let s = joint_motion(&DhParams::AUBO_I5, &q, &q1, v * f, &tcp, t);
                q = q1;
                s
            }
            Move::JointPose { pose: p1, v, .. } => {
                // Solved as the controller would, from the present joints; a checked program's
                // poses are reachable, so the straight line is only a fallback.
                match kinematics::inverse(&p1, &tcp, Some(&q)) {
                    Some(q1) => {
                        let s = joint_motion(&DhParams::AUBO_I5, &q, &q1, v * f, &tcp, t);
                        q = q1;
                        s
                    }
                    None => line_motion(&pose, &p1, v * f, t),
                }
            }
            Move::Line { pose: p1, v, .. } => line_motion(&pose, &p1, v * f, t),
        };
        if let Some(last) = samples.last() {
            pose = last.pose;
            t = last.t_s;
        }
        sink(&samples, stroke, dip);
    };
    run(&program.start, None, false);
    for (k, st) in program.strokes.iter().enumerate() {
        for (i, m) in st.moves().enumerate() {
            run(m, Some(k), i < st.dip.len());
        }
    }
}

/// The simulator's joint positions at start, rad (controller convention): the tool points
/// straight down with the flange 0.44 m above the base, in front of the arm.
pub const HOME_JOINTS: [f64; 6] = [0.0, -0.3, 1.2, -0.0708, std::f64::consts::FRAC_PI_2, 0.0];

/// Turns an executed TCP path back into commanded brush states on the paper, for the forward
/// model (`brush_model::ForwardModel`): the position where the tool axis meets the paper, the
/// depth below it (H; negative above the paper, where the brush leaves nothing), the tilt α of
/// the tool axis from the paper normal and the direction β it leans towards. Joint moves are
/// included (they happen above the paper). The result is one sequence: the forward model ends a
/// contact wherever H ≤ 0.
pub fn trace_to_states(trace: &[TraceEntry], frame: &PaperFrame) -> Vec<brush_model::TrackPoint> {
    let inv = frame.iso.rotation.inverse();
    trace
        .iter()
        .map(|t| {
            let p = frame.to_paper(t.pose.position());
            let z = inv * (t.pose.to_iso().rotation * nalgebra::Vector3::z());
            let alpha = z.z.clamp(-1.0, 1.0).acos();
            let beta = if z.x.hypot(z.y) > 1e-12 { z.y.atan2(z.x) } else { 0.0 };
            // Round-off of a pose at the surface must not count as contact.
            let h = if p[2].abs() < 1e-6 { 0.0 } else { p[2] };
            brush_model::TrackPoint { x_mm: p[0], y_mm: p[1], h_mm: h, alpha_rad: alpha, beta_rad: beta }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_level_frame_in_front_puts_the_centre_in_front_of_the_arm() {
        let f = level_frame_in_front([60.0, 40.0], [10.0, 20.0, 110.0, 60.0]);
        assert_eq!(f.bounds_mm, [10.0, 20.0, 110.0, 60.0]);
        let cases: [([f64; 3], [f64; 3]); 3] = [
            // paper (x, y, depth) mm → base m: the centre, +x along base +x, +y along base −y.
            ([60.0, 40.0, 0.0], IN_FRONT_M),
            ([70.0, 40.0, 0.0], [0.46, 0.05, 0.05]),
            ([60.0, 50.0, 5.0], [0.45, 0.04, 0.045]),
        ];
        for (paper, base) in cases {
            let got = f.iso * nalgebra::Point3::new(paper[0] / 1000.0, paper[1] / 1000.0, paper[2] / 1000.0);
            for i in 0..3 {
                assert!((got[i] - base[i]).abs() < 1e-12, "{paper:?} → {got:?}, expected {base:?}");
            }
            let back = f.to_paper(base);
            assert!((0..3).all(|i| (back[i] - paper[i]).abs() < 1e-9), "{base:?} → {back:?}");
        }
    }
}
