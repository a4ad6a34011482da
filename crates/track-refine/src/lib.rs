//! # track-refine
//!
//! Refines a character's brush track by gradient descent on an image loss, keeping the physics
//! of the moving brush.
//!
//! The input is a track as `trajectory::build_track` writes it (commanded states: position,
//! depth, tilt; directions derived by `brush_model::ForwardModel`), the brush profile and the
//! glyph raster ([`Target`]). [`refine`] moves the pressed points (x, y in mm), their depths
//! (h, mm) and, where the brush is tilted, their tilts (α, rad) so that the soft union of the
//! footprints matches the glyph better, while a smoothness, a spacing and a barrier term keep
//! the track one the robot can write. What is free and what is fixed, and the loss, are in
//! [`Problem`]; each footprint is the B-BSM teardrop with a soft edge (a smoothstep of the
//! signed distance to its outline), with derivatives in closed form.
//!
//! Directions are never free: the forward model re-derives them every
//! [`RefineOptions::rederive_every`] steps and after the last; inside a step each dragged
//! footprint keeps the path sample it aims at (see [`Problem`]). After the last step depths
//! and tilts are clamped into the profile's calibrated ranges (every step is projected into
//! them anyway).
//!
//! Where the footprint images of the image term come from is [`RefineOptions::gradients`]:
//! the analytic soft footprint (the default), or, with the cargo feature `generator`, the
//! B-BSMG generator (`GenModel`, through `refine_with_generator`).
//!
//! ```no_run
//! use brush_model::{BrushProfile, Track};
//! use track_refine::{RefineOptions, Target, refine};
//! # fn get() -> (Track, Target) { unimplemented!() }
//! let pen1 = BrushProfile::builtin("pen1").unwrap();
//! let (track, target) = get();
//! let out = refine(&track, &pen1, &target, &RefineOptions::default()).unwrap();
//! println!("loss {:.4} → {:.4}", out.curve[0].total, out.curve.last().unwrap().total);
//! ```
//!
//! Deterministic: no randomness, and every parallel sum runs over fixed chunks in a fixed
//! order, so the result is the same for any thread count.

// The crates whose types this crate's API takes or returns, so that a project depending on
// this crate alone can name them (`track_refine::brush_model::Press`).
pub use brush_model;

// The README's examples run as doctests (`cargo test --doc`).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

mod descent;
mod error;
#[cfg(feature = "generator")]
mod generator;
mod image;
mod options;
mod problem;
mod soft;
mod soft_render;
mod target;

use std::time::Instant;

use brush_model::{BrushProfile, Track};

pub use error::RefineError;
#[cfg(feature = "generator")]
pub use generator::{GenMode, GenModel};
pub use options::{Gradients, RefineOptions};
pub use problem::{Directions, LossTerms, Problem};
pub use soft_render::{SoftCanvas, soft_render, soft_render_vjp};
pub use target::Target;

/// A refined track and how the refinement went.
#[derive(Clone, Debug)]
pub struct Refined {
    /// The refined track: depths and tilts inside the profile's ranges, every direction
    /// derived by the forward model.
    pub track: Track,
    /// The loss before each step, then once after the last (with re-derived directions):
    /// `iterations + 1` entries.
    pub curve: Vec<LossTerms>,
    /// Number of variables.
    pub variables: usize,
    /// Number of footprints (pressed points) in the image term.
    pub footprints: usize,
    /// Wall time, ms.
    pub millis: f64,
}

