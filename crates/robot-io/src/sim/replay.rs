//! A whole program executed as the simulator server executes what `robot send` sends it,
//! without a connection: joint and linear moves on the trapezoidal time law, blended linear
//! moves rounded and run on one time law, and (for path-buffer sends) each timed stroke's
//! waypoints on their timing.

use crate::RobotError;
use crate::exec::{HOME_JOINTS, TaggedEntry, TraceEntry};
use crate::kinematics::DhParams;
use crate::pose::Pose;
use crate::program::{Move, Program, check_blends};
use crate::timing::ProgramTiming;

use super::blend::{BlendMove, blended_line_motion};
use super::dispatch::path_motion;
use super::{ramped_joint_motion, ramped_line_motion};

/// How the pressed strokes of a program reach the controller (as `robot send --motion`).
#[derive(Clone, Copy, Debug)]
pub enum SendMotion<'a> {
    /// Each timed stroke of the timing (by its stroke index) as one path buffer of its joint
    /// waypoints; the moves around it (dip, approach, lift) as moves.
    PathBuffer(&'a ProgramTiming),
    /// Every move as sent (a `moveLine` per point of a compacted program), blends rounded.
    Moves,
}

/// Executes `program` on an arm with parameters `dh` as the simulator server executes what
/// `robot send` sends it: from [`HOME_JOINTS`], the start pose solved from there and reached by
/// a joint move, then every move in order on the controller's time law
/// ([`ramped_line_motion`], [`ramped_joint_motion`]); consecutive blended `moveLine`s rounded
/// at their corners and run on one time law ([`blended_line_motion`]); with
/// [`SendMotion::PathBuffer`] each timed stroke's pressed moves replaced by its waypoints on
/// their timing. Speeds are scaled by the program's speed fraction (path buffers are not).
///
/// # Examples
/// ```
/// use robot_io::brush_model::{BrushProfile, Stroke, Track, TrackPoint};
/// use robot_io::DhParams;
/// use robot_io::sim::{SendMotion, execute_as_sent};
/// use robot_io::{RobotConfig, build_program, level_frame_in_front, time_program};
/// let profile = BrushProfile::builtin("pen1").unwrap();
/// let pt = |x: f64| TrackPoint { x_mm: x, y_mm: 60.0, h_mm: 3.0, alpha_rad: 0.0, beta_rad: 0.0 };
/// let track = Track { strokes: vec![Stroke { points: (0..=100).map(|i| pt(30.0 + 0.2 * f64::from(i))).collect() }] };
/// let frame = level_frame_in_front([50.0, 60.0], [0.0, 0.0, 210.0, 297.0]);
/// let cfg = RobotConfig::default();
/// let (program, _) = build_program(&track, &profile, &frame, &cfg).unwrap();
/// let timing = time_program(&program, &DhParams::AUBO_I5, &cfg).unwrap();
/// let trace = execute_as_sent(&program, &DhParams::AUBO_I5, SendMotion::PathBuffer(&timing)).unwrap();
/// assert!(trace.iter().any(|e| e.kind == robot_io::TraceKind::PathBuffer));
/// // The brush tip goes 3 mm into the paper and no deeper.
/// let lowest_m = trace.iter().map(|e| e.pose.0[2]).fold(f64::INFINITY, f64::min);
/// assert!((lowest_m - (0.05 - 0.003)).abs() < 1e-6);
/// ```
///
/// # Errors
/// With [`SendMotion::Moves`], [`check_blends`]'s error for a program whose blends a controller
/// refuses; [`RobotError::Unsafe`] when a target is unreachable for `dh`.
pub fn execute_as_sent(
    program: &Program,
    dh: &DhParams,
    motion: SendMotion<'_>,
) -> Result<Vec<TraceEntry>, RobotError> {
    Ok(execute_as_sent_tagged(program, dh, motion)?.into_iter().map(|e| e.entry).collect())
}

