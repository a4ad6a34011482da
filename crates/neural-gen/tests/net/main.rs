//! neural-gen's tests, one test binary (a `tests/*.rs` file each would link its own): the
//! generator (direct kernels against candle, checkpoints, training) and its VJP.

mod generator;
mod vjp;
