//! The writing program: per stroke travel, descend, press along, lift; and the safety
//! envelope checked before anything moves. The configuration it is built from (`robot.json`)
//! is in the crate's `config` module.

use brush_model::{BrushProfile, Track, TrackPoint};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use crate::RobotError;
pub(crate) use crate::config::{
    Approach, CONTROLLER_MAX_ACC, CONTROLLER_MAX_BLEND_M, CONTROLLER_MAX_SPEED, CONTROLLER_MAX_SPEED_FRACTION,
    CONTROLLER_MAX_TCP_OFFSET_M, DWELL_SINK_MM, InkStation, Limits, RobotConfig, dip_plan,
};
use crate::frame::PaperFrame;
use crate::kinematics;
use crate::pose::{Pose, brush_pose, lifted_pose};

/// A move shorter than this (mm, TCP path) is a turn in place: its speed does not set its
/// duration, so no rate per mm or per second is computed for it.
pub const IN_PLACE_MM: f64 = 1e-3;

/// The smallest extent a track may have, mm (the larger side of its bounding box on the
/// paper): a smaller one is a track in the wrong unit (metres), not a character.
pub const MIN_TRACK_EXTENT_MM: f64 = 2.0;

/// The deepest press of a track must reach this fraction of the brush profile's smallest
/// calibrated press (`ranges.h_mm.min`): a track that never presses that deep is in the wrong
/// unit or made for another brush.
pub const MIN_DEEPEST_PRESS_FRACTION: f64 = 0.25;

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
    /// Joint move to a TCP pose: the controller solves the joints (AUBO: inverse kinematics
    /// from the arm's present joints, `RobotAlgorithm.inverseKinematics`; URScript: `movej`
    /// to a pose), so no joint angle computed from assumed kinematics is ever commanded.
    JointPose {
        /// Target TCP pose.
        pose: Pose,
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

impl Move {
    /// The TCP pose the move ends at (`None` for a joint move to joints).
    pub fn target(&self) -> Option<Pose> {
        match *self {
            Move::Line { pose, .. } | Move::JointPose { pose, .. } => Some(pose),
            Move::Joint { .. } => None,
        }
    }
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
    /// Joint move to the first safe pose (a [`Move::JointPose`]: the controller solves it).
    pub start: Move,
    /// Strokes in writing order.
    pub strokes: Vec<StrokeProgram>,
    /// The paper frame the program was built for: paper (m, z into the paper) → base (m). The
    /// runner uses it to lift the brush straight out of the paper after a fault.
    #[serde(skip)]
    pub paper_to_base: Isometry3<f64>,
    /// Speed of a retreat (lifting after a fault or a stop), m/s: the travel speed.
    pub retreat_speed_m_s: f64,
    /// Acceleration of a retreat, m/s²: the travel acceleration.
    pub retreat_acc_m_s2: f64,
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
    /// How deep a base-frame position lies below the paper surface, mm (negative: above it).
    pub fn depth_mm(&self, position_m: [f64; 3]) -> f64 {
        (self.paper_to_base.inverse() * nalgebra::Point3::from(position_m)).z * 1000.0
    }
    /// The pose `lift_m` above the paper, straight out of the paper from `pose` (along the
    /// paper normal), same orientation.
    pub fn lifted_out(&self, pose: &Pose, lift_m: f64) -> Pose {
        let mut local = self.paper_to_base.inverse() * nalgebra::Point3::from(pose.position());
        local.z = -lift_m;
        let p = self.paper_to_base * local;
        Pose([p.x, p.y, p.z, pose.0[3], pose.0[4], pose.0[5]])
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
    /// Angle between the paper's into-paper normal and the expected approach direction, rad.
    pub paper_normal_angle_rad: f64,
    /// Largest tilt α, rad.
    pub max_tilt_rad: f64,
    /// Largest orientation change per mm of travel while pressed, rad/mm.
    pub max_turn_rad_per_mm: f64,
    /// Largest orientation change per second of a move at its commanded speed, rad/s.
    pub max_wrist_rate_rad_s: f64,
    /// Largest depth change per mm of travel along the paper while pressed, mm/mm.
    pub max_depth_change_per_mm: f64,
    /// Estimated writing time at the configured speeds, s (path length / speed, accelerations
    /// ignored).
    pub estimated_seconds: f64,
    /// Ink dips in the program.
    pub dips: usize,
}

fn unsafe_at(stroke: usize, point: Option<usize>, reason: String) -> RobotError {
    RobotError::Unsafe { stroke: Some(stroke), point, reason }
}

/// Refuses a paper frame whose into-paper normal (paper z = x × y, mapped to the base frame)
/// points more than `approach.max_angle_rad` away from `approach.into_paper_base`: touch points
/// that are mirrored (a reflection cannot be fitted by a rotation, so Kabsch turns the sheet
/// upside down instead) or a sheet the brush would reach from below. Returns the angle, rad.
///
/// # Errors
/// [`RobotError::Unsafe`] naming both directions and the angle.
pub fn check_approach(frame: &PaperFrame, approach: &Approach) -> Result<f64, RobotError> {
    let n = frame.iso.rotation * Vector3::z();
    let want = Vector3::from(approach.into_paper_base).normalize();
    let angle = n.dot(&want).clamp(-1.0, 1.0).acos();
    if angle > approach.max_angle_rad {
        return Err(RobotError::Unsafe {
            stroke: None,
            point: None,
            reason: format!(
                "paper.json: the touch points put the paper's into-paper normal (z = x × y) along ({:.3}, {:.3}, {:.3}) in the base frame, {:.1}° from the approach direction ({:.3}, {:.3}, {:.3}) (robot.json approach.max_angle_rad = {:.4}, {:.0}°): the paper axes are mirrored or the sheet faces away from the brush; check the order and signs of paper_mm and robot_m",
                n.x,
                n.y,
                n.z,
                angle.to_degrees(),
                want.x,
                want.y,
                want.z,
                approach.max_angle_rad,
                approach.max_angle_rad.to_degrees()
            ),
        });
    }
    Ok(angle)
}

/// One commanded line move with what the envelope allows there.
struct Checked {
    stroke: usize,
    point: Option<usize>,
    what: &'static str,
    pose: Pose,
    v_m_s: f64,
    /// Deepest the pose may lie below the paper surface, mm (`None`: off the sheet, free).
    max_depth_mm: Option<f64>,
}

fn check_point(
    p: &TrackPoint,
    profile: &BrushProfile,
    frame: &PaperFrame,
    cfg: &RobotConfig,
    at: impl Fn(String) -> RobotError,
) -> Result<(), RobotError> {
    if ![p.x_mm, p.y_mm, p.h_mm, p.alpha_rad, p.beta_rad].iter().all(|v| v.is_finite()) {
        return Err(at("a value is not finite".into()));
    }
    let hmax = profile.ranges.h_mm.max;
    if p.h_mm > hmax + 1e-9 {
        return Err(at(format!("press h = {:.3} mm is deeper than the profile's range (max {hmax} mm)", p.h_mm)));
    }
    if p.h_mm < 0.0 {
        return Err(at(format!("press h = {:.3} mm is above the paper", p.h_mm)));
    }
    let l = &cfg.limits;
    let a = p.alpha_rad;
    if a.abs() > l.max_tilt_rad {
        return Err(at(format!(
            "tilt α = {a:.4} rad ({:.1}°) is beyond limits.max_tilt_rad = {:.4} rad ({:.1}°)",
            a.to_degrees(),
            l.max_tilt_rad,
            l.max_tilt_rad.to_degrees()
        )));
    }
    let r = profile.ranges.alpha_rad;
    let tol = l.alpha_tolerance_rad;
    if a < r.min - tol - 1e-12 || a > r.max + tol + 1e-12 {
        return Err(at(format!(
            "tilt α = {a:.4} rad ({:.1}°) is outside the brush profile's calibrated range [{:.4}, {:.4}] rad ([{:.1}°, {:.1}°]) widened by limits.alpha_tolerance_rad = {tol:.4} rad",
            a.to_degrees(),
            r.min,
            r.max,
            r.min.to_degrees(),
            r.max.to_degrees()
        )));
    }
    if !frame.contains(p.x_mm, p.y_mm) {
        let b = frame.bounds_mm;
        return Err(at(format!(
            "point ({:.1}, {:.1}) mm lies outside the paper [{}, {}]–[{}, {}] mm",
            p.x_mm, p.y_mm, b[0], b[1], b[2], b[3]
        )));
    }
    Ok(())
}

/// Maxima over the checked moves, for the report.
#[derive(Default)]
struct Peaks {
    tilt: f64,
    turn_per_mm: f64,
    wrist: f64,
    depth_per_mm: f64,
}

/// Checks the pressed moves between consecutive track points: no turn in place while pressed,
/// orientation change per mm and depth change per mm while pressed.
fn check_segment(
    a: &TrackPoint,
    b: &TrackPoint,
    pa: &Pose,
    pb: &Pose,
    l: &Limits,
    peaks: &mut Peaks,
    at: impl Fn(String) -> RobotError,
) -> Result<(), RobotError> {
    let pressed = a.is_pressed() && b.is_pressed();
    if !pressed {
        return Ok(());
    }
    let len_mm = dist(pa, pb) * 1000.0;
    let turn = pa.to_iso().rotation.angle_to(&pb.to_iso().rotation);
    if len_mm < IN_PLACE_MM {
        if turn > 1e-6 {
            return Err(at(format!(
                "the brush turns {turn:.4} rad ({:.1}°) in place while pressed (h = {:.3} mm): lift it to the surface (h = 0) to turn",
                turn.to_degrees(),
                b.h_mm
            )));
        }
        return Ok(());
    }
    let per_mm = turn / len_mm;
    peaks.turn_per_mm = peaks.turn_per_mm.max(per_mm);
    if per_mm > l.max_turn_rad_per_mm {
        return Err(at(format!(
            "the brush turns {turn:.4} rad ({:.1}°) over {len_mm:.3} mm while pressed: {per_mm:.3} rad/mm, beyond limits.max_turn_rad_per_mm = {}",
            turn.to_degrees(),
            l.max_turn_rad_per_mm
        )));
    }
    let dxy = (b.x_mm - a.x_mm).hypot(b.y_mm - a.y_mm);
    if dxy >= IN_PLACE_MM {
        let dh = (b.h_mm - a.h_mm).abs();
        let per_mm = dh / dxy;
        peaks.depth_per_mm = peaks.depth_per_mm.max(per_mm);
        if per_mm > l.max_depth_change_per_mm {
            return Err(at(format!(
                "the press depth changes {dh:.3} mm over {dxy:.3} mm of travel while pressed: {per_mm:.2} mm/mm, beyond limits.max_depth_change_per_mm = {}",
                l.max_depth_change_per_mm
            )));
        }
    }
    Ok(())
}

/// Builds the program for a track and checks the whole safety envelope before anything moves
/// (the list, with the defaults, is in docs/robot.md, "Safety checks"): every setting within
/// what the controller accepts and within [`Limits`]; the paper facing the brush
/// ([`check_approach`]); every press within the profile's h range, α within the profile's range
/// and the tilt limit, every point on the sheet; orientation change per mm and depth change per
/// mm while pressed, orientation change per second of every move; every commanded pose no
/// deeper than the track asks there (travel, approach, lift and dip above the paper); and every
/// pose reachable by the AUBO-i5 with the brush orientation asked for.
///
/// # Examples
/// ```
/// use robot_io::brush_model::{BrushProfile, Stroke, Track, TrackPoint};
/// use robot_io::{RobotConfig, build_program, level_frame_in_front};
/// let profile = BrushProfile::builtin("pen1").unwrap();
/// // One straight stroke, 30 mm long, pressed 3 mm deep.
/// let pt = |x: f64| TrackPoint { x_mm: x, y_mm: 60.0, h_mm: 3.0, alpha_rad: 0.0, beta_rad: 0.0 };
/// let track = Track { strokes: vec![Stroke { points: (0..=200).map(|i| pt(30.0 + 0.15 * f64::from(i))).collect() }] };
/// let frame = level_frame_in_front([50.0, 60.0], [0.0, 0.0, 210.0, 297.0]);
/// let cfg = RobotConfig::default();
/// let (program, _report) = build_program(&track, &profile, &frame, &cfg).unwrap();
/// assert_eq!(program.strokes.len(), 1);
/// // A press deeper than the profile's range is refused before anything moves.
/// let deep = Track { strokes: vec![Stroke { points: vec![TrackPoint { h_mm: 50.0, ..pt(40.0) }; 2] }] };
/// assert!(build_program(&deep, &profile, &frame, &cfg).is_err());
/// ```
///
/// # Errors
/// [`RobotError::Unsafe`] naming the first offending stroke and point, the value and the limit.
pub fn build_program(
    track: &Track,
    profile: &BrushProfile,
    frame: &PaperFrame,
    cfg: &RobotConfig,
) -> Result<(Program, CheckReport), RobotError> {
    build_program_chars(track, None, profile, frame, cfg)
}

/// [`build_program`] for a track whose strokes belong to characters (`stroke_chars[i]`: the
/// character of stroke `i`, as a sheet `track.json` records it), which the ink reload rule
/// `before_each_char` needs.
///
/// # Errors
/// As [`build_program`]; also when the reload rule needs character boundaries not given.
pub fn build_program_chars(
    track: &Track,
    stroke_chars: Option<&[usize]>,
    profile: &BrushProfile,
    frame: &PaperFrame,
    cfg: &RobotConfig,
) -> Result<(Program, CheckReport), RobotError> {
    let refuse = |reason: String| RobotError::Unsafe { stroke: None, point: None, reason };
    cfg.validate().map_err(|m| refuse(format!("robot.json: {m}")))?;
    if track.strokes.is_empty() || track.point_count() == 0 {
        return Err(refuse("the track has no points".into()));
    }
    let tcp_offset_m = profile.brush.length_mm / 1000.0;
    if !(tcp_offset_m.is_finite() && (0.0..CONTROLLER_MAX_TCP_OFFSET_M).contains(&tcp_offset_m)) {
        return Err(refuse(format!(
            "the brush length {} mm (the tool offset) is beyond what the controller accepts (0 ≤ offset < {} mm)",
            profile.brush.length_mm,
            CONTROLLER_MAX_TCP_OFFSET_M * 1000.0
        )));
    }
    let normal_angle = check_approach(frame, &cfg.approach)?;
    let station = cfg.station();
    let dips = match &station {
        Some(s) => dip_plan(track, stroke_chars, s)?,
        None => vec![false; track.strokes.len()],
    };
    let mut b = Builder::new(profile, frame, cfg, tcp_offset_m);
    for (si, stroke) in track.strokes.iter().enumerate() {
        if stroke.points.is_empty() {
            continue;
        }
        b.stroke(si, &stroke.points, station.as_ref().filter(|_| dips[si]))?;
    }
    b.check_envelope()?;
    check_plausible(track, profile)?;
    Ok(b.finish(track, normal_angle, station.map_or(0.0, |s| s.dwell_s)))
}

/// Refuses a track whose size or depth no brush writes: an extent under
/// [`MIN_TRACK_EXTENT_MM`], or a deepest press under [`MIN_DEEPEST_PRESS_FRACTION`] of the
/// profile's smallest calibrated press (both the signs of a track in metres).
fn check_plausible(track: &Track, profile: &BrushProfile) -> Result<(), RobotError> {
    let refuse = |reason: String| RobotError::Unsafe { stroke: None, point: None, reason };
    let (mut lo, mut hi, mut deepest) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2], 0.0f64);
    for p in track.points() {
        lo = [lo[0].min(p.x_mm), lo[1].min(p.y_mm)];
        hi = [hi[0].max(p.x_mm), hi[1].max(p.y_mm)];
        deepest = deepest.max(p.h_mm);
    }
    let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    if extent < MIN_TRACK_EXTENT_MM {
        return Err(refuse(format!(
            "the track spans only {extent:.4} mm on the paper (at least {MIN_TRACK_EXTENT_MM} mm expected): track.json is in millimetres"
        )));
    }
    let need = MIN_DEEPEST_PRESS_FRACTION * profile.ranges.h_mm.min;
    if deepest < need {
        return Err(refuse(format!(
            "the deepest press is {deepest:.4} mm, under {need:.3} mm ({MIN_DEEPEST_PRESS_FRACTION} of the brush profile's smallest calibrated press {} mm): the track is in another unit or for another brush",
            profile.ranges.h_mm.min
        )));
    }
    Ok(())
}

