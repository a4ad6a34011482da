//! Synthetic scans of a glyph: a character rendered as a photographed or scanned copybook page
//! would show it (uneven light, paper texture, slight rotation, blur, JPEG), for tests and
//! measurements of `--image`. Deterministic for a seed.

use image::GrayImage;
use numerics::{Edge, Normalise, SplitMix64, gaussian_blur};
use thiserror::Error;

use crate::glyph::Glyph;
use crate::{distance, raster};

/// Errors from [`synth_scan`].
#[derive(Debug, Error)]
pub enum ScanError {
    /// An option is out of range.
    #[error("scan option {field}: {message}")]
    BadOption {
        /// The field.
        field: &'static str,
        /// What was expected.
        message: String,
    },
    /// JPEG encoding or decoding failed.
    #[error("cannot encode or decode the scan image")]
    Jpeg(#[source] image::ImageError),
}

/// How a synthetic scan is degraded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScanOptions {
    /// Side of the square image, px (32..=2048).
    pub size_px: u32,
    /// Side of the glyph's em box as a share of the image side (0.3..=1).
    pub em_fraction: f64,
    /// Rotation of the page about the image centre, radians (positive: clockwise on screen).
    pub rotation_rad: f64,
    /// Brightness lost from the lit side to the far side of the page (0..1).
    pub light_gradient: f64,
    /// Direction the light falls off towards, radians (0: to the right).
    pub light_angle_rad: f64,
    /// Brightness lost in the corners relative to the centre (0..1).
    pub vignette: f64,
    /// Paper texture amplitude, relative brightness (0..0.5): fibres at two scales plus grain.
    pub texture: f64,
    /// Gaussian blur σ of the optics, px (0 for none).
    pub blur_px: f64,
    /// Ink reflectance as a share of the paper's (0..1; 0 is black ink).
    pub ink_level: f64,
    /// JPEG quality (1..=100).
    pub jpeg_quality: u8,
    /// Seed of the texture noise.
    pub seed: u64,
}

impl Default for ScanOptions {
    fn default() -> Self {
        Self {
            size_px: 384,
            em_fraction: 0.8,
            rotation_rad: 0.0,
            light_gradient: 0.35,
            light_angle_rad: 0.0,
            vignette: 0.25,
            texture: 0.08,
            blur_px: 1.0,
            ink_level: 0.15,
            jpeg_quality: 70,
            seed: 0,
        }
    }
}

impl ScanOptions {
    /// The default degradations with a rotation drawn uniformly from ±3° and a light direction
    /// drawn uniformly from the circle, both from `seed`.
    pub fn seeded(seed: u64) -> Self {
        let mut r = SplitMix64(seed ^ 0x5CA7_5CA7);
        let rotation_rad = (r.next_f64() * 2.0 - 1.0) * 3f64.to_radians();
        let light_angle_rad = r.next_f64() * std::f64::consts::TAU;
        Self { rotation_rad, light_angle_rad, seed, ..Self::default() }
    }

    fn check(&self) -> Result<(), ScanError> {
        let bad = |field, message: &str| Err(ScanError::BadOption { field, message: message.to_string() });
        if !(32..=2048).contains(&self.size_px) {
            return bad("size_px", "expected 32..=2048");
        }
        if !(0.3..=1.0).contains(&self.em_fraction) {
            return bad("em_fraction", "expected 0.3..=1");
        }
        for (f, v, hi) in [
            ("light_gradient", self.light_gradient, 1.0),
            ("vignette", self.vignette, 1.0),
            ("texture", self.texture, 0.5),
            ("ink_level", self.ink_level, 1.0),
            ("blur_px", self.blur_px, 20.0),
        ] {
            if !(0.0..=hi).contains(&v) {
                return bad(f, &format!("expected 0..={hi}"));
            }
        }
        if !self.rotation_rad.is_finite() || !self.light_angle_rad.is_finite() {
            return bad("rotation_rad", "expected a finite angle");
        }
        if !(1..=100).contains(&self.jpeg_quality) {
            return bad("jpeg_quality", "expected 1..=100");
        }
        Ok(())
    }
}

