//! `robot.json`: the robot's settings (speeds, heights, blend), the limits of the safety
//! envelope, the side the brush comes from, the ink station and its reload rule
//! ([`dip_plan`]), and the ranges the controller accepts.

use std::path::Path;

use brush_model::{Track, TrackPoint};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::RobotError;

/// A `robot.json` setting outside what it may be: which field, and what is wrong with it.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{message}")]
pub struct SettingError {
    /// The setting's path in `robot.json` (`write_speed_m_s`, `limits.max_blend_mm`,
    /// `ink.reload.every_mm`, …).
    pub field: String,
    /// What is wrong and what is expected, naming the field and the value.
    pub message: String,
}

impl SettingError {
    fn new(field: &str, message: String) -> Self {
        Self { field: field.to_string(), message }
    }
}

/// The largest acceleration the controller accepts in `moveLine`/`moveJoint`, m/s² (or rad/s²).
pub const CONTROLLER_MAX_ACC: f64 = 20.0;
/// The largest speed the controller accepts in `moveLine`/`moveJoint`, m/s (or rad/s).
pub const CONTROLLER_MAX_SPEED: f64 = 3.2;
/// The largest blend radius the controller accepts, m (the smallest is 0).
pub const CONTROLLER_MAX_BLEND_M: f64 = 0.1;
/// The tool offset along the flange z the controller accepts: `0 ≤ z <` this, m.
pub const CONTROLLER_MAX_TCP_OFFSET_M: f64 = 0.5;
/// The speed fraction the controller accepts: `0 < f ≤` this.
pub const CONTROLLER_MAX_SPEED_FRACTION: f64 = 1.0;

/// The slowest linear speed a setting may ask for, m/s: below 1 mm/s a stroke takes minutes
/// and the brush blots; such a value is a unit mistake, not a writing speed.
pub const MIN_LINEAR_SPEED_M_S: f64 = 1e-3;
/// The slowest joint speed a setting may ask for, rad/s.
pub const MIN_JOINT_SPEED_RAD_S: f64 = 1e-2;
/// The smallest acceleration a setting may ask for, m/s² (rad/s² for joints).
pub const MIN_ACC: f64 = 1e-2;
/// The smallest speed fraction a setting may ask for (1 %, the teach pendant's slowest).
pub const MIN_SPEED_FRACTION: f64 = 0.01;
/// The highest travel height (`lift_mm`, `limits.min_lift_mm`), mm.
pub const MAX_LIFT_MM: f64 = 200.0;
/// The largest `limits.max_step_mm`, mm.
pub const MAX_STEP_LIMIT_MM: f64 = 20.0;

/// A number as a message shows it: plain, or in exponent form when very small or large.
fn number(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-3..1e6).contains(&v.abs()) { format!("{v:e}") } else { format!("{v}") }
}

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

/// How far the brush sinks further into the ink during the dwell of a dip, mm: the dwell is a
/// slow straight move of this length lasting `dwell_s` (every transport and export carries a
/// line move; none needs a separate wait command).
pub const DWELL_SINK_MM: f64 = 1.0;

/// The longest dwell accepted, s.
pub const MAX_DWELL_S: f64 = 60.0;

/// When the brush goes back to the ink. A dip only ever happens between strokes, before the
/// stroke the rule picks; the first stroke always starts with a dip.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Reload {
    /// `{"every_strokes": N}`: before every N-th stroke (1: before each stroke).
    EveryStrokes(usize),
    /// `{"every_mm": L}`: a load lasts L mm of pressed path: dip before a stroke that would take
    /// the pressed path since the last dip beyond L (a single stroke longer than L still runs
    /// on one load).
    EveryMm(f64),
    /// `"before_each_char"`: before the first stroke of each character (needs the character
    /// boundaries: a sheet `track.json`'s `stroke_chars`).
    BeforeEachChar,
}

