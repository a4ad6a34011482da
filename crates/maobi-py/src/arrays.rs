//! numpy in and out: any real dtype and any memory layout accepted (converted once), the
//! argument named in every error; results handed to numpy without a copy.

use numpy::{PyArray1, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyAnyMethods;

use crate::errors::value_err;

/// An array argument read as `f64`, row-major: its values and its shape.
pub(crate) struct F64Array {
    pub(crate) data: Vec<f64>,
    pub(crate) shape: Vec<usize>,
}

/// `obj` (a numpy array, a list, a scalar) as a contiguous `f64` array: refused unless its dtype
/// is a real number (float, integer or bool is refused too: bool is no length), naming `name`.
pub(crate) fn f64_array(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<F64Array> {
    let py = obj.py();
    let np = py.import("numpy")?;
    let arr =
        np.call_method1("asarray", (obj,)).map_err(|e| value_err(format!("{name}: not an array of numbers ({e})")))?;
    let kind: String = arr.getattr("dtype")?.getattr("kind")?.extract()?;
    if kind != "f" && kind != "i" && kind != "u" {
        let dtype = arr.getattr("dtype")?.str()?.to_string();
        return Err(value_err(format!("{name}: dtype {dtype} (expected real numbers: a float or integer array)")));
    }
    // `asarray(order="C")`, not `ascontiguousarray`: a 0-d array stays 0-d.
    let kw = pyo3::types::PyDict::new(py);
    kw.set_item("dtype", np.getattr("float64")?)?;
    kw.set_item("order", "C")?;
    let c = np.call_method("asarray", (arr,), Some(&kw))?;
    let a = c.cast_into::<PyArrayDyn<f64>>().map_err(|e| value_err(format!("{name}: {e}")))?;
    let shape = a.shape().to_vec();
    let ro = a.readonly();
    let data = ro.as_slice().map_err(|e| value_err(format!("{name}: {e}")))?.to_vec();
    Ok(F64Array { data, shape })
}

/// Refuses a NaN or infinite value of `a`, naming `name` and the index.
pub(crate) fn check_finite(a: &F64Array, name: &str) -> PyResult<()> {
    if let Some(i) = a.data.iter().position(|v| !v.is_finite()) {
        return Err(value_err(format!("{name}{}: {} (expected finite values)", index_of(i, &a.shape), a.data[i])));
    }
    Ok(())
}

/// The numpy index of flat element `i` in an array of `shape`, as `[i, j]` (empty for a
/// scalar).
pub(crate) fn index_of(mut i: usize, shape: &[usize]) -> String {
    if shape.is_empty() {
        return String::new();
    }
    let mut idx = vec![0; shape.len()];
    for (k, &n) in shape.iter().enumerate().rev() {
        idx[k] = i % n.max(1);
        i /= n.max(1);
    }
    format!("[{}]", idx.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(", "))
}

/// An `(N, cols)` array argument (one row for a 1-D array of `cols` values): its rows, checked
/// finite.
pub(crate) fn rows(obj: &Bound<'_, PyAny>, name: &str, cols: usize, what: &str) -> PyResult<Vec<Vec<f64>>> {
    let mut a = f64_array(obj, name)?;
    if a.shape.len() == 1 && a.shape[0] == cols {
        a.shape = vec![1, cols];
    }
    if a.shape.len() != 2 || a.shape[1] != cols {
        return Err(value_err(format!("{name}: shape {:?} (expected (N, {cols}): {what})", a.shape)));
    }
    check_finite(&a, name)?;
    Ok(a.data.chunks_exact(cols).map(<[f64]>::to_vec).collect())
}

/// A 2-D image argument (ink = 1) as `f32`: values, height, width; checked finite.
pub(crate) fn image(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<(Vec<f32>, usize, usize)> {
    let a = f64_array(obj, name)?;
    if a.shape.len() != 2 || a.shape[0] == 0 || a.shape[1] == 0 {
        return Err(value_err(format!("{name}: shape {:?} (expected an image (H, W), ink = 1)", a.shape)));
    }
    check_finite(&a, name)?;
    Ok((a.data.iter().map(|&v| v as f32).collect(), a.shape[0], a.shape[1]))
}

/// `data` as a numpy array of `shape`, without a copy.
pub(crate) fn to_numpy<'py, T: numpy::Element>(
    py: Python<'py>,
    data: Vec<T>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyAny>> {
    let a = PyArray1::from_vec(py, data);
    Ok(a.reshape(shape.to_vec())?.into_any())
}

/// A JSON value as Python objects (dicts, lists, floats, ...) through the `json` module.
pub(crate) fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(v).map_err(|e| crate::lib_err("JSON", e))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// A path argument (str or `os.PathLike`) as a path.
pub(crate) fn path_arg(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<std::path::PathBuf> {
    obj.extract::<std::path::PathBuf>()
        .map_err(|_| value_err(format!("{name}: expected a path (str or os.PathLike), got {}", type_name(obj))))
}

/// The most bytes an input file may hold (256 MiB: far above any profile, CSV, font, image,
/// generator or robot file maobi writes or reads, far below what would exhaust memory).
pub(crate) const MAX_INPUT_BYTES: u64 = 256 << 20;

/// A path argument naming a file to read: refused unless it is a regular file (after symbolic
/// links) of at most [`MAX_INPUT_BYTES`], before anything opens it. A FIFO would block the open
/// forever, a device like `/dev/zero` has no size and never ends.
pub(crate) fn input_file(path: &std::path::Path, name: &str) -> PyResult<()> {
    let meta = match std::fs::metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(pyo3::exceptions::PyFileNotFoundError::new_err(format!(
                "{name}: {} does not exist",
                path.display()
            )));
        }
        Err(e) => return Err(crate::lib_err(&format!("{name}: {}", path.display()), e)),
    };
    if !meta.is_file() {
        let what = if meta.is_dir() { "a folder" } else { "not a regular file (a device, pipe or socket)" };
        return Err(value_err(format!("{name}: {} is {what}: expected a file", path.display())));
    }
    if meta.len() > MAX_INPUT_BYTES {
        return Err(value_err(format!(
            "{name}: {} holds {} bytes: expected at most {} MiB",
            path.display(),
            meta.len(),
            MAX_INPUT_BYTES >> 20
        )));
    }
    Ok(())
}

/// A path argument naming a file to read ([`path_arg`], then [`input_file`]).
pub(crate) fn input_path(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<std::path::PathBuf> {
    let p = path_arg(obj, name)?;
    input_file(&p, name)?;
    Ok(p)
}

/// A number for a message: plain, or in exponent form when plain would be a wall of digits
/// (`1e300`, `1e-300`).
pub(crate) fn num(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-6..1e15).contains(&v.abs()) { format!("{v}") } else { format!("{v:e}") }
}

/// The Python type name of `obj`, for messages.
pub(crate) fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type().name().map(|n| n.to_string()).unwrap_or_else(|_| "?".into())
}
