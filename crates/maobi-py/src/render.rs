//! Rendering presses and tracks, and the metrics.

use bezier_raster::{Coverage, ModelKind, Stamp, render_stamps};
use brush_model::{Extrapolation, PointMm, Press, ProfileError, TrackPoint};
use pyo3::prelude::*;
use trajectory::CharBox;

use crate::arrays::{image, num, rows, to_numpy};
use crate::brush::brush_arg;
use crate::errors::value_err;
use crate::{guarded, lib_err};

/// The most pixels one image may have (a 8192² image, 256 MiB of f32).
const MAX_PIXELS: u64 = 1 << 26;

/// `box_mm=`: the side of a square box whose top-left corner is the paper's origin, or
/// `(x0_mm, y0_mm, side_mm)`.
pub(crate) fn box_arg(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<CharBox> {
    let (x0, y0, side) = if let Ok(side) = obj.extract::<f64>() {
        (0.0, 0.0, side)
    } else if let Ok(t) = obj.extract::<(f64, f64, f64)>() {
        t
    } else {
        return Err(value_err(format!(
            "{name}: expected a side in mm or (x0_mm, y0_mm, side_mm), got {}",
            crate::arrays::type_name(obj)
        )));
    };
    if !(x0.is_finite() && y0.is_finite() && x0.abs() <= MAX_COORD_MM && y0.abs() <= MAX_COORD_MM) {
        return Err(value_err(format!(
            "{name}: corner ({}, {}) mm (expected finite, within ±{MAX_COORD_MM} mm)",
            num(x0),
            num(y0)
        )));
    }
    if !(side.is_finite() && side > 0.0 && side <= 10_000.0) {
        return Err(value_err(format!("{name}: side {} mm (expected a positive length of at most 10 m)", num(side))));
    }
    Ok(CharBox { x0_mm: x0, y0_mm: y0, size_mm: side })
}

/// The farthest a press or a box corner may lie from the paper's origin, mm (100 m): beyond
/// it, pixel coordinates overflow the rasteriser's integers.
pub(crate) const MAX_COORD_MM: f64 = 1e5;

/// The smallest pixel an image may have, mm (1 µm): a finer one puts pixel coordinates beyond
/// the rasteriser's integers.
const MIN_PX_MM: f64 = 1e-3;

/// Refuses a box whose pixels would be finer than [`MIN_PX_MM`] at `size` px, naming `name`.
pub(crate) fn check_scale(b: &CharBox, size: u32, name: &str) -> PyResult<()> {
    if !(b.size_mm.is_finite() && b.size_mm > 0.0 && b.size_mm <= 10_000.0) || b.size_mm / f64::from(size) < MIN_PX_MM {
        return Err(value_err(format!(
            "{name}: side {} mm at {size} px (expected a positive length of at most 10 m, and pixels of at least {MIN_PX_MM} mm)",
            num(b.size_mm)
        )));
    }
    if !(b.x0_mm.is_finite() && b.y0_mm.is_finite() && b.x0_mm.abs() <= MAX_COORD_MM && b.y0_mm.abs() <= MAX_COORD_MM) {
        return Err(value_err(format!(
            "{name}: corner ({}, {}) mm (expected finite, within ±{MAX_COORD_MM} mm)",
            num(b.x0_mm),
            num(b.y0_mm)
        )));
    }
    Ok(())
}

/// `size_px=`: the side of a square image.
pub(crate) fn size_arg(size_px: i64) -> PyResult<u32> {
    if size_px < 1 || (size_px as u64) * (size_px as u64) > MAX_PIXELS {
        return Err(value_err(format!("size_px={size_px}: expected 1 to 8192 px")));
    }
    Ok(size_px as u32)
}

/// `model=`: a stroke model by name.
pub(crate) fn model_arg(name: &str) -> PyResult<ModelKind> {
    name.parse::<ModelKind>().map_err(|e| value_err(format!("model={name:?}: {e}")))
}

/// An `(N, 5)` presses array: `x_mm, y_mm, h_mm, alpha_rad, beta_rad` per row.
fn presses_arg(obj: &Bound<'_, PyAny>) -> PyResult<Vec<TrackPoint>> {
    let r = rows(obj, "presses", 5, "x_mm, y_mm, h_mm, alpha_rad, beta_rad per press")?;
    if let Some(i) = r.iter().position(|p| p[0].abs() > MAX_COORD_MM || p[1].abs() > MAX_COORD_MM) {
        return Err(value_err(format!(
            "presses[{i}]: (x_mm, y_mm) = ({}, {}) (expected within ±{MAX_COORD_MM} mm of the paper's origin)",
            num(r[i][0]),
            num(r[i][1])
        )));
    }
    Ok(r.into_iter()
        .map(|r| TrackPoint { x_mm: r[0], y_mm: r[1], h_mm: r[2], alpha_rad: r[3], beta_rad: r[4] })
        .collect())
}

/// An image as a `(H, W)` float32 array, without a copy.
pub(crate) fn image_out<'py>(py: Python<'py>, c: Coverage) -> PyResult<Bound<'py, PyAny>> {
    let (w, h) = (c.width() as usize, c.height() as usize);
    to_numpy(py, c.into_vec(), &[h, w])
}

