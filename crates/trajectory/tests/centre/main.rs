//! trajectory's tests, one test binary (a `tests/*.rs` file each would link its own): fonts,
//! skeletons and their stroke counts, template registration and synthetic scans, track building.

// Test helpers are `pub` for the modules of this test crate, which nothing outside can name.
#![allow(unreachable_pub)]

mod common;

mod fonts;
mod scan;
mod skeleton;
mod skeleton_counts;
mod template;
mod template_debug;
mod track;