/// `robot.json` → `ink`: the ink station and the reload rule.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InkStation {
    /// TCP pose just above the ink, base frame (m, rad).
    pub pose: [f64; 6],
    /// How far down into the ink from `pose`, mm.
    pub depth_mm: f64,
    /// How long the brush soaks, s (0: straight back up): it sinks [`DWELL_SINK_MM`] further
    /// over this time.
    #[serde(default)]
    pub dwell_s: f64,
    /// When to dip.
    pub reload: Reload,
    /// Where the ink pot is for a 3-axis plotter (G-code), paper mm (may lie off the sheet);
    /// without it the G-code export has no dips and says so.
    #[serde(default)]
    pub paper_mm: Option<[f64; 2]>,
}

impl InkStation {
    /// The legacy `dip` form: every N strokes, no dwell.
    pub fn from_dip(d: &DipStation) -> Self {
        InkStation {
            pose: d.pose,
            depth_mm: d.depth_mm,
            dwell_s: 0.0,
            reload: Reload::EveryStrokes(d.every_strokes),
            paper_mm: None,
        }
    }
}

/// Where the brush comes from: the paper's into-paper normal (paper z = x × y) must point
/// within `max_angle_rad` of `into_paper_base`, or the frame is refused (a mirrored or upside
/// down `paper.json`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Approach {
    /// The expected into-paper direction in the base frame (any length > 0); default base −z
    /// (the brush comes from above).
    pub into_paper_base: [f64; 3],
    /// Largest angle between the fitted into-paper normal and `into_paper_base`, rad (0, π/2];
    /// default π/3 (60°).
    pub max_angle_rad: f64,
}

impl Default for Approach {
    fn default() -> Self {
        Self { into_paper_base: [0.0, 0.0, -1.0], max_angle_rad: std::f64::consts::FRAC_PI_3 }
    }
}

/// Hard limits the program must respect (`robot.json` → `limits`; every field optional). How
/// each default was chosen is in docs/robot.md, "Safety checks".
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Limits {
    /// Largest linear TCP speed, m/s.
    pub max_linear_speed_m_s: f64,
    /// Largest linear TCP acceleration, m/s².
    pub max_linear_acc_m_s2: f64,
    /// Largest joint speed, rad/s.
    pub max_joint_speed_rad_s: f64,
    /// Largest joint acceleration, rad/s².
    pub max_joint_acc_rad_s2: f64,
    /// Largest blend radius, mm.
    pub max_blend_mm: f64,
    /// Smallest safe height above the paper for travel, mm.
    pub min_lift_mm: f64,
    /// Largest tilt α of the brush from the paper normal, rad.
    pub max_tilt_rad: f64,
    /// How far α may leave the brush profile's calibrated α range, rad.
    pub alpha_tolerance_rad: f64,
    /// Largest orientation change of the tool per mm of TCP travel while pressed (both ends of
    /// a move deeper than the surface), rad/mm.
    pub max_turn_rad_per_mm: f64,
    /// Largest orientation change per second of a move at its commanded speed (write speed on
    /// the paper, travel speed in the air), rad/s.
    pub max_wrist_rate_rad_s: f64,
    /// Largest change of press depth per mm of travel along the paper while pressed, mm/mm
    /// (moves in place, straight down or up, are exempt).
    pub max_depth_change_per_mm: f64,
    /// Largest distance along the paper between two consecutive pressed points (h > 0 at both)
    /// of a stroke, mm: the planner's pressed points lie a fraction of a millimetre apart, so a
    /// longer step with the brush down is a corrupt or hand-edited track. Glides at the surface
    /// (h = 0) are not bounded.
    pub max_step_mm: f64,
    /// Largest joint jerk of a timed stroke (its waypoints' third differences), rad/s³.
    pub max_joint_jerk_rad_s3: f64,
    /// Smallest distance from a singularity along a timed stroke: the smallest singular value
    /// of the arm's Jacobian (position rows in m/rad, orientation rows in rad/rad).
    pub min_singular_value: f64,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_linear_speed_m_s: 0.25,
            max_linear_acc_m_s2: 2.0,
            max_joint_speed_rad_s: 1.5,
            max_joint_acc_rad_s2: 3.0,
            max_blend_mm: 2.0,
            min_lift_mm: 5.0,
            max_tilt_rad: 30f64.to_radians(),
            alpha_tolerance_rad: 2f64.to_radians(),
            max_turn_rad_per_mm: 1.0,
            max_wrist_rate_rad_s: 20.0,
            max_depth_change_per_mm: 40.0,
            max_step_mm: 5.0,
            max_joint_jerk_rad_s3: 50.0,
            min_singular_value: 0.02,
        }
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
    /// Optional ink dipping every N strokes (the older form of `ink`).
    pub dip: Option<DipStation>,
    /// Optional ink station with a dwell and a reload rule (docs/robot.md, "Ink").
    pub ink: Option<InkStation>,
    /// The side of the paper the brush comes from.
    pub approach: Approach,
    /// Limits.
    pub limits: Limits,
    /// How pressed strokes are timed (docs/robot.md, "Motion: timing and the path buffer").
    pub timing: Timing,
    /// The tool's mass (brush and holder), kg, when known: a controller that reports its
    /// payload (a UR arm over RTDE) must report this one before anything moves.
    pub payload_kg: Option<f64>,
    /// How a 3-axis plotter's work coordinates lie on the paper (the G-code export and
    /// `robot send --controller grbl`; docs/robot.md, "GRBL brush plotters").
    pub plotter: PlotterConfig,
}