/// The program as it is built, stroke by stroke, with what the envelope check needs.
struct Builder<'a> {
    profile: &'a BrushProfile,
    frame: &'a PaperFrame,
    cfg: &'a RobotConfig,
    tcp_offset_m: f64,
    tcp: Isometry3<f64>,
    lift_m: f64,
    /// The last inverse-kinematics solution: the seed of the next, so joints move little.
    seed: Option<[f64; 6]>,
    /// The joint move to the first safe pose, and that pose.
    start: Option<(Move, Pose)>,
    strokes: Vec<StrokeProgram>,
    /// Every commanded line move in the order they run, with what the envelope allows there.
    checked: Vec<Checked>,
    /// The pose above the end of the last stroke.
    last_up: Option<Pose>,
    peaks: Peaks,
    totals: Totals,
}

/// Running totals for the report: the deepest press and the distances, m.
#[derive(Default)]
struct Totals {
    max_press_mm: f64,
    pressed_m: f64,
    travel_m: f64,
    dip_m: f64,
    dips: usize,
}

impl<'a> Builder<'a> {
    fn new(profile: &'a BrushProfile, frame: &'a PaperFrame, cfg: &'a RobotConfig, tcp_offset_m: f64) -> Self {
        Self {
            profile,
            frame,
            cfg,
            tcp_offset_m,
            tcp: tcp_iso(tcp_offset_m),
            lift_m: cfg.lift_mm / 1000.0,
            seed: None,
            start: None,
            strokes: Vec::new(),
            checked: Vec::new(),
            last_up: None,
            peaks: Peaks::default(),
            totals: Totals::default(),
        }
    }

