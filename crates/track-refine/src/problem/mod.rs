//! The refinement problem: which values of a track are free ([`layout`]), how the footprints'
//! directions follow the motion ([`aim`]), the footprints at an iterate and the chain rule back
//! to the variables ([`footprint`]), the image term (through the seam in `crate::image`) and
//! the regularisers ([`regularise`]).

mod aim;
mod footprint;

pub(crate) use footprint::pixel_box_on;
mod layout;
mod regularise;

use std::sync::Arc;

use brush_model::{BrushProfile, Track};

pub use aim::Directions;
use layout::Layout;

use crate::image::{Analytic, ImageModel, Raster};
use crate::{Gradients, RefineError, RefineOptions, Target};

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

/// A track prepared for refinement against a target raster: which values are free, the loss
/// over them and its gradient. [`refine`](crate::refine) runs the descent on it; the methods
/// are public for inspection and tests.
///
/// **Variables.** Points of a stroke that sit at one place in the input (a pressed point and the
/// glide or ease state at the same spot) share one position variable `(x, y)` in mm, so they
/// stay together and the structure the robot check relies on is kept. Each *pressed* point
/// (`h` at least the profile's lightest calibrated press, so it leaves a footprint) has its
/// own depth `h` (mm). Where a pressed point is tilted (`α` at least the forward model's tilt
/// threshold), its position group has one tilt variable `α` (rad), shared by the group. The
/// variable vector holds every group's `x, y`, then every pressed point's `h`, then every tilt
/// variable's `α`. Everything else is fixed: the number and order of strokes and points, the pen
/// lifts, and the depth of every unpressed state (the reverse entry's zero presses, the
/// turn-over glide at `trajectory::glide_h_mm`, the eases between pieces stay unpressed).
///
/// **Directions are not variables.** Which way a footprint points follows from the motion
/// (docs/brush-model.md): [`Problem::directions`] re-derives it with the forward model the way
/// `trajectory::build_track` does (upright directions, `ForwardModel::with_directions` with the
/// tilt threshold at infinity; a tilted brush leans the way those point); [`crate::refine`]
/// re-derives them every few steps and after the last. Inside a step each dragged footprint
/// keeps the path sample the drag rule aimed it at ([`Directions::aim`]) and its direction
/// follows its own point and that sample, which is how the gradient is taken
/// ([`RefineOptions::aim_coupling`]); a stroke's first footprints, before the brush has moved the
/// rule's reach since touch-down, keep the farthest sample they aim at the same way
/// ([`RefineOptions::aim_far`]); where another rule set the direction, or with the coupling
/// off, the angle itself is held fixed.
///
/// **Loss** (all terms dimensionless or mm², summed):
/// * image: `Σ_p (U_p − G_p)² / Σ_p G_p`, with `U_p = 1 − Π_i (1 − c_i(p))` the soft union of
///   every pressed point's footprint coverage at pixel centre `p` and `G` the glyph raster
///   (ink = 1); the coverages are the soft-edged analytic teardrop's, or the generator's
///   images on the generator path;
/// * smoothness: `w_s / n · (Σ |Δ²(q − q₀)|² + Σ (Δ²(h − h₀))²)`, the first sum over each
///   stroke's position groups, the second over runs of consecutive pressed points, `n` the
///   number of position groups: second differences of the *change* from the input track (so
///   the planned reversals and corners are not smoothed away, only kinks the refinement would
///   add);
/// * spacing: `w_sp / n · Σ (|q_{j+1} − q_j| − d₀_j)²` over consecutive groups, keeping the
///   point spacing of the input;
/// * barrier: `w_b · Σ (max(0, lo − v)² + max(0, v − hi)²) / m²` for every depth and tilt `v`
///   with range `[lo, hi]` (`m` = 2 % of the range), zero inside the range. The optimiser
///   projects every iterate into the ranges, so the barrier only shapes the loss outside them.
///
/// # Examples
/// The loss and its gradient at the input track:
/// ```
/// use track_refine::brush_model::{BrushProfile, PointMm, Stroke, Track, TrackPoint};
/// use track_refine::{Problem, RefineOptions, Target};
///
/// let pen1 = BrushProfile::builtin("pen1")?;
/// let target = Target::new(40, 40, vec![1.0; 1600], PointMm::new(0.0, 0.0), 1.0)?;
/// let pt = |x_mm| TrackPoint { x_mm, y_mm: 20.0, h_mm: 12.0, alpha_rad: 0.0, beta_rad: std::f64::consts::PI };
/// let track = Track { strokes: vec![Stroke { points: (0..=10).map(|i| pt(15.0 + i as f64)).collect() }] };
/// let p = Problem::new(&track, &pen1, &target, &RefineOptions::default())?;
/// let theta = p.initial();
/// assert_eq!(theta.len(), p.len()); // 11 positions (x, y) and 11 depths: upright, no tilts
/// assert_eq!(p.len(), 33);
/// let dirs = p.directions(&theta);
/// let (loss, grad) = p.loss_grad(&theta, &dirs);
/// assert_eq!(loss.smooth, 0.0); // no change from the input yet
/// assert_eq!(grad.len(), p.len());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct Problem<'a> {
    /// The brush profile (read by an image model that must match it).
    pub(crate) profile: &'a BrushProfile,
    target: &'a Target,
    /// The options (`gradients` records the image model).
    pub(crate) opts: RefineOptions,
    /// What is free and where it sits in the variable vector.
    vars: Layout,
    /// Σ of the target's ink.
    ink_sum: f64,
    /// Edge half-width, mm.
    edge_mm: f64,
    /// Where the image term's coverages and derivatives come from ([`Analytic`] unless an
    /// image model is plugged in, e.g. by `Problem::with_generator`).
    pub(crate) image: Arc<dyn ImageModel>,
}

