//! # neural-gen
//!
//! The B-BSMG generator: a small differentiable network (candle) from a press `(h, α, β)` to
//! its footprint image, trained on the analytic B-BSM rendered on the fly by bezier-raster.
//!
//! * [`config`]: architecture, normalisation (the profile's calibrated ranges), canvas, recipe,
//!   metrics: the JSON saved beside the weights.
//! * [`model`]: [`Generator`]: forward pass, batched rendering in the `maobi stroke` canvas
//!   convention, the vector–Jacobian product with respect to `(h, α, β)`, safetensors
//!   checkpoints with consistency checks.
//! * [`mod@train`]: AdamW on MSE, warm-up + cosine schedule, validation grid, early stopping.
//! * [`compose`]: a whole track rendered with the generator (batched along the track).
//! * [`eval`]: CSIM/SSIM of the generator against the analytic footprints.
//! * [`adam`]: a fused AdamW (one in-place pass per variable).
//! * [`conv`]: a faster CPU convolution for candle (direct, with bias and ReLU fused in, forward
//!   and backward) and a pixel shuffle with a direct backward.
//! * [`vjp`]: batched images and input VJPs without autograd ([`InputVjp`],
//!   [`Generator::images_and_vjps`]), for track refinement.
//! * [`ltp`]: the LearningToPaint-sized renderer network, kept as a speed reference.

// The crates whose types this crate's API takes or returns, so that a project depending on
// this crate alone can name them (`neural_gen::brush_model::Press`).
pub use bezier_raster;
pub use brush_model;
pub use candle_core;
pub use stroke_metrics;

// The README's examples run as doctests (`cargo test --doc`).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

pub mod adam;
pub mod compose;
pub mod config;
pub mod conv;
pub mod eval;
// Kept for the speed comparison with PyTorch (benches/ltp.rs, examples/ltp_speed.rs) only: not
// part of the API a downstream crate should use.
mod kernels;
#[doc(hidden)]
pub mod ltp;
pub mod model;
pub mod train;
pub mod vjp;

use thiserror::Error;

pub use config::{Arch, GeneratorConfig, Metrics, Recipe};
pub use model::Generator;
pub use train::{TrainOptions, TrainPoint, TrainReport, train};
pub use vjp::{InputVjp, Tape};

/// Errors of neural-gen.
#[derive(Debug, Error)]
pub enum NeuralGenError {
    /// A file could not be read or written.
    #[error("{}: {context}", path.display())]
    Io {
        /// The file.
        path: std::path::PathBuf,
        /// What was being done (`cannot read`, `cannot write`, …).
        context: &'static str,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The weights could not be saved.
    #[error("{}: cannot save the weights", path.display())]
    Save {
        /// The file.
        path: std::path::PathBuf,
        /// candle's error.
        #[source]
        source: candle_core::Error,
    },
    /// A config or checkpoint is malformed or does not match.
    #[error("{source_name}: {message}")]
    Config {
        /// File or part.
        source_name: String,
        /// What is wrong.
        message: String,
    },
    /// A buffer has the wrong size.
    #[error("{0}")]
    Shape(String),
    /// An error inside candle.
    #[error("candle")]
    Candle(#[from] candle_core::Error),
}