    /// Solves the inverse kinematics for `pose`, seeded by the last solution.
    fn reach(&mut self, pose: &Pose, si: usize, pi: usize, what: &str) -> Result<[f64; 6], RobotError> {
        let q = kinematics::inverse(pose, &self.tcp, self.seed.as_ref()).ok_or_else(|| {
            unsafe_at(
                si,
                Some(pi),
                format!(
                    "{what} pose {:?} is not reachable by the AUBO-i5 with this brush orientation",
                    pose.0.map(|v| (v * 1e4).round() / 1e4)
                ),
            )
        })?;
        self.seed = Some(q);
        Ok(q)
    }

    /// One stroke: its points checked, then travel above the first point (after a dip when
    /// `dip` is given), descent, the pressed moves and the lift.
    fn stroke(&mut self, si: usize, points: &[TrackPoint], dip: Option<&InkStation>) -> Result<(), RobotError> {
        let cfg = self.cfg;
        for (pi, p) in points.iter().enumerate() {
            check_point(p, self.profile, self.frame, cfg, |reason| unsafe_at(si, Some(pi), reason))?;
            self.totals.max_press_mm = self.totals.max_press_mm.max(p.h_mm);
            self.peaks.tilt = self.peaks.tilt.max(p.alpha_rad.abs());
        }
        let first = &points[0];
        let up = lifted_pose(self.frame, first, self.lift_m);
        self.reach(&up, si, 0, "approach")?;
        if self.start.is_none() {
            self.start = Some((Move::JointPose { pose: up, a: cfg.joint_acc_rad_s2, v: cfg.joint_speed_rad_s }, up));
        }
        if let Some(prev) = self.last_up {
            self.totals.travel_m += dist(&prev, &up);
        }
        let dip = match dip {
            Some(station) => self.dip(si, station, &up)?,
            None => Vec::new(),
        };
        self.check(si, Some(0), "travel (above the first point)", up, cfg.travel_speed_m_s, Some(0.0));
        let press = self.press(si, points)?;
        let first_pose = brush_pose(self.frame, first);
        let last_i = points.len() - 1;
        let end_up = lifted_pose(self.frame, &points[last_i], self.lift_m);
        self.reach(&end_up, si, last_i, "lift")?;
        self.check(si, Some(last_i), "lift", end_up, cfg.travel_speed_m_s, Some(0.0));
        self.strokes.push(StrokeProgram {
            index: si,
            dip,
            approach: vec![
                Move::Line { pose: up, a: cfg.travel_acc_m_s2, v: cfg.travel_speed_m_s, blend_m: 0.0 },
                Move::Line { pose: first_pose, a: cfg.write_acc_m_s2, v: cfg.write_speed_m_s, blend_m: 0.0 },
            ],
            press,
            lift: Move::Line { pose: end_up, a: cfg.travel_acc_m_s2, v: cfg.travel_speed_m_s, blend_m: 0.0 },
        });
        self.last_up = Some(end_up);
        Ok(())
    }

