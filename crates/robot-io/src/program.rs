//! The writing program: per stroke travel, descend, press along, lift; the robot configuration;
//! and the safety envelope checked before anything moves.

use std::path::Path;

use brush_model::{BrushProfile, Track};
use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use serde::{Deserialize, Serialize};

use crate::RobotError;
use crate::frame::PaperFrame;
use crate::kinematics;
use crate::pose::{Pose, brush_pose, lifted_pose};

/// An ink-dipping station.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DipStation {
    /// TCP pose just above the ink, base frame.
    pub pose: [f64; 6],
    /// How far down to dip, mm.
    pub depth_mm: f64,
    /// Dip before every N-th stroke (1: before each stroke, as the paper does).
    pub every_strokes: usize,
}

/// Hard limits the program must respect.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Limits {
    /// Largest linear TCP speed, m/s.
    pub max_linear_speed_m_s: f64,
    /// Largest linear TCP acceleration, m/s².
    pub max_linear_acc_m_s2: f64,
    /// Largest joint speed, rad/s.
    pub max_joint_speed_rad_s: f64,
}

impl Default for Limits {
    fn default() -> Self {
        Self { max_linear_speed_m_s: 0.25, max_linear_acc_m_s2: 2.0, max_joint_speed_rad_s: 1.5 }
    }
}

/// `robot.json`: speeds, heights and options of the writing program.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RobotConfig {
    /// Robot name on the controller (default: the first `getRobotNames` returns).
    pub robot_name: Option<String>,
    /// TCP speed while pressing, m/s.
    pub write_speed_m_s: f64,
    /// TCP acceleration while pressing, m/s².
    pub write_acc_m_s2: f64,
    /// TCP speed while travelling between strokes, m/s.
    pub travel_speed_m_s: f64,
    /// TCP acceleration while travelling, m/s².
    pub travel_acc_m_s2: f64,
    /// Joint speed of the first move, rad/s.
    pub joint_speed_rad_s: f64,
    /// Joint acceleration of the first move, rad/s².
    pub joint_acc_rad_s2: f64,
    /// Safe height above the paper for travel, mm.
    pub lift_mm: f64,
    /// Blend radius between points inside a stroke, mm.
    pub blend_mm: f64,
    /// Controller speed fraction (0, 1].
    pub speed_fraction: f64,
    /// Optional ink dipping.
    pub dip: Option<DipStation>,
    /// Limits.
    pub limits: Limits,
}

impl Default for RobotConfig {
    fn default() -> Self {
        Self {
            robot_name: None,
            write_speed_m_s: 0.02,
            write_acc_m_s2: 0.3,
            travel_speed_m_s: 0.1,
            travel_acc_m_s2: 0.6,
            joint_speed_rad_s: 0.5,
            joint_acc_rad_s2: 1.0,
            lift_mm: 20.0,
            blend_mm: 0.5,
            speed_fraction: 1.0,
            dip: None,
            limits: Limits::default(),
        }
    }
}

impl RobotConfig {
    /// Loads and validates `robot.json` (missing fields take the defaults).
    ///
    /// # Errors
    /// [`RobotError::Config`] naming the file and field.
    pub fn load(path: &Path) -> Result<Self, RobotError> {
        let name = path.display().to_string();
        let c: RobotConfig = crate::load_json(path)?;
        c.validate().map_err(|m| RobotError::Config { file: name, message: m })?;
        Ok(c)
    }

    /// Checks every value; the message names the field.
    ///
    /// # Errors
    /// A one-line description of the first bad field.
    pub fn validate(&self) -> Result<(), String> {
        let pos = [
            ("write_speed_m_s", self.write_speed_m_s),
            ("write_acc_m_s2", self.write_acc_m_s2),
            ("travel_speed_m_s", self.travel_speed_m_s),
            ("travel_acc_m_s2", self.travel_acc_m_s2),
            ("joint_speed_rad_s", self.joint_speed_rad_s),
            ("joint_acc_rad_s2", self.joint_acc_rad_s2),
            ("lift_mm", self.lift_mm),
            ("speed_fraction", self.speed_fraction),
            ("limits.max_linear_speed_m_s", self.limits.max_linear_speed_m_s),
            ("limits.max_linear_acc_m_s2", self.limits.max_linear_acc_m_s2),
            ("limits.max_joint_speed_rad_s", self.limits.max_joint_speed_rad_s),
        ];
        for (f, v) in pos {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{f} must be a positive number, got {v}"));
            }
        }
        if !(self.blend_mm.is_finite() && self.blend_mm >= 0.0) {
            return Err(format!("blend_mm must be ≥ 0, got {}", self.blend_mm));
        }
        if self.speed_fraction > 1.0 {
            return Err(format!("speed_fraction must be in (0, 1], got {}", self.speed_fraction));
        }
        let l = &self.limits;
        for (f, v, max) in [
            ("write_speed_m_s", self.write_speed_m_s, l.max_linear_speed_m_s),
            ("travel_speed_m_s", self.travel_speed_m_s, l.max_linear_speed_m_s),
            ("write_acc_m_s2", self.write_acc_m_s2, l.max_linear_acc_m_s2),
            ("travel_acc_m_s2", self.travel_acc_m_s2, l.max_linear_acc_m_s2),
            ("joint_speed_rad_s", self.joint_speed_rad_s, l.max_joint_speed_rad_s),
        ] {
            if v > max {
                return Err(format!("{f} = {v} exceeds the limit {max}"));
            }
        }
        if let Some(d) = &self.dip {
            if d.every_strokes == 0
                || !(d.depth_mm.is_finite() && d.depth_mm > 0.0)
                || d.pose.iter().any(|v| !v.is_finite())
            {
                return Err("dip: every_strokes ≥ 1, depth_mm > 0 and a finite pose are required".into());
            }
        }
        Ok(())
    }
}

