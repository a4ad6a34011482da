//! The library side of the `maobi` command line: the pipelines that join several crates
//! (glyph → track → render → scores), shared by the binary and by `cargo xtask gates`.

// The crates whose types this library's API takes or returns.
pub use bezier_raster;
pub use brush_model;
pub use neural_gen;
pub use robot_io;
pub use stroke_metrics;
pub use track_refine;
pub use trajectory;

// The README's examples run as doctests (`cargo test --doc`).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

pub mod generator;
pub mod pipeline;
pub mod plot;
pub mod sheet;
