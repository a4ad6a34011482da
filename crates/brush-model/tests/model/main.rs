//! brush-model's tests, one test binary (a `tests/*.rs` file each would link its own): golden
//! values from statsmodels, profiles, properties of the footprint and the forward model, and
//! the regression.

mod golden;
mod profile;
mod properties;
mod regression;