/// `robot.json` → `plotter`: how the G-code's work coordinates lie on the paper. The work zero
/// is the paper's top-left corner with the brush tip just touching it (the touch-off); X runs
/// right along the paper's x.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlotterConfig {
    /// Which way the machine's +Y runs on the paper.
    pub y_axis: YAxis,
}

/// Which way a plotter's +Y runs on the paper (`robot.json` `plotter.y_axis`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum YAxis {
    /// Away from you, up the page (right-handed, the CNC convention GRBL machines follow): the
    /// sheet lies at negative Y, `Y = −y`.
    #[default]
    Away,
    /// Toward you, down the page (as the paper's y and SVG): `Y = y`.
    Toward,
}

impl YAxis {
    /// The G-code Y of paper `y_mm`.
    pub fn y(self, y_mm: f64) -> f64 {
        match self {
            // `0.0 - y` keeps 0 a plain zero.
            YAxis::Away => 0.0 - y_mm,
            YAxis::Toward => y_mm,
        }
    }
}

/// The heaviest tool `payload_kg` may name, kg (a UR16e's rated payload; a brush weighs grams).
pub const MAX_PAYLOAD_KG: f64 = 16.0;

/// How pressed strokes are timed (`robot.json` → `timing`; every field optional): the write
/// speed and acceleration and the joint speed and acceleration of [`RobotConfig`] bound the
/// motion, these add the rest.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Timing {
    /// The fixed interval between the joint waypoints of a timed stroke (the path buffer's), s.
    pub interval_s: f64,
    /// Largest jerk along the path while writing, m/s³.
    pub write_jerk_m_s3: f64,
    /// Largest rate at which the press depth changes while writing, mm/s.
    pub max_depth_rate_mm_s: f64,
    /// Largest joint jerk the timing plans for, rad/s³ (at most `limits.max_joint_jerk_rad_s3`).
    pub joint_jerk_rad_s3: f64,
}

impl Default for Timing {
    fn default() -> Self {
        Self { interval_s: 0.01, write_jerk_m_s3: 3.0, max_depth_rate_mm_s: 20.0, joint_jerk_rad_s3: 20.0 }
    }
}

/// The shortest waypoint interval a timed stroke may use, s (the controller's cycle is assumed
/// no shorter than 1 ms).
pub const MIN_INTERVAL_S: f64 = 1e-3;
/// The longest waypoint interval a timed stroke may use, s.
pub const MAX_INTERVAL_S: f64 = 0.1;

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
            ink: None,
            approach: Approach::default(),
            limits: Limits::default(),
            timing: Timing::default(),
            plotter: PlotterConfig::default(),
            payload_kg: None,
        }
    }
}

