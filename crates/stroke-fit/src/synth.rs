//! Synthetic stroke photos from known footprints, with what real scans have: blur, noise,
//! uneven paper, ink bleed, specks, JPEG compression. For tests and the sample calibration set.

use bezier_raster::{Bsm, Coverage, Rasterizer};
use brush_model::{Footprint, PointMm};
use numerics::{Edge, Normalise, SplitMix64, gaussian_blur};

/// How to spoil a clean footprint image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Degradation {
    /// Gaussian blur σ, px (0: none).
    pub blur_px: f64,
    /// Gaussian noise σ on grey levels (0…1).
    pub noise: f64,
    /// Paper brightness falls linearly by this much across the image (0: even).
    pub gradient: f64,
    /// Ink bleed: the outline grows by this many px.
    pub bleed_px: f64,
    /// Number of small specks (1–2 px) sprinkled on the paper.
    pub specks: usize,
    /// Re-encode as JPEG at this quality (None: lossless).
    pub jpeg_quality: Option<u8>,
}

impl Default for Degradation {
    fn default() -> Self {
        Self { blur_px: 1.2, noise: 0.04, gradient: 0.25, bleed_px: 0.0, specks: 4, jpeg_quality: Some(85) }
    }
}

/// A standard normal draw from `rng` (Box–Muller on half-open uniforms, the first floored at
/// 1e-12): the synthetic photos' noise, a stream of its own that fixtures record (numerics'
/// [`SplitMix64::normal`] uses open uniforms instead).
fn normal(rng: &mut SplitMix64) -> f64 {
    let (u, v) = (rng.next_f64().max(1e-12), rng.next_f64());
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

/// A grey photo (`width × height`, 0 black … 1 white) of `fp` with its root at `anchor_mm`
/// and direction `beta_rad`, at `px_per_mm`, spoiled by `d` with random `seed`.
#[allow(
    clippy::too_many_arguments,
    reason = "xtask's fixtures call this shape; grouping the placement (anchor, β) and the canvas (scale, size) is a change for both at once"
)]
///
/// # Examples
/// ```
/// use stroke_fit::brush_model::{Footprint, PointMm};
/// use stroke_fit::{Degradation, synthetic_photo};
/// let fp = Footprint { lt_mm: 6.0, lh_mm: 2.0, lr_mm: 1.5 };
/// let clean = Degradation { blur_px: 0.0, noise: 0.0, gradient: 0.0, bleed_px: 0.0, specks: 0, jpeg_quality: None };
/// let gray = synthetic_photo(&fp, PointMm::new(1.0, 5.0), 0.0, 10.0, 100, 100, &clean, 7);
/// assert_eq!(gray.len(), 100 * 100);
/// // Dark ink on light paper: the pixels darker than mid-grey cover the footprint's area.
/// let dark_px = gray.iter().filter(|g| **g < 0.5).count() as f64;
/// let area_px = fp.area_mm2() * 10.0 * 10.0;
/// assert!((dark_px - area_px).abs() < 0.05 * area_px);
/// // One seed, one photo.
/// assert_eq!(synthetic_photo(&fp, PointMm::new(1.0, 5.0), 0.0, 10.0, 100, 100, &Degradation::default(), 3),
///            synthetic_photo(&fp, PointMm::new(1.0, 5.0), 0.0, 10.0, 100, 100, &Degradation::default(), 3));
/// ```
pub fn synthetic_photo(
    fp: &Footprint,
    anchor_mm: PointMm,
    beta_rad: f64,
    px_per_mm: f64,
    width: u32,
    height: u32,
    d: &Degradation,
    seed: u64,
) -> Vec<f32> {
    let mut cov = Coverage::new(width, height);
    let grown = Footprint {
        lt_mm: fp.lt_mm + d.bleed_px / px_per_mm,
        lh_mm: fp.lh_mm + d.bleed_px / px_per_mm,
        lr_mm: fp.lr_mm + d.bleed_px / px_per_mm,
    };
    let anchor = PointMm::new(
        anchor_mm.x_mm - d.bleed_px / px_per_mm * beta_rad.cos(),
        anchor_mm.y_mm - d.bleed_px / px_per_mm * beta_rad.sin(),
    );
    Rasterizer::new().render(
        &Bsm,
        if d.bleed_px > 0.0 { &grown } else { fp },
        if d.bleed_px > 0.0 { anchor } else { anchor_mm },
        beta_rad,
        px_per_mm,
        &mut cov,
    );
    let (w, h) = (width as usize, height as usize);
    let mut ink: Vec<f64> = cov.data().iter().map(|&v| v as f64).collect();
    let mut rng = SplitMix64(seed);
    for _ in 0..d.specks {
        let (x, y) = ((rng.next_f64() * w as f64) as usize, (rng.next_f64() * h as f64) as usize);
        for (dx, dy) in [(0, 0), (1, 0), (0, 1)] {
            if x + dx < w && y + dy < h {
                ink[(y + dy) * w + x + dx] = 1.0;
            }
        }
    }
    if d.blur_px > 0.0 {
        ink = gaussian_blur(&ink, w, h, d.blur_px, Edge::Clamp, Normalise::Kernel);
    }
    let mut out = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let paper = 0.95 - d.gradient * (x as f64 / w as f64 * 0.7 + y as f64 / h as f64 * 0.3);
            let v = paper * (1.0 - 0.9 * ink[y * w + x]) + d.noise * normal(&mut rng);
            out.push(v.clamp(0.0, 1.0) as f32);
        }
    }
    if let Some(q) = d.jpeg_quality {
        let bytes: Vec<u8> = out.iter().map(|v| (v * 255.0).round() as u8).collect();
        let mut jpg = Vec::new();
        image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpg, q)
            .encode(&bytes, width, height, image::ExtendedColorType::L8)
            .expect("encodes");
        let back = image::load_from_memory(&jpg).expect("decodes").to_luma8();
        out = back.pixels().map(|p| p.0[0] as f32 / 255.0).collect();
    }
    out
}

