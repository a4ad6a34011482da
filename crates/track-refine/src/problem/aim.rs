//! Aim coupling: the footprints' directions re-derived by the forward model, and inside a step
//! each dragged footprint's direction following its point and the path sample it aims at.

use brush_model::{Extrapolation, ForwardModel, Stroke, Track, TrackPoint};

use super::Problem;

/// Directions of the pressed points (rad), in the order of the problem's pressed points, plus
/// the full re-derived track the directions came from.
#[derive(Clone, Debug)]
pub struct Directions {
    /// Footprint direction (root → tip) of each pressed point, rad.
    pub beta_rad: Vec<f64>,
    /// Where each pressed point's footprint aims, when the forward model's drag rule set it
    /// (the path sample its tip points at): the position groups of the segment holding the
    /// sample and its fraction along that segment. With [`RefineOptions::aim_coupling`](crate::RefineOptions::aim_coupling) the
    /// direction follows the point and its aim inside a step; `None` keeps the angle.
    pub aim: Vec<Option<(usize, usize, f64)>>,
    /// With [`RefineOptions::aim_reach`](crate::RefineOptions::aim_reach), how each aim slides
    /// along the path when the footprint's length (so the drag rule's reach) changes: the aim moves by `(reach − r₀)·(kx, ky)` mm,
    /// `[kx, ky, r₀]` (`k` the backward tangent over its cosine with the aim's direction, `r₀`
    /// the reach when the directions were derived); zero where the aim does not depend on it.
    pub slide: Vec<[f64; 3]>,
    /// The track at the iterate, every β as the forward model derives it.
    pub track: Track,
}

