//! The refinement problem: which values of a track are free, the loss over them and its
//! gradient.
//!
//! **Variables.** Points of a stroke that sit at one place in the input (a pressed point and the
//! glide or ease state at the same spot) share one position variable `(x, y)` in mm, so they
//! stay together and the structure the robot check relies on is kept. Each *pressed* point
//! (`h` at least the profile's lightest calibrated press, so it leaves a footprint) has its
//! own depth `h` (mm). Where a pressed point is tilted (`α` at least the forward model's tilt
//! threshold), its position group has one tilt variable `α` (rad), shared by the group.
//! Everything else is fixed: the number and order of strokes and points, the pen lifts, and
//! the depth of every unpressed state (the reverse entry's zero presses, the turn-over glide at
//! `trajectory::GLIDE_H_MM`, the eases between pieces stay unpressed).
//!
//! **Directions are not variables.** Which way a footprint points follows from the motion
//! (docs/brush-model.md): [`Problem::directions`] re-derives it with the forward model the way
//! `trajectory::build_track` does (upright directions, `ForwardModel::with_directions` with the
//! tilt threshold at infinity; a tilted brush leans the way those point); [`crate::refine`]
//! re-derives them every few steps and after the last. Inside a step each dragged footprint
//! keeps the path sample the drag rule aimed it at ([`Directions::aim`]) and its direction
//! follows its own point and that sample, which is how the gradient is taken
//! ([`RefineOptions::aim_coupling`]); a stroke's first footprints, before the brush has moved the
//! rule's reach since touch-down, keep the farthest sample they aim at the same way
//! ([`RefineOptions::aim_far`]); where another rule set the direction, or with the coupling
//! off, the angle itself is held fixed. Holding every angle fixed was tried first: moving a root
//! sideways at a fixed angle moves the whole footprint, while the model swings it about its tip,
//! so each re-derivation undid what the steps had gained (docs/trajectory.md, "Refinement");
//! holding the first footprints' angles did the same on a smaller scale.
//!
//! **Loss** (all terms dimensionless or mm², summed):
//! * image: `Σ_p (U_p − G_p)² / Σ_p G_p`, with `U_p = 1 − Π_i (1 − c_i(p))` the soft union of
//!   every pressed point's soft footprint ([`crate::soft`]) at pixel centre `p` and `G` the
//!   glyph raster (ink = 1);
//! * smoothness: `w_s / n · (Σ |Δ²(q − q₀)|² + Σ (Δ²(h − h₀))²)`, the first sum over each
//!   stroke's position groups, the second over runs of consecutive pressed points, `n` the
//!   number of position groups: second differences of the *change* from the input track (so
//!   the planned reversals and corners are not smoothed away, only kinks the refinement would
//!   add);
//! * spacing: `w_sp / n · Σ (|q_{j+1} − q_j| − d₀_j)²` over consecutive groups, keeping the
//!   point spacing of the input;
//! * barrier: `w_b · Σ (max(0, lo − v)² + max(0, v − hi)²) / m²` for every depth and tilt `v`
//!   with range `[lo, hi]` (`m` = 2 % of the range). It is zero inside the range: the track
//!   builder puts many depths exactly on a bound (widths the brush cannot make), and a barrier
//!   reaching inside pushed them off it and cost image loss. The optimiser projects every
//!   iterate into the ranges, so the barrier only shapes the loss outside them.

use brush_model::{BrushProfile, Extrapolation, ForwardModel, Stroke, Track, TrackPoint};
use rayon::prelude::*;

use crate::soft::{Shape, edge};
use crate::{RefineError, RefineOptions, Target};

/// The values of the loss terms at one iterate.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LossTerms {
    /// The sum of the terms below.
    pub total: f64,
    /// Image term (squared error of the soft union against the glyph over the glyph's ink).
    pub image: f64,
    /// Smoothness term (weighted).
    pub smooth: f64,
    /// Spacing term (weighted).
    pub spacing: f64,
    /// Range barriers (weighted).
    pub barrier: f64,
}

/// Footprints per parallel chunk of the image sum (a fixed size, so that the order of the
/// floating-point sums, and hence the result, does not depend on the thread count).
pub(crate) const CHUNK: usize = 256;

/// Bins of a footprint's half-width bounds ([`crate::soft::WidthBounds`]): pixels they class as
/// fully inside or outside skip the Newton solve.
const WIDTH_BINS: usize = 32;

/// A point of the flattened track.
#[derive(Clone, Copy, Debug)]
struct Slot {
    /// Position group.
    group: usize,
    /// Depth variable (pressed points).
    h_var: Option<usize>,
}

/// One footprint prepared for the image sums.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Fp {
    pub(crate) x: f64,
    pub(crate) y: f64,
    /// Depth, mm; tilt, rad; direction (root → tip), rad (read by the generator path).
    #[cfg_attr(not(feature = "generator"), allow(dead_code))]
    pub(crate) h: f64,
    #[cfg_attr(not(feature = "generator"), allow(dead_code))]
    pub(crate) alpha: f64,
    #[cfg_attr(not(feature = "generator"), allow(dead_code))]
    pub(crate) beta: f64,
    cb: f64,
    sb: f64,
    shape: Shape,
    /// `∂(lt, lh, lr)/∂h`.
    dh: [f64; 3],
    /// `∂(lt, lh, lr)/∂α`.
    da: [f64; 3],
    /// Pixel bounds, inclusive: columns `i0..=i1`, rows `j0..=j1` (empty when `i0 > i1`).
    pub(crate) i0: i64,
    pub(crate) i1: i64,
    pub(crate) j0: i64,
    pub(crate) j1: i64,
}