/// One motion command.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Move {
    /// Joint move to `q` (rad).
    Joint {
        /// Target joints, rad.
        q: [f64; 6],
        /// Joint acceleration, rad/s².
        a: f64,
        /// Joint speed, rad/s.
        v: f64,
    },
    /// Linear TCP move.
    Line {
        /// Target pose.
        pose: Pose,
        /// Acceleration, m/s².
        a: f64,
        /// Speed, m/s.
        v: f64,
        /// Blend radius, m.
        blend_m: f64,
    },
}

/// The moves of one stroke, in the order they run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StrokeProgram {
    /// Stroke index in the track.
    pub index: usize,
    /// Optional ink dip before the stroke (travel, down, up).
    pub dip: Vec<Move>,
    /// Travel at safe height above the first point, then descend onto it.
    pub approach: Vec<Move>,
    /// The pressed points, blended.
    pub press: Vec<Move>,
    /// Lift to safe height.
    pub lift: Move,
}

impl StrokeProgram {
    /// Every move of the stroke in order.
    pub fn moves(&self) -> impl Iterator<Item = &Move> {
        self.dip.iter().chain(&self.approach).chain(&self.press).chain(std::iter::once(&self.lift))
    }
}

/// A complete writing program.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Program {
    /// Tool offset along the flange z: the brush length, m.
    pub tcp_offset_m: f64,
    /// Speed fraction to set first.
    pub speed_fraction: f64,
    /// Joint move to the first safe pose.
    pub start: Move,
    /// Strokes in writing order.
    pub strokes: Vec<StrokeProgram>,
}

impl Program {
    /// The tool transform (flange → brush tip).
    pub fn tcp(&self) -> Isometry3<f64> {
        tcp_iso(self.tcp_offset_m)
    }
    /// Number of motion commands.
    pub fn move_count(&self) -> usize {
        1 + self.strokes.iter().map(|s| s.moves().count()).sum::<usize>()
    }
}

/// Flange → TCP: `offset_m` along the flange z.
pub fn tcp_iso(offset_m: f64) -> Isometry3<f64> {
    Isometry3::from_parts(Translation3::new(0.0, 0.0, offset_m), UnitQuaternion::identity())
}

/// What the safety check found.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CheckReport {
    /// Strokes.
    pub strokes: usize,
    /// Track points.
    pub points: usize,
    /// Motion commands.
    pub moves: usize,
    /// Deepest press, mm.
    pub max_press_mm: f64,
    /// Paper frame fit residual, mm.
    pub frame_residual_mm: f64,
    /// Estimated writing time at the configured speeds, s (path length / speed, accelerations
    /// ignored).
    pub estimated_seconds: f64,
}

