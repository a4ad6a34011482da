//! A URScript program as the UR stand-in runs it: read by maobi's own URScript reader (the subset
//! maobi writes, and nothing else), then executed on the arm's kinematics into a timed path with
//! the register writes on its timeline.

use nalgebra::Isometry3;

use crate::exec::{TraceEntry, TraceKind};
use crate::export::{ReadMove, URSCRIPT_PROGRAM, URSCRIPT_PROGRESS_REGISTER, read_urscript_named};
use crate::kinematics::DhParams;
use crate::pose::Pose;
use crate::program::{CONTROLLER_MAX_ACC, CONTROLLER_MAX_BLEND_M, CONTROLLER_MAX_SPEED};
use crate::sim::{
    BLEND_SLACK_M, BlendMove, MAX_BLEND_CHAIN, blended_line_motion, ramped_joint_motion, ramped_line_motion,
};
use crate::ur::pose_from_ur;

/// The programs the stand-in runs: maobi's program and the lift a stopped run sends.
pub(super) const PROGRAM_NAMES: [&str; 2] = [URSCRIPT_PROGRAM, "maobi_lift"];

/// Most samples one program's path holds (64 MiB): a longer program is refused.
pub const MAX_PROGRAM_SAMPLES: usize = 1 << 20;

/// A program ready to play: its name, its timed path (t from 0 at the program's start), the
/// joints at the end of each move (with the time it ends), the register writes, the TCP it sets,
/// and the line where it stops early when a target cannot be reached.
#[derive(Debug)]
pub(super) struct Compiled {
    pub(super) name: String,
    pub(super) samples: Vec<TraceEntry>,
    pub(super) joints: Vec<(f64, [f64; 6])>,
    pub(super) registers: Vec<(f64, usize, i32)>,
    pub(super) tcp: Isometry3<f64>,
    /// A runtime error (a target out of reach) at this time, s: the program stops there.
    pub(super) error: Option<(f64, String)>,
}

/// The name of the program in `text` (`def NAME():` after the header comments), when it is one
/// the stand-in runs.
///
/// # Errors
/// Why not, naming the line.
pub(super) fn program_name(text: &str) -> Result<&'static str, String> {
    let (n, first) = text
        .lines()
        .enumerate()
        .find(|(_, l)| !l.starts_with('#'))
        .ok_or_else(|| "the script is only comments".to_string())?;
    PROGRAM_NAMES.into_iter().find(|name| first == format!("def {name}():")).ok_or_else(|| {
        let shown: String = first.chars().take(80).collect();
        format!(
            "line {}: {shown:?} is not `def maobi_program():` or `def maobi_lift():` (the programs this stand-in runs)",
            n + 1
        )
    })
}

/// Reads `text` and executes it from joints `q0` (rad) on `dh`: every move solved and timed as
/// the UR5e stand-in moves (joint moves linear in joint space, line and process moves straight
/// with circular blends, trapezoidal speed profiles at the given speed and acceleration).
///
/// # Errors
/// The reader's refusal (the line, and the function when it is outside maobi's subset), or a
/// value out of the controller's ranges, naming the line.
pub(super) fn compile(text: &str, dh: &DhParams, q0: &[f64; 6], tcp0: &Isometry3<f64>) -> Result<Compiled, String> {
    let name = program_name(text)?;
    let read = read_urscript_named(text, name).map_err(|at| format!("line {}: {}", at.line, at.reason))?;
    let tcp = Pose([0.0, 0.0, read.tcp_offset_m, 0.0, 0.0, 0.0]).to_iso();
    let _ = tcp0;
    let mut arm = Arm {
        dh,
        q: *q0,
        at: Pose::from_iso(&dh.forward(q0, &tcp)),
        t: 0.0,
        out: Compiled {
            name: name.to_string(),
            samples: Vec::new(),
            joints: Vec::new(),
            registers: Vec::new(),
            tcp,
            error: None,
        },
    };
    let mut chain: Vec<(usize, BlendMove)> = Vec::new();
    let moves = read.moves;
    for (i, &(line, m)) in moves.iter().enumerate() {
        match m {
            ReadMove::Progress { strokes } => {
                let v = i32::try_from(strokes)
                    .map_err(|_| format!("line {line}: register value {strokes} out of range"))?;
                arm.out.registers.push((arm.t, URSCRIPT_PROGRESS_REGISTER, v));
            }
            ReadMove::Joint { q: target, a, v } | ReadMove::JointPose { target, a, v, .. } => {
                in_range(line, "the joint acceleration", a, CONTROLLER_MAX_ACC)?;
                in_range(line, "the joint speed", v, CONTROLLER_MAX_SPEED)?;
                let pose = matches!(m, ReadMove::JointPose { .. });
                if !arm.joint_move(line, target, pose, a, v)? {
                    break;
                }
            }
            ReadMove::Line { target, a, v, blend_m } | ReadMove::Process { target, a, v, blend_m } => {
                in_range(line, "the tool acceleration", a, CONTROLLER_MAX_ACC)?;
                in_range(line, "the tool speed", v, CONTROLLER_MAX_SPEED)?;
                if !(blend_m.is_finite() && (0.0..=CONTROLLER_MAX_BLEND_M).contains(&blend_m)) {
                    return Err(format!(
                        "line {line}: the blend radius {blend_m} is outside [0, {CONTROLLER_MAX_BLEND_M}]"
                    ));
                }
                let pose = pose_from_ur(&target);
                chain.push((line, BlendMove { pose, v_m_s: v, a_m_s2: a, blend_m }));
                let next_blends =
                    matches!(moves.get(i + 1), Some((_, ReadMove::Line { .. } | ReadMove::Process { .. })));
                if blend_m > 0.0 && next_blends && chain.len() < MAX_BLEND_CHAIN {
                    continue;
                }
                // The chain ends here: its blends checked, every target solved, then executed.
                check_blends(&arm.at, &chain)?;
                if !arm.line_moves(&chain)? {
                    break;
                }
                chain.clear();
            }
            ReadMove::PathBuffer { .. } => return Err(format!("line {line}: not URScript")),
        }
    }
    Ok(arm.out)
}