/// Smooth value noise in [-1, 1] on an `n × n` image: random values on a grid every `cell` px,
/// interpolated bilinearly.
fn value_noise(n: usize, cell: usize, r: &mut SplitMix64) -> Vec<f32> {
    let g = n / cell + 2;
    let grid: Vec<f64> = (0..g * g).map(|_| r.next_f64() * 2.0 - 1.0).collect();
    let mut out = vec![0.0f32; n * n];
    for y in 0..n {
        for x in 0..n {
            let (fx, fy) = (x as f64 / cell as f64, y as f64 / cell as f64);
            let (x0, y0) = (fx.floor() as usize, fy.floor() as usize);
            let (tx, ty) = (fx - x0 as f64, fy - y0 as f64);
            let at = |i: usize, j: usize| grid[j * g + i];
            let v = (at(x0, y0) * (1.0 - tx) + at(x0 + 1, y0) * tx) * (1.0 - ty)
                + (at(x0, y0 + 1) * (1.0 - tx) + at(x0 + 1, y0 + 1) * tx) * ty;
            out[y * n + x] = v as f32;
        }
    }
    out
}

/// A synthetic scan of `g` as a JPEG file's bytes (8-bit grey): the em box centred on the page,
/// the page rotated, lit unevenly, with paper texture and optics blur, encoded at the given
/// quality. Ink is dark on light paper, as `--image` expects.
///
/// # Errors
/// [`ScanError::BadOption`] for options out of range; [`ScanError::Jpeg`] if encoding fails.
pub fn synth_scan(g: &Glyph, o: &ScanOptions) -> Result<Vec<u8>, ScanError> {
    o.check()?;
    let n = o.size_px as usize;
    let em_px = ((n as f64 * o.em_fraction).round() as u32).max(16);
    let cov = raster::render_glyph(g, em_px);
    let m = em_px as usize;
    // Ink on the page, rotated about the centre.
    let c = n as f64 / 2.0;
    let (s, co) = o.rotation_rad.sin_cos();
    let mut ink = vec![0.0f32; n * n];
    for y in 0..n {
        for x in 0..n {
            let (dx, dy) = (x as f64 + 0.5 - c, y as f64 + 0.5 - c);
            // Page point that lands here: rotate back.
            let (u, v) = (co * dx + s * dy + m as f64 / 2.0, -s * dx + co * dy + m as f64 / 2.0);
            if u < 0.0 || v < 0.0 || u >= m as f64 || v >= m as f64 {
                continue;
            }
            ink[y * n + x] = distance::sample(cov.data(), m, m, u, v) as f32;
        }
    }
    let ink = gaussian_blur(&ink, n, n, o.blur_px, Edge::Clamp, Normalise::Sum);
    let mut r = SplitMix64(o.seed);
    let fibres = value_noise(n, (n / 24).max(2), &mut r);
    let fine = value_noise(n, 3, &mut r);
    let (ls, lc) = o.light_angle_rad.sin_cos();
    let mut gray = Vec::with_capacity(n * n);
    for y in 0..n {
        for x in 0..n {
            let (px, py) = ((x as f64 + 0.5 - c) / c, (y as f64 + 0.5 - c) / c);
            let light = 1.0
                - o.light_gradient * (0.5 + 0.5 * (px * lc + py * ls).clamp(-1.0, 1.0))
                - o.vignette * (px * px + py * py) / 2.0;
            let grain = r.next_f64() * 2.0 - 1.0;
            let tex = 1.0 + o.texture * (0.6 * fibres[y * n + x] as f64 + 0.3 * fine[y * n + x] as f64 + 0.3 * grain);
            let paper = 0.93 * light * tex;
            let v = paper * (1.0 - (1.0 - o.ink_level) * ink[y * n + x] as f64);
            gray.push((v * 255.0).round().clamp(0.0, 255.0) as u8);
        }
    }
    let mut out = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, o.jpeg_quality)
        .encode(&gray, n as u32, n as u32, image::ExtendedColorType::L8)
        .map_err(ScanError::Jpeg)?;
    Ok(out)
}

/// Decodes a synthetic scan (or any JPEG/PNG bytes) to 8-bit grey.
///
/// # Errors
/// [`ScanError::Jpeg`] when the bytes are no image.
pub fn decode_gray(bytes: &[u8]) -> Result<GrayImage, ScanError> {
    Ok(image::load_from_memory(bytes).map_err(ScanError::Jpeg)?.to_luma8())
}