/// [`execute_as_sent`] with each sample tagged with its stroke (its position in the program)
/// and whether its move is part of that stroke's ink dip, as
/// [`crate::exec::execute_program_tagged`] tags them.
///
/// # Errors
/// As [`execute_as_sent`].
pub fn execute_as_sent_tagged(
    program: &Program,
    dh: &DhParams,
    motion: SendMotion<'_>,
) -> Result<Vec<TaggedEntry>, RobotError> {
    if matches!(motion, SendMotion::Moves) {
        check_blends(program)?;
    }
    let tcp = program.tcp();
    let f = program.speed_fraction;
    let mut arm = Arm {
        dh,
        tcp,
        q: HOME_JOINTS,
        pose: Pose::from_iso(&dh.forward(&HOME_JOINTS, &tcp)),
        t: 0.0,
        out: Vec::new(),
        chain: Vec::new(),
        tag: (None, false),
    };
    let unreachable = |stroke: Option<usize>, pose: &Pose| RobotError::Unsafe {
        stroke,
        point: None,
        reason: format!("the pose {:?} is not reachable by this arm", pose.0),
    };
    let run = |arm: &mut Arm<'_>, m: &Move, stroke: Option<usize>| -> Result<(), RobotError> {
        match *m {
            Move::Joint { q, v, a } => {
                arm.flush();
                arm.joint(q, v * f, a);
            }
            Move::JointPose { pose, v, a } => {
                arm.flush();
                let q = dh.inverse(&pose, &tcp, Some(&arm.q)).ok_or_else(|| unreachable(stroke, &pose))?;
                arm.joint(q, v * f, a);
            }
            Move::Line { pose, v, a, blend_m } => {
                let seed = arm.chain.last().map_or(arm.q, |(_, q)| *q);
                let q = dh.inverse(&pose, &tcp, Some(&seed)).ok_or_else(|| unreachable(stroke, &pose))?;
                arm.chain.push((BlendMove { pose, v_m_s: v * f, a_m_s2: a, blend_m }, q));
                if blend_m <= 0.0 {
                    arm.flush();
                }
            }
        }
        Ok(())
    };
    run(&mut arm, &program.start, None)?;
    for (k, st) in program.strokes.iter().enumerate() {
        let timed = match motion {
            SendMotion::PathBuffer(t) => t.strokes.iter().find(|t| t.stroke == st.index),
            SendMotion::Moves => None,
        };
        for (i, m) in st.dip.iter().chain(&st.approach).enumerate() {
            arm.tag_as(Some(k), i < st.dip.len());
            run(&mut arm, m, Some(st.index))?;
        }
        arm.tag_as(Some(k), false);
        match timed {
            Some(t) => {
                arm.flush();
                let samples = path_motion(dh, &t.joints, t.interval_s, &tcp, arm.t);
                arm.take(samples, *t.joints.last().expect("a timed stroke has waypoints"));
            }
            None => {
                for m in &st.press {
                    run(&mut arm, m, Some(st.index))?;
                }
            }
        }
        run(&mut arm, &st.lift, Some(st.index))?;
    }
    arm.flush();
    Ok(arm.out)
}

/// The arm while a program is replayed: its joints and pose, the time, the trace so far and
/// the blended moves waiting for the next.
struct Arm<'a> {
    dh: &'a DhParams,
    tcp: nalgebra::Isometry3<f64>,
    q: [f64; 6],
    pose: Pose,
    t: f64,
    out: Vec<TaggedEntry>,
    chain: Vec<(BlendMove, [f64; 6])>,
    /// The stroke (position in the program) and whether in its dip, of the moves now running.
    tag: (Option<usize>, bool),
}

impl Arm<'_> {
    /// Appends a move's samples; the arm ends at joints `q`.
    fn take(&mut self, samples: Vec<TraceEntry>, q: [f64; 6]) {
        if let Some(last) = samples.last() {
            self.t = last.t_s;
            self.pose = last.pose;
        }
        self.q = q;
        let (stroke, dip) = self.tag;
        self.out.extend(samples.into_iter().map(|entry| TaggedEntry { entry, stroke, dip }));
    }

    /// The moves from here on belong to `stroke` (its dip when `dip`): the waiting ones run
    /// first when that changes (a blend never joins two parts).
    fn tag_as(&mut self, stroke: Option<usize>, dip: bool) {
        if self.tag != (stroke, dip) {
            self.flush();
            self.tag = (stroke, dip);
        }
    }

    fn joint(&mut self, q: [f64; 6], v: f64, a: f64) {
        let samples = ramped_joint_motion(self.dh, &self.q, &q, v, a, &self.tcp, self.t);
        self.take(samples, q);
    }

    /// Runs the waiting blended moves (the last ends at rest on its target).
    fn flush(&mut self) {
        let Some(&(last, q)) = self.chain.last() else { return };
        let moves: Vec<BlendMove> = self.chain.drain(..).map(|(m, _)| m).collect();
        let samples = match moves.as_slice() {
            [m] => ramped_line_motion(&self.pose, &m.pose, m.v_m_s, m.a_m_s2, self.t),
            _ => blended_line_motion(&self.pose, &moves, self.t),
        };
        self.take(samples, q);
        self.pose = last.pose;
    }
}
