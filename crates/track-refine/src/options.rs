//! The settings of refinement.

use serde::{Deserialize, Serialize};

use crate::RefineError;

/// Settings of [`refine`](crate::refine). Units are in the field names; the defaults are what
/// `maobi write --refine` uses (how they were chosen: docs/trajectory.md, "Refinement").
///
/// # Examples
/// ```
/// use track_refine::RefineOptions;
///
/// // Fewer steps, the rest as the defaults; from JSON the same way (unknown fields refused).
/// let opts = RefineOptions { iterations: 8, ..RefineOptions::default() };
/// opts.validate()?;
/// let from_json: RefineOptions = serde_json::from_str(r#"{"iterations": 8}"#)?;
/// assert_eq!(from_json, opts);
/// assert!(RefineOptions { edge_px: 0.0, ..opts }.validate().is_err());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RefineOptions {
    /// Gradient steps.
    pub iterations: usize,
    /// Side of the analysis raster callers render the glyph at, px (the target's size; used
    /// by `maobi::pipeline`, not by [`refine`](crate::refine) itself, which takes the target
    /// as given).
    pub analysis_px: u32,
    /// Half-width of a footprint's soft edge, in target pixels.
    pub edge_px: f64,
    /// Adam step for positions, mm.
    pub step_mm: f64,
    /// Adam step for depths, mm.
    pub step_h_mm: f64,
    /// Adam step for tilts, rad.
    pub step_alpha_rad: f64,
    /// Weight of the smoothness term, per mm².
    pub smooth_weight: f64,
    /// Weight of the spacing term, per mm².
    pub spacing_weight: f64,
    /// Weight of the range barriers.
    pub barrier_weight: f64,
    /// Re-derive directions with the forward model every this many steps (and after the last).
    pub rederive_every: usize,
    /// The optimiser's floor under a gradient's scale, as a multiple of the root mean square of
    /// the first gradient over variables of the same kind (positions, depths, tilts).
    pub grad_floor: f64,
    /// Reset the optimiser's floor ([`Self::grad_floor`]) from the present gradient every this
    /// many steps (at a direction re-derivation; 0: only from the first gradient).
    pub floor_every: usize,
    /// Width (σ) of the Gaussian that smooths each gradient along the track, mm
    /// ([`Problem::smooth_gradient`](crate::Problem::smooth_gradient)); 0 turns it off.
    pub gradient_sigma_mm: f64,
    /// Inside a step, let each dragged footprint's direction follow its point and the path
    /// sample it aims at (the forward model's rule with that sample held), instead of holding
    /// the angle fixed.
    pub aim_coupling: bool,
    /// With [`Self::aim_coupling`], also couple the footprints the drag rule aims at the
    /// farthest sample since touch-down (before the brush has moved its reach: a stroke's
    /// first footprints) to that sample, instead of holding their angle (on by default; why:
    /// docs/trajectory.md, "Refinement").
    pub aim_far: bool,
    /// With [`Self::aim_coupling`], let each aim slide along the path as the footprint's length
    /// changes with its depth and tilt (the drag rule's reach is a share of that length), so
    /// the gradient with respect to depth sees the turn of the footprint that follows.
    pub aim_reach: bool,
    /// Where the image term and its gradient come from (the judge is never this: callers
    /// score with the analytic renderer and the executed simulation).
    pub gradients: Gradients,
}

/// Where the footprint images of the image term and their gradients come from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Gradients {
    /// The analytic soft footprint (the B-BSM teardrop with a soft edge) with closed-form
    /// derivatives: the default.
    #[default]
    Analytic,
    /// The B-BSMG generator's images, gradients from the network's VJP and the images'
    /// spatial gradients (`GenModel`, cargo feature `generator`): through
    /// `refine_with_generator`, which takes the generator; [`refine`](crate::refine) refuses it
    /// with [`RefineError::BadOption`].
    Generator,
}

impl Gradients {
    /// What [`refine`](crate::refine) expects instead of [`Gradients::Generator`].
    #[cfg(feature = "generator")]
    pub(crate) const REFUSED: &'static str =
        "`analytic` for `refine`; the generator path takes its generator through `refine_with_generator`";
    /// What [`refine`](crate::refine) expects instead of [`Gradients::Generator`].
    #[cfg(not(feature = "generator"))]
    pub(crate) const REFUSED: &'static str = "`analytic` (track-refine was built without its `generator` feature)";
}

impl Default for RefineOptions {
    fn default() -> Self {
        Self {
            iterations: 20,
            analysis_px: 256,
            edge_px: 0.75,
            step_mm: 3.0,
            step_h_mm: 0.25,
            step_alpha_rad: 0.5f64.to_radians(),
            smooth_weight: 1.0,
            spacing_weight: 1.0,
            barrier_weight: 1e-3,
            rederive_every: 5,
            grad_floor: 10.0,
            floor_every: 0,
            gradient_sigma_mm: 8.0,
            aim_coupling: true,
            aim_far: true,
            aim_reach: false,
            gradients: Gradients::Analytic,
        }
    }
}

impl RefineOptions {
    /// Checks every field.
    ///
    /// # Errors
    /// [`RefineError::BadOption`] naming the first bad field.
    pub fn validate(&self) -> Result<(), RefineError> {
        let bad = |name, value: String, expected| Err(RefineError::BadOption { name, value, expected });
        if self.iterations > 100_000 {
            return bad("iterations", self.iterations.to_string(), "at most 100000");
        }
        if !(16..=4096).contains(&self.analysis_px) {
            return bad("analysis_px", self.analysis_px.to_string(), "16..=4096 px");
        }
        if !(self.edge_px.is_finite() && self.edge_px > 0.0 && self.edge_px <= 16.0) {
            return bad("edge_px", self.edge_px.to_string(), "a half-width above 0 and at most 16 px");
        }
        for (name, v) in [
            ("step_mm", self.step_mm),
            ("step_h_mm", self.step_h_mm),
            ("step_alpha_rad", self.step_alpha_rad),
            ("smooth_weight", self.smooth_weight),
            ("spacing_weight", self.spacing_weight),
            ("barrier_weight", self.barrier_weight),
            ("grad_floor", self.grad_floor),
            ("gradient_sigma_mm", self.gradient_sigma_mm),
        ] {
            if !(v.is_finite() && (0.0..=1e6).contains(&v)) {
                return bad(name, v.to_string(), "a finite value in [0, 1e6]");
            }
        }
        if self.rederive_every == 0 {
            return bad("rederive_every", "0".into(), "at least 1 step");
        }
        Ok(())
    }
}