impl RobotConfig {
    /// Loads and validates `robot.json` (missing fields take the defaults).
    ///
    /// # Errors
    /// [`RobotError::Read`] or [`RobotError::Json`] naming the file; [`RobotError::Setting`]
    /// naming the file, with the field as its source.
    pub fn load(path: &Path) -> Result<Self, RobotError> {
        let c: RobotConfig = crate::load_json(path)?;
        c.validate().map_err(|source| RobotError::Setting { file: path.to_path_buf(), source })?;
        Ok(c)
    }

    /// Checks every value against the range the controller accepts (the `CONTROLLER_*`
    /// constants) and against [`Limits`]; the message names the field, the value and the limit.
    ///
    /// # Errors
    /// [`SettingError`] for the first bad field: its name and what is wrong.
    pub fn validate(&self) -> Result<(), SettingError> {
        if let Some(m) = self.payload_kg
            && !(m.is_finite() && (0.0..=MAX_PAYLOAD_KG).contains(&m))
        {
            return Err(SettingError::new(
                "payload_kg",
                format!("payload_kg = {} is not a mass from 0 to {MAX_PAYLOAD_KG} kg", number(m)),
            ));
        }
        self.check_controller_ranges()?;
        self.check_limits()?;
        self.check_approach_settings()?;
        self.check_ink()
    }

