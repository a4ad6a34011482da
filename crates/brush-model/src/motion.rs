//! The forward model of the moving brush: from the brush's continuous path (where its tip meets
//! the paper, how deep it presses, how it is tilted) to the footprints it leaves.
//!
//! This is the one place that decides which way a footprint points. Track building, every
//! renderer and the robot simulator's `render-trace` go through it, so a plan shows what the
//! robot's motion would write (docs/brush-model.md, "The moving brush").
//!
//! # The model
//!
//! The input is a sequence of commanded brush states, [`TrackPoint`]s read as *controls*:
//! `(x, y)` where the brush axis meets the paper (mm), `h` the depth past first contact (mm,
//! `h ≤ 0` means the tip is not pressed and leaves nothing), `α` the tilt of the tool axis from
//! the paper normal (rad) and `β` the direction the tool axis leans towards (rad, paper frame,
//! only meaningful when tilted). Between two states the brush moves in a straight line at a
//! linearly changing depth while the tool axis turns along the great circle between the two
//! axes (what a controller's `moveLine` does with position and slerped orientation). The path is
//! sampled every [`ForwardModel::step_mm`] (and every [`ForwardModel::step_rad`] of tool-axis
//! turn), and each pressed sample leaves one footprint of the brush profile's size at its
//! `(h, α)`, rooted at the sample. Its direction (root → tip) is:
//!
//! * **tilted** (`α ≥ tilt_threshold_rad`): the lean direction `β`; the bundle is bent that way
//!   whatever the motion;
//! * **upright**: the hairs are dragged. The tip lies on the path the brush has already pressed
//!   along since it touched down: walking back along that path, the first point at least
//!   the profile's [`HairMotion::trail_reach`] footprint lengths away in a straight line. This
//!   is a spatial lag: after a reversal (逆锋, a backward move then forward) the tip stays ahead
//!   until the brush has passed it, and on curves the tail stays on the stroke. While the pressed
//!   path is still shorter than that, the tip points at its farthest point once that is
//!   `min_motion_mm` away; before the brush has moved that far it keeps its last direction, and
//!   right at touch-down it trails the motion that follows (the first `min_motion_mm` of pressed
//!   travel sets the hairs).
//!
//! The hairs follow motion only from the profile's [`HairMotion::contact_h_mm`] on: a state
//! pressed lighter (`0 < h < contact_h_mm`) touches the paper but neither inks nor turns the
//! hairs. They keep the bend they had and move with the brush (the pressed path so far is
//! carried along rigidly), so a brush that eases up, glides and presses again starts from the
//! old bend, and only pressed motion pulls the tip round. Lifting to `h ≤ 0` ends the contact:
//! the hairs straighten, the history is forgotten. With `contact_h_mm = 0` every touch turns
//! the hairs (the model before profile version 2).
//!
//! The hair parameters belong to the brush ([`BrushProfile::hairs`]); a [`ForwardModel`] holds
//! only how finely the path is sampled and the tilt threshold, so every sweep of a profile
//! follows that brush's hairs.

use std::f64::consts::FRAC_PI_2;

use crate::profile::{BrushProfile, Extrapolation, HairMotion, ProfileError};
use crate::units::{Press, Stroke, Track, TrackPoint, wrap_angle_rad};

