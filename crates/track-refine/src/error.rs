//! The crate's error.

use brush_model::ProfileError;
use thiserror::Error;

/// Errors of refinement.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum RefineError {
    /// The track has no points.
    #[error("the track has no points: nothing to refine (expected at least one stroke with points)")]
    EmptyTrack,
    /// The target raster is unusable (the message says what is wrong and what was expected).
    #[error("target raster: {0}")]
    Target(String),
    /// An option is out of its range.
    #[error("refine option `{name}` = {value}: expected {expected}")]
    BadOption {
        /// The option's field name.
        name: &'static str,
        /// Its value.
        value: String,
        /// What is accepted.
        expected: &'static str,
    },
    /// The profile refused a press of the track.
    #[error(transparent)]
    Profile(#[from] ProfileError),
    /// The generator could not be prepared for refinement (cargo feature `generator`).
    #[cfg(feature = "generator")]
    #[error("the generator could not be prepared for refinement")]
    Generator(#[from] neural_gen::NeuralGenError),
    /// The generator was trained for another brush profile than the track's.
    #[error(
        "the generator was trained for brush profile `{generator}`, the track uses `{track}` (expected the same profile)"
    )]
    GeneratorProfile {
        /// The generator's profile name.
        generator: String,
        /// The refined track's profile name.
        track: String,
    },
    /// The loss stopped being a number.
    #[error("the loss became {value} at iteration {iteration} (expected a finite value)")]
    NotFinite {
        /// Iteration, from 0.
        iteration: usize,
        /// The value.
        value: f64,
    },
}