/// A pixel in a footprint's soft edge, kept from the union pass for the gradient pass.
#[derive(Clone, Copy, Debug)]
struct EdgePx {
    /// Pixel index, row-major.
    k: u32,
    /// `1 − c`.
    one_minus_c: f64,
    /// `∂c/∂d`, per mm.
    dc: f64,
    /// `∂d/∂(x, y, h, α, β)` of the footprint at this pixel.
    a: [f64; 5],
}

/// Directions of the pressed points (rad), in the order of the problem's pressed points, plus
/// the full re-derived track the directions came from.
#[derive(Clone, Debug)]
pub struct Directions {
    /// Footprint direction (root → tip) of each pressed point, rad.
    pub beta_rad: Vec<f64>,
    /// Where each pressed point's footprint aims, when the forward model's drag rule set it
    /// (the path sample its tip points at): the position groups of the segment holding the
    /// sample and its fraction along that segment. With [`RefineOptions::aim_coupling`] the
    /// direction follows the point and its aim inside a step; `None` keeps the angle.
    pub aim: Vec<Option<(usize, usize, f64)>>,
    /// With [`RefineOptions::aim_reach`], how each aim slides along the path when the footprint's
    /// length (so the drag rule's reach) changes: the aim moves by `(reach − r₀)·(kx, ky)` mm,
    /// `[kx, ky, r₀]` (`k` the backward tangent over its cosine with the aim's direction, `r₀`
    /// the reach when the directions were derived); zero where the aim does not depend on it.
    pub slide: Vec<[f64; 3]>,
    /// The track at the iterate, every β as the forward model derives it.
    pub track: Track,
}

/// A track prepared for refinement against a target raster (see the module doc).
pub struct Problem<'a> {
    profile: &'a BrushProfile,
    target: &'a Target,
    opts: RefineOptions,
    /// The input points, stroke by stroke.
    strokes: Vec<Vec<TrackPoint>>,
    /// Per stroke, per point.
    slots: Vec<Vec<Slot>>,
    /// Initial group positions.
    q0: Vec<[f64; 2]>,
    /// Per stroke, the range of its groups.
    stroke_groups: Vec<std::ops::Range<usize>>,
    /// Group → α variable.
    group_alpha: Vec<Option<usize>>,
    /// Pressed points as (stroke, index), in variable order of their depths.
    pressed: Vec<(usize, usize)>,
    /// Initial depths of the pressed points.
    h0: Vec<f64>,
    /// Initial tilt of each α variable.
    a0: Vec<f64>,
    /// Allowed tilt range of the α variables.
    alpha_range: (f64, f64),
    /// Σ of the target's ink.
    ink_sum: f64,
    /// Edge half-width, mm.
    edge_mm: f64,
    /// The generator the image term uses ([`crate::Gradients::Generator`]).
    #[cfg(feature = "generator")]
    generator: Option<std::sync::Arc<crate::generator::GenModel>>,
}

impl<'a> Problem<'a> {
    /// Prepares `track` for refinement.
    ///
    /// # Errors
    /// [`RefineError::EmptyTrack`] without points; [`RefineError::Target`] for a blank target;
    /// [`RefineError::Profile`] when the profile cannot size a pressed point.
    pub fn new(
        track: &Track,
        profile: &'a BrushProfile,
        target: &'a Target,
        opts: &RefineOptions,
    ) -> Result<Self, RefineError> {
        opts.validate()?;
        if track.point_count() == 0 {
            return Err(RefineError::EmptyTrack);
        }
        let ink_sum: f64 = target.ink.iter().map(|&v| v as f64).sum();
        if !(ink_sum > 0.0) {
            return Err(RefineError::Target("the target raster has no ink (expected some pixels above 0)".into()));
        }
        let model = ForwardModel::default();
        let hmin = profile.ranges.h_mm.min;
        let mut strokes = Vec::new();
        let mut slots = Vec::new();
        let mut q0 = Vec::new();
        let mut stroke_groups = Vec::new();
        let mut group_alpha: Vec<Option<usize>> = Vec::new();
        let mut pressed = Vec::new();
        let mut h0 = Vec::new();
        let mut a0 = Vec::new();
        for (si, s) in track.strokes.iter().enumerate() {
            let g_start = q0.len();
            let mut st = Vec::with_capacity(s.points.len());
            for (pi, p) in s.points.iter().enumerate() {
                let same = pi > 0 && {
                    let a = s.points[pi - 1];
                    a.x_mm == p.x_mm && a.y_mm == p.y_mm
                };
                if !same {
                    q0.push([p.x_mm, p.y_mm]);
                    group_alpha.push(None);
                }
                let group = q0.len() - 1;
                let h_var = if p.h_mm >= hmin {
                    profile.predict_oriented(&p.press(), Extrapolation::Allow)?;
                    pressed.push((si, pi));
                    h0.push(p.h_mm);
                    if model.is_tilted(p) && group_alpha[group].is_none() {
                        group_alpha[group] = Some(a0.len());
                        a0.push(p.alpha_rad);
                    }
                    Some(h0.len() - 1)
                } else {
                    None
                };
                st.push(Slot { group, h_var });
            }
            stroke_groups.push(g_start..q0.len());
            strokes.push(s.points.clone());
            slots.push(st);
        }
        let ar = profile.ranges.alpha_rad;
        let alpha_range = (ar.min.max(model.tilt_threshold_rad), ar.max);
        let edge_mm = opts.edge_px * target.mm_per_px;
        Ok(Self {
            profile,
            target,
            opts: *opts,
            strokes,
            slots,
            q0,
            stroke_groups,
            group_alpha,
            pressed,
            h0,
            a0,
            alpha_range,
            ink_sum,
            edge_mm,
            #[cfg(feature = "generator")]
            generator: None,
        })
        .and_then(|p| p.choose_generator())
    }