    /// The dip before stroke `si`: above the ink, down into it, the dwell, back up; then `up`
    /// (above the stroke's first point) must still be reachable.
    fn dip(&mut self, si: usize, d: &InkStation, up: &Pose) -> Result<Vec<Move>, RobotError> {
        let cfg = self.cfg;
        let above = Pose(d.pose);
        let down = above.raised(-d.depth_mm / 1000.0);
        let soak = down.raised(-DWELL_SINK_MM / 1000.0);
        let dwells = d.dwell_s > 0.0;
        self.reach(&above, si, 0, "dip station")?;
        self.reach(&down, si, 0, "dip station")?;
        let (vt, vd) = (cfg.travel_speed_m_s, cfg.travel_speed_m_s * 0.5);
        // The dwell: sink DWELL_SINK_MM further over dwell_s.
        let v_soak = DWELL_SINK_MM / 1000.0 / d.dwell_s;
        let a = cfg.travel_acc_m_s2;
        let mut moves =
            vec![Move::Line { pose: above, a, v: vt, blend_m: 0.0 }, Move::Line { pose: down, a, v: vd, blend_m: 0.0 }];
        if dwells {
            self.reach(&soak, si, 0, "dip station")?;
            moves.push(Move::Line { pose: soak, a, v: v_soak, blend_m: 0.0 });
        }
        moves.push(Move::Line { pose: above, a, v: vd, blend_m: 0.0 });
        self.totals.dips += 1;
        self.totals.dip_m += dist(self.last_up.as_ref().unwrap_or(&above), &above) + dist(&above, up);
        self.totals.dip_m += 2.0 * (d.depth_mm + if dwells { DWELL_SINK_MM } else { 0.0 }) / 1000.0 * 2.0;
        // The station must be off the sheet if it lies below the paper's plane, and the pose
        // above the ink must be above that plane (travel reaches it straight).
        let off_sheet = |pose: &Pose| {
            let q = self.frame.to_paper(pose.position());
            !self.frame.contains(q[0], q[1])
        };
        let in_ink = if off_sheet(&down) && off_sheet(&soak) { None } else { Some(0.0) };
        self.check(si, None, "dip station (above the ink)", above, vt, Some(0.0));
        self.check(si, None, "dip station (in the ink)", down, vd, in_ink);
        if dwells {
            self.check(si, None, "dip station (in the ink)", soak, v_soak, in_ink);
        }
        self.check(si, None, "dip station (above the ink)", above, vd, Some(0.0));
        self.reach(up, si, 0, "approach")?;
        Ok(moves)
    }