/// The forward model's constants. [`ForwardModel::default`] holds the values documented in
/// docs/brush-model.md.
///
/// # Examples
/// ```
/// use brush_model::{BrushProfile, Extrapolation, ForwardModel, TrackPoint};
/// let pen1 = BrushProfile::builtin("pen1").unwrap();
/// // An upright brush pressed 15 mm and pulled 20 mm along −x.
/// let states: Vec<TrackPoint> =
///     (0..=20).map(|i| TrackPoint { x_mm: f64::from(20 - i), y_mm: 0.0, h_mm: 15.0, alpha_rad: 0.0, beta_rad: 0.0 }).collect();
/// let sweep = ForwardModel::default().sweep(&pen1, &states, Extrapolation::Refuse);
/// assert!(!sweep.stamps.is_empty());
/// // Dragged hairs trail the motion: the last footprint points back, along +x.
/// let last = sweep.directions.last().unwrap().unwrap();
/// assert!(last.abs() < 1e-9);
/// // Tilted past the threshold, every footprint points the way the brush leans.
/// let tilted: Vec<TrackPoint> = states.iter().map(|p| TrackPoint { alpha_rad: 0.08, beta_rad: 0.05, ..*p }).collect();
/// let sweep = ForwardModel::default().sweep(&pen1, &tilted, Extrapolation::Refuse);
/// assert!(sweep.directions.iter().all(|d| (d.unwrap() - 0.05).abs() < 1e-9));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForwardModel {
    /// Tilt at and above which the footprint points along the lean direction β, rad.
    pub tilt_threshold_rad: f64,
    /// Travel before a dragged brush's direction follows the motion, mm.
    pub min_motion_mm: f64,
    /// Largest distance between path samples, mm.
    pub step_mm: f64,
    /// Largest tool-axis turn between path samples, rad.
    pub step_rad: f64,
    /// Largest depth change between path samples, mm.
    pub step_h_mm: f64,
}

/// Default tilt threshold: 2° (below it a tilt hardly bends the bundle, so the drag decides).
pub const TILT_THRESHOLD_RAD: f64 = 2.0 * std::f64::consts::PI / 180.0;

/// The nominal trailing reach ([`HairMotion::trail_reach`]), as a fraction of the footprint
/// length. Chosen on the tuning set (docs/trajectory.md, Track building).
pub const TRAIL_REACH: f64 = 0.5;

/// How far outside the profile's calibrated depth range a pressed state may lie and still count
/// as the range's end, mm (1 µm): an executed path (joints interpolated between solved poses,
/// read back through forward kinematics) follows a press at the range's end only to a few
/// hundredths of a micrometre, far below any depth a brush tells apart, and such a press must
/// leave the footprint of the end it was commanded at (with [`Extrapolation::Refuse`]; with
/// [`Extrapolation::Allow`] every depth is used as it is).
pub const DEPTH_EDGE_TOLERANCE_MM: f64 = 1e-3;

impl Default for ForwardModel {
    fn default() -> Self {
        Self {
            tilt_threshold_rad: TILT_THRESHOLD_RAD,
            min_motion_mm: 0.3,
            step_mm: 0.1,
            step_rad: 0.5f64.to_radians(),
            step_h_mm: 0.25,
        }
    }
}

/// The footprints of one brush path.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Sweep {
    /// One stamp per pressed sample, in order: anchor, `h`, `α` and the derived direction `β`
    /// (root → tip).
    pub stamps: Vec<TrackPoint>,
    /// For each input state, the direction its footprint points in (rad), or `None` when it is
    /// not pressed (`h ≤ 0`) or the profile refused its press.
    pub directions: Vec<Option<f64>>,
}

/// A sample of the path: a commanded state plus the index of the input state it sits on (if
/// any).
#[derive(Clone, Copy, Debug)]
struct Sample {
    p: TrackPoint,
    vertex: Option<usize>,
}

impl ForwardModel {
    /// Whether a state is tilted enough for its lean direction to set the footprint's.
    pub fn is_tilted(&self, p: &TrackPoint) -> bool {
        p.alpha_rad >= self.tilt_threshold_rad
    }

    /// Samples the path through `states` (see the module doc): consecutive states joined by
    /// straight moves, depth linear, tool axis along the great circle.
    fn samples(&self, states: &[TrackPoint]) -> Vec<Sample> {
        let mut out = Vec::with_capacity(states.len() * 2);
        for (i, s) in states.iter().enumerate() {
            if i > 0 {
                let a = states[i - 1];
                let d = (s.x_mm - a.x_mm).hypot(s.y_mm - a.y_mm);
                let (ua, ub) = (axis(&a), axis(s));
                let turn = angle_between(ua, ub);
                let n = (d / self.step_mm)
                    .max(turn / self.step_rad)
                    .max((s.h_mm - a.h_mm).abs() / self.step_h_mm)
                    .ceil()
                    .clamp(1.0, 1e6) as usize;
                for k in 1..n {
                    let f = k as f64 / n as f64;
                    let (alpha, beta) = from_axis(slerp(ua, ub, turn, f), a.beta_rad, s.beta_rad, f);
                    let p = TrackPoint {
                        x_mm: a.x_mm + f * (s.x_mm - a.x_mm),
                        y_mm: a.y_mm + f * (s.y_mm - a.y_mm),
                        h_mm: a.h_mm + f * (s.h_mm - a.h_mm),
                        alpha_rad: alpha,
                        beta_rad: beta,
                    };
                    out.push(Sample { p, vertex: None });
                }
            }
            out.push(Sample { p: *s, vertex: Some(i) });
        }
        out
    }