/// Refines `track` against `target` with the analytic image term (see the crate doc).
///
/// # Errors
/// [`RefineError`] for an empty track, an unusable target or option (among them
/// [`Gradients::Generator`], which needs `refine_with_generator`), a press the profile
/// refuses, or a loss that stops being finite.
///
/// # Examples
/// A stroke pressed too lightly and 1 mm off the centre of a bar moves onto it:
/// ```
/// use track_refine::brush_model::{BrushProfile, PointMm, Stroke, Track, TrackPoint};
/// use track_refine::{RefineOptions, Target, refine};
///
/// let pen1 = BrushProfile::builtin("pen1")?;
/// // A bar 7 mm tall from x = 10 to 40 mm, at 0.5 mm per pixel.
/// let (w, h, mm_per_px) = (100u32, 60u32, 0.5);
/// let ink = (0..w * h)
///     .map(|i| {
///         let (x, y) = ((i % w) as f64 * mm_per_px, (i / w) as f64 * mm_per_px);
///         if (10.0..40.0).contains(&x) && (11.5..18.5).contains(&y) { 1.0 } else { 0.0 }
///     })
///     .collect();
/// let target = Target::new(w, h, ink, PointMm::new(0.0, 0.0), mm_per_px)?;
/// let pt = |x_mm| TrackPoint { x_mm, y_mm: 14.0, h_mm: 12.0, alpha_rad: 0.0, beta_rad: std::f64::consts::PI };
/// let track = Track { strokes: vec![Stroke { points: (0..=25).map(|i| pt(12.0 + i as f64)).collect() }] };
/// let out = refine(&track, &pen1, &target, &RefineOptions { iterations: 5, ..Default::default() })?;
/// assert_eq!(out.curve.len(), 6);
/// assert!(out.curve[5].total < out.curve[0].total);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn refine(
    track: &Track,
    profile: &BrushProfile,
    target: &Target,
    opts: &RefineOptions,
) -> Result<Refined, RefineError> {
    let t0 = Instant::now();
    descent::run(Problem::new(track, profile, target, opts)?, opts, t0)
}

/// As [`refine`] on the generator path (cargo feature `generator`), with `generator` giving
/// the footprint images and their derivatives (e.g. `GenModel::new(&neural_gen::Generator::load(path)?)`;
/// the `maobi` binary passes its committed pen1 checkpoint). The judge stays the caller's
/// analytic render.
///
/// # Errors
/// As [`refine`]; [`RefineError::GeneratorProfile`] when the generator was trained for another
/// brush profile.
///
/// # Examples
/// ```
/// use std::sync::Arc;
/// use neural_gen::{Arch, Generator, GeneratorConfig};
/// use track_refine::brush_model::{BrushProfile, PointMm, Stroke, Track, TrackPoint};
/// use track_refine::{GenModel, RefineOptions, Target, refine_with_generator};
///
/// let pen1 = BrushProfile::builtin("pen1")?;
/// // An untrained tiny generator (a real one comes from `Generator::load`).
/// let generator = Generator::new(GeneratorConfig::new(pen1.clone(), Arch::tiny_32()), 5)?;
/// let model = Arc::new(GenModel::new(&generator)?);
/// let target = Target::new(40, 40, vec![1.0; 1600], PointMm::new(0.0, 0.0), 1.0)?;
/// let pt = |x_mm| TrackPoint { x_mm, y_mm: 20.0, h_mm: 12.0, alpha_rad: 0.0, beta_rad: std::f64::consts::PI };
/// let track = Track { strokes: vec![Stroke { points: (0..=4).map(|i| pt(15.0 + i as f64)).collect() }] };
/// let opts = RefineOptions { iterations: 1, ..Default::default() };
/// let out = refine_with_generator(&track, &pen1, &target, &opts, model)?;
/// assert_eq!(out.curve.len(), 2);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[cfg(feature = "generator")]
pub fn refine_with_generator(
    track: &Track,
    profile: &BrushProfile,
    target: &Target,
    opts: &RefineOptions,
    generator: std::sync::Arc<GenModel>,
) -> Result<Refined, RefineError> {
    let t0 = Instant::now();
    let analytic = RefineOptions { gradients: Gradients::Analytic, ..*opts };
    descent::run(Problem::new(track, profile, target, &analytic)?.with_generator(generator)?, opts, t0)
}
