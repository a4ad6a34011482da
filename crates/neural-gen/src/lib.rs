//! # neural-gen
//!
//! The B-BSMG generator: a small differentiable network (candle) from a press `(h, α, β)` to
//! its footprint image, trained on the analytic B-BSM rendered on the fly by bezier-raster.
//!
//! * Configuration ([`GeneratorConfig`], [`Arch`]): architecture, normalisation (the
//!   profile's calibrated ranges), canvas, recipe, metrics: the JSON saved beside the weights.
//! * [`Generator`]: forward pass and batched rendering on the crate's direct kernels (the
//!   `maobi stroke` canvas convention), the candle graph for autograd checks, the vector–Jacobian
//!   product with respect to `(h, α, β)`, safetensors checkpoints with consistency checks.
//! * [`train()`]: AdamW on MSE on the direct kernels, warm-up + cosine schedule, validation
//!   grid, early stopping.
//! * [`render_track`]: a whole track rendered with the generator (batched along the track).
//! * [`evaluate`]: CSIM/SSIM of the generator against the analytic footprints.
//! * [`InputVjp`]: batched images, input VJPs and Jacobians without autograd, for track
//!   refinement (and what [`Generator::forward`] runs on).
//!
//! Errors are [`NeuralGenError`]; what is wrong with a config or checkpoint is a typed
//! [`ConfigError`] (an inconsistent architecture an [`ArchError`]).

// The crates whose types this crate's API takes or returns, so that a project depending on
// this crate alone can name them (`neural_gen::brush_model::Press`).
pub use bezier_raster;
pub use brush_model;
pub use candle_core;
pub use safe_output;
pub use stroke_metrics;

// The README's examples run as doctests (`cargo test --doc`).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

// Candle's graph with a fused AdamW: the reference training step of the tests and benchmarks.
#[cfg(any(test, feature = "bench"))]
mod adam;
mod compose;
mod config;
mod conv;
#[cfg(test)]
mod conv_tests;
mod direct;
mod eval;
mod kernels;
#[cfg(any(test, feature = "bench"))]
mod ltp;
mod model;
mod net;
mod train;
mod vjp;

use thiserror::Error;

pub use compose::render_track;
pub use config::{Arch, ArchError, CONFIG_VERSION, GeneratorConfig, Metrics, Recipe};
pub use eval::{HELD_OUT_SEED, evaluate, held_out_spec};
pub use model::{Generator, config_path};
pub use net::Tape;
pub use train::{SCHEDULE, TrainOptions, TrainPoint, TrainReport, checkpoint_path, train};
pub use vjp::InputVjp;

/// What the benchmarks and speed examples measure beside the generator, not part of the API a
/// downstream crate should use: the trainer on the direct kernels for any [`bench::NetSpec`]
/// network, the LearningToPaint-size network (for the speed comparison with PyTorch,
/// `benches/ltp.rs`) and the training step through candle's graph. Compiled with the `bench`
/// feature, which the crate's own benches, examples and tests turn on (a dev-dependency on
/// itself), as does xtask.
#[cfg(feature = "bench")]
pub mod bench {
    pub use crate::direct::DirectTrainer;
    pub use crate::ltp::{Kernels as LtpKernels, Ltp};
    pub use crate::net::{NetSpec, StageSpec};
    pub use crate::train::NetworkStep;
}

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
    /// A file could not be written (the error names it; nothing was half-written).
    #[error(transparent)]
    Write(#[from] safe_output::Error),
    /// The weights could not be saved.
    #[error("{}: cannot save the weights", path.display())]
    Save {
        /// The file.
        path: std::path::PathBuf,
        /// candle's error.
        #[source]
        source: candle_core::Error,
    },
    /// A config or checkpoint is malformed or does not match, or the brush profile refuses a
    /// press.
    #[error("{source_name}")]
    Config {
        /// File or part.
        source_name: String,
        /// What is wrong.
        #[source]
        problem: ConfigError,
    },
    /// A buffer has the wrong size.
    #[error("{0}")]
    Shape(String),
    /// An error inside candle.
    #[error("candle")]
    Candle(#[from] candle_core::Error),
}

/// What is wrong with a generator's config, checkpoint, options or profile: the cause of
/// [`NeuralGenError::Config`].
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ConfigError {
    /// The config is not valid JSON for a [`GeneratorConfig`].
    #[error("not a generator config")]
    Json(#[source] serde_json::Error),
    /// The config's format version is not the one this build reads.
    #[error("version {found} (this build reads {supported})")]
    Version {
        /// The file's version.
        found: u32,
        /// [`CONFIG_VERSION`].
        supported: u32,
    },
    /// The image size does not match the architecture.
    #[error("size {size} does not match the architecture's output {output}")]
    Size {
        /// The config's size, px.
        size: u32,
        /// The architecture's output side, px.
        output: usize,
    },
    /// The architecture is inconsistent or too large.
    #[error("inconsistent architecture")]
    Arch(#[source] ArchError),
    /// The brush profile is invalid or refuses a press.
    #[error("brush profile")]
    Profile(#[source] brush_model::ProfileError),
    /// The canvas scale is out of range.
    #[error("px_per_mm {px_per_mm}: expected a scale above 0 and at most 10000 px/mm")]
    Scale {
        /// The config's scale, px/mm.
        px_per_mm: f64,
    },
    /// The weights are not a safetensors file.
    #[error("not a readable safetensors file")]
    Safetensors(#[source] candle_core::Error),
    /// The weights hold another number of tensors than the architecture.
    #[error("{found} tensors, the architecture has {expected}")]
    TensorCount {
        /// Tensors in the file.
        found: usize,
        /// Tensors of the architecture.
        expected: usize,
    },
    /// A tensor the architecture names is missing.
    #[error("tensor `{name}` missing")]
    MissingTensor {
        /// The tensor's name.
        name: String,
    },
    /// A tensor has the wrong shape.
    #[error("tensor `{name}` has shape {found:?}, the architecture needs {expected:?}")]
    TensorShape {
        /// The tensor's name.
        name: String,
        /// Its shape in the file.
        found: Vec<usize>,
        /// The shape the architecture needs.
        expected: Vec<usize>,
    },
    /// A tensor holds NaN or infinite values.
    #[error("tensor `{name}` holds NaN or infinite weights")]
    NonFinite {
        /// The tensor's name.
        name: String,
    },
    /// Training options out of range.
    #[error("steps {steps}, batch {batch}, val_every {val_every} must be at least 1 and lr {lr} positive")]
    TrainOptions {
        /// Steps.
        steps: usize,
        /// Batch size.
        batch: usize,
        /// Validation period, steps.
        val_every: usize,
        /// Peak learning rate.
        lr: f64,
    },
    /// An evaluation over no presses.
    #[error("no held-out presses (n = 0): nothing to measure")]
    NoPresses,
}