impl<'a> Problem<'a> {
    /// Prepares `track` for refinement with the analytic image term.
    ///
    /// # Errors
    /// [`RefineError::BadOption`] for an option out of range (among them
    /// [`Gradients::Generator`], which needs a generator: `Problem::with_generator`);
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
        let vars = Layout::new(track, profile)?;
        let edge_mm = opts.edge_px * target.mm_per_px;
        // The generator path needs a generator: it comes through `with_generator`.
        if opts.gradients == Gradients::Generator {
            return Err(RefineError::BadOption {
                name: "gradients",
                value: "generator".into(),
                expected: Gradients::REFUSED,
            });
        }
        Ok(Self { profile, target, opts: *opts, vars, ink_sum, edge_mm, image: Arc::new(Analytic { edge_mm }) })
    }

    /// Number of variables: 2 per position group, 1 per pressed point, 1 per tilt group.
    pub fn len(&self) -> usize {
        self.vars.len()
    }

    /// Whether there is nothing to refine (no variables).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of pressed points (footprints in the image term).
    pub fn pressed_count(&self) -> usize {
        self.vars.pressed.len()
    }

    /// The input track as a variable vector.
    pub fn initial(&self) -> Vec<f64> {
        self.vars.initial()
    }

    /// Per variable, the optimiser step (mm for positions and depths, rad for tilts).
    pub(crate) fn steps(&self) -> Vec<f64> {
        self.vars.steps(&self.opts)
    }

    /// Per variable, its kind: 0 position, 1 depth, 2 tilt.
    pub(crate) fn kinds(&self) -> Vec<u8> {
        self.vars.kinds()
    }

    /// Clamps depths and tilts into their ranges.
    pub fn project(&self, theta: &mut [f64]) {
        let r = self.profile.ranges.h_mm;
        let (ho, ao) = (self.vars.h_off(), self.vars.a_off());
        for h in &mut theta[ho..ao] {
            *h = h.clamp(r.min, r.max);
        }
        for a in &mut theta[ao..] {
            *a = a.clamp(self.vars.alpha_range.0, self.vars.alpha_range.1);
        }
    }

    /// The target as the image sums read it.
    fn raster(&self) -> Raster<'_> {
        let t = self.target;
        Raster {
            width: t.width as usize,
            height: t.height as usize,
            origin: [t.origin_mm.x_mm, t.origin_mm.y_mm],
            mm_per_px: t.mm_per_px,
            ink: &t.ink,
            ink_sum: self.ink_sum,
        }
    }

    /// The soft union image `U` at an iterate, row-major over the target (for inspection and
    /// tests).
    pub fn soft_image(&self, theta: &[f64], dirs: &Directions) -> Vec<f64> {
        self.image.union(&self.raster(), &self.footprints(theta, dirs)).image()
    }

    /// The loss at an iterate with fixed directions.
    pub fn loss(&self, theta: &[f64], dirs: &Directions) -> LossTerms {
        self.evaluate(theta, dirs, false).0
    }

    /// The loss and its gradient with respect to the variables, at fixed directions.
    pub fn loss_grad(&self, theta: &[f64], dirs: &Directions) -> (LossTerms, Vec<f64>) {
        self.evaluate(theta, dirs, true)
    }

    fn evaluate(&self, theta: &[f64], dirs: &Directions, want_grad: bool) -> (LossTerms, Vec<f64>) {
        let mut grad = vec![0.0; if want_grad { theta.len() } else { 0 }];
        let fps = self.footprints(theta, dirs);
        let (image, per_fp) = self.image.image_term(&self.raster(), &fps, want_grad);
        if want_grad {
            self.scatter(theta, dirs, &fps, &per_fp, &mut grad);
        }
        let smooth = self.smoothness(theta, &mut grad, want_grad);
        let spacing = self.spacing(theta, &mut grad, want_grad);
        let barrier = self.barrier(theta, &mut grad, want_grad);
        let total = image + smooth + spacing + barrier;
        (LossTerms { total, image, smooth, spacing, barrier }, grad)
    }
}