    /// The footprints the brush leaves moving through `states` (one stroke, or a whole executed
    /// path with lifts in it: states with `h ≤ 0` are off the paper), its hairs moving as
    /// `profile.hairs` says.
    ///
    /// `extrapolation` is passed to the profile; a press it refuses leaves no footprint and
    /// its direction is `None`.
    pub fn sweep(&self, profile: &BrushProfile, states: &[TrackPoint], extrapolation: Extrapolation) -> Sweep {
        let hairs = profile.hairs;
        let samples = self.samples(states);
        let mut directions = vec![None; states.len()];
        let mut stamps = Vec::with_capacity(samples.len());
        // The pressed path since touch-down (positions, less `shift`: how far the brush has
        // carried its bent hairs while touching without a press), and the current direction.
        let mut history: Vec<(f64, f64)> = Vec::new();
        let mut shift = (0.0, 0.0);
        let mut prev: Option<(f64, f64)> = None;
        let mut last: Option<f64> = None;
        for (i, s) in samples.iter().enumerate() {
            let p = s.p;
            if !p.is_pressed() {
                history.clear();
                shift = (0.0, 0.0);
                prev = None;
                last = None;
                continue;
            }
            let here = (p.x_mm, p.y_mm);
            if !follows(&hairs, &p) {
                // Touching without a press: the hairs keep their bend and move with the brush.
                if let Some(q) = prev {
                    shift = (shift.0 + here.0 - q.0, shift.1 + here.1 - q.1);
                }
                prev = Some(here);
                continue;
            }
            prev = Some(here);
            let p = at_range_edge(profile, p, extrapolation);
            let Ok(len) = footprint_length(profile, &p, extrapolation) else {
                history.push((here.0 - shift.0, here.1 - shift.1));
                continue;
            };
            let dir = if self.is_tilted(&p) {
                p.beta_rad
            } else {
                self.dragged(&history, shift, here, hairs.trail_reach * len)
                    .or(last)
                    .or_else(|| self.ahead(&hairs, &samples[i..], here))
                    .unwrap_or(FRAC_PI_2)
            };
            last = Some(dir);
            history.push((here.0 - shift.0, here.1 - shift.1));
            if let Some(v) = s.vertex {
                directions[v] = Some(dir);
            }
            stamps.push(TrackPoint { beta_rad: dir, ..p });
        }
        Sweep { stamps, directions }
    }

    /// An upright brush's direction from its pressed history: towards the first history point
    /// (walking back) at least `reach` away, else the farthest if it is `min_motion_mm` away.
    /// `history` holds positions less `shift` (see [`ForwardModel::sweep`]).
    fn dragged(&self, history: &[(f64, f64)], shift: (f64, f64), here: (f64, f64), reach: f64) -> Option<f64> {
        // The walk below computes `hypot` at every point; most points lie well inside `reach`,
        // so first find the answer when some point is at least `reach` away, skipping the
        // `hypot` of every point whose squared distance is short of `reach²` by far more than
        // both roundings (the same point, the same direction, in a fraction of the time).
        let short = reach * reach * (1.0 - 1e-9);
        for &(x, y) in history.iter().rev() {
            let q = (x + shift.0, y + shift.1);
            let (dx, dy) = (q.0 - here.0, q.1 - here.1);
            if dx * dx + dy * dy < short {
                continue;
            }
            if dx.hypot(dy) >= reach {
                return Some(direction(here, q));
            }
        }
        // No point is `reach` away: the farthest one, as the full walk finds it (the first,
        // walking back, of those at the largest `hypot`). Only points whose squared distance is
        // within far more than both roundings of the largest can be that point: `hypot` is
        // computed for those alone.
        let sq = |q: &(f64, f64)| (q.0 - here.0) * (q.0 - here.0) + (q.1 - here.1) * (q.1 - here.1);
        let near = history.iter().map(|&(x, y)| sq(&(x + shift.0, y + shift.1))).fold(0.0f64, f64::max) * (1.0 - 1e-9);
        let mut far = (0.0f64, None);
        for &(x, y) in history.iter().rev() {
            let q = (x + shift.0, y + shift.1);
            if sq(&q) < near {
                continue;
            }
            let d = (q.0 - here.0).hypot(q.1 - here.1);
            if d >= reach {
                return Some(direction(here, q));
            }
            if d > far.0 {
                far = (d, Some(q));
            }
        }
        match far {
            (d, Some(q)) if d >= self.min_motion_mm => Some(direction(here, q)),
            _ => None,
        }
    }