    /// The pressed moves of a stroke (the first point is reached by the descent), each pose
    /// reachable and each segment within the pressed limits.
    fn press(&mut self, si: usize, points: &[TrackPoint]) -> Result<Vec<Move>, RobotError> {
        let cfg = self.cfg;
        let mut press = Vec::with_capacity(points.len());
        let mut prev: Option<(Pose, &TrackPoint)> = None;
        for (pi, p) in points.iter().enumerate() {
            let pose = brush_pose(self.frame, p);
            self.reach(&pose, si, pi, "pressed")?;
            if let Some((pp, pt)) = prev {
                let step_mm = (p.x_mm - pt.x_mm).hypot(p.y_mm - pt.y_mm);
                if pt.is_pressed() && p.is_pressed() && step_mm > cfg.limits.max_step_mm {
                    return Err(unsafe_at(
                        si,
                        Some(pi),
                        format!(
                            "the brush would move {step_mm:.3} mm along the paper between two points of one stroke, beyond limits.max_step_mm = {} mm",
                            cfg.limits.max_step_mm
                        ),
                    ));
                }
                self.totals.pressed_m += dist(&pp, &pose);
                check_segment(pt, p, &pp, &pose, &cfg.limits, &mut self.peaks, |reason| {
                    unsafe_at(si, Some(pi), reason)
                })?;
            }
            let is_end = pi == 0 || pi + 1 == points.len();
            let blend_m = if is_end { 0.0 } else { cfg.blend_mm / 1000.0 };
            if pi > 0 {
                press.push(Move::Line { pose, a: cfg.write_acc_m_s2, v: cfg.write_speed_m_s, blend_m });
            }
            let what = if pi == 0 { "descent onto the first point" } else { "pressed" };
            self.check(si, Some(pi), what, pose, cfg.write_speed_m_s, Some(p.h_mm));
            prev = Some((pose, p));
        }
        Ok(press)
    }