/// Renders presses with the analytic footprint (B-BSM by default): each row of `presses`
/// (`x_mm, y_mm, h_mm, alpha_rad, beta_rad`) is one footprint whose root end sits at
/// `(x_mm, y_mm)` on the paper, pointing along `beta_rad` (root → tip, radians from +x towards
/// +y, y down), its lengths the brush's at `(h_mm, alpha_rad, beta_rad)`; rows with
/// `h_mm <= 0` leave nothing. `box_mm` is the paper square the image shows (a side, its corner
/// at the origin, or `(x0_mm, y0_mm, side_mm)`), `size_px` its side in pixels. Footprints
/// compose by per-pixel maximum. Returns a `(size_px, size_px)` float32 image, ink = 1.
///
/// Raises `ValueError` for a press outside the brush's calibrated ranges (unless
/// `extrapolate=True`), a bad shape or a value that is not finite.
#[pyfunction]
#[pyo3(signature = (presses, box_mm, size_px, *, brush = None, model = "bsm", extrapolate = false))]
pub(crate) fn render_presses<'py>(
    py: Python<'py>,
    presses: &Bound<'py, PyAny>,
    box_mm: &Bound<'py, PyAny>,
    size_px: i64,
    brush: Option<&Bound<'py, PyAny>>,
    model: &str,
    extrapolate: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let PressesRender { pts, b, size, profile } = PressesRender::new(presses, box_mm, size_px, brush)?;
    let kind = model_arg(model)?;
    let ex = if extrapolate { Extrapolation::Allow } else { Extrapolation::Refuse };
    let img = guarded(py, "render_presses", move || {
        check_ranges(&pts, &profile, extrapolate)?;
        let mut stamps = Vec::with_capacity(pts.len());
        for (i, p) in pts.iter().enumerate().filter(|(_, p)| p.is_pressed()) {
            let fp = profile
                .predict_oriented(&Press::new(p.h_mm, p.alpha_rad, p.beta_rad), ex)
                .map_err(|e| crate::brush::profile_err(&format!("presses[{i}]"), e))?;
            stamps.push(Stamp { footprint: fp, anchor: p.anchor(), beta_rad: p.beta_rad });
        }
        Ok(render_stamps(&stamps, kind.model(), PointMm::new(b.x0_mm, b.y0_mm), size as f64 / b.size_mm, size, size))
    })?;
    image_out(py, img)
}

/// The arguments the three press renderers share, checked in the order their errors are
/// raised: `presses`, `box_mm`, `size_px`, the box's scale at that size, `brush`.
struct PressesRender {
    /// The presses, one per row.
    pts: Vec<TrackPoint>,
    /// The paper square the image shows.
    b: CharBox,
    /// The image's side, px.
    size: u32,
    /// The brush (the default one when none was given).
    profile: brush_model::BrushProfile,
}

impl PressesRender {
    /// Reads and checks `presses`, `box_mm`, `size_px` and `brush`.
    fn new(
        presses: &Bound<'_, PyAny>,
        box_mm: &Bound<'_, PyAny>,
        size_px: i64,
        brush: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let pts = presses_arg(presses)?;
        let b = box_arg(box_mm, "box_mm")?;
        let size = size_arg(size_px)?;
        check_scale(&b, size, "box_mm")?;
        let profile = brush_arg(brush)?;
        Ok(PressesRender { pts, b, size, profile })
    }
}

/// The soft canvas of a box at `size` px.
fn canvas(b: &CharBox, size: u32, edge_px: f64) -> PyResult<track_refine::SoftCanvas> {
    if !(edge_px.is_finite() && edge_px > 0.0 && edge_px <= 16.0) {
        return Err(value_err(format!("edge_px={edge_px}: expected a half-width above 0 and at most 16 px")));
    }
    Ok(track_refine::SoftCanvas {
        width: size,
        height: size,
        origin_mm: PointMm::new(b.x0_mm, b.y0_mm),
        mm_per_px: b.size_mm / size as f64,
        edge_px,
    })
}