    /// At touch-down: opposite to the first `min_motion_mm` of the coming pressed motion.
    fn ahead(&self, hairs: &HairMotion, rest: &[Sample], here: (f64, f64)) -> Option<f64> {
        for s in rest.iter().skip(1) {
            if !follows(hairs, &s.p) {
                return None;
            }
            let q = (s.p.x_mm, s.p.y_mm);
            if (q.0 - here.0).hypot(q.1 - here.1) >= self.min_motion_mm {
                return Some(direction(q, here));
            }
        }
        None
    }

    /// The footprints of a whole track, stroke by stroke (a lift between strokes): each stroke's
    /// stamps form one stroke of the result.
    pub fn sweep_track(&self, profile: &BrushProfile, track: &Track, extrapolation: Extrapolation) -> Track {
        Track {
            strokes: track
                .strokes
                .iter()
                .map(|s| Stroke { points: self.sweep(profile, &s.points, extrapolation).stamps })
                .collect(),
        }
    }

    /// Track points with each `β` set to the direction the model gives their footprint (the
    /// lean direction where tilted). A state that leaves no footprint (`h ≤ 0`) takes the
    /// direction of the next one that does (so a tilted brush turns its wrist while it is off
    /// the paper), or of the previous one at the end.
    pub fn with_directions(
        &self,
        profile: &BrushProfile,
        states: &[TrackPoint],
        extrapolation: Extrapolation,
    ) -> Vec<TrackPoint> {
        let dirs = self.sweep(profile, states, extrapolation).directions;
        let mut out = states.to_vec();
        let mut next: Option<f64> = None;
        for i in (0..out.len()).rev() {
            match dirs[i] {
                Some(d) => {
                    out[i].beta_rad = d;
                    next = Some(d);
                }
                None => {
                    if let Some(d) = next {
                        out[i].beta_rad = d;
                    }
                }
            }
        }
        // After the last footprint: its direction.
        if let Some(last) = dirs.iter().rposition(Option::is_some) {
            let d = out[last].beta_rad;
            out[last + 1..].iter_mut().for_each(|p| p.beta_rad = d);
        }
        out
    }
}

/// Whether the hairs follow the motion of a state: in contact and pressed at least
/// `contact_h_mm`.
fn follows(hairs: &HairMotion, p: &TrackPoint) -> bool {
    p.is_pressed() && p.h_mm >= hairs.contact_h_mm
}

/// `p` with a depth within [`DEPTH_EDGE_TOLERANCE_MM`] outside the calibrated range set to the
/// range's end (when `extrapolation` refuses presses outside it).
fn at_range_edge(profile: &BrushProfile, p: TrackPoint, extrapolation: Extrapolation) -> TrackPoint {
    let r = profile.ranges.h_mm;
    if extrapolation == Extrapolation::Allow || r.contains(p.h_mm) {
        return p;
    }
    let h_mm = if p.h_mm < r.min && p.h_mm >= r.min - DEPTH_EDGE_TOLERANCE_MM {
        r.min
    } else if p.h_mm > r.max && p.h_mm <= r.max + DEPTH_EDGE_TOLERANCE_MM {
        r.max
    } else {
        p.h_mm
    };
    TrackPoint { h_mm, ..p }
}