/// A speed or acceleration `v` of the move on `line` in the controller's range `(0, max]`.
fn in_range(line: usize, what: &str, v: f64, max: f64) -> Result<(), String> {
    if v.is_finite() && v > 0.0 && v <= max {
        Ok(())
    } else {
        Err(format!("line {line}: {what} {v} is outside (0, {max}]"))
    }
}

/// UR's rule (the script manual, movej/movel): a blend region must not overlap the blend of the
/// waypoint before or after it; neither may it reach past the move's start (maobi's stricter
/// rule, at most half of either move, implies it). `at`: where the chain starts. (1 nm of slack
/// for the printed digits.)
fn check_blends(at: &Pose, chain: &[(usize, BlendMove)]) -> Result<(), String> {
    let mut lens = Vec::with_capacity(chain.len());
    let mut from = *at;
    for (_, bm) in chain {
        lens.push((nalgebra::Vector3::from(bm.pose.position()) - nalgebra::Vector3::from(from.position())).norm());
        from = bm.pose;
    }
    let n = chain.len();
    let r = |k: usize| if k + 1 < n { chain[k].1.blend_m } else { 0.0 };
    for k in 0..n {
        let before = if k == 0 { 0.0 } else { r(k - 1) };
        let overlaps = r(k) + before > lens[k] + BLEND_SLACK_M;
        if overlaps {
            return Err(format!(
                "line {}: blend radius {} m and the one before ({} m) overlap on a move of {} m (UR skips such a move with 'Overlapping Blends')",
                chain[k].0,
                r(k),
                before,
                lens[k]
            ));
        }
    }
    Ok(())
}

/// The stand-in arm as a program moves it: its joints, TCP pose and clock, and the path so far.
struct Arm<'a> {
    dh: &'a DhParams,
    q: [f64; 6],
    at: Pose,
    t: f64,
    out: Compiled,
}

impl Arm<'_> {
    /// A joint move to `target` (joints, or with `pose` a UR pose solved near the current
    /// joints) at joint speed `v` and acceleration `a`. `Ok(false)`: the pose is out of reach,
    /// the program stops there (the runtime error recorded).
    fn joint_move(&mut self, line: usize, target: [f64; 6], pose: bool, a: f64, v: f64) -> Result<bool, String> {
        let tcp = self.out.tcp;
        let to = if pose { self.dh.inverse(&pose_from_ur(&target), &tcp, Some(&self.q)) } else { Some(target) };
        let Some(to) = to else {
            self.out.error = Some((self.t, format!("line {line}: movej: the pose is out of the arm's reach")));
            return Ok(false);
        };
        let samples = ramped_joint_motion(self.dh, &self.q, &to, v, a, &tcp, self.t);
        push(&mut self.out, samples, line)?;
        self.q = to;
        self.at = Pose::from_iso(&self.dh.forward(&self.q, &tcp));
        self.ended();
        Ok(true)
    }

    /// A chain of line and process moves (`(line, move)`, the last one's blend ignored): every
    /// target solved, then one straight or blended motion. `Ok(false)`: a target is out of
    /// reach, the program stops there (the runtime error recorded).
    fn line_moves(&mut self, chain: &[(usize, BlendMove)]) -> Result<bool, String> {
        for (l, bm) in chain {
            let Some(qk) = self.dh.inverse(&bm.pose, &self.out.tcp, Some(&self.q)) else {
                self.out.error = Some((self.t, format!("line {l}: the pose is out of the arm's reach")));
                return Ok(false);
            };
            self.q = qk;
        }
        let mut moves: Vec<BlendMove> = chain.iter().map(|(_, m)| *m).collect();
        if let Some(last) = moves.last_mut() {
            last.blend_m = 0.0;
        }
        let samples = if moves.len() == 1 {
            let m = moves[0];
            ramped_line_motion(&self.at, &m.pose, m.v_m_s, m.a_m_s2, self.t)
        } else {
            blended_line_motion(&self.at, &moves, self.t)
        };
        push(&mut self.out, samples, chain[0].0)?;
        self.at = moves.last().map_or(self.at, |m| m.pose);
        self.ended();
        Ok(true)
    }

    /// A move ended: the clock at its last sample, the joints recorded there.
    fn ended(&mut self) {
        self.t = self.out.samples.last().map_or(self.t, |s| s.t_s);
        self.out.joints.push((self.t, self.q));
    }
}

/// Appends a move's samples, refusing a program whose path grows beyond
/// [`MAX_PROGRAM_SAMPLES`].
fn push(out: &mut Compiled, samples: Vec<TraceEntry>, line: usize) -> Result<(), String> {
    if out.samples.len() + samples.len() > MAX_PROGRAM_SAMPLES {
        return Err(format!(
            "line {line}: the program's path needs more than {MAX_PROGRAM_SAMPLES} samples: too long for the stand-in"
        ));
    }
    out.samples.extend(samples.into_iter().map(|mut s| {
        if s.kind == TraceKind::PathBuffer {
            s.kind = TraceKind::Line;
        }
        s
    }));
    Ok(())
}
