//! `maobi.Brush` (a brush profile: built-in, loaded, saved, its footprint model vectorised over
//! arrays) and `maobi.calibrate`.

use std::path::Path;

use brush_model::{BrushProfile, Extrapolation, Form, Measurement, PressRanges, ProfileError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::{F64Array, check_finite, f64_array, json_to_py, path_arg, to_numpy, type_name};
use crate::errors::value_err;
use crate::{guarded, lib_err};

/// A brush profile: the brush (bundle length and radius, mm), its calibrated press ranges and
/// the linear model from a press `(h_mm, alpha_rad, beta_rad)` to the footprint's lengths
/// `(lt_mm, lh_mm, lr_mm)` (tip length, root length, belly half-width).
/// The most presses one `Brush.predict` call evaluates (2^24: 16.8 M, about 800 MB of inputs
/// and results).
const MAX_PREDICT: usize = 1 << 24;

#[pyclass(module = "maobi", name = "Brush", frozen)]
#[derive(Clone)]
pub(crate) struct Brush {
    pub(crate) profile: BrushProfile,
}

/// A profile error as the right Python exception: an unknown built-in or a press out of range
/// is a `ValueError`, a missing file `FileNotFoundError`, the rest `MaobiError`.
pub(crate) fn profile_err(context: &str, e: ProfileError) -> PyErr {
    match e {
        ProfileError::UnknownBuiltin(_) | ProfileError::OutOfRange { .. } => {
            value_err(format!("{context}: {}", crate::errors::chain(&e)))
        }
        e => lib_err(context, e),
    }
}

/// `brush=`: `None` (pen1), a built-in name, a profile JSON path or a [`Brush`].
pub(crate) fn brush_arg(obj: Option<&Bound<'_, PyAny>>) -> PyResult<BrushProfile> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(BrushProfile::builtin("pen1").expect("pen1 is built in"));
    };
    if let Ok(b) = obj.cast::<Brush>() {
        return Ok(b.get().profile.clone());
    }
    if let Ok(name) = obj.extract::<String>() {
        if BrushProfile::BUILTINS.contains(&name.as_str()) {
            return BrushProfile::builtin(&name).map_err(|e| profile_err("brush", e));
        }
        if !Path::new(&name).exists() && !name.ends_with(".json") {
            return Err(value_err(format!(
                "brush={name:?}: not a built-in brush ({}) nor an existing profile file",
                BrushProfile::BUILTINS.join(", ")
            )));
        }
    }
    let path = path_arg(obj, "brush").map_err(|_| {
        value_err(format!("brush: expected a built-in name, a profile path or a maobi.Brush, got {}", type_name(obj)))
    })?;
    crate::arrays::input_file(&path, "brush")?;
    BrushProfile::load(&path).map_err(|e| profile_err("brush", e))
}

#[pymethods]
impl Brush {
    /// A built-in brush: `pen1`, `pen2` or a scaled pen1 (`pen1-s84` … `pen1-s25`).
    ///
    /// Raises `ValueError` for an unknown name.
    #[staticmethod]
    fn builtin(name: &str) -> PyResult<Self> {
        BrushProfile::builtin(name).map(|profile| Self { profile }).map_err(|e| {
            value_err(format!("{}: expected one of {}", crate::errors::chain(&e), BrushProfile::BUILTINS.join(", ")))
        })
    }