/// The footprint length `lh + lt` of a press, mm.
fn footprint_length(profile: &BrushProfile, p: &TrackPoint, ex: Extrapolation) -> Result<f64, ProfileError> {
    profile.predict_oriented(&Press::new(p.h_mm, p.alpha_rad, 0.0), ex).map(|f| f.length_mm())
}

fn direction(from: (f64, f64), to: (f64, f64)) -> f64 {
    (to.1 - from.1).atan2(to.0 - from.0)
}

/// The tool axis (holder → tip) of a state in the paper frame, z into the paper.
fn axis(p: &TrackPoint) -> [f64; 3] {
    let (s, c) = p.alpha_rad.sin_cos();
    [s * p.beta_rad.cos(), s * p.beta_rad.sin(), c]
}

fn angle_between(a: [f64; 3], b: [f64; 3]) -> f64 {
    let dot = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]).clamp(-1.0, 1.0);
    let cross = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    (cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]).sqrt().atan2(dot)
}

/// Great-circle interpolation between unit vectors `a` and `b` (`turn` apart) at fraction `f`.
fn slerp(a: [f64; 3], b: [f64; 3], turn: f64, f: f64) -> [f64; 3] {
    if turn < 1e-9 {
        return a;
    }
    let (wa, wb) = (((1.0 - f) * turn).sin() / turn.sin(), (f * turn).sin() / turn.sin());
    if !(wa.is_finite() && wb.is_finite()) {
        // Opposite axes: no unique great circle (never the case for tilts below 90°).
        return if f < 0.5 { a } else { b };
    }
    [wa * a[0] + wb * b[0], wa * a[1] + wb * b[1], wa * a[2] + wb * b[2]]
}

