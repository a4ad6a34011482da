//! `maobi.Generator`: the B-BSMG generator's forward pass and its vector–Jacobian product with
//! respect to the presses, on maobi's own kernels (`neural_gen::InputVjp`).

use std::sync::Arc;

use brush_model::{BrushProfile, Extrapolation, Press};
use neural_gen::InputVjp;
use pyo3::prelude::*;

use crate::arrays::{path_arg, rows, to_numpy};
use crate::brush::Brush;
use crate::errors::value_err;
use crate::{guarded, lib_err};

/// The most pixels of one call's images (B × size²: 2^26, 256 MiB of f32; 4,096 presses at
/// 128 px).
const MAX_BATCH_PIXELS: usize = 1 << 26;

/// The B-BSMG generator: a press `(h_mm, alpha_rad, beta_rad)` to its footprint image
/// (`size × size`, ink = 1, in the `maobi stroke` canvas convention: `px_per_mm`, footprint
/// centred), and the exact gradient of any image loss back to the press.
#[pyclass(module = "maobi", name = "Generator", frozen)]
pub(crate) struct Generator {
    net: Arc<InputVjp>,
    profile: BrushProfile,
    size: usize,
    px_per_mm: f64,
}

impl Generator {
    /// The `(B, 3)` presses argument, checked against the brush's calibrated ranges (the
    /// generator was trained there) unless `extrapolate`.
    fn presses(&self, params: &Bound<'_, PyAny>, extrapolate: bool) -> PyResult<Vec<Press>> {
        let r = rows(params, "params", 3, "h_mm, alpha_rad, beta_rad per press")?;
        // The images are B × size² floats: bounded before anything is sized from B.
        let per = (self.size * self.size).max(1);
        if r.len() > MAX_BATCH_PIXELS / per {
            return Err(value_err(format!(
                "params: {} presses: expected at most {} in one call (their {s}×{s} px images; split the batch)",
                r.len(),
                MAX_BATCH_PIXELS / per,
                s = self.size
            )));
        }
        let out: Vec<Press> = r.iter().map(|v| Press::new(v[0], v[1], v[2])).collect();
        if !extrapolate {
            for (i, p) in out.iter().enumerate() {
                self.profile.predict(p, Extrapolation::Refuse).map_err(|e| match e {
                    brush_model::ProfileError::OutOfRange { quantity, value, min, max, .. } => value_err(format!(
                        "params[{i}]: {quantity} = {value:.6} is outside the range [{min:.6}, {max:.6}] the generator was trained on (pass extrapolate=True to use it anyway)"
                    )),
                    e => crate::brush::profile_err(&format!("params[{i}]"), e),
                })?;
            }
        }
        Ok(out)
    }
}

#[pymethods]
impl Generator {
    /// The generator saved at `path` (a `.safetensors` file with its `.json` config beside it,
    /// as `maobi train` writes them), or the committed pen1 generator when `path` is `None`.
    #[staticmethod]
    #[pyo3(signature = (path = None))]
    fn load(py: Python<'_>, path: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let p = path.filter(|p| !p.is_none()).map(|p| path_arg(p, "path")).transpose()?;
        if let Some(p) = &p {
            crate::arrays::input_file(&neural_gen::config_path(p), "path (its config)")?;
            crate::arrays::input_file(p, "path")?;
        }
        guarded(py, "Generator.load", move || {
            let g = match &p {
                Some(p) => neural_gen::Generator::load(p).map_err(|e| lib_err("path", e))?,
                None => neural_gen::Generator::pen1().map_err(|e| lib_err("the committed pen1 generator", e))?,
            };
            let net = g.kernels().map_err(|e| lib_err("Generator.load", e))?.clone();
            Ok(Self {
                net: Arc::new(net),
                size: g.config.size as usize,
                px_per_mm: g.config.px_per_mm,
                profile: g.config.profile.clone(),
            })
        })
    }

    /// Side of the images, px.
    #[getter]
    fn size(&self) -> usize {
        self.size
    }

    /// Scale of the images, px per mm.
    #[getter]
    fn px_per_mm(&self) -> f64 {
        self.px_per_mm
    }

    /// The brush the generator was trained for.
    #[getter]
    fn brush(&self) -> Brush {
        Brush { profile: self.profile.clone() }
    }

    /// Footprint images for a `(B, 3)` array of presses (`h_mm, alpha_rad, beta_rad`):
    /// `(B, size, size)` float32, ink = 1. Raises `ValueError` for a press outside the ranges
    /// the generator was trained on unless `extrapolate=True`.
    #[pyo3(signature = (params, *, extrapolate = false))]
    fn forward<'py>(
        &self,
        py: Python<'py>,
        params: &Bound<'py, PyAny>,
        extrapolate: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let presses = self.presses(params, extrapolate)?;
        let b = presses.len();
        let net = self.net.clone();
        let images = guarded(py, "Generator.forward", move || Ok(net.forward(&presses).into_images()))?;
        to_numpy(py, images, &[b, self.size, self.size])
    }

    /// The gradient of `Σ grad_images · forward(params)` with respect to `params`: for
    /// `grad_images` = ∂L/∂images (`(B, size, size)`), ∂L/∂(h_mm, alpha_rad, beta_rad) as a
    /// `(B, 3)` float64 array (per mm, per radian), by reverse-mode differentiation through
    /// the network (maobi's `InputVjp`).
    #[pyo3(signature = (params, grad_images, *, extrapolate = false))]
    fn vjp<'py>(
        &self,
        py: Python<'py>,
        params: &Bound<'py, PyAny>,
        grad_images: &Bound<'py, PyAny>,
        extrapolate: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let presses = self.presses(params, extrapolate)?;
        let b = presses.len();
        let up = crate::arrays::f64_array(grad_images, "grad_images")?;
        if up.shape != [b, self.size, self.size] {
            return Err(value_err(format!(
                "grad_images: shape {:?} (expected ({b}, {s}, {s}): one gradient image per press)",
                up.shape,
                s = self.size
            )));
        }
        crate::arrays::check_finite(&up, "grad_images")?;
        // The network runs in f32: a value beyond its range would become infinite there.
        if let Some(i) = up.data.iter().position(|v| v.abs() > f64::from(f32::MAX)) {
            return Err(value_err(format!(
                "grad_images{}: {} (expected values within ±{:e}, the network's f32 range)",
                crate::arrays::index_of(i, &up.shape),
                crate::arrays::num(up.data[i]),
                f32::MAX
            )));
        }
        let net = self.net.clone();
        let g = guarded(py, "Generator.vjp", move || {
            let upstream: Vec<f32> = up.data.iter().map(|&v| v as f32).collect();
            let tape = net.forward(&presses);
            net.vjp(&tape, &upstream).map_err(|e| lib_err("Generator.vjp", e))
        })?;
        to_numpy(py, g.into_iter().flatten().collect::<Vec<f64>>(), &[b, 3])
    }

    fn __repr__(&self) -> String {
        format!("maobi.Generator(brush {:?}, {}² px at {} px/mm)", self.profile.name, self.size, self.px_per_mm)
    }
}
