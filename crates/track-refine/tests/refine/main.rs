//! track-refine's tests, one test binary (a `tests/*.rs` file each would link its own): the
//! refinement on small tracks and targets, the physics it keeps, and the generator path.

mod common;

mod generator;
mod physics;
mod refine;