    /// The names of the built-in brushes.
    #[staticmethod]
    fn builtins() -> Vec<&'static str> {
        BrushProfile::BUILTINS.to_vec()
    }

    /// A brush profile JSON file (as `maobi calibrate -o` writes it), validated.
    ///
    /// Raises `FileNotFoundError`, or `MaobiError` naming the field for an invalid profile.
    #[staticmethod]
    fn load(path: &Bound<'_, PyAny>) -> PyResult<Self> {
        let p = crate::arrays::input_path(path, "path")?;
        BrushProfile::load(&p).map(|profile| Self { profile }).map_err(|e| profile_err("path", e))
    }

    /// A brush profile from its JSON text, validated.
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Self> {
        BrushProfile::from_json(text, "text").map(|profile| Self { profile }).map_err(|e| profile_err("text", e))
    }

    /// The profile as JSON (the file format of `save`).
    fn to_json(&self) -> String {
        self.profile.to_json()
    }

    /// Writes the profile JSON to `path` (a temporary file beside it, then renamed).
    fn save(&self, path: &Bound<'_, PyAny>) -> PyResult<()> {
        let p = path_arg(path, "path")?;
        crate::write::write_atomic(&p, self.profile.to_json().as_bytes())
    }

    /// The profile's name.
    #[getter]
    fn name(&self) -> String {
        self.profile.name.clone()
    }

    /// The bundle's length, mm.
    #[getter]
    fn length_mm(&self) -> f64 {
        self.profile.brush.length_mm
    }

    /// The bundle's radius, mm.
    #[getter]
    fn radius_mm(&self) -> f64 {
        self.profile.brush.radius_mm
    }

    /// `"nominal"` (derived from the geometry) or `"calibrated"` (fitted to measurements).
    #[getter]
    fn source(&self) -> &'static str {
        match self.profile.source {
            brush_model::Source::Nominal => "nominal",
            brush_model::Source::Calibrated => "calibrated",
        }
    }

    /// The calibrated press ranges: `{"h_mm": (min, max), "alpha_rad": ..., "beta_rad": ...}`.
    #[getter]
    fn ranges<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let r = &self.profile.ranges;
        let d = PyDict::new(py);
        d.set_item("h_mm", (r.h_mm.min, r.h_mm.max))?;
        d.set_item("alpha_rad", (r.alpha_rad.min, r.alpha_rad.max))?;
        d.set_item("beta_rad", (r.beta_rad.min, r.beta_rad.max))?;
        Ok(d)
    }

    /// The footprint lengths `(lt_mm, lh_mm, lr_mm)` for presses, vectorised: `h_mm` (press
    /// depth, mm), `alpha_rad` (tilt) and `beta_rad` (rotation, radians) broadcast against each
    /// other like numpy; each result has the broadcast shape. As `maobi footprint --json`.
    ///
    /// Raises `ValueError` for a press outside the calibrated ranges (unless
    /// `extrapolate=True`), outside what the brush can do at all (depth 0 to its length, tilt
    /// within ±π/2, rotation within ±2π), or not finite; `MaobiError` for a press whose
    /// footprint degenerates.
    #[pyo3(signature = (h_mm, alpha_rad = None, beta_rad = None, *, extrapolate = false))]
    fn predict<'py>(
        &self,
        py: Python<'py>,
        h_mm: &Bound<'py, PyAny>,
        alpha_rad: Option<&Bound<'py, PyAny>>,
        beta_rad: Option<&Bound<'py, PyAny>>,
        extrapolate: bool,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let zero = 0.0f64.into_pyobject(py)?.into_any();
        let a = alpha_rad.cloned().unwrap_or_else(|| zero.clone());
        let b = beta_rad.cloned().unwrap_or(zero);
        let np = py.import("numpy")?;
        // Each argument's dtype is checked before broadcasting, so the error names it.
        let (h, a, b) = (f64_array(h_mm, "h_mm")?, f64_array(&a, "alpha_rad")?, f64_array(&b, "beta_rad")?);
        let arr = |x: &F64Array| -> PyResult<Bound<'py, PyAny>> { to_numpy(py, x.data.clone(), &x.shape) };
        let shaped = np
            .call_method1("broadcast_arrays", (arr(&h)?, arr(&a)?, arr(&b)?))
            .map_err(|e| value_err(format!("h_mm, alpha_rad, beta_rad: shapes do not broadcast ({e})")))?;
        let parts: Vec<Bound<'py, PyAny>> = shaped.extract()?;
        // The broadcast is a view; its copies and the three results are sized from it.
        let n: usize = parts[0].getattr("size")?.extract()?;
        if n > MAX_PREDICT {
            return Err(value_err(format!(
                "h_mm, alpha_rad, beta_rad: broadcast to {n} presses (expected at most {MAX_PREDICT} in one call)"
            )));
        }
        let [h, a, b] = [("h_mm", &parts[0]), ("alpha_rad", &parts[1]), ("beta_rad", &parts[2])]
            .map(|(n, x)| f64_array(x, n).and_then(|v| check_finite(&v, n).map(|_| v)));
        let (h, a, b) = (h?, a?, b?);
        let profile = self.profile.clone();
        let shape = h.shape.clone();
        let ex = if extrapolate { Extrapolation::Allow } else { Extrapolation::Refuse };
        let out = guarded(py, "Brush.predict", move || {
            let n = h.data.len();
            let (mut lt, mut lh, mut lr) = (Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(n));
            for i in 0..n {
                let (hv, av, bv) = (h.data[i], a.data[i], b.data[i]);
                let at = crate::arrays::index_of(i, &h.shape);
                physical_press(hv, av, bv, profile.brush.length_mm, &at)?;
                let fp = profile.predict(&brush_model::Press::new(hv, av, bv), ex).map_err(|e| match e {
                    ProfileError::OutOfRange { profile, quantity, value, min, max } => value_err(format!(
                        "press{at}: {quantity} = {value:.6} is outside the calibrated range [{min:.6}, {max:.6}] of brush `{profile}` (pass extrapolate=True to use it anyway)"
                    )),
                    e => profile_err(&format!("press{at}"), e),
                })?;
                lt.push(fp.lt_mm);
                lh.push(fp.lh_mm);
                lr.push(fp.lr_mm);
            }
            Ok((lt, lh, lr))
        })?;
        Ok((to_numpy(py, out.0, &shape)?, to_numpy(py, out.1, &shape)?, to_numpy(py, out.2, &shape)?))
    }

    fn __repr__(&self) -> String {
        format!(
            "maobi.Brush({:?}, {}, length {} mm, radius {} mm, h {}–{} mm)",
            self.profile.name,
            self.source(),
            self.profile.brush.length_mm,
            self.profile.brush.radius_mm,
            self.profile.ranges.h_mm.min,
            self.profile.ranges.h_mm.max
        )
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other.cast::<Brush>().is_ok_and(|o| o.get().profile.to_json() == self.profile.to_json())
    }

    fn __hash__(&self) -> u64 {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        self.profile.to_json().hash(&mut h);
        h.finish()
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        let from_json = slf.get_type().getattr("from_json")?;
        Ok((from_json, (slf.get().profile.to_json(),)))
    }
}

