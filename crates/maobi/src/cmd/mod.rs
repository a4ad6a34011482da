//! One module per subcommand.

pub mod calibrate;
pub mod calibrate_sheet;
pub mod compare;
pub mod dataset;
pub mod eval_generator;
pub mod evaluate;
pub mod fit_stroke;
pub mod footprint;
pub mod models;
pub mod observe;
pub mod preview;
pub mod robot;
pub mod stroke;
pub mod train;
pub mod write;