/// Encodes grey levels as an 8-bit PNG that records its scale (`pHYs`, pixels per metre).
///
/// # Examples
/// ```
/// use stroke_fit::{load_ink, scale_from_metadata};
/// use stroke_fit::brush_model::{Footprint, PointMm};
/// use stroke_fit::{Degradation, png_with_scale, synthetic_photo};
/// let fp = Footprint { lt_mm: 6.0, lh_mm: 2.0, lr_mm: 1.5 };
/// let gray = synthetic_photo(&fp, PointMm::new(1.0, 5.0), 0.0, 12.5, 125, 125, &Degradation::default(), 1);
/// let path = std::env::temp_dir().join(format!("maobi-doc-stroke-{}.png", std::process::id()));
/// std::fs::write(&path, png_with_scale(&gray, 125, 125, 12.5)).unwrap();
/// // The file carries its scale, so a calibration photo needs no separate one.
/// let (scale, mask) = (scale_from_metadata(&path), load_ink(&path));
/// std::fs::remove_file(&path).unwrap();
/// assert!((scale.unwrap() - 12.5).abs() < 1e-9);
/// assert_eq!(mask.unwrap().width, 125);
/// ```
pub fn png_with_scale(gray: &[f32], width: u32, height: u32, px_per_mm: f64) -> Vec<u8> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, width, height);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_pixel_dims(Some(png::PixelDimensions {
            xppu: (px_per_mm * 1000.0).round() as u32,
            yppu: (px_per_mm * 1000.0).round() as u32,
            unit: png::Unit::Meter,
        }));
        let mut wr = enc.write_header().expect("header");
        let bytes: Vec<u8> = gray.iter().map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8).collect();
        wr.write_image_data(&bytes).expect("data");
    }
    out
}