/// Builds the program for a track and checks the whole safety envelope before anything moves:
/// every press within the profile's h range, every point on the sheet, speeds within the limits,
/// and every pose (pressed and lifted) reachable by the AUBO-i5 with the brush orientation asked
/// for.
///
/// # Errors
/// [`RobotError::Unsafe`] naming the first offending stroke and point and why.
pub fn build_program(
    track: &Track,
    profile: &BrushProfile,
    frame: &PaperFrame,
    cfg: &RobotConfig,
) -> Result<(Program, CheckReport), RobotError> {
    cfg.validate().map_err(|m| RobotError::Unsafe { stroke: None, point: None, reason: format!("robot.json: {m}") })?;
    if track.strokes.is_empty() || track.point_count() == 0 {
        return Err(RobotError::Unsafe { stroke: None, point: None, reason: "the track has no points".into() });
    }
    let tcp_offset_m = profile.brush.length_mm / 1000.0;
    let tcp = tcp_iso(tcp_offset_m);
    let lift_m = cfg.lift_mm / 1000.0;
    let hmax = profile.ranges.h_mm.max;
    let mut seed: Option<[f64; 6]> = None;
    let mut reach = |pose: &Pose, si: usize, pi: usize, what: &str| -> Result<[f64; 6], RobotError> {
        let q = kinematics::inverse(pose, &tcp, seed.as_ref()).ok_or_else(|| RobotError::Unsafe {
            stroke: Some(si),
            point: Some(pi),
            reason: format!(
                "{what} pose {:?} is not reachable by the AUBO-i5 with this brush orientation",
                pose.0.map(|v| (v * 1e4).round() / 1e4)
            ),
        })?;
        seed = Some(q);
        Ok(q)
    };
    let mut strokes = Vec::with_capacity(track.strokes.len());
    let mut start = None;
    let (mut max_press, mut path_m, mut travel_m) = (0.0f64, 0.0f64, 0.0f64);
    let mut last_up: Option<Pose> = None;
    for (si, stroke) in track.strokes.iter().enumerate() {
        if stroke.points.is_empty() {
            continue;
        }
        for (pi, p) in stroke.points.iter().enumerate() {
            let unsafe_at = |reason: String| RobotError::Unsafe { stroke: Some(si), point: Some(pi), reason };
            if ![p.x_mm, p.y_mm, p.h_mm, p.alpha_rad, p.beta_rad].iter().all(|v| v.is_finite()) {
                return Err(unsafe_at("a value is not finite".into()));
            }
            if p.h_mm > hmax + 1e-9 {
                return Err(unsafe_at(format!(
                    "press h = {:.3} mm is deeper than the profile's range (max {hmax} mm)",
                    p.h_mm
                )));
            }
            if p.h_mm < 0.0 {
                return Err(unsafe_at(format!("press h = {:.3} mm is above the paper", p.h_mm)));
            }
            if !frame.contains(p.x_mm, p.y_mm) {
                let b = frame.bounds_mm;
                return Err(unsafe_at(format!(
                    "point ({:.1}, {:.1}) mm lies outside the paper [{}, {}]–[{}, {}] mm",
                    p.x_mm, p.y_mm, b[0], b[1], b[2], b[3]
                )));
            }
            max_press = max_press.max(p.h_mm);
        }
        let first = &stroke.points[0];
        let up = lifted_pose(frame, first, lift_m);
        let q_up = reach(&up, si, 0, "approach")?;
        if start.is_none() {
            start = Some(Move::Joint { q: q_up, a: cfg.joint_acc_rad_s2, v: cfg.joint_speed_rad_s });
        }
        if let Some(prev) = last_up {
            travel_m += dist(&prev, &up);
        }
        let mut dip = Vec::new();
        if let Some(d) = &cfg.dip {
            if si % d.every_strokes == 0 {
                let above = Pose(d.pose);
                let down = above.raised(-d.depth_mm / 1000.0);
                reach(&above, si, 0, "dip station")?;
                reach(&down, si, 0, "dip station")?;
                dip = vec![
                    Move::Line { pose: above, a: cfg.travel_acc_m_s2, v: cfg.travel_speed_m_s, blend_m: 0.0 },
                    Move::Line { pose: down, a: cfg.travel_acc_m_s2, v: cfg.travel_speed_m_s * 0.5, blend_m: 0.0 },
                    Move::Line { pose: above, a: cfg.travel_acc_m_s2, v: cfg.travel_speed_m_s * 0.5, blend_m: 0.0 },
                ];
                reach(&up, si, 0, "approach")?;
            }
        }
        let mut press = Vec::with_capacity(stroke.points.len());
        let mut prev_pose: Option<Pose> = None;
        for (pi, p) in stroke.points.iter().enumerate() {
            let pose = brush_pose(frame, p);
            reach(&pose, si, pi, "pressed")?;
            if let Some(pp) = prev_pose {
                path_m += dist(&pp, &pose);
            }
            let last = pi + 1 == stroke.points.len();
            let blend = if last || pi == 0 { 0.0 } else { cfg.blend_mm / 1000.0 };
            if pi > 0 {
                press.push(Move::Line { pose, a: cfg.write_acc_m_s2, v: cfg.write_speed_m_s, blend_m: blend });
            }
            prev_pose = Some(pose);
        }
        let first_pose = brush_pose(frame, first);
        let last_p = stroke.points.last().expect("non-empty");
        let end_up = lifted_pose(frame, last_p, lift_m);
        reach(&end_up, si, stroke.points.len() - 1, "lift")?;
        strokes.push(StrokeProgram {
            index: si,
            dip,
            approach: vec![
                Move::Line { pose: up, a: cfg.travel_acc_m_s2, v: cfg.travel_speed_m_s, blend_m: 0.0 },
                Move::Line { pose: first_pose, a: cfg.write_acc_m_s2, v: cfg.write_speed_m_s, blend_m: 0.0 },
            ],
            press,
            lift: Move::Line { pose: end_up, a: cfg.travel_acc_m_s2, v: cfg.travel_speed_m_s, blend_m: 0.0 },
        });
        last_up = Some(end_up);
    }
    let program = Program {
        tcp_offset_m,
        speed_fraction: cfg.speed_fraction,
        start: start.expect("at least one stroke"),
        strokes,
    };
    let report = CheckReport {
        strokes: program.strokes.len(),
        points: track.point_count(),
        moves: program.move_count(),
        max_press_mm: max_press,
        frame_residual_mm: frame.residual_mm,
        estimated_seconds: path_m / cfg.write_speed_m_s
            + (travel_m + 2.0 * lift_m * program.strokes.len() as f64) / cfg.travel_speed_m_s,
    };
    Ok((program, report))
}

fn dist(a: &Pose, b: &Pose) -> f64 {
    let (p, q) = (a.position(), b.position());
    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
}
