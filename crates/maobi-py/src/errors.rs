//! Errors as Python exceptions: `maobi.MaobiError` for what maobi refuses, `ValueError` for an
//! argument out of its domain, `FileNotFoundError` for a missing file; panics caught.

use std::error::Error;
use std::panic::{AssertUnwindSafe, catch_unwind};

use pyo3::exceptions::{PyException, PyFileNotFoundError, PyValueError};
use pyo3::prelude::*;

pyo3::create_exception!(
    maobi,
    MaobiError,
    PyException,
    "What maobi refuses or cannot do (a profile that does not validate, a program that fails the safety check, an unreadable file); the message names the argument, file or field."
);

/// The message of an error and every source under it, joined by `: `.
pub(crate) fn chain(e: &(dyn Error + 'static)) -> String {
    let mut msg = e.to_string();
    let mut cur = e.source();
    while let Some(s) = cur {
        let text = s.to_string();
        if !msg.contains(&text) {
            msg.push_str(": ");
            msg.push_str(&text);
        }
        cur = s.source();
    }
    msg
}

/// A library error as a Python exception, its message prefixed by `context` (the argument or
/// call): `FileNotFoundError` when a file is missing somewhere in its chain, `MaobiError`
/// otherwise.
pub(crate) fn lib_err(context: &str, e: impl Error + 'static) -> PyErr {
    let msg = if context.is_empty() { chain(&e) } else { format!("{context}: {}", chain(&e)) };
    let mut cur: Option<&(dyn Error + 'static)> = Some(&e);
    while let Some(s) = cur {
        if let Some(io) = s.downcast_ref::<std::io::Error>() {
            if io.kind() == std::io::ErrorKind::NotFound {
                return PyFileNotFoundError::new_err(msg);
            }
        }
        cur = s.source();
    }
    MaobiError::new_err(msg)
}

/// A `ValueError` with `msg`.
pub(crate) fn value_err(msg: impl Into<String>) -> PyErr {
    PyValueError::new_err(msg.into())
}

/// Runs `f` with the GIL released, turning a panic into `MaobiError` naming `what`.
pub(crate) fn guarded<T: Send>(py: Python<'_>, what: &str, f: impl FnOnce() -> PyResult<T> + Send) -> PyResult<T> {
    let t0 = std::time::Instant::now();
    let out = guarded_untimed(py, what, f);
    LAST_CALL_S.with(|c| c.set(t0.elapsed().as_secs_f64()));
    out
}

thread_local! {
    /// Seconds the last [`guarded`] work took on this thread (GIL released), for the benchmark.
    static LAST_CALL_S: std::cell::Cell<f64> = const { std::cell::Cell::new(f64::NAN) };
}

/// Seconds the calling thread's last heavy call spent in maobi's library code (with the GIL
/// released), without the conversions in and out: what `benches/python_overhead.py` subtracts
/// from a call's wall time to get the cost of calling from Python.
#[pyfunction]
pub(crate) fn _last_call_seconds() -> f64 {
    LAST_CALL_S.with(std::cell::Cell::get)
}

fn guarded_untimed<T: Send>(py: Python<'_>, what: &str, f: impl FnOnce() -> PyResult<T> + Send) -> PyResult<T> {
    py.detach(|| match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(payload) => {
            let text = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            Err(MaobiError::new_err(format!("{what}: internal error in maobi (please report it): {text}")))
        }
    })
}

/// Panics inside [`guarded`]: the test that a panic reaches Python as `MaobiError`.
#[pyfunction]
pub(crate) fn _panic_for_tests(py: Python<'_>) -> PyResult<()> {
    guarded(py, "_panic_for_tests", || -> PyResult<()> { panic!("deliberate panic") })
}
