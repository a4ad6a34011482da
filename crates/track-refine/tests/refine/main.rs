//! track-refine's tests, one test binary (a `tests/*.rs` file each would link its own): the
//! refinement on small tracks and targets, the physics it keeps, and the generator path.

// Test helpers are `pub` for the modules of this test crate, which nothing outside can name.
#![allow(unreachable_pub)]

mod common;

mod generator;
mod physics;
mod refine;
