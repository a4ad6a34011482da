//! # numerics
//!
//! Small deterministic numerics that several of maobi's crates share, each written once:
//!
//! * [`nelder_mead`]: derivative-free minimisation over `N` parameters ([`NelderMead`] sets the
//!   steps, the iteration count and the stop).
//! * [`gaussian_blur`]: a separable Gaussian blur of a row-major raster of `f32` or `f64`
//!   ([`Pixel`]), zero or clamped edges ([`Edge`]).
//! * [`for_each_block`]: the square blocks of a row-major raster, for statistics per block.
//! * [`SplitMix64`]: a tiny seedable generator whose streams never change (fixtures are compared
//!   byte for byte), with uniform and normal draws, and its finaliser [`SplitMix64::mix`] as a
//!   64-bit hash.
//!
//! No dependencies, no randomness besides what a seed gives, no threads: the same inputs give
//! the same bits on every platform.
//!
//! ```
//! use numerics::{NelderMead, SplitMix64, nelder_mead};
//!
//! // Minimise a bowl whose bottom is at (3, −1).
//! let bowl = |x: &[f64; 2]| (x[0] - 3.0).powi(2) + 2.0 * (x[1] + 1.0).powi(2);
//! let (x, v) = nelder_mead(bowl, [0.0, 0.0], &NelderMead::new([1.0, 1.0], 200));
//! assert!((x[0] - 3.0).abs() < 1e-4 && (x[1] + 1.0).abs() < 1e-4 && v < 1e-8);
//!
//! // One seed, one stream.
//! let (mut a, mut b) = (SplitMix64(7), SplitMix64(7));
//! assert_eq!(a.next_u64(), b.next_u64());
//! ```

#![warn(unreachable_pub)]

// The README's examples run as doctests (`cargo test --doc`).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

mod blocks;
mod blur;
mod nelder_mead;
mod splitmix;

pub use blocks::for_each_block;
pub use blur::{Edge, Normalise, Pixel, gaussian_blur};
pub use nelder_mead::{NelderMead, OutsideContraction, nelder_mead};
pub use splitmix::SplitMix64;
