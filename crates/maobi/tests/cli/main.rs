//! The `maobi` binary's tests, run against the real binary: one test binary for the package
//! (a `tests/*.rs` file each would link its own copy of everything), one module per area.

// Test helpers are `pub` for the modules of this test crate, which nothing outside can name.
#![allow(unreachable_pub)]

mod common;

mod aubo_script;
mod brush;
mod calibrate_sheet;
mod closed_loop;
mod grbl;
mod neural;
mod newcomer;
mod observe;
mod photos;
mod preview;
mod prop_parsers;
mod raster;
mod refine;
mod robot;
mod robustness;
mod safety;
mod sheet;
mod styles;
mod transport;
mod untrusted;
mod ur;
mod write;
