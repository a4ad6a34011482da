//! One module per subcommand.

pub mod calibrate;
pub mod compare;
pub mod dataset;
pub mod footprint;
pub mod models;
pub mod stroke;