/// Refuses presses outside the brush's calibrated ranges (unless extrapolating).
fn check_ranges(pts: &[TrackPoint], profile: &brush_model::BrushProfile, extrapolate: bool) -> PyResult<()> {
    if extrapolate {
        return Ok(());
    }
    for (i, p) in pts.iter().enumerate().filter(|(_, p)| p.is_pressed()) {
        profile.predict_oriented(&p.press(), Extrapolation::Refuse).map_err(|e| match e {
            ProfileError::OutOfRange { profile, quantity, value, min, max } => value_err(format!(
                "presses[{i}]: {quantity} = {value:.6} is outside the calibrated range [{min:.6}, {max:.6}] of brush `{profile}` (pass extrapolate=True to use it anyway)"
            )),
            e => crate::brush::profile_err(&format!("presses[{i}]"), e),
        })?;
    }
    Ok(())
}

/// Renders presses with the soft footprint that track refinement optimises (the B-BSM teardrop
/// with its edge softened over `edge_px` pixels each side; the union `1 − Π(1 − c)`), as
/// `render_presses` places them. Differentiable: `render_presses_soft_vjp` is its
/// vector–Jacobian product. Returns a `(size_px, size_px)` float64 image, ink = 1.
#[pyfunction]
#[pyo3(signature = (presses, box_mm, size_px, *, brush = None, edge_px = 0.75, extrapolate = false))]
pub(crate) fn render_presses_soft<'py>(
    py: Python<'py>,
    presses: &Bound<'py, PyAny>,
    box_mm: &Bound<'py, PyAny>,
    size_px: i64,
    brush: Option<&Bound<'py, PyAny>>,
    edge_px: f64,
    extrapolate: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let PressesRender { pts, b, size, profile } = PressesRender::new(presses, box_mm, size_px, brush)?;
    let c = canvas(&b, size, edge_px)?;
    let img = guarded(py, "render_presses_soft", move || {
        check_ranges(&pts, &profile, extrapolate)?;
        track_refine::soft_render(&pts, &profile, &c).map_err(|e| lib_err("render_presses_soft", e))
    })?;
    to_numpy(py, img, &[size as usize, size as usize])
}

/// The vector–Jacobian product of `render_presses_soft`: for `grad_image` = ∂L/∂image
/// (`(size_px, size_px)`), returns `(image, grad_presses)`, `grad_presses` the `(N, 5)` array
/// ∂L/∂(x_mm, y_mm, h_mm, alpha_rad, beta_rad) (per mm and per radian), in closed form (the
/// analytic soft-footprint derivatives of track refinement). Rows with `h_mm <= 0` get zeros.
#[pyfunction]
#[pyo3(signature = (presses, box_mm, size_px, grad_image, *, brush = None, edge_px = 0.75, extrapolate = false))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn render_presses_soft_vjp<'py>(
    py: Python<'py>,
    presses: &Bound<'py, PyAny>,
    box_mm: &Bound<'py, PyAny>,
    size_px: i64,
    grad_image: &Bound<'py, PyAny>,
    brush: Option<&Bound<'py, PyAny>>,
    edge_px: f64,
    extrapolate: bool,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let PressesRender { pts, b, size, profile } = PressesRender::new(presses, box_mm, size_px, brush)?;
    let c = canvas(&b, size, edge_px)?;
    let up = crate::arrays::f64_array(grad_image, "grad_image")?;
    if up.shape != [size as usize, size as usize] {
        return Err(value_err(format!("grad_image: shape {:?} (expected ({size}, {size}), the image's)", up.shape)));
    }
    crate::arrays::check_finite(&up, "grad_image")?;
    let n = pts.len();
    let (img, grads) = guarded(py, "render_presses_soft_vjp", move || {
        check_ranges(&pts, &profile, extrapolate)?;
        track_refine::soft_render_vjp(&pts, &profile, &c, &up.data).map_err(|e| lib_err("render_presses_soft_vjp", e))
    })?;
    let flat: Vec<f64> = grads.into_iter().flatten().collect();
    Ok((to_numpy(py, img, &[size as usize, size as usize])?, to_numpy(py, flat, &[n, 5])?))
}

