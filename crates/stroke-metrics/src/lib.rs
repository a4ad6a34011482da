//! # stroke-metrics
//!
//! Similarity of two grayscale ink images, as the B-BSMG paper and maobi's gates measure it.
//! Images are `f32` buffers, row-major, **ink = 1.0, paper = 0.0**. Nothing here renders or
//! loads images; wrap your buffer in a [`GrayRef`].
//!
//! | metric | definition |
//! |---|---|
//! | [`csim`] | cosine similarity of the flattened images; both blank → 1, one blank → 0 |
//! | [`ssim`] | Wang et al. 2004: Gaussian window 11×11, σ = 1.5, K1 = 0.01, K2 = 0.03, L = 1, population variances, mean over the region 5 px inside each border; equals `skimage.metrics.structural_similarity(a, b, data_range=1.0, gaussian_weights=True, sigma=1.5, use_sample_covariance=False)` |
//! | [`iou`] | intersection over union of the two images thresholded at 0.5 (`v ≥ 0.5` is ink); both blank → 1 |
//! | [`mse`] | mean squared difference |
//! | [`psnr`] | `10·log10(1/MSE)` dB (data range 1); `+∞` for identical images |
//!
//! [`Summary`] gives best, worst, mean and count over many pairs, the layout of the paper's
//! tables.
//!
//! ```
//! use stroke_metrics::{GrayRef, ssim, csim};
//! let a: Vec<f32> = (0..32 * 32).map(|i| ((i % 32) as f32 / 31.0)).collect();
//! let img = GrayRef::new(&a, 32, 32).unwrap();
//! assert!((ssim(img, img).unwrap() - 1.0).abs() < 1e-12);
//! assert!((csim(img, img).unwrap() - 1.0).abs() < 1e-12);
//! ```

// The README's examples run as doctests (`cargo test --doc`).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

mod ssim;
mod summary;

use serde::{Deserialize, Serialize};
use thiserror::Error;

pub use ssim::{SSIM_RADIUS, SsimWorkspace, ssim};
pub use summary::Summary;

/// Errors from the metrics.
#[derive(Debug, Error, PartialEq, Eq)]
pub enum MetricsError {
    /// The buffer's length is not `width × height`.
    #[error("image buffer has {len} values, but {width}×{height} needs {}", width * height)]
    BadLength {
        /// Buffer length.
        len: usize,
        /// Declared width, px.
        width: usize,
        /// Declared height, px.
        height: usize,
    },
    /// The two images differ in size.
    #[error("images differ in size: {0}×{1} vs {2}×{3}")]
    SizeMismatch(usize, usize, usize, usize),
    /// The image is smaller than the SSIM window.
    #[error("SSIM needs images at least 11×11 px, got {0}×{1}")]
    TooSmall(usize, usize),
}

/// A borrowed grayscale image: `width × height` values, row-major, ink = 1.
#[derive(Clone, Copy, Debug)]
pub struct GrayRef<'a> {
    data: &'a [f32],
    width: usize,
    height: usize,
}

impl<'a> GrayRef<'a> {
    /// Wraps a buffer.
    ///
    /// # Errors
    /// [`MetricsError::BadLength`] if `data.len() != width·height`.
    pub fn new(data: &'a [f32], width: usize, height: usize) -> Result<Self, MetricsError> {
        if data.len() != width * height {
            return Err(MetricsError::BadLength { len: data.len(), width, height });
        }
        Ok(Self { data, width, height })
    }
    /// The values, row-major.
    pub fn data(&self) -> &'a [f32] {
        self.data
    }
    /// Width, px.
    pub fn width(&self) -> usize {
        self.width
    }
    /// Height, px.
    pub fn height(&self) -> usize {
        self.height
    }
    fn row(&self, y: usize) -> &'a [f32] {
        &self.data[y * self.width..(y + 1) * self.width]
    }
}

fn same_size(a: GrayRef<'_>, b: GrayRef<'_>) -> Result<(), MetricsError> {
    if a.width != b.width || a.height != b.height {
        return Err(MetricsError::SizeMismatch(a.width, a.height, b.width, b.height));
    }
    Ok(())
}