impl Problem<'_> {
    /// The track at an iterate with every direction re-derived by the forward model, as
    /// `trajectory::build_track` derives them (see [`Problem`]), and the pressed points'
    /// directions.
    pub fn directions(&self, theta: &[f64]) -> Directions {
        let dragged = ForwardModel { tilt_threshold_rad: f64::INFINITY, ..ForwardModel::default() };
        let strokes: Vec<Stroke> = self
            .vars
            .states(theta)
            .into_iter()
            .map(|pts| {
                let mut points = dragged.with_directions(self.profile, &pts, Extrapolation::Refuse);
                // A brush easing up in place keeps its lean (as build_track does).
                for i in 1..points.len() {
                    let (a, b) = (points[i - 1], points[i]);
                    if b.h_mm <= 0.0 && a.h_mm > 0.0 && a.x_mm == b.x_mm && a.y_mm == b.y_mm {
                        points[i].beta_rad = a.beta_rad;
                    }
                }
                Stroke { points }
            })
            .collect();
        let beta_rad: Vec<f64> = self.vars.pressed.iter().map(|&(s, i)| strokes[s].points[i].beta_rad).collect();
        let (aim, slide) = if self.opts.aim_coupling {
            self.vars
                .pressed
                .iter()
                .zip(&beta_rad)
                .map(|(&(s, i), &b)| match self.find_aim(&strokes[s].points, s, i, b) {
                    Some((a, k)) => (Some(a), k),
                    None => (None, [0.0; 3]),
                })
                .unzip()
        } else {
            (vec![None; beta_rad.len()], vec![[0.0; 3]; beta_rad.len()])
        };
        Directions { beta_rad, aim, slide, track: Track { strokes } }
    }

    /// The path sample an upright brush's footprint at point `i` aims at under the forward
    /// model's drag rule (walking back along the pressed path since touch-down, the first sample
    /// at least the profile's `hairs.trail_reach` footprint lengths away), found by sampling
    /// the path as the model does; `None` where another rule set the direction or the found
    /// sample disagrees with `beta` (then the angle is kept fixed). The walk stops where the
    /// brush was lifted or pressed lighter than the hairs' contact depth (there the model
    /// carries the bend along; a sample found past it would not be the one the model aims at,
    /// and the check against `beta` keeps the angle instead).
    fn find_aim(&self, pts: &[TrackPoint], s: usize, i: usize, beta: f64) -> Option<((usize, usize, f64), [f64; 3])> {
        let model = ForwardModel::default();
        let hairs = self.profile.hairs;
        let p = pts[i];
        let len = self.profile.predict_oriented(&p.press(), Extrapolation::Allow).ok()?.length_mm();
        let reach = hairs.trail_reach * len;
        // The farthest sample so far (the drag rule's fallback before the brush has moved
        // `reach` since touch-down): distance, segment's groups, fraction.
        let mut far: Option<(f64, [f64; 2], usize, usize, f64)> = None;
        'walk: for k in (0..i).rev() {
            let (a, b) = (pts[k], pts[k + 1]);
            let d = (b.x_mm - a.x_mm).hypot(b.y_mm - a.y_mm);
            let turn = axis_angle(&a, &b);
            let n = (d / model.step_mm)
                .max(turn / model.step_rad)
                .max((b.h_mm - a.h_mm).abs() / model.step_h_mm)
                .ceil()
                .clamp(1.0, 1e6) as usize;
            // Samples of this segment from b's side back to a (a itself last).
            for m in (0..n).rev() {
                let f = m as f64 / n as f64;
                let h = a.h_mm + f * (b.h_mm - a.h_mm);
                if !(h > 0.0 && h >= hairs.contact_h_mm) {
                    break 'walk;
                }
                let (x, y) = (a.x_mm + f * (b.x_mm - a.x_mm), a.y_mm + f * (b.y_mm - a.y_mm));
                let d = (x - p.x_mm).hypot(y - p.y_mm);
                if self.opts.aim_far && far.is_none_or(|(fd, ..)| d > fd) {
                    far = Some((d, [x, y], self.vars.slots[s][k].group, self.vars.slots[s][k + 1].group, f));
                }
                if d >= reach {
                    let dir = (y - p.y_mm).atan2(x - p.x_mm);
                    if brush_model::wrap_angle_rad(dir - beta).abs() > 1e-9 {
                        return None;
                    }
                    let aim = (self.vars.slots[s][k].group, self.vars.slots[s][k + 1].group, f);
                    // Backward tangent of the segment, over its cosine with the aim's direction
                    // (the aim slides by dσ = d(reach)/cos along it); none where nearly square.
                    let (bx, by) = (a.x_mm - b.x_mm, a.y_mm - b.y_mm);
                    let (bl, r) = (bx.hypot(by), d.max(1e-12));
                    let cos = ((x - p.x_mm) * bx + (y - p.y_mm) * by) / (r * bl.max(1e-12));
                    if !self.opts.aim_reach || bl < 1e-9 || cos < 0.2 {
                        return Some((aim, [0.0; 3]));
                    }
                    return Some((aim, [bx / bl / cos, by / bl / cos, self.reach(p.h_mm, p.alpha_rad)]));
                }
            }
        }
        // Touch-down reached within `reach`: the rule aims at the farthest sample once that is
        // `min_motion_mm` away.
        let (d, [x, y], ga, gb, f) = far?;
        let dir = (y - p.y_mm).atan2(x - p.x_mm);
        if d < model.min_motion_mm || brush_model::wrap_angle_rad(dir - beta).abs() > 1e-9 {
            return None;
        }
        Some(((ga, gb, f), [0.0; 3]))
    }

    /// The drag rule's reach of a press, mm: the profile's `hairs.trail_reach` × footprint
    /// length (at β = 0, as the forward model takes it), from the profile's linear model.
    fn reach(&self, h: f64, alpha: f64) -> f64 {
        let m = &self.profile.model;
        self.profile.hairs.trail_reach * (m.lt_mm.eval(h, alpha, 0.0) + m.lh_mm.eval(h, alpha, 0.0))
    }

    /// `∂reach/∂(h, α)` of [`Self::reach`] (constant: the profile's model is linear in h and α).
    pub(super) fn reach_grad(&self) -> [f64; 2] {
        let m = &self.profile.model;
        let c = |t: &brush_model::Terms| [t.h_mm.unwrap_or(0.0), t.alpha_rad.unwrap_or(0.0)];
        let (a, b) = (c(&m.lt_mm), c(&m.lh_mm));
        let tr = self.profile.hairs.trail_reach;
        [tr * (a[0] + b[0]), tr * (a[1] + b[1])]
    }

    /// The point (mm) a coupled footprint aims at in the iterate `theta`: its path sample
    /// (`aim`: the segment's two groups and the fraction along it), slid along the path by the
    /// change of the reach since the directions were derived (`slide`, see
    /// [`Directions::slide`]; none where it is zero) for a press of depth `h` and tilt `alpha`.
    pub(super) fn aim_point(
        &self,
        theta: &[f64],
        (ga, gb, f): (usize, usize, f64),
        slide: [f64; 3],
        h: f64,
        alpha: f64,
    ) -> (f64, f64) {
        let [kx, ky, r0] = slide;
        let dr = if kx != 0.0 || ky != 0.0 { self.reach(h, alpha) - r0 } else { 0.0 };
        (
            (1.0 - f) * theta[2 * ga] + f * theta[2 * gb] + dr * kx,
            (1.0 - f) * theta[2 * ga + 1] + f * theta[2 * gb + 1] + dr * ky,
        )
    }
}

/// The angle between the tool axes of two states, rad (as the forward model samples turns).
fn axis_angle(a: &TrackPoint, b: &TrackPoint) -> f64 {
    let ax = |p: &TrackPoint| {
        let (s, c) = p.alpha_rad.sin_cos();
        [s * p.beta_rad.cos(), s * p.beta_rad.sin(), c]
    };
    let (u, v) = (ax(a), ax(b));
    let dot = (u[0] * v[0] + u[1] * v[1] + u[2] * v[2]).clamp(-1.0, 1.0);
    let cr = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
    (cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]).sqrt().atan2(dot)
}