/// Renders a track through the forward model of the moving brush, as `maobi write` renders its
/// plan (render.png): the footprints the brush leaves along every stroke, directions from the
/// motion. `box_mm` defaults to the track's character box, `brush` to the track's brush;
/// returns a `(size_px, size_px)` float32 image, ink = 1.
#[pyfunction]
#[pyo3(signature = (track, *, size_px = 512, box_mm = None, brush = None, model = "bsm"))]
pub(crate) fn render_track<'py>(
    py: Python<'py>,
    track: &Bound<'py, crate::write::Track>,
    size_px: i64,
    box_mm: Option<&Bound<'py, PyAny>>,
    brush: Option<&Bound<'py, PyAny>>,
    model: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let t = track.get().file.clone();
    let b = match box_mm.filter(|o| !o.is_none()) {
        Some(o) => box_arg(o, "box_mm")?,
        None => match t.char_box_mm {
            Some([x0, y0, s]) => CharBox { x0_mm: x0, y0_mm: y0, size_mm: s },
            None => return Err(value_err("box_mm: the track records no character box: give box_mm")),
        },
    };
    let size = size_arg(size_px)?;
    let what = if box_mm.is_some_and(|o| !o.is_none()) { "box_mm" } else { "track: char_box_mm" };
    check_scale(&b, size, what)?;
    let profile = match brush.filter(|o| !o.is_none()) {
        Some(_) => brush_arg(brush)?,
        None => t.brush.clone(),
    };
    let kind = model_arg(model)?;
    let img = guarded(py, "render_track", move || {
        pipeline::render_char(&t.track(), &profile, kind, Extrapolation::Refuse, &b, size).map_err(|e| match e {
            pipeline::Error::Profile(p) => crate::brush::profile_err("track", p),
            e => lib_err("render_track", e),
        })
    })?;
    image_out(py, img)
}

/// An image's values, height and width.
type Image = (Vec<f32>, usize, usize);

/// Two images of one size, checked, as `f32`.
fn pair(a: &Bound<'_, PyAny>, b: &Bound<'_, PyAny>) -> PyResult<(Image, Vec<f32>)> {
    let ia = image(a, "a")?;
    let ib = image(b, "b")?;
    if (ia.1, ia.2) != (ib.1, ib.2) {
        return Err(value_err(format!(
            "a is {}×{} px, b is {}×{} px: expected images of one size",
            ia.2, ia.1, ib.2, ib.1
        )));
    }
    Ok((ia, ib.0))
}

/// `f` of two images of one size (the GIL released), its errors named after `what`.
fn metric<T: Send>(
    py: Python<'_>,
    a: &Bound<'_, PyAny>,
    b: &Bound<'_, PyAny>,
    what: &'static str,
    f: fn(stroke_metrics::GrayRef<'_>, stroke_metrics::GrayRef<'_>) -> Result<T, stroke_metrics::MetricsError>,
) -> PyResult<T> {
    let ((da, h, w), db) = pair(a, b)?;
    guarded(py, what, move || {
        let ga = stroke_metrics::GrayRef::new(&da, w, h).map_err(|e| lib_err(what, e))?;
        let gb = stroke_metrics::GrayRef::new(&db, w, h).map_err(|e| lib_err(what, e))?;
        f(ga, gb).map_err(|e| lib_err(what, e))
    })
}

/// Cosine similarity of two `(H, W)` images (ink = 1), as `maobi compare`.
#[pyfunction]
pub(crate) fn csim(py: Python<'_>, a: &Bound<'_, PyAny>, b: &Bound<'_, PyAny>) -> PyResult<f64> {
    metric(py, a, b, "csim", stroke_metrics::csim)
}

/// Structural similarity (SSIM, Gaussian window σ = 1.5) of two `(H, W)` images (ink = 1), as
/// `maobi compare`.
#[pyfunction]
pub(crate) fn ssim(py: Python<'_>, a: &Bound<'_, PyAny>, b: &Bound<'_, PyAny>) -> PyResult<f64> {
    metric(py, a, b, "ssim", stroke_metrics::ssim)
}

/// Intersection over union of two `(H, W)` images thresholded at 0.5, as `maobi compare`.
#[pyfunction]
pub(crate) fn iou(py: Python<'_>, a: &Bound<'_, PyAny>, b: &Bound<'_, PyAny>) -> PyResult<f64> {
    metric(py, a, b, "iou", stroke_metrics::iou)
}

/// Every figure of `maobi compare --json` for two `(H, W)` images (ink = 1):
/// `{"csim", "ssim", "iou", "mse", "psnr"}` (`psnr` in dB, `None` for identical images); with
/// paths instead of arrays, the images are read as the CLI reads them (dark ink on light paper).
#[pyfunction]
pub(crate) fn compare<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let load = |o: &Bound<'py, PyAny>, name: &str| -> PyResult<Bound<'py, PyAny>> {
        if o.extract::<String>().is_ok() || o.hasattr("__fspath__").unwrap_or(false) {
            let p = crate::arrays::input_path(o, name)?;
            let c = Coverage::load(&p).map_err(|e| lib_err(name, e))?;
            image_out(py, c)
        } else {
            Ok(o.clone())
        }
    };
    let (a, b) = (load(a, "a")?, load(b, "b")?);
    let s = metric(py, &a, &b, "compare", stroke_metrics::compare)?;
    let v = serde_json::to_value(s).map_err(|e| lib_err("compare", e))?;
    crate::arrays::json_to_py(py, &v)
}