/// `(α, β)` of a tool axis; for an axis along the normal β is interpolated between the ends'.
fn from_axis(v: [f64; 3], beta_a: f64, beta_b: f64, f: f64) -> (f64, f64) {
    let horiz = v[0].hypot(v[1]);
    let alpha = horiz.atan2(v[2]);
    let beta = if horiz > 1e-12 { v[1].atan2(v[0]) } else { beta_a + f * wrap_angle_rad(beta_b - beta_a) };
    (alpha, beta)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::units::wrap_angle_rad as wrap;

    fn pt(x: f64, y: f64, h: f64) -> TrackPoint {
        TrackPoint { x_mm: x, y_mm: y, h_mm: h, alpha_rad: 0.0, beta_rad: 0.0 }
    }

    fn pen1() -> BrushProfile {
        BrushProfile::builtin("pen1").unwrap()
    }

    #[test]
    fn an_upright_brush_trails_its_motion() {
        let m = ForwardModel::default();
        let path = [pt(0.0, 0.0, 15.0), pt(30.0, 0.0, 15.0)];
        let s = m.sweep(&pen1(), &path, Extrapolation::Refuse);
        // Moving along +x, the tip points back along −x (β = ±π) everywhere, touch-down included.
        for st in &s.stamps {
            assert!((wrap(st.beta_rad - std::f64::consts::PI)).abs() < 1e-9, "{}", st.beta_rad);
        }
        assert!(s.stamps.len() >= 300, "sampled every 0.1 mm: {}", s.stamps.len());
    }

    #[test]
    fn a_reverse_entry_points_the_tip_ahead_until_the_brush_passes_it() {
        let m = ForwardModel::default();
        // Touch down at x = 10, press back to 0, then forward to 40.
        let path = [pt(10.0, 0.0, 12.0), pt(0.0, 0.0, 12.0), pt(40.0, 0.0, 12.0)];
        let s = m.sweep(&pen1(), &path, Extrapolation::Refuse);
        let dirs = s.directions;
        // Backward move: tip ahead (+x, β = 0).
        assert!(wrap(dirs[0].unwrap()).abs() < 1e-9);
        assert!(wrap(dirs[1].unwrap()).abs() < 1e-9);
        // Far along the forward move: trailing (β = π).
        assert!((wrap(dirs[2].unwrap()) - std::f64::consts::PI).abs() < 1e-9);
        // Just after the reversal the tip is still ahead (it lies on the backward path).
        let reach = TRAIL_REACH * 1.25 * 12.0;
        let early = s.stamps.iter().find(|p| p.x_mm > 0.5 && p.x_mm < 1.0 && wrap(p.beta_rad).abs() < 1e-9);
        assert!(early.is_some());
        // Once past the reach the tip trails.
        assert!(
            s.stamps
                .iter()
                .rev()
                .take_while(|p| p.x_mm > reach + 0.2)
                .all(|p| (wrap(p.beta_rad).abs() - std::f64::consts::PI).abs() < 1e-9)
        );
    }

    #[test]
    fn a_tilted_brush_points_where_it_leans_and_turns_continuously() {
        let m = ForwardModel::default();
        let a = 5f64.to_radians();
        let p0 = TrackPoint { x_mm: 0.0, y_mm: 0.0, h_mm: 15.0, alpha_rad: a, beta_rad: 0.0 };
        let p1 = TrackPoint { x_mm: 0.15, y_mm: 0.0, h_mm: 15.0, alpha_rad: a, beta_rad: FRAC_PI_2 };
        let s = m.sweep(&pen1(), &[p0, p1], Extrapolation::Refuse);
        assert_eq!(s.directions, vec![Some(0.0), Some(FRAC_PI_2)]);
        // A quarter turn of the lean direction at 5° tilt is a 7° turn of the tool axis: at most
        // 0.5° per sample, so the wrist turn leaves ≥ 14 footprints in between, in order.
        assert!(s.stamps.len() >= 15, "{}", s.stamps.len());
        assert!(s.stamps.windows(2).all(|w| w[1].beta_rad >= w[0].beta_rad - 1e-12));
    }

    #[test]
    fn lifting_forgets_the_drag_and_leaves_nothing() {
        let m = ForwardModel::default();
        let path = [
            pt(0.0, 0.0, 12.0),
            pt(10.0, 0.0, 12.0),
            pt(10.0, 0.0, 0.0),
            pt(0.0, 0.0, 0.0),
            pt(0.0, 0.0, 12.0),
            pt(0.0, 10.0, 12.0),
        ];
        let s = m.sweep(&pen1(), &path, Extrapolation::Refuse);
        assert!(s.stamps.iter().all(|p| p.h_mm > 0.0));
        assert_eq!(s.directions[3], None);
        // Pressed again at the origin and moving down the page: trails upwards (β = −π/2),
        // from the touch-down on.
        assert!((s.directions[4].unwrap() + FRAC_PI_2).abs() < 1e-9);
        let dirs = m.with_directions(&pen1(), &path, Extrapolation::Refuse);
        assert!((dirs[3].beta_rad + FRAC_PI_2).abs() < 1e-9, "off-paper states take the next direction");
    }

    #[test]
    fn a_press_without_motion_keeps_its_direction() {
        let m = ForwardModel::default();
        let path = [pt(0.0, 0.0, 12.0), pt(0.0, 5.0, 12.0), pt(0.0, 5.0, 18.0)];
        let s = m.sweep(&pen1(), &path, Extrapolation::Refuse);
        assert!((s.directions[2].unwrap() + FRAC_PI_2).abs() < 1e-9);
    }

    /// pen1 whose hairs follow motion from `contact_h_mm`.
    fn pen1_contact(contact_h_mm: f64) -> BrushProfile {
        BrushProfile { hairs: HairMotion { contact_h_mm, ..HairMotion::NOMINAL }, ..pen1() }
    }

    /// A reverse entry pressed back from x = 10 to 0, eased up to `glide_h` at the start,
    /// glided forward to x = 12 and pressed again along +x to 40: the directions of the
    /// footprints from the press again on.
    fn after_a_glide(profile: &BrushProfile, glide_h: f64) -> Vec<(f64, f64)> {
        let path = [
            pt(10.0, 0.0, 12.0),
            pt(0.0, 0.0, 12.0),
            pt(0.0, 0.0, glide_h),
            pt(12.0, 0.0, glide_h),
            pt(12.0, 0.0, 12.0),
            pt(40.0, 0.0, 12.0),
        ];
        let s = ForwardModel::default().sweep(profile, &path, Extrapolation::Refuse);
        s.stamps.iter().filter(|p| p.x_mm >= 12.0).map(|p| (p.x_mm, wrap(p.beta_rad))).collect()
    }

    /// The assumption the profile carries: a glide at 0.01 mm turns the hairs over only when
    /// they follow any touch (`contact_h_mm = 0`, the rule before); hairs that need 1 mm keep the
    /// entry's forward bend through such a glide, and point forward (β = 0) until pressed motion
    /// has pulled them round; a glide pressed past the contact depth turns them.
    #[test]
    fn hairs_turn_only_from_the_contact_depth() {
        let trailing = |d: &[(f64, f64)]| d.iter().all(|&(_, b)| (b.abs() - std::f64::consts::PI).abs() < 1e-9);
        assert!(trailing(&after_a_glide(&pen1_contact(0.0), 0.01)));
        assert!(trailing(&after_a_glide(&pen1_contact(1.0), 2.0)));
        let stiff = after_a_glide(&pen1_contact(1.0), 0.01);
        // Pressed again at x = 12, the tip still lies ahead: the old bend, carried along.
        assert!(stiff[0].1.abs() < 1e-9, "{:?}", &stiff[..3]);
        let reach = TRAIL_REACH * 1.25 * 12.0;
        let forward: Vec<f64> = stiff.iter().filter(|d| d.1.abs() < 1e-9).map(|d| d.0).collect();
        let until = forward.iter().copied().fold(0.0, f64::max);
        // (until the carried entry, x 12–22, is nearer ahead than the new pressed path behind)
        assert!(until > 16.0 && until < 12.0 + reach + 0.2, "forward until x = {until}");
        assert!(trailing(&stiff.iter().copied().filter(|d| d.0 > 12.0 + reach + 0.2).collect::<Vec<_>>()));
        // A press straight from such a glide on a fresh stroke takes the motion that follows.
        let path = [pt(0.0, 0.0, 0.01), pt(0.0, 5.0, 0.01), pt(0.0, 5.0, 12.0), pt(0.0, 15.0, 12.0)];
        let s = ForwardModel::default().sweep(&pen1_contact(1.0), &path, Extrapolation::Refuse);
        assert!((s.directions[2].unwrap() + FRAC_PI_2).abs() < 1e-9, "{:?}", s.directions);
    }

    /// With every touch following (contact 0) the rule is the one before the contact depth: a
    /// glide at 0.01 mm extends the pressed path.
    #[test]
    fn a_contact_depth_of_zero_is_the_old_rule() {
        let path =
            [pt(10.0, 0.0, 12.0), pt(0.0, 0.0, 12.0), pt(0.0, 0.0, 0.01), pt(0.0, 8.0, 0.01), pt(0.0, 8.0, 12.0)];
        let m = ForwardModel::default();
        let zero = m.sweep(&pen1_contact(0.0), &path, Extrapolation::Refuse);
        // Pressed at (0, 8) after gliding down the page: the tip points back up the glide.
        assert!((zero.directions[4].unwrap() + FRAC_PI_2).abs() < 1e-9, "{:?}", zero.directions);
        let one = m.sweep(&pen1_contact(1.0), &path, Extrapolation::Refuse);
        // Hairs needing 1 mm kept the entry's bend (tip ahead along +x, β = 0).
        assert!(one.directions[4].unwrap().abs() < 1e-9, "{:?}", one.directions);
    }

    /// A stroke pressed at pen1's shallowest calibrated depth, read back as an arm executes it
    /// (a few hundredths of a micrometre either side of 11 mm), leaves every footprint of the
    /// stroke at 11 mm; 2 µm shallower is lighter than the range and leaves none, and with
    /// extrapolation allowed the depths are used as they are.
    #[test]
    fn a_press_read_back_just_outside_the_range_leaves_the_footprint_of_its_end() {
        let m = ForwardModel::default();
        let pen1 = pen1();
        let (min, max) = (pen1.ranges.h_mm.min, pen1.ranges.h_mm.max);
        let exact: Vec<TrackPoint> = (0..=100).map(|i| pt(f64::from(i) * 0.1, 0.0, min)).collect();
        let wobble = |d: f64| -> Vec<TrackPoint> {
            exact.iter().enumerate().map(|(i, p)| TrackPoint { h_mm: p.h_mm - d * (i % 3) as f64, ..*p }).collect()
        };
        let want = m.sweep(&pen1, &exact, Extrapolation::Refuse);
        assert!(want.stamps.len() >= 100);
        for d in [1e-10, 3e-6, 2e-5, 0.5 * DEPTH_EDGE_TOLERANCE_MM] {
            let got = m.sweep(&pen1, &wobble(d), Extrapolation::Refuse);
            assert_eq!(got.stamps.len(), want.stamps.len(), "{d} mm shallower than the range");
            for (g, w) in got.stamps.iter().zip(&want.stamps) {
                assert_eq!((g.x_mm, g.y_mm, g.beta_rad), (w.x_mm, w.y_mm, w.beta_rad));
                assert!((g.h_mm - min).abs() < 1e-9, "{d}: {}", g.h_mm);
            }
        }
        let light = m.sweep(&pen1, &wobble(2.0 * DEPTH_EDGE_TOLERANCE_MM), Extrapolation::Refuse);
        assert!(light.stamps.len() < want.stamps.len() / 2, "{}", light.stamps.len());
        assert!(light.stamps.iter().all(|p| p.h_mm == min));
        // The deep end likewise.
        let deep: Vec<TrackPoint> = exact.iter().map(|p| TrackPoint { h_mm: max + 1e-5, ..*p }).collect();
        let got = m.sweep(&pen1, &deep, Extrapolation::Refuse);
        assert_eq!(got.stamps.len(), want.stamps.len());
        assert!(got.stamps.iter().all(|p| p.h_mm == max));
        // Extrapolation allowed: depths as given.
        let got = m.sweep(&pen1, &wobble(3e-6), Extrapolation::Allow);
        assert!(got.stamps.iter().any(|p| p.h_mm < min));
    }

    /// The drag direction as the plain walk finds it (`hypot` at every point, walking back):
    /// what [`ForwardModel::dragged`]'s shortcuts must reproduce bit for bit.
    fn dragged_by_the_full_walk(m: &ForwardModel, history: &[(f64, f64)], here: (f64, f64), reach: f64) -> Option<f64> {
        let mut far = (0.0f64, None);
        for &q in history.iter().rev() {
            let d = (q.0 - here.0).hypot(q.1 - here.1);
            if d >= reach {
                return Some(direction(here, q));
            }
            if d > far.0 {
                far = (d, Some(q));
            }
        }
        match far {
            (d, Some(q)) if d >= m.min_motion_mm => Some(direction(here, q)),
            _ => None,
        }
    }

    proptest::proptest! {
        /// Short histories (the farthest point decides), long ones (the reach decides), points
        /// repeated (ties: the latest wins) and points on a circle round `here` (equal distances
        /// up to rounding).
        #[test]
        fn the_drag_direction_is_the_full_walks_bit_for_bit(
            steps in proptest::collection::vec((-1.0f64..1.0, -1.0f64..1.0, 0u8..4), 1..200),
            scale in proptest::prop_oneof![proptest::strategy::Just(1e-3), proptest::strategy::Just(0.05), proptest::strategy::Just(0.4)],
            reach in 0.2f64..6.0,
            here in (-3.0f64..3.0, -3.0f64..3.0),
        ) {
            let m = ForwardModel::default();
            let mut history = Vec::new();
            let mut at = (0.0f64, 0.0f64);
            for (i, &(dx, dy, kind)) in steps.iter().enumerate() {
                match kind {
                    // The same point again.
                    0 => {}
                    // On a circle of radius `reach / 2` round `here`.
                    1 => {
                        let a = i as f64 * 0.7;
                        at = (here.0 + 0.5 * reach * a.cos(), here.1 + 0.5 * reach * a.sin());
                    }
                    _ => at = (at.0 + dx * scale, at.1 + dy * scale),
                }
                history.push(at);
            }
            let got = m.dragged(&history, (0.0, 0.0), here, reach).map(f64::to_bits);
            let want = dragged_by_the_full_walk(&m, &history, here, reach).map(f64::to_bits);
            proptest::prop_assert_eq!(got, want);
        }
    }
}
