//! One footprint measured on the paper: a single press's ink, rectified from the photo, and the
//! B-BSM outline fitted to it.

use bezier_raster::connected_components;
use serde::Serialize;
use stroke_fit::{InkMask, fit_footprint};

use crate::{Frame, InkMap, ObserveError, Registration, rectify};

/// The finest scale a footprint's window is rectified at, px per paper mm (finer costs fitting
/// time for little).
pub const FOOTPRINT_MAX_PX_PER_MM: f64 = 10.0;

/// The coarsest scale a footprint's window is rectified at, px per paper mm.
pub const FOOTPRINT_MIN_PX_PER_MM: f64 = 4.0;

/// A blob of ink at least this share of the largest one in a window makes the window hold
/// several footprints.
const SECOND_BLOB_SHARE: f64 = 0.2;

/// A single footprint as measured on the paper (the lengths as `brush_model::Footprint`
/// defines them: the root end at the origin, the belly `lh_mm` along the axis with half-width
/// `lr_mm`, the tip `lt_mm` beyond it).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FootprintMeasure {
    /// Tip length (belly to tip), mm.
    pub lt_mm: f64,
    /// Root length (root end to belly), mm.
    pub lh_mm: f64,
    /// Belly half-width, mm.
    pub lr_mm: f64,
    /// The root end, paper mm.
    pub root_mm: [f64; 2],
    /// Direction root → tip, rad from paper +x towards +y.
    pub beta_rad: f64,
    /// IoU of the fitted outline with the ink (both thresholded at ½).
    pub iou: f64,
    /// The ink's area, mm².
    pub area_mm2: f64,
}

/// Measures the one footprint inside the paper box `window_mm` (`[x0, y0, x1, y1]`, mm): the
/// ink there is rectified through the registration at the photo's own scale
/// ([`Registration::px_per_mm`], kept within [`FOOTPRINT_MIN_PX_PER_MM`] and
/// [`FOOTPRINT_MAX_PX_PER_MM`]), thresholded at
/// ½ coverage, its largest blob kept, and the B-BSM outline fitted to it
/// (`stroke_fit::fit_footprint`: moments start, both ends tried as the root, Nelder–Mead on
/// soft IoU), so which end is the tip is decided by the shape.
///
/// # Errors
/// [`ObserveError::NoFootprint`] when the window holds no blob of ink,
/// [`ObserveError::SeveralFootprints`] when it holds a second blob at least a fifth the size
/// of the largest.
///
/// # Examples
/// ```
/// use bezier_raster::brush_model::{Footprint, PointMm};
/// use bezier_raster::{ModelKind, Stamp, render_stamps};
/// use observe::{Homography, InkMap, Registration, measure_footprint};
/// // A footprint rooted at paper (10, 20) mm pointing along +x, seen at 6 photo px per mm.
/// let fp = Footprint { lt_mm: 9.0, lh_mm: 4.0, lr_mm: 2.5 };
/// let stamp = Stamp { footprint: fp, anchor: PointMm::new(10.0, 20.0), beta_rad: 0.0 };
/// let ink = render_stamps(&[stamp], ModelKind::Bsm.model(), PointMm::new(0.0, 0.0), 6.0, 240, 240);
/// let map = InkMap { width: 240, height: 240, ink: ink.data().to_vec(), paper: vec![true; 240 * 240], ink_level: 0.1 };
/// let paper = [[0.0, 0.0], [40.0, 0.0], [40.0, 40.0], [0.0, 40.0]];
/// let photo = paper.map(|p| [6.0 * p[0], 6.0 * p[1]]);
/// let reg = Registration {
///     paper_to_photo: Homography::fit(&paper, &photo).expect("a square"),
///     marks: vec![],
///     residual_rms_mm: 0.0,
///     residual_max_mm: 0.0,
///     leave_one_out_max_mm: 0.0,
///     edge_mm: 0.0,
///     px_per_mm: 6.0,
///     corner_shift: 0,
/// };
/// let m = measure_footprint(&map, &reg, [5.0, 14.0, 30.0, 26.0])?;
/// assert!((m.lt_mm - 9.0).abs() < 0.2 && (m.lh_mm - 4.0).abs() < 0.2 && (m.lr_mm - 2.5).abs() < 0.1, "{m:?}");
/// assert!(m.beta_rad.abs() < 0.02 && (m.root_mm[0] - 10.0).abs() < 0.2, "{m:?}");
/// # Ok::<(), observe::ObserveError>(())
/// ```
pub fn measure_footprint(
    ink: &InkMap,
    reg: &Registration,
    window_mm: [f64; 4],
) -> Result<FootprintMeasure, ObserveError> {
    let [x0, y0, x1, y1] = window_mm;
    let scale = if reg.px_per_mm.is_finite() { reg.px_per_mm } else { FOOTPRINT_MIN_PX_PER_MM }
        .clamp(FOOTPRINT_MIN_PX_PER_MM, FOOTPRINT_MAX_PX_PER_MM);
    let frame = Frame {
        x0_mm: x0,
        y0_mm: y0,
        px_per_mm: scale,
        width: ((x1 - x0) * scale).ceil().max(1.0) as u32,
        height: ((y1 - y0) * scale).ceil().max(1.0) as u32,
    };
    let cov = rectify(ink, reg, &frame);
    let (w, h) = (frame.width as usize, frame.height as usize);
    let mask: Vec<bool> = cov.data().iter().map(|&c| c >= 0.5).collect();
    let (label, sizes) = connected_components(&mask, w, h, true);
    let mut order: Vec<usize> = (1..sizes.len()).filter(|&l| sizes[l] >= 20).collect();
    order.sort_by_key(|&l| std::cmp::Reverse(sizes[l]));
    let Some(&big) = order.first() else { return Err(ObserveError::NoFootprint { window_mm }) };
    if let Some(&second) = order.get(1) {
        let share = sizes[second] as f64 / sizes[big] as f64;
        if share >= SECOND_BLOB_SHARE {
            return Err(ObserveError::SeveralFootprints { window_mm, share });
        }
    }
    let keep: Vec<bool> = label.iter().map(|&l| l as usize == big).collect();
    let gray: Vec<f32> = cov.data().iter().map(|c| 1.0 - c).collect();
    let area_mm2 = sizes[big] as f64 / (scale * scale);
    let fit = fit_footprint(&InkMask { width: w, height: h, ink: keep, gray }, scale);
    Ok(FootprintMeasure {
        lt_mm: fit.lt_mm,
        lh_mm: fit.lh_mm,
        lr_mm: fit.lr_mm,
        root_mm: [x0 + fit.anchor_mm[0], y0 + fit.anchor_mm[1]],
        beta_rad: fit.beta_rad,
        iou: fit.iou,
        area_mm2,
    })
}