    /// Records a commanded line move for the envelope check.
    fn check(
        &mut self,
        stroke: usize,
        point: Option<usize>,
        what: &'static str,
        pose: Pose,
        v_m_s: f64,
        max_depth_mm: Option<f64>,
    ) {
        self.checked.push(Checked { stroke, point, what, pose, v_m_s, max_depth_mm });
    }

    /// The envelope over every commanded line move, in the order they run: nothing deeper
    /// than the track asks there, and no faster wrist than the limit at the move's speed.
    fn check_envelope(&mut self) -> Result<(), RobotError> {
        let max_rate = self.cfg.limits.max_wrist_rate_rad_s;
        let mut prev = self.start.expect("at least one stroke").1;
        for c in &self.checked {
            let depth = self.frame.to_paper(c.pose.position())[2];
            if let Some(max) = c.max_depth_mm.filter(|&max| depth > max + 1e-6) {
                return Err(unsafe_at(
                    c.stroke,
                    c.point,
                    format!(
                        "the {} pose lies {depth:.3} mm below the paper surface where at most {max:.3} mm is allowed",
                        c.what
                    ),
                ));
            }
            let len_mm = dist(&prev, &c.pose) * 1000.0;
            if len_mm >= IN_PLACE_MM {
                let turn = prev.to_iso().rotation.angle_to(&c.pose.to_iso().rotation);
                let rate = turn * c.v_m_s * 1000.0 / len_mm;
                self.peaks.wrist = self.peaks.wrist.max(rate);
                if rate > max_rate {
                    return Err(unsafe_at(
                        c.stroke,
                        c.point,
                        format!(
                            "the {} move turns the brush {turn:.4} rad ({:.1}°) over {len_mm:.3} mm at {} m/s: {rate:.2} rad/s, beyond limits.max_wrist_rate_rad_s = {max_rate}",
                            c.what,
                            turn.to_degrees(),
                            c.v_m_s,
                        ),
                    ));
                }
            }
            prev = c.pose;
        }
        Ok(())
    }