    /// Refuses the generator path here: it needs a generator, given through
    /// [`crate::refine_with_generator`] (the crate carries no weights of its own).
    fn choose_generator(self) -> Result<Self, RefineError> {
        match self.opts.gradients {
            crate::Gradients::Analytic => Ok(self),
            #[cfg(feature = "generator")]
            crate::Gradients::Generator => Err(RefineError::BadOption {
                name: "gradients",
                value: "generator".into(),
                expected: "`analytic` for `refine`; the generator path takes its generator through `refine_with_generator`",
            }),
            #[cfg(not(feature = "generator"))]
            crate::Gradients::Generator => Err(RefineError::BadOption {
                name: "gradients",
                value: "generator".into(),
                expected: "`analytic` (track-refine was built without its `generator` feature)",
            }),
        }
    }

    /// The same problem with the image term on `generator` (the generator path): footprint
    /// images from the network, gradients from its VJP and the images' spatial gradients.
    ///
    /// # Errors
    /// [`RefineError::Generator`] when the generator was trained for another brush profile.
    #[cfg(feature = "generator")]
    pub fn with_generator(
        mut self,
        generator: std::sync::Arc<crate::generator::GenModel>,
    ) -> Result<Self, RefineError> {
        if generator.profile_name() != self.profile.name {
            return Err(RefineError::Generator(format!(
                "the generator was trained for brush profile `{}`, the track uses `{}`",
                generator.profile_name(),
                self.profile.name
            )));
        }
        self.generator = Some(generator);
        self.opts.gradients = crate::Gradients::Generator;
        Ok(self)
    }

    /// Number of variables: 2 per position group, 1 per pressed point, 1 per tilt group.
    pub fn len(&self) -> usize {
        2 * self.q0.len() + self.h0.len() + self.a0.len()
    }

    /// Whether there is nothing to refine (no variables).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of pressed points (footprints in the image term).
    pub fn pressed_count(&self) -> usize {
        self.pressed.len()
    }

    fn h_off(&self) -> usize {
        2 * self.q0.len()
    }

    fn a_off(&self) -> usize {
        2 * self.q0.len() + self.h0.len()
    }

    /// The input track as a variable vector.
    pub fn initial(&self) -> Vec<f64> {
        let mut v: Vec<f64> = self.q0.iter().flat_map(|q| q.iter().copied()).collect();
        v.extend_from_slice(&self.h0);
        v.extend_from_slice(&self.a0);
        v
    }

    /// Per variable, the optimiser step (mm for positions and depths, rad for tilts).
    pub(crate) fn steps(&self) -> Vec<f64> {
        let mut s = vec![self.opts.step_mm; 2 * self.q0.len()];
        s.extend(std::iter::repeat_n(self.opts.step_h_mm, self.h0.len()));
        s.extend(std::iter::repeat_n(self.opts.step_alpha_rad, self.a0.len()));
        s
    }

    /// Smooths a gradient along each stroke (a Sobolev-type preconditioner): the position
    /// part over each stroke's position groups and the depth part over each run of consecutive
    /// pressed points, with a Gaussian of `sigma_mm` along the track (in points of the input's
    /// median spacing). Every update is then a smooth displacement field, so the directions the
    /// forward model derives from the motion change smoothly between re-derivations; `sigma_mm`
    /// = 0 leaves the gradient as it is.
    pub fn smooth_gradient(&self, grad: &mut [f64], sigma_mm: f64) {
        if !(sigma_mm > 0.0) {
            return;
        }
        let mut gaps: Vec<f64> = Vec::new();
        for r in &self.stroke_groups {
            for j in r.start..r.end.saturating_sub(1) {
                gaps.push((self.q0[j + 1][0] - self.q0[j][0]).hypot(self.q0[j + 1][1] - self.q0[j][1]));
            }
        }
        if gaps.is_empty() {
            return;
        }
        gaps.sort_by(f64::total_cmp);
        let spacing = gaps[gaps.len() / 2].max(1e-6);
        let sigma = sigma_mm / spacing;
        let radius = (3.0 * sigma).ceil() as usize;
        let kernel: Vec<f64> = (0..=radius).map(|k| (-0.5 * (k as f64 / sigma).powi(2)).exp()).collect();
        let blur = |v: &mut [f64], stride: usize, ranges: &[std::ops::Range<usize>]| {
            for r in ranges {
                for c in 0..stride {
                    let src: Vec<f64> = (r.start..r.end).map(|j| v[stride * j + c]).collect();
                    let n = src.len();
                    for (i, j) in (r.start..r.end).enumerate() {
                        let (lo, hi) = (i.saturating_sub(radius), (i + radius).min(n - 1));
                        let (mut acc, mut wsum) = (0.0, 0.0);
                        for (k, s) in src.iter().enumerate().take(hi + 1).skip(lo) {
                            let w = kernel[k.abs_diff(i)];
                            acc += w * s;
                            wsum += w;
                        }
                        v[stride * j + c] = acc / wsum;
                    }
                }
            }
        };
        let (ho, ao) = (self.h_off(), self.a_off());
        blur(&mut grad[..ho], 2, &self.stroke_groups);
        // Runs of consecutive pressed points.
        let mut runs = Vec::new();
        let mut start = 0;
        for k in 1..=self.pressed.len() {
            let cont = k < self.pressed.len() && {
                let (a, b) = (self.pressed[k - 1], self.pressed[k]);
                a.0 == b.0 && a.1 + 1 == b.1
            };
            if !cont {
                runs.push(start..k);
                start = k;
            }
        }
        blur(&mut grad[ho..ao], 1, &runs);
    }