    /// Every speed, acceleration and blend positive and within what the controller accepts;
    /// the heights and rates positive.
    fn check_controller_ranges(&self) -> Result<(), SettingError> {
        let l = &self.limits;
        // (field, value, the physical lower bound, the controller's upper bound, unit): every
        // setting has a range, so a unit mistake (mm/s for m/s, 1e-300) is refused rather than
        // written into a program.
        let ranged = [
            ("write_speed_m_s", self.write_speed_m_s, MIN_LINEAR_SPEED_M_S, CONTROLLER_MAX_SPEED, "m/s"),
            ("write_acc_m_s2", self.write_acc_m_s2, MIN_ACC, CONTROLLER_MAX_ACC, "m/s²"),
            ("travel_speed_m_s", self.travel_speed_m_s, MIN_LINEAR_SPEED_M_S, CONTROLLER_MAX_SPEED, "m/s"),
            ("travel_acc_m_s2", self.travel_acc_m_s2, MIN_ACC, CONTROLLER_MAX_ACC, "m/s²"),
            ("joint_speed_rad_s", self.joint_speed_rad_s, MIN_JOINT_SPEED_RAD_S, CONTROLLER_MAX_SPEED, "rad/s"),
            ("joint_acc_rad_s2", self.joint_acc_rad_s2, MIN_ACC, CONTROLLER_MAX_ACC, "rad/s²"),
            ("speed_fraction", self.speed_fraction, MIN_SPEED_FRACTION, CONTROLLER_MAX_SPEED_FRACTION, ""),
            ("limits.max_linear_speed_m_s", l.max_linear_speed_m_s, MIN_LINEAR_SPEED_M_S, CONTROLLER_MAX_SPEED, "m/s"),
            ("limits.max_linear_acc_m_s2", l.max_linear_acc_m_s2, MIN_ACC, CONTROLLER_MAX_ACC, "m/s²"),
            (
                "limits.max_joint_speed_rad_s",
                l.max_joint_speed_rad_s,
                MIN_JOINT_SPEED_RAD_S,
                CONTROLLER_MAX_SPEED,
                "rad/s",
            ),
            ("limits.max_joint_acc_rad_s2", l.max_joint_acc_rad_s2, MIN_ACC, CONTROLLER_MAX_ACC, "rad/s²"),
            ("limits.max_blend_mm", l.max_blend_mm, f64::MIN_POSITIVE, CONTROLLER_MAX_BLEND_M * 1000.0, "mm"),
            ("lift_mm", self.lift_mm, f64::MIN_POSITIVE, MAX_LIFT_MM, "mm"),
            ("limits.min_lift_mm", l.min_lift_mm, f64::MIN_POSITIVE, MAX_LIFT_MM, "mm"),
            ("limits.max_tilt_rad", l.max_tilt_rad, f64::MIN_POSITIVE, std::f64::consts::FRAC_PI_2, "rad"),
            ("limits.max_turn_rad_per_mm", l.max_turn_rad_per_mm, f64::MIN_POSITIVE, 10.0, "rad/mm"),
            ("limits.max_wrist_rate_rad_s", l.max_wrist_rate_rad_s, f64::MIN_POSITIVE, 100.0, "rad/s"),
            ("limits.max_depth_change_per_mm", l.max_depth_change_per_mm, f64::MIN_POSITIVE, 1000.0, "mm/mm"),
            ("limits.max_step_mm", l.max_step_mm, f64::MIN_POSITIVE, MAX_STEP_LIMIT_MM, "mm"),
            ("limits.max_joint_jerk_rad_s3", l.max_joint_jerk_rad_s3, MIN_ACC, 10_000.0, "rad/s³"),
            ("limits.min_singular_value", l.min_singular_value, f64::MIN_POSITIVE, 1.0, ""),
            ("timing.interval_s", self.timing.interval_s, MIN_INTERVAL_S, MAX_INTERVAL_S, "s"),
            ("timing.write_jerk_m_s3", self.timing.write_jerk_m_s3, MIN_ACC, 1000.0, "m/s³"),
            ("timing.max_depth_rate_mm_s", self.timing.max_depth_rate_mm_s, 0.1, 1000.0, "mm/s"),
            ("timing.joint_jerk_rad_s3", self.timing.joint_jerk_rad_s3, MIN_ACC, 10_000.0, "rad/s³"),
        ];
        for (f, v, min, max, unit) in ranged {
            let (v_s, unit) = (number(v), if unit.is_empty() { String::new() } else { format!(" {unit}") });
            if !(v.is_finite() && v > 0.0) {
                return Err(SettingError::new(f, format!("{f} must be a positive number, got {v_s}")));
            }
            if v < min {
                return Err(SettingError::new(
                    f,
                    format!("{f} = {v_s} is below the smallest accepted value {min}{unit} (is it in the wrong unit?)"),
                ));
            }
            if v > max {
                return Err(SettingError::new(
                    f,
                    format!("{f} = {v_s} is beyond what the controller accepts (at most {max}{unit})"),
                ));
            }
        }
        Ok(())
    }