/// Cosine similarity of the two images as vectors. Both blank: 1; exactly one blank: 0.
///
/// # Examples
/// ```
/// use stroke_metrics::{GrayRef, csim};
/// let a = [1.0, 1.0, 0.0, 0.0];
/// let b = [1.0, 0.0, 0.0, 0.0];
/// let (a, b) = (GrayRef::new(&a, 2, 2).unwrap(), GrayRef::new(&b, 2, 2).unwrap());
/// // (1·1) / (√2 · 1)
/// assert!((csim(a, b).unwrap() - 0.5f64.sqrt()).abs() < 1e-12);
/// // Images of different sizes are an error, not a score.
/// let c = [0.0; 6];
/// assert!(csim(a, GrayRef::new(&c, 3, 2).unwrap()).is_err());
/// ```
///
/// # Errors
/// [`MetricsError::SizeMismatch`].
pub fn csim(a: GrayRef<'_>, b: GrayRef<'_>) -> Result<f64, MetricsError> {
    same_size(a, b)?;
    let (mut ab, mut aa, mut bb) = (0.0f64, 0.0f64, 0.0f64);
    for (&x, &y) in a.data.iter().zip(b.data) {
        let (x, y) = (x as f64, y as f64);
        ab += x * y;
        aa += x * x;
        bb += y * y;
    }
    Ok(match (aa > 0.0, bb > 0.0) {
        (false, false) => 1.0,
        (true, true) => (ab / (aa.sqrt() * bb.sqrt())).min(1.0),
        _ => 0.0,
    })
}

/// Intersection over union of the ink masks (`v ≥ 0.5`). Both blank: 1.
///
/// # Examples
/// ```
/// use stroke_metrics::{GrayRef, iou};
/// // Ink is v ≥ 0.5: a has pixels 0 and 1, b has pixels 1 and 2.
/// let a = [0.9, 0.5, 0.4, 0.0];
/// let b = [0.0, 1.0, 0.7, 0.1];
/// let (a, b) = (GrayRef::new(&a, 4, 1).unwrap(), GrayRef::new(&b, 4, 1).unwrap());
/// assert!((iou(a, b).unwrap() - 1.0 / 3.0).abs() < 1e-12);
/// ```
///
/// # Errors
/// [`MetricsError::SizeMismatch`].
pub fn iou(a: GrayRef<'_>, b: GrayRef<'_>) -> Result<f64, MetricsError> {
    same_size(a, b)?;
    let (mut inter, mut union) = (0usize, 0usize);
    for (&x, &y) in a.data.iter().zip(b.data) {
        let (p, q) = (x >= 0.5, y >= 0.5);
        inter += (p && q) as usize;
        union += (p || q) as usize;
    }
    Ok(if union == 0 { 1.0 } else { inter as f64 / union as f64 })
}

/// Mean squared difference.
///
/// # Errors
/// [`MetricsError::SizeMismatch`].
pub fn mse(a: GrayRef<'_>, b: GrayRef<'_>) -> Result<f64, MetricsError> {
    same_size(a, b)?;
    if a.data.is_empty() {
        return Ok(0.0);
    }
    let s: f64 = a.data.iter().zip(b.data).map(|(&x, &y)| (x as f64 - y as f64).powi(2)).sum();
    Ok(s / a.data.len() as f64)
}

/// Peak signal-to-noise ratio for data range 1, dB: `10·log10(1/MSE)`; `+∞` when identical.
///
/// # Errors
/// [`MetricsError::SizeMismatch`].
pub fn psnr(a: GrayRef<'_>, b: GrayRef<'_>) -> Result<f64, MetricsError> {
    let m = mse(a, b)?;
    Ok(if m == 0.0 { f64::INFINITY } else { -10.0 * m.log10() })
}

/// All five scores of one pair.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Scores {
    /// Cosine similarity.
    pub csim: f64,
    /// Structural similarity.
    pub ssim: f64,
    /// Intersection over union at 0.5.
    pub iou: f64,
    /// Mean squared error.
    pub mse: f64,
    /// PSNR in dB; `None` (JSON `null`) when the images are identical (infinite PSNR).
    pub psnr: Option<f64>,
}

/// Computes [`Scores`] for a pair.
///
/// # Errors
/// [`MetricsError::SizeMismatch`] or [`MetricsError::TooSmall`].
pub fn compare(a: GrayRef<'_>, b: GrayRef<'_>) -> Result<Scores, MetricsError> {
    let p = psnr(a, b)?;
    Ok(Scores {
        csim: csim(a, b)?,
        ssim: ssim(a, b)?,
        iou: iou(a, b)?,
        mse: mse(a, b)?,
        psnr: p.is_finite().then_some(p),
    })
}