/// What any brush can physically do, extrapolating or not (as `maobi footprint` checks its
/// flags): depth 0 to the bundle's length, tilt within ±π/2, rotation within ±2π.
fn physical_press(h: f64, a: f64, b: f64, length_mm: f64, at: &str) -> PyResult<()> {
    if !(0.0..=length_mm).contains(&h) {
        return Err(value_err(format!("h_mm{at} = {h}: expected a depth from 0 to the brush's length {length_mm} mm")));
    }
    if a.abs() > std::f64::consts::FRAC_PI_2 {
        return Err(value_err(format!("alpha_rad{at} = {a}: expected a tilt within ±π/2")));
    }
    if b.abs() > std::f64::consts::TAU {
        return Err(value_err(format!("beta_rad{at} = {b}: expected a rotation within ±2π")));
    }
    Ok(())
}

/// Fits a brush profile to measured footprints, as `maobi calibrate` does: `measurements` is an
/// `(N, 6)` array of `h_mm, alpha_rad, beta_rad, lt_mm, lh_mm, lr_mm` (angles in radians) or
/// the path of a measurements CSV (`h_mm,alpha_deg,beta_deg,lt_mm,lh_mm,lr_mm`, degrees).
/// `form` is `"general"` (Eq. 6) or `"paper"` (Eq. 1–5); `brush` the brush whose length and
/// radius the profile records (default pen1); `name` the profile's name (default: the CSV's
/// stem, or `"calibrated"`). Returns `(brush, report)`, the report the dict of
/// `maobi calibrate --json`.
#[pyfunction]
#[pyo3(signature = (measurements, *, form = "general", brush = None, name = None))]
pub(crate) fn calibrate<'py>(
    py: Python<'py>,
    measurements: &Bound<'py, PyAny>,
    form: &str,
    brush: Option<&Bound<'py, PyAny>>,
    name: Option<String>,
) -> PyResult<(Brush, Bound<'py, PyAny>)> {
    let form = match form {
        "general" => Form::General,
        "paper" => Form::Paper,
        other => return Err(value_err(format!("form={other:?}: expected \"general\" or \"paper\""))),
    };
    let base = brush_arg(brush)?;
    let is_path = measurements.extract::<String>().is_ok() || measurements.hasattr("__fspath__")?;
    let (rows, default_name) = if is_path {
        let p = crate::arrays::input_path(measurements, "measurements")?;
        let stem = p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "calibrated".into());
        let rows =
            guarded(py, "calibrate", || brush_model::load_measurements(&p).map_err(|e| lib_err("measurements", e)))?;
        (rows, stem)
    } else {
        (measurement_rows(measurements)?, "calibrated".to_string())
    };
    let name = name.unwrap_or(default_name);
    let (profile, report) = guarded(py, "calibrate", move || {
        let report = brush_model::fit(&rows, form).map_err(|e| lib_err("measurements: cannot fit", e))?;
        let ranges = PressRanges::spanning(&rows);
        let profile = BrushProfile::calibrated(&name, base.brush, ranges, report.clone());
        profile
            .validate("the fitted profile")
            .map_err(|e| lib_err("measurements: the fitted model is not a usable profile", e))?;
        let json = serde_json::to_value(&report).map_err(|e| lib_err("report", e))?;
        Ok((profile, json))
    })?;
    Ok((Brush { profile }, json_to_py(py, &report)?))
}