    /// The settings within [`Limits`], and the limits themselves sane.
    fn check_limits(&self) -> Result<(), SettingError> {
        let l = &self.limits;
        if !(l.alpha_tolerance_rad.is_finite() && l.alpha_tolerance_rad >= 0.0) {
            return Err(SettingError::new(
                "limits.alpha_tolerance_rad",
                format!("limits.alpha_tolerance_rad must be ≥ 0, got {}", l.alpha_tolerance_rad),
            ));
        }
        if l.max_tilt_rad >= std::f64::consts::FRAC_PI_2 {
            return Err(SettingError::new(
                "limits.max_tilt_rad",
                format!(
                    "limits.max_tilt_rad = {} must be below π/2 (the brush would lie flat on the paper)",
                    l.max_tilt_rad
                ),
            ));
        }
        if !(self.blend_mm.is_finite() && self.blend_mm >= 0.0) {
            return Err(SettingError::new("blend_mm", format!("blend_mm must be ≥ 0, got {}", self.blend_mm)));
        }
        for (f, v, max, limit) in [
            ("write_speed_m_s", self.write_speed_m_s, l.max_linear_speed_m_s, "max_linear_speed_m_s"),
            ("travel_speed_m_s", self.travel_speed_m_s, l.max_linear_speed_m_s, "max_linear_speed_m_s"),
            ("write_acc_m_s2", self.write_acc_m_s2, l.max_linear_acc_m_s2, "max_linear_acc_m_s2"),
            ("travel_acc_m_s2", self.travel_acc_m_s2, l.max_linear_acc_m_s2, "max_linear_acc_m_s2"),
            ("joint_speed_rad_s", self.joint_speed_rad_s, l.max_joint_speed_rad_s, "max_joint_speed_rad_s"),
            ("joint_acc_rad_s2", self.joint_acc_rad_s2, l.max_joint_acc_rad_s2, "max_joint_acc_rad_s2"),
            ("blend_mm", self.blend_mm, l.max_blend_mm, "max_blend_mm"),
            (
                "timing.joint_jerk_rad_s3",
                self.timing.joint_jerk_rad_s3,
                l.max_joint_jerk_rad_s3,
                "max_joint_jerk_rad_s3",
            ),
        ] {
            if v > max {
                return Err(SettingError::new(f, format!("{f} = {v} exceeds the limit {max} (limits.{limit})")));
            }
        }
        if self.lift_mm < l.min_lift_mm {
            return Err(SettingError::new(
                "lift_mm",
                format!("lift_mm = {} is below the limit min_lift_mm = {}", self.lift_mm, l.min_lift_mm),
            ));
        }
        Ok(())
    }

    /// The robot name, and the approach direction and angle.
    fn check_approach_settings(&self) -> Result<(), SettingError> {
        if self.robot_name.as_deref().is_some_and(|n| n.trim().is_empty()) {
            return Err(SettingError::new(
                "robot_name",
                "robot_name must not be empty (omit it to use the controller's first robot)".to_string(),
            ));
        }
        // The name goes into every method name sent to the controller (`NAME.MotionControl…`).
        if let Some(n) = self
            .robot_name
            .as_deref()
            .filter(|n| n.len() > 64 || !n.chars().all(|c| c.is_ascii_alphanumeric() || c == '_'))
        {
            return Err(SettingError::new(
                "robot_name",
                format!(
                    "robot_name {n:?} must be 1 to 64 letters, digits or underscores (it becomes part of every method name)"
                ),
            ));
        }
        let a = &self.approach;
        let n = Vector3::from(a.into_paper_base);
        if !(n.iter().all(|v| v.is_finite()) && n.norm() > 1e-9) {
            return Err(SettingError::new(
                "approach.into_paper_base",
                format!("approach.into_paper_base must be a non-zero finite vector, got {:?}", a.into_paper_base),
            ));
        }
        if !(a.max_angle_rad.is_finite() && a.max_angle_rad > 0.0 && a.max_angle_rad <= std::f64::consts::FRAC_PI_2) {
            return Err(SettingError::new(
                "approach.max_angle_rad",
                format!("approach.max_angle_rad must be in (0, π/2], got {}", a.max_angle_rad),
            ));
        }
        Ok(())
    }

