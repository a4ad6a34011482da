//! The `maobi` Python package's native module (`maobi._native`), built with maturin and PyO3:
//! the brush model, the renderers, the metrics, the character pipeline, the generator and the
//! robot programs of the workspace's library crates, with numpy arrays in and out. The Python
//! layer (`python/maobi/`) re-exports it with type stubs; `docs/python.md` is the API.
//!
//! Every entry point that does real work releases the GIL and catches panics
//! (`errors::guarded`): a bug in maobi raises `maobi.MaobiError`, never a Rust panic in Python.

mod arrays;
mod brush;
mod errors;
mod generator;
mod render;
mod robot;
mod write;

use pyo3::prelude::*;

pub(crate) use errors::{MaobiError, guarded, lib_err};

/// The native module: classes and functions the `maobi` package re-exports.
#[pymodule]
#[pyo3(name = "_native")]
fn native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("MaobiError", m.py().get_type::<MaobiError>())?;
    m.add_class::<brush::Brush>()?;
    m.add_function(wrap_pyfunction!(brush::calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(render::render_presses, m)?)?;
    m.add_function(wrap_pyfunction!(render::render_presses_soft, m)?)?;
    m.add_function(wrap_pyfunction!(render::render_presses_soft_vjp, m)?)?;
    m.add_function(wrap_pyfunction!(render::render_track, m)?)?;
    m.add_function(wrap_pyfunction!(render::csim, m)?)?;
    m.add_function(wrap_pyfunction!(render::ssim, m)?)?;
    m.add_function(wrap_pyfunction!(render::iou, m)?)?;
    m.add_function(wrap_pyfunction!(render::compare, m)?)?;
    m.add_class::<write::Track>()?;
    m.add_class::<write::Written>()?;
    m.add_function(wrap_pyfunction!(write::write, m)?)?;
    m.add_function(wrap_pyfunction!(write::glyph, m)?)?;
    m.add_function(wrap_pyfunction!(write::load_image, m)?)?;
    m.add_function(wrap_pyfunction!(write::save_image, m)?)?;
    m.add_class::<generator::Generator>()?;
    m.add_function(wrap_pyfunction!(robot::robot_check, m)?)?;
    m.add_function(wrap_pyfunction!(robot::robot_export, m)?)?;
    m.add_function(wrap_pyfunction!(errors::_panic_for_tests, m)?)?;
    m.add_function(wrap_pyfunction!(errors::_last_call_seconds, m)?)?;
    Ok(())
}
