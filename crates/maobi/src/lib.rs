//! The library side of the `maobi` command line: the pipelines that join several crates
//! (glyph → track → render → scores), shared by the binary and by `cargo xtask gates`.

pub mod generator;
pub mod pipeline;
pub mod plot;
pub mod sheet;