    /// The program and the report (`dwell_s`: the station's dwell per dip, s).
    fn finish(self, track: &Track, normal_angle_rad: f64, dwell_s: f64) -> (Program, CheckReport) {
        let cfg = self.cfg;
        let t = self.totals;
        let program = Program {
            tcp_offset_m: self.tcp_offset_m,
            speed_fraction: cfg.speed_fraction,
            start: self.start.expect("at least one stroke").0,
            strokes: self.strokes,
            paper_to_base: self.frame.iso,
            retreat_speed_m_s: cfg.travel_speed_m_s,
            retreat_acc_m_s2: cfg.travel_acc_m_s2,
        };
        let report = CheckReport {
            strokes: program.strokes.len(),
            points: track.point_count(),
            moves: program.move_count(),
            max_press_mm: t.max_press_mm,
            frame_residual_mm: self.frame.residual_mm,
            paper_normal_angle_rad: normal_angle_rad,
            max_tilt_rad: self.peaks.tilt,
            max_turn_rad_per_mm: self.peaks.turn_per_mm,
            max_wrist_rate_rad_s: self.peaks.wrist,
            max_depth_change_per_mm: self.peaks.depth_per_mm,
            estimated_seconds: t.pressed_m / cfg.write_speed_m_s
                + (t.travel_m + t.dip_m + 2.0 * self.lift_m * program.strokes.len() as f64) / cfg.travel_speed_m_s
                + dwell_s * t.dips as f64,
            dips: t.dips,
        };
        (program, report)
    }
}

fn dist(a: &Pose, b: &Pose) -> f64 {
    let (p, q) = (a.position(), b.position());
    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
}

/// How far the moves of a compacted stroke may pass from a point they leave out, m (the TCP
/// position; the press depth lies along the paper normal, so it is bounded by the same
/// distance).
pub const COMPACT_TOLERANCE_M: f64 = 5e-5;
/// How far the tool orientation of a compacted stroke may turn from a point it leaves out, rad.
pub const COMPACT_TOLERANCE_RAD: f64 = 2e-3;
/// Most points one compacted move may stand for.
const COMPACT_MAX_SPAN: usize = 2000;

/// A move-per-point program made valid for a controller that blends: each stroke's pressed
/// points merged where the straight move between the points kept passes within
/// [`COMPACT_TOLERANCE_M`] and [`COMPACT_TOLERANCE_RAD`] of every point left out (no move
/// shorter than [`IN_PLACE_MM`] that does not turn, no zero-length move), and every blend
/// radius at most half the shorter of the two moves it joins (and at most `cfg.blend_mm`); no
/// blend where the path turns back by more than 90° (the brush stops there). The dips,
/// approaches and lifts are unchanged.
///
/// # Examples
/// ```
/// # use robot_io::brush_model::{BrushProfile, Stroke, Track, TrackPoint};
/// # use robot_io::{level_frame_in_front, RobotConfig, build_program, check_blends, compact_program};
/// let profile = BrushProfile::builtin("pen1").unwrap();
/// let pt = |x: f64| TrackPoint { x_mm: x, y_mm: 60.0, h_mm: 3.0, alpha_rad: 0.0, beta_rad: 0.0 };
/// let track = Track { strokes: vec![Stroke { points: (0..200).map(|i| pt(30.0 + 0.15 * f64::from(i))).collect() }] };
/// let frame = level_frame_in_front([50.0, 60.0], [0.0, 0.0, 210.0, 297.0]);
/// let cfg = RobotConfig::default();
/// let (program, _) = build_program(&track, &profile, &frame, &cfg).unwrap();
/// let compact = compact_program(&program, &cfg);
/// assert_eq!(compact.strokes[0].press.len(), 1); // a straight stroke is one move
/// check_blends(&compact).unwrap();
/// ```
pub fn compact_program(program: &Program, cfg: &RobotConfig) -> Program {
    let mut out = program.clone();
    for st in &mut out.strokes {
        let Some(Move::Line { pose: first, .. }) = st.approach.last().copied() else { continue };
        let mut poses = vec![first];
        let mut spec = Vec::new();
        for m in &st.press {
            if let Move::Line { pose, a, v, .. } = *m {
                poses.push(pose);
                spec.push((a, v));
            }
        }
        if poses.len() < 2 {
            continue;
        }
        let keep = compact_indices(&poses);
        let lens: Vec<f64> = keep.windows(2).map(|w| dist(&poses[w[0]], &poses[w[1]])).collect();
        let mut press = Vec::with_capacity(keep.len());
        for (k, &i) in keep.iter().enumerate().skip(1) {
            let blend_m = if k + 1 < keep.len() && !turns_back(&poses[keep[k - 1]], &poses[i], &poses[keep[k + 1]]) {
                (cfg.blend_mm / 1000.0).min(0.5 * lens[k - 1].min(lens[k]))
            } else {
                0.0
            };
            let (a, v) = spec[i - 1];
            press.push(Move::Line { pose: poses[i], a, v, blend_m });
        }
        st.press = press;
    }
    out
}