    /// Per variable, its kind: 0 position, 1 depth, 2 tilt.
    pub(crate) fn kinds(&self) -> Vec<u8> {
        let mut k = vec![0u8; 2 * self.q0.len()];
        k.extend(std::iter::repeat_n(1u8, self.h0.len()));
        k.extend(std::iter::repeat_n(2u8, self.a0.len()));
        k
    }

    /// Clamps depths and tilts into their ranges.
    pub fn project(&self, theta: &mut [f64]) {
        let r = self.profile.ranges.h_mm;
        let (ho, ao) = (self.h_off(), self.a_off());
        for h in &mut theta[ho..ao] {
            *h = h.clamp(r.min, r.max);
        }
        for a in &mut theta[ao..] {
            *a = a.clamp(self.alpha_range.0, self.alpha_range.1);
        }
    }

    /// The commanded states at an iterate, β as in the input (not yet re-derived).
    fn states(&self, theta: &[f64]) -> Vec<Vec<TrackPoint>> {
        let (ho, ao) = (self.h_off(), self.a_off());
        self.strokes
            .iter()
            .zip(&self.slots)
            .map(|(pts, slots)| {
                pts.iter()
                    .zip(slots)
                    .map(|(p, s)| {
                        let mut q = *p;
                        q.x_mm = theta[2 * s.group];
                        q.y_mm = theta[2 * s.group + 1];
                        if let Some(h) = s.h_var {
                            q.h_mm = theta[ho + h];
                        }
                        if let Some(a) = self.group_alpha[s.group] {
                            q.alpha_rad = theta[ao + a];
                        }
                        q
                    })
                    .collect()
            })
            .collect()
    }