    /// The ink station (`dip` or `ink`, not both) and its reload rule.
    fn check_ink(&self) -> Result<(), SettingError> {
        if let Some(d) = &self.dip {
            if d.every_strokes == 0
                || !(d.depth_mm.is_finite() && d.depth_mm > 0.0)
                || d.pose.iter().any(|v| !v.is_finite())
            {
                return Err(SettingError::new(
                    "dip",
                    "dip: every_strokes ≥ 1, depth_mm > 0 and a finite pose are required".to_string(),
                ));
            }
        }
        if let Some(i) = &self.ink {
            if self.dip.is_some() {
                return Err(SettingError::new(
                    "ink",
                    "give either dip or ink, not both (ink replaces dip)".to_string(),
                ));
            }
            if !(i.depth_mm.is_finite() && i.depth_mm > 0.0) {
                return Err(SettingError::new("ink.depth_mm", format!("ink.depth_mm must be > 0, got {}", i.depth_mm)));
            }
            if i.pose.iter().any(|v| !v.is_finite()) {
                return Err(SettingError::new(
                    "ink.pose",
                    "ink.pose must be six finite numbers [x, y, z, rx, ry, rz] (m, rad)".to_string(),
                ));
            }
            if !(i.dwell_s.is_finite() && (0.0..=MAX_DWELL_S).contains(&i.dwell_s)) {
                return Err(SettingError::new(
                    "ink.dwell_s",
                    format!("ink.dwell_s must be within 0..={MAX_DWELL_S} s, got {}", i.dwell_s),
                ));
            }
            match i.reload {
                Reload::EveryStrokes(0) => {
                    return Err(SettingError::new(
                        "ink.reload.every_strokes",
                        "ink.reload.every_strokes must be ≥ 1".to_string(),
                    ));
                }
                Reload::EveryMm(mm) if !(mm.is_finite() && mm > 0.0) => {
                    return Err(SettingError::new(
                        "ink.reload.every_mm",
                        format!("ink.reload.every_mm must be > 0 mm, got {mm}"),
                    ));
                }
                _ => {}
            }
            if i.paper_mm.is_some_and(|p| p.iter().any(|v| !v.is_finite())) {
                return Err(SettingError::new(
                    "ink.paper_mm",
                    "ink.paper_mm must be two finite numbers (paper mm)".to_string(),
                ));
            }
        }
        Ok(())
    }

    /// The ink station in use: `ink`, or the older `dip` as one.
    pub fn station(&self) -> Option<InkStation> {
        self.ink.or_else(|| self.dip.as_ref().map(InkStation::from_dip))
    }
}

/// Pressed path length of a stroke on the paper, mm (between consecutive points both pressed).
pub fn pressed_mm(points: &[TrackPoint]) -> f64 {
    points
        .windows(2)
        .filter(|w| w[0].is_pressed() && w[1].is_pressed())
        .map(|w| (w[1].x_mm - w[0].x_mm).hypot(w[1].y_mm - w[0].y_mm))
        .sum()
}

/// Before which strokes the brush goes to the ink, by the station's reload rule: one flag per
/// stroke of `track` (empty strokes never dip). `stroke_chars` gives each stroke's character
/// (a sheet `track.json`'s `stroke_chars`), needed by `before_each_char`.
///
/// # Errors
/// [`RobotError::Unsafe`] when the rule needs character boundaries that were not given, or
/// they do not match the track.
pub fn dip_plan(track: &Track, stroke_chars: Option<&[usize]>, station: &InkStation) -> Result<Vec<bool>, RobotError> {
    let n = track.strokes.len();
    if let Some(c) = stroke_chars {
        if c.len() != n {
            return Err(RobotError::Unsafe {
                stroke: None,
                point: None,
                reason: format!("the track's stroke_chars has {} entries for {n} strokes", c.len()),
            });
        }
    }
    let mut out = vec![false; n];
    let mut since_mm = 0.0;
    let mut first = true;
    let mut last_char = None;
    for (si, st) in track.strokes.iter().enumerate() {
        if st.points.is_empty() {
            continue;
        }
        let len = pressed_mm(&st.points);
        let dip = match station.reload {
            Reload::EveryStrokes(k) => si % k.max(1) == 0,
            Reload::EveryMm(l) => first || (since_mm > 0.0 && since_mm + len > l),
            Reload::BeforeEachChar => {
                let Some(c) = stroke_chars else {
                    return Err(RobotError::Unsafe {
                        stroke: None,
                        point: None,
                        reason: "robot.json ink.reload = before_each_char needs the track's character boundaries (its stroke_chars), and this track has none".into(),
                    });
                };
                first || last_char != Some(c[si])
            }
        };
        if dip {
            since_mm = 0.0;
        }
        since_mm += len;
        last_char = stroke_chars.map(|c| c[si]);
        first = false;
        out[si] = dip;
    }
    Ok(out)
}