/// The rows of an `(N, 6)` measurements array (angles in radians), each value checked.
fn measurement_rows(obj: &Bound<'_, PyAny>) -> PyResult<Vec<Measurement>> {
    let rows = crate::arrays::rows(obj, "measurements", 6, "h_mm, alpha_rad, beta_rad, lt_mm, lh_mm, lr_mm")?;
    let mut out = Vec::with_capacity(rows.len());
    for (i, r) in rows.iter().enumerate() {
        let col = ["h_mm", "alpha_rad", "beta_rad", "lt_mm", "lh_mm", "lr_mm"];
        let bad = |k: usize, what: &str| {
            value_err(format!("measurements[{i}, {k}] ({}) = {}: expected {what}", col[k], r[k]))
        };
        if !(0.0..=2000.0).contains(&r[0]) {
            return Err(bad(0, "a depth of 0 to 2000 mm"));
        }
        if r[1].abs() > std::f64::consts::FRAC_PI_2 {
            return Err(bad(1, "a tilt within ±π/2 rad"));
        }
        if r[2].abs() > std::f64::consts::TAU {
            return Err(bad(2, "a rotation within ±2π rad"));
        }
        for (k, v) in r.iter().enumerate().skip(3) {
            if !(*v > 0.0 && *v <= 2000.0) {
                return Err(bad(k, "a positive length of at most 2000 mm"));
            }
        }
        out.push(Measurement {
            press: brush_model::Press::new(r[0], r[1], r[2]),
            footprint: brush_model::Footprint { lt_mm: r[3], lh_mm: r[4], lr_mm: r[5] },
        });
    }
    if out.is_empty() {
        return Err(value_err("measurements: no rows (expected at least one measured press per regressor)"));
    }
    Ok(out)
}