    /// The track at an iterate with every direction re-derived by the forward model, as
    /// `trajectory::build_track` derives them (see the module doc), and the pressed points'
    /// directions.
    pub fn directions(&self, theta: &[f64]) -> Directions {
        let model = ForwardModel::default();
        let dragged = ForwardModel { tilt_threshold_rad: f64::INFINITY, ..model };
        let strokes: Vec<Stroke> = self
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
        let beta_rad: Vec<f64> = self.pressed.iter().map(|&(s, i)| strokes[s].points[i].beta_rad).collect();
        let (aim, slide) = if self.opts.aim_coupling {
            self.pressed
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
    /// at least `trail_reach` footprint lengths away), found by sampling the path as the model
    /// does; `None` where another rule set the direction or the found sample disagrees with
    /// `beta` (then the angle is kept fixed).
    fn find_aim(&self, pts: &[TrackPoint], s: usize, i: usize, beta: f64) -> Option<((usize, usize, f64), [f64; 3])> {
        let model = ForwardModel::default();
        let p = pts[i];
        let len = self.profile.predict_oriented(&p.press(), Extrapolation::Allow).ok()?.length_mm();
        let reach = model.trail_reach * len;
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
                if !(h > 0.0) {
                    break 'walk;
                }
                let (x, y) = (a.x_mm + f * (b.x_mm - a.x_mm), a.y_mm + f * (b.y_mm - a.y_mm));
                let d = (x - p.x_mm).hypot(y - p.y_mm);
                if self.opts.aim_far && far.is_none_or(|(fd, ..)| d > fd) {
                    far = Some((d, [x, y], self.slots[s][k].group, self.slots[s][k + 1].group, f));
                }
                if d >= reach {
                    let dir = (y - p.y_mm).atan2(x - p.x_mm);
                    if brush_model::motion::wrap(dir - beta).abs() > 1e-9 {
                        return None;
                    }
                    let aim = (self.slots[s][k].group, self.slots[s][k + 1].group, f);
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
        if d < model.min_motion_mm || brush_model::motion::wrap(dir - beta).abs() > 1e-9 {
            return None;
        }
        Some(((ga, gb, f), [0.0; 3]))
    }

    /// The drag rule's reach of a press, mm: `trail_reach` × footprint length (at β = 0, as
    /// the forward model takes it), from the profile's linear model.
    fn reach(&self, h: f64, alpha: f64) -> f64 {
        let m = &self.profile.model;
        ForwardModel::default().trail_reach * (m.lt_mm.eval(h, alpha, 0.0) + m.lh_mm.eval(h, alpha, 0.0))
    }

    /// `∂reach/∂(h, α)` of [`Self::reach`] (constant: the profile's model is linear in h and α).
    fn reach_grad(&self) -> [f64; 2] {
        let m = &self.profile.model;
        let c = |t: &brush_model::Terms| [t.h_mm.unwrap_or(0.0), t.alpha_rad.unwrap_or(0.0)];
        let (a, b) = (c(&m.lt_mm), c(&m.lh_mm));
        let tr = ForwardModel::default().trail_reach;
        [tr * (a[0] + b[0]), tr * (a[1] + b[1])]
    }

    /// The point (mm) a coupled footprint aims at in the iterate `theta`: its path sample
    /// (`aim`: the segment's two groups and the fraction along it), slid along the path by the
    /// change of the reach since the directions were derived (`slide`, see
    /// [`Directions::slide`]; none where it is zero) for a press of depth `h` and tilt `alpha`.
    fn aim_point(
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

    /// The footprints at an iterate with the given directions.
    fn footprints(&self, theta: &[f64], dirs: &Directions) -> Vec<Fp> {
        let (ho, ao) = (self.h_off(), self.a_off());
        let m = &self.profile.model;
        let t = self.target;
        let e = self.edge_mm;
        self.pressed
            .iter()
            .enumerate()
            .map(|(k, &(s, i))| {
                let slot = self.slots[s][i];
                let p = self.strokes[s][i];
                let x = theta[2 * slot.group];
                let y = theta[2 * slot.group + 1];
                let h = theta[ho + k];
                let alpha = self.group_alpha[slot.group].map_or(p.alpha_rad, |a| theta[ao + a]);
                let beta = match dirs.aim[k] {
                    Some(aim) => {
                        let (ax, ay) = self.aim_point(theta, aim, dirs.slide[k], h, alpha);
                        (ay - y).atan2(ax - x)
                    }
                    None => dirs.beta_rad[k],
                };
                let wrapped = (beta + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
                let bs = self.profile.ranges.beta_rad.clamp(wrapped);
                let terms = [&m.lt_mm, &m.lh_mm, &m.lr_mm];
                let [lt, lh, lr] = terms.map(|t| t.eval(h, alpha, bs).max(1e-6));
                let dh = terms.map(|t| t.h_mm.unwrap_or(0.0));
                let da = terms.map(|t| t.alpha_rad.unwrap_or(0.0));
                let (sb, cb) = beta.sin_cos();
                let shape = Shape { lt, lh, lr };
                // Local box u ∈ [−e, L + e], |v| ≤ lr + e, rotated onto the paper.
                let (ul, uh, vh) = (-e, shape.length() + e, lr + e);
                let (mut xmin, mut xmax, mut ymin, mut ymax) =
                    (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
                for (u, v) in [(ul, -vh), (ul, vh), (uh, -vh), (uh, vh)] {
                    let (px, py) = (x + u * cb - v * sb, y + u * sb + v * cb);
                    xmin = xmin.min(px);
                    xmax = xmax.max(px);
                    ymin = ymin.min(py);
                    ymax = ymax.max(py);
                }
                let col = |v: f64, up: bool| {
                    let f = (v - t.origin_mm.x_mm) / t.mm_per_px - 0.5;
                    if up { f.floor() as i64 } else { f.ceil() as i64 }
                };
                let row = |v: f64, up: bool| {
                    let f = (v - t.origin_mm.y_mm) / t.mm_per_px - 0.5;
                    if up { f.floor() as i64 } else { f.ceil() as i64 }
                };
                let (w, hgt) = (t.width as i64, t.height as i64);
                Fp {
                    x,
                    y,
                    h,
                    alpha,
                    beta,
                    cb,
                    sb,
                    shape,
                    dh,
                    da,
                    i0: col(xmin, false).max(0),
                    i1: col(xmax, true).min(w - 1),
                    j0: row(ymin, false).max(0),
                    j1: row(ymax, true).min(hgt - 1),
                }
            })
            .collect()
    }

    /// Visits every pixel of a footprint's box with its local coordinates `(u, v)` when inside
    /// the footprint's band ([`visit`]).
    #[inline]
    fn visit(&self, f: &Fp, each: impl FnMut(usize, f64, f64)) {
        visit(self.target, self.edge_mm, f, each);
    }

    /// The soft union's per-pixel state: `Σ ln(1 − c)` over unsaturated coverages and the
    /// number of saturated ones (`c = 1`).
    fn union(&self, fps: &[Fp]) -> (Vec<f64>, Vec<u32>) {
        let (s, sat, _) = self.union_edges(fps, false);
        (s, sat)
    }

    /// As [`Self::union`], and when `want_edges`, per footprint the pixels of its soft edge
    /// (`0 < c < 1`) with what the gradient pass needs ([`EdgePx`]), in visiting order, so
    /// that pass neither scans the footprint's box again nor solves for `t*` again.
    fn union_edges(&self, fps: &[Fp], want_edges: bool) -> (Vec<f64>, Vec<u32>, Vec<Vec<EdgePx>>) {
        let n = (self.target.width * self.target.height) as usize;
        let e = self.edge_mm;
        type Part = (Vec<f64>, Vec<u32>, Vec<Vec<EdgePx>>);
        let parts: Vec<Part> = fps
            .par_chunks(CHUNK)
            .map(|chunk| {
                let mut s = vec![0.0f64; n];
                let mut sat = vec![0u32; n];
                let mut edges = Vec::with_capacity(if want_edges { chunk.len() } else { 0 });
                for f in chunk {
                    let wb = f.shape.width_bounds(WIDTH_BINS);
                    let l = f.shape.length();
                    let mut list = Vec::new();
                    self.visit(f, |k, u, v| {
                        if u > 0.0 && u < l {
                            match wb.classify(u, v.abs(), e) {
                                Some(true) => {
                                    sat[k] += 1;
                                    return;
                                }
                                Some(false) => return,
                                None => {}
                            }
                        }
                        let c = if want_edges {
                            let m = f.shape.measure_grad_with(u, v, &wb);
                            let (c, dc) = edge(m.d, e);
                            if c > 0.0 && c < 1.0 && dc != 0.0 {
                                let [gu, gv, glt, glh, glr] = m.grad;
                                list.push(EdgePx {
                                    k: k as u32,
                                    one_minus_c: 1.0 - c,
                                    dc,
                                    a: [
                                        -f.cb * gu + f.sb * gv,
                                        -f.sb * gu - f.cb * gv,
                                        glt * f.dh[0] + glh * f.dh[1] + glr * f.dh[2],
                                        glt * f.da[0] + glh * f.da[1] + glr * f.da[2],
                                        // Turning the footprint: ∂u/∂β = v, ∂v/∂β = −u.
                                        gu * v - gv * u,
                                    ],
                                });
                            }
                            c
                        } else {
                            edge(f.shape.measure(u, v), e).0
                        };
                        if c >= 1.0 {
                            sat[k] += 1;
                        } else if c > 0.0 {
                            s[k] += (1.0 - c).ln();
                        }
                    });
                    if want_edges {
                        edges.push(list);
                    }
                }
                (s, sat, edges)
            })
            .collect();
        let mut s = vec![0.0f64; n];
        let mut sat = vec![0u32; n];
        let mut edges = Vec::with_capacity(if want_edges { fps.len() } else { 0 });
        for (ps, pt, pe) in parts {
            for k in 0..n {
                s[k] += ps[k];
                sat[k] += pt[k];
            }
            edges.extend(pe);
        }
        (s, sat, edges)
    }

    /// The soft union image `U` at an iterate (for inspection and tests).
    pub fn soft_image(&self, theta: &[f64], dirs: &Directions) -> Vec<f64> {
        #[cfg(feature = "generator")]
        if let Some(g) = &self.generator {
            return g.image_term(&self.raster(), &self.footprints(theta, dirs), false).union;
        }
        let (s, sat) = self.union(&self.footprints(theta, dirs));
        s.iter().zip(&sat).map(|(&s, &n)| if n > 0 { 1.0 } else { 1.0 - s.exp() }).collect()
    }

    /// The loss at an iterate with fixed directions.
    pub fn loss(&self, theta: &[f64], dirs: &Directions) -> LossTerms {
        self.evaluate(theta, dirs, false).0
    }

    /// The loss and its gradient with respect to the variables, at fixed directions.
    pub fn loss_grad(&self, theta: &[f64], dirs: &Directions) -> (LossTerms, Vec<f64>) {
        self.evaluate(theta, dirs, true)
    }

    #[cfg(feature = "generator")]
    fn raster(&self) -> crate::generator::Raster<'_> {
        let t = self.target;
        crate::generator::Raster {
            width: t.width as usize,
            height: t.height as usize,
            origin: [t.origin_mm.x_mm, t.origin_mm.y_mm],
            mm_per_px: t.mm_per_px,
            ink: &t.ink,
            ink_sum: self.ink_sum,
        }
    }

    fn evaluate(&self, theta: &[f64], dirs: &Directions, want_grad: bool) -> (LossTerms, Vec<f64>) {
        let mut grad = vec![0.0; if want_grad { theta.len() } else { 0 }];
        let fps = self.footprints(theta, dirs);
        let (image, per_fp) = self.image_term(&fps, want_grad);
        if want_grad {
            self.scatter(theta, dirs, &fps, &per_fp, &mut grad);
        }
        let smooth = self.smoothness(theta, &mut grad, want_grad);
        let spacing = self.spacing(theta, &mut grad, want_grad);
        let barrier = self.barrier(theta, &mut grad, want_grad);
        let total = image + smooth + spacing + barrier;
        (LossTerms { total, image, smooth, spacing, barrier }, grad)
    }

    /// The image term and, when `want_grad`, each footprint's `∂/∂(x, y, h, α, β)`: on the
    /// generator when the problem has one, else analytic.
    fn image_term(&self, fps: &[Fp], want_grad: bool) -> (f64, Vec<[f64; 5]>) {
        #[cfg(feature = "generator")]
        if let Some(g) = &self.generator {
            let t = g.image_term(&self.raster(), fps, want_grad);
            return (t.image, t.per_fp);
        }
        let (s, sat, edges) = self.union_edges(fps, want_grad);
        // Image term and ∂L/∂U.
        let mut image = 0.0;
        let mut q = vec![0.0f64; s.len()];
        for k in 0..s.len() {
            let prod = if sat[k] > 0 { 0.0 } else { s[k].exp() };
            let u = 1.0 - prod;
            let r = u - self.target.ink[k] as f64;
            image += r * r;
            // ∂L/∂U · Π(1 − c): what each unsaturated footprint's (1 − c) multiplies.
            q[k] = 2.0 * r / self.ink_sum * prod;
        }
        image /= self.ink_sum;
        let mut per_fp = Vec::new();
        if want_grad {
            per_fp = edges
                .par_iter()
                .map(|list| {
                    let mut g = [0.0f64; 5];
                    for px in list {
                        let qk = q[px.k as usize];
                        if qk == 0.0 {
                            continue;
                        }
                        // ∂U/∂c_i = Π_{j≠i}(1 − c_j) = Π/(1 − c_i), so ∂L/∂d = q/(1 − c)·∂c/∂d.
                        let w = qk / px.one_minus_c * px.dc;
                        for (gi, ai) in g.iter_mut().zip(&px.a) {
                            *gi += w * ai;
                        }
                    }
                    g
                })
                .collect();
        }
        (image, per_fp)
    }

    /// Adds the footprints' partials to the variables' gradient (through the aim coupling of
    /// each direction).
    fn scatter(&self, theta: &[f64], dirs: &Directions, fps: &[Fp], per_fp: &[[f64; 5]], grad: &mut [f64]) {
        {
            let (ho, ao) = (self.h_off(), self.a_off());
            for (k, &(si, pi)) in self.pressed.iter().enumerate() {
                let slot = self.slots[si][pi];
                let g = per_fp[k];
                grad[2 * slot.group] += g[0];
                grad[2 * slot.group + 1] += g[1];
                grad[ho + k] += g[2];
                if let Some(a) = self.group_alpha[slot.group] {
                    grad[ao + a] += g[3];
                }
                if let Some((ga, gb, fr)) = dirs.aim[k] {
                    // β = atan2(aim − p): ∂β/∂aim = (−r_y, r_x)/|r|², ∂β/∂p = −∂β/∂aim.
                    let fp = &fps[k];
                    let [kx, ky, _] = dirs.slide[k];
                    let (ax, ay) = self.aim_point(theta, (ga, gb, fr), dirs.slide[k], fp.h, fp.alpha);
                    let (rx, ry) = (ax - fp.x, ay - fp.y);
                    let r2 = rx * rx + ry * ry;
                    if r2 > 0.0 {
                        let (bx, by) = (-ry / r2 * g[4], rx / r2 * g[4]);
                        if kx != 0.0 || ky != 0.0 {
                            // The aim slides with the reach: ∂aim/∂(h, α) = k·∂reach/∂(h, α).
                            let [rh, ra] = self.reach_grad();
                            let ga_k = bx * kx + by * ky;
                            grad[self.h_off() + k] += ga_k * rh;
                            if let Some(a) = self.group_alpha[slot.group] {
                                grad[self.a_off() + a] += ga_k * ra;
                            }
                        }
                        grad[2 * slot.group] -= bx;
                        grad[2 * slot.group + 1] -= by;
                        grad[2 * ga] += (1.0 - fr) * bx;
                        grad[2 * ga + 1] += (1.0 - fr) * by;
                        grad[2 * gb] += fr * bx;
                        grad[2 * gb + 1] += fr * by;
                    }
                }
            }
        }
    }

    fn smoothness(&self, theta: &[f64], grad: &mut [f64], want_grad: bool) -> f64 {
        let w = self.opts.smooth_weight / self.q0.len().max(1) as f64;
        let mut sum = 0.0;
        // Positions: second differences of the displacement over each stroke's groups.
        for r in &self.stroke_groups {
            for j in r.start + 1..r.end.saturating_sub(1) {
                for c in 0..2 {
                    let d = |g: usize| theta[2 * g + c] - self.q0[g][c];
                    let dd = d(j - 1) - 2.0 * d(j) + d(j + 1);
                    sum += w * dd * dd;
                    if want_grad {
                        grad[2 * (j - 1) + c] += 2.0 * w * dd;
                        grad[2 * j + c] -= 4.0 * w * dd;
                        grad[2 * (j + 1) + c] += 2.0 * w * dd;
                    }
                }
            }
        }
        // Depths: over runs of consecutive pressed points of a stroke.
        let ho = self.h_off();
        for k in 1..self.pressed.len().saturating_sub(1) {
            let (a, b, c) = (self.pressed[k - 1], self.pressed[k], self.pressed[k + 1]);
            if a.0 != b.0 || b.0 != c.0 || a.1 + 1 != b.1 || b.1 + 1 != c.1 {
                continue;
            }
            let d = |i: usize| theta[ho + i] - self.h0[i];
            let dd = d(k - 1) - 2.0 * d(k) + d(k + 1);
            sum += w * dd * dd;
            if want_grad {
                grad[ho + k - 1] += 2.0 * w * dd;
                grad[ho + k] -= 4.0 * w * dd;
                grad[ho + k + 1] += 2.0 * w * dd;
            }
        }
        sum
    }

    fn spacing(&self, theta: &[f64], grad: &mut [f64], want_grad: bool) -> f64 {
        let w = self.opts.spacing_weight / self.q0.len().max(1) as f64;
        let mut sum = 0.0;
        for r in &self.stroke_groups {
            for j in r.start..r.end.saturating_sub(1) {
                let d0 = (self.q0[j + 1][0] - self.q0[j][0]).hypot(self.q0[j + 1][1] - self.q0[j][1]);
                let (dx, dy) = (theta[2 * j + 2] - theta[2 * j], theta[2 * j + 3] - theta[2 * j + 1]);
                let d = dx.hypot(dy);
                let r = d - d0;
                sum += w * r * r;
                if want_grad && d > 0.0 {
                    let (gx, gy) = (2.0 * w * r * dx / d, 2.0 * w * r * dy / d);
                    grad[2 * j + 2] += gx;
                    grad[2 * j + 3] += gy;
                    grad[2 * j] -= gx;
                    grad[2 * j + 1] -= gy;
                }
            }
        }
        sum
    }

    fn barrier(&self, theta: &[f64], grad: &mut [f64], want_grad: bool) -> f64 {
        let w = self.opts.barrier_weight;
        let mut sum = 0.0;
        let r = self.profile.ranges.h_mm;
        let mut one = |i: usize, lo: f64, hi: f64| {
            let m = 0.02 * (hi - lo).max(1e-9);
            let v = theta[i];
            let (below, above) = ((lo - v).max(0.0), (v - hi).max(0.0));
            sum += w * (below * below + above * above) / (m * m);
            if want_grad {
                grad[i] += w * 2.0 * (above - below) / (m * m);
            }
        };
        let (ho, ao) = (self.h_off(), self.a_off());
        for i in ho..ao {
            one(i, r.min, r.max);
        }
        for i in ao..theta.len() {
            one(i, self.alpha_range.0, self.alpha_range.1);
        }
        sum
    }
}

/// Visits every pixel of footprint `f`'s box on `t` whose centre lies in the footprint's band
/// (`−e ≤ u ≤ L + e`, `|v| ≤ lr + e`, `e` the edge half-width in mm), row by row, with its
/// index and local coordinates `(u, v)`. Each row scans only the columns where the band can
/// be, not the whole box.
#[inline]
fn visit(t: &Target, e: f64, f: &Fp, mut each: impl FnMut(usize, f64, f64)) {
    let (ul, uh, vh) = (-e, f.shape.length() + e, f.shape.lr + e);
    let w = t.width as usize;
    // On each row, the columns where the band can be: `ul ≤ u ≤ uh` and `|v| ≤ vh` bound
    // `px·cb` and `px·sb`; each bound gives an interval of `px` (widened by a hair, the
    // per-pixel tests below decide).
    let interval = |a: f64, lo: f64, hi: f64| -> Option<(f64, f64)> {
        if a > 1e-12 {
            Some((lo / a, hi / a))
        } else if a < -1e-12 {
            Some((hi / a, lo / a))
        } else if lo <= 0.0 && 0.0 <= hi {
            Some((f64::NEG_INFINITY, f64::INFINITY))
        } else {
            None
        }
    };
    for j in f.j0..=f.j1 {
        let py = t.origin_mm.y_mm + (j as f64 + 0.5) * t.mm_per_px - f.y;
        let (Some(a), Some(b)) =
            (interval(f.cb, ul - py * f.sb, uh - py * f.sb), interval(f.sb, py * f.cb - vh, py * f.cb + vh))
        else {
            continue;
        };
        let (lo, hi) = (a.0.max(b.0) - 1e-9, a.1.min(b.1) + 1e-9);
        if lo > hi {
            continue;
        }
        let col = |px: f64| (px + f.x - t.origin_mm.x_mm) / t.mm_per_px - 0.5;
        let c0 = col(lo).ceil().max(f.i0 as f64) as i64;
        let c1 = col(hi).floor().min(f.i1 as f64) as i64;
        for i in c0..=c1 {
            let px = t.origin_mm.x_mm + (i as f64 + 0.5) * t.mm_per_px - f.x;
            let u = px * f.cb + py * f.sb;
            if u < ul || u > uh {
                continue;
            }
            let v = -px * f.sb + py * f.cb;
            if v.abs() > vh {
                continue;
            }
            each(j as usize * w + i as usize, u, v);
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// `visit` scans only part of each row; it must reach exactly the pixels a scan of the
    /// whole box reaches, at every angle, including the axis-aligned ones.
    #[test]
    fn visiting_rows_by_interval_reaches_every_pixel_of_the_band() {
        let t = Target::new(64, 48, vec![0.0; 64 * 48], brush_model::PointMm::new(1.0, 2.0), 0.7).unwrap();
        let e = 0.5;
        let shape = Shape { lt: 13.5, lh: 5.25, lr: 3.0 };
        for k in 0..72 {
            let beta = k as f64 * std::f64::consts::TAU / 72.0 + if k % 9 == 0 { 0.0 } else { 0.013 };
            let (sb, cb) = beta.sin_cos();
            for (x, y, box_) in
                [(20.0, 18.0, (0, 63, 0, 47)), (3.0, 30.0, (0, 20, 10, 40)), (44.5, 4.1, (40, 63, 0, 12))]
            {
                let f = Fp {
                    x,
                    y,
                    h: 0.0,
                    alpha: 0.0,
                    beta,
                    cb,
                    sb,
                    shape,
                    dh: [0.0; 3],
                    da: [0.0; 3],
                    i0: box_.0,
                    i1: box_.1,
                    j0: box_.2,
                    j1: box_.3,
                };
                let mut got = Vec::new();
                visit(&t, e, &f, |k, u, v| got.push((k, u, v)));
                let mut want = Vec::new();
                let (ul, uh, vh) = (-e, shape.length() + e, shape.lr + e);
                for j in f.j0..=f.j1 {
                    let py = t.origin_mm.y_mm + (j as f64 + 0.5) * t.mm_per_px - f.y;
                    for i in f.i0..=f.i1 {
                        let px = t.origin_mm.x_mm + (i as f64 + 0.5) * t.mm_per_px - f.x;
                        let (u, v) = (px * cb + py * sb, -px * sb + py * cb);
                        if (ul..=uh).contains(&u) && v.abs() <= vh {
                            want.push((j as usize * 64 + i as usize, u, v));
                        }
                    }
                }
                assert_eq!(got, want, "β {beta} at ({x}, {y})");
            }
        }
    }
}