/// Whether the path turns back at `b` (by more than 90° between `a → b` and `b → c`): the brush
/// stops there instead of blending, as the planner's reversals ask (a blend would round the
/// reversal's tip off: measured on the held-out characters, docs/robot.md).
fn turns_back(a: &Pose, b: &Pose, c: &Pose) -> bool {
    let (pa, pb, pc) = (a.position(), b.position(), c.position());
    let (u, w) = ([pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]], [pc[0] - pb[0], pc[1] - pb[1], pc[2] - pb[2]]);
    u[0] * w[0] + u[1] * w[1] + u[2] * w[2] < 0.0
}

/// The points kept (indices into `poses`, the first and the last always).
fn compact_indices(poses: &[Pose]) -> Vec<usize> {
    let iso: Vec<Isometry3<f64>> = poses.iter().map(Pose::to_iso).collect();
    let same = |a: usize, b: usize| {
        (iso[a].translation.vector - iso[b].translation.vector).norm() < IN_PLACE_MM / 1000.0
            && iso[a].rotation.angle_to(&iso[b].rotation) < 1e-6
    };
    // Whether every point strictly between a and b lies within the tolerance of the move a → b.
    let covers = |a: usize, b: usize| {
        let (pa, pb) = (iso[a].translation.vector, iso[b].translation.vector);
        let ab = pb - pa;
        let len2 = ab.norm_squared();
        (a + 1..b).all(|i| {
            let p = iso[i].translation.vector;
            let f = if len2 > 0.0 { ((p - pa).dot(&ab) / len2).clamp(0.0, 1.0) } else { 0.0 };
            let off = (pa + ab * f - p).norm();
            let r = iso[a].rotation.try_slerp(&iso[b].rotation, f, 1e-12).unwrap_or(iso[a].rotation);
            off <= COMPACT_TOLERANCE_M && r.angle_to(&iso[i].rotation) <= COMPACT_TOLERANCE_RAD
        })
    };
    let n = poses.len();
    let mut keep = vec![0];
    let mut a = 0;
    while a < n - 1 {
        let mut b = a + 1;
        while b + 1 < n && b + 1 - a <= COMPACT_MAX_SPAN && covers(a, b + 1) {
            b += 1;
        }
        if !same(a, b) || b == n - 1 {
            if same(a, b) {
                // The last point coincides with the one kept before it: end there.
                keep.pop();
            }
            keep.push(b);
        }
        a = b;
    }
    if keep.len() < 2 {
        keep = vec![0, n - 1];
    }
    keep
}

/// Checks what a blending controller needs of a program's pressed moves: no zero-length move
/// (shorter than [`IN_PLACE_MM`] without turning), and every blend radius at most half the
/// shorter of the two moves it joins.
///
/// # Errors
/// [`RobotError::Unsafe`] naming the stroke and move, the radius and the moves' lengths.
pub fn check_blends(program: &Program) -> Result<(), RobotError> {
    for st in &program.strokes {
        let Some(Move::Line { pose: first, .. }) = st.approach.last().copied() else { continue };
        let mut prev = first;
        let mut prev_len: Option<f64> = None;
        let mut prev_blend = 0.0;
        for (k, m) in st.press.iter().enumerate() {
            let Move::Line { pose, blend_m, .. } = *m else { continue };
            let len = dist(&prev, &pose);
            let turn = prev.to_iso().rotation.angle_to(&pose.to_iso().rotation);
            if len * 1000.0 < IN_PLACE_MM && turn < 1e-6 {
                return Err(unsafe_at(st.index, Some(k + 1), "a zero-length move".into()));
            }
            if let Some(pl) = prev_len
                && prev_blend > 0.5 * pl.min(len) + 1e-12
            {
                return Err(unsafe_at(
                    st.index,
                    Some(k),
                    format!(
                        "blend radius {:.4} mm is more than half the shorter of its moves ({:.4} mm, {:.4} mm)",
                        prev_blend * 1000.0,
                        pl * 1000.0,
                        len * 1000.0
                    ),
                ));
            }
            prev = pose;
            prev_len = Some(len);
            prev_blend = blend_m;
        }
        if prev_blend > 0.0 {
            return Err(unsafe_at(st.index, Some(st.press.len()), "the last pressed move blends into the lift".into()));
        }
    }
    Ok(())
}
