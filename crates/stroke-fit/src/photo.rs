//! Loading a stroke photo: grey levels, scale from metadata, background flattening, Otsu
//! threshold, and the one ink blob.

use std::path::{Path, PathBuf};

use bezier_raster::{ImageFileError, decode_image};
use bezier_raster::{connected_components, fill_holes, otsu_threshold};
use thiserror::Error;

/// Errors from reading and normalising a photo. Each names the file.
#[derive(Debug, Error)]
pub enum PhotoError {
    /// The file cannot be read or decoded.
    #[error("{}: cannot read image", path.display())]
    Image {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: ImageFileError,
    },
    /// The image shows no ink.
    #[error("{}: no ink found (the image has no dark stroke on light paper)", path.display())]
    NoInk {
        /// The file.
        path: PathBuf,
    },
    /// The image is mostly ink.
    #[error("{}: {percent:.0}% of the image is ink; expected one dark stroke on light paper", path.display())]
    AllInk {
        /// The file.
        path: PathBuf,
        /// Ink share, %.
        percent: f64,
    },
    /// More than one large ink blob.
    #[error(
        "{}: {count} large ink blobs (the second is {ratio:.0}% of the largest); expected one stroke per image",
        path.display()
    )]
    SeveralBlobs {
        /// The file.
        path: PathBuf,
        /// Blobs at least 20 % of the largest.
        count: usize,
        /// Second largest over largest, %.
        ratio: f64,
    },
    /// No scale given and none in the file.
    #[error("{path}: no scale: none was given and the file stores no resolution (PNG pHYs or JPEG density)")]
    NoScale {
        /// The file.
        path: String,
    },
}

/// A normalised stroke photo: the ink mask of its one stroke.
#[derive(Clone, Debug)]
pub struct InkMask {
    /// Width, px.
    pub width: usize,
    /// Height, px.
    pub height: usize,
    /// `true` where the stroke is.
    pub ink: Vec<bool>,
    /// The photo's grey levels (0 black … 1 white), for overlays.
    pub gray: Vec<f32>,
}

/// The scale stored in an image file, px per mm: PNG `pHYs` (per metre) or JPEG JFIF density
/// (dpi or dots per cm). `None` when the file has none.
pub fn scale_from_metadata(path: &Path) -> Option<f64> {
    let bytes = std::fs::read(path).ok()?;
    if bytes.starts_with(b"\x89PNG") {
        let dec = png::Decoder::new(std::io::Cursor::new(&bytes)).read_info().ok()?;
        let d = dec.info().pixel_dims?;
        return (d.unit == png::Unit::Meter && d.xppu > 0).then(|| d.xppu as f64 / 1000.0);
    }
    if bytes.starts_with(&[0xFF, 0xD8]) {
        // APP0 JFIF: FF E0, length, "JFIF\0", version (2), units (1), Xdensity (2), Ydensity (2).
        let i = bytes.windows(5).position(|w| w == b"JFIF\0")?;
        let units = *bytes.get(i + 7)?;
        let x = u16::from_be_bytes([*bytes.get(i + 8)?, *bytes.get(i + 9)?]) as f64;
        return match units {
            1 if x > 1.0 => Some(x / 25.4),
            2 if x > 1.0 => Some(x / 10.0),
            _ => None,
        };
    }
    None
}

/// Loads a photo and isolates its stroke: grey levels, background flattened (each pixel divided
/// by a plane fitted to the paper's brightness), Otsu threshold, specks removed,
/// pinholes filled, the largest blob kept.
///
/// # Errors
/// [`PhotoError`] for unreadable files, no ink, mostly ink, or several large blobs.
pub fn load_ink(path: &Path) -> Result<InkMask, PhotoError> {
    // Size-checked before decoding (bezier_raster::MAX_LOAD_PIXELS).
    let img = decode_image(path).map_err(|source| PhotoError::Image { path: path.to_path_buf(), source })?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    mask_from_gray(gray_on_white(&img), w, h, path)
}

/// Grey levels (0 black … 1 white) of an image as printed on white paper: transparency is
/// composited on white, so a stroke drawn only in the alpha channel (black RGB, alpha = ink)
/// reads as ink rather than as an all-black image.
fn gray_on_white(img: &image::DynamicImage) -> Vec<f32> {
    if !img.color().has_alpha() {
        return img.to_luma32f().into_raw();
    }
    let la = img.to_luma_alpha32f();
    la.pixels().map(|p| p.0[0] * p.0[1] + (1.0 - p.0[1])).collect()
}

/// As [`load_ink`], from grey levels in memory (0 black … 1 white); `name` labels errors.
///
/// # Errors
/// As [`load_ink`].
pub fn mask_from_gray(gray: Vec<f32>, w: usize, h: usize, name: impl AsRef<Path>) -> Result<InkMask, PhotoError> {
    let name = name.as_ref();
    if w < 8 || h < 8 {
        return Err(PhotoError::NoInk { path: name.into() });
    }
    let flat = flatten_background(&gray, w, h);
    let lo = flat.iter().cloned().fold(f32::INFINITY, f32::min);
    let hi = flat.iter().cloned().fold(f32::NEG_INFINITY, f32::max);
    if hi - lo < 0.15 {
        // No contrast: blank paper, or all ink.
        let mean = gray.iter().sum::<f32>() / gray.len() as f32;
        return Err(if mean < 0.3 {
            PhotoError::AllInk { path: name.into(), percent: 100.0 }
        } else {
            PhotoError::NoInk { path: name.into() }
        });
    }
    let q: Vec<u8> = flat.iter().map(|v| (((v - lo) / (hi - lo)) * 255.0).round() as u8).collect();
    let t = otsu_threshold(&q);
    let mut ink: Vec<bool> = q.iter().map(|&v| v <= t).collect();
    let share = ink.iter().filter(|&&b| b).count() as f64 / (w * h) as f64;
    if share > 0.6 {
        return Err(PhotoError::AllInk { path: name.into(), percent: 100.0 * share });
    }
    let (label, sizes) = connected_components(&ink, w, h, true);
    let mut order: Vec<usize> = (1..sizes.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(sizes[i]));
    let Some(&big) = order.first() else { return Err(PhotoError::NoInk { path: name.into() }) };
    if sizes[big] < 20 {
        return Err(PhotoError::NoInk { path: name.into() });
    }
    let large = order.iter().filter(|&&i| sizes[i] as f64 >= 0.2 * sizes[big] as f64).count();
    if large > 1 {
        return Err(PhotoError::SeveralBlobs {
            path: name.into(),
            count: large,
            ratio: 100.0 * sizes[order[1]] as f64 / sizes[big] as f64,
        });
    }
    for (i, v) in ink.iter_mut().enumerate() {
        *v = label[i] as usize == big;
    }
    // Fill holes inside the blob.
    fill_holes(&mut ink, w, h, usize::MAX);
    Ok(InkMask { width: w, height: h, ink, gray })
}

/// Divides each pixel by the paper brightness there: per 32×32 block the 90th-percentile grey
/// level; blocks at least 80 % as bright as the brightest are paper; a plane fitted to those by
/// least squares models the lighting (scans and photos have smooth gradients), so blocks covered
/// by ink do not bias it.
fn flatten_background(g: &[f32], w: usize, h: usize) -> Vec<f32> {
    const B: usize = 32;
    let mut blocks = Vec::with_capacity(w.div_ceil(B) * h.div_ceil(B));
    numerics::for_each_block(g, w, h, B, |bx, by, vals| {
        vals.sort_by(f32::total_cmp);
        let cx = ((bx * B + ((bx + 1) * B).min(w)) as f64) / 2.0;
        let cy = ((by * B + ((by + 1) * B).min(h)) as f64) / 2.0;
        blocks.push((cx, cy, vals[((vals.len() - 1) as f32 * 0.9) as usize] as f64));
    });
    let top = blocks.iter().map(|b| b.2).fold(0.0, f64::max);
    let paper: Vec<_> = blocks.iter().filter(|b| b.2 >= 0.8 * top).collect();
    // Least squares for p(x, y) = a + b·x + c·y (normal equations, 3×3).
    let (mut m, mut r) = ([[0.0f64; 3]; 3], [0.0f64; 3]);
    for &&(x, y, v) in &paper {
        let f = [1.0, x, y];
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] += f[i] * f[j];
            }
            r[i] += f[i] * v;
        }
    }
    let coef = solve3(m, r).filter(|_| paper.len() >= 4).unwrap_or([top, 0.0, 0.0]);
    let mut out = vec![0.0f32; w * h];
    for y in 0..h {
        for x in 0..w {
            let p = (coef[0] + coef[1] * (x as f64 + 0.5) + coef[2] * (y as f64 + 0.5)).max(0.05);
            out[y * w + x] = (g[y * w + x] as f64 / p).min(1.0) as f32;
        }
    }
    out
}

/// Solves a 3×3 system by Cramer's rule; `None` when singular.
fn solve3(m: [[f64; 3]; 3], r: [f64; 3]) -> Option<[f64; 3]> {
    let det = |a: [[f64; 3]; 3]| {
        a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
            + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])
    };
    let d = det(m);
    if d.abs() < 1e-12 * (1.0 + m[0][0].abs()).powi(3) {
        return None;
    }
    let mut out = [0.0; 3];
    for (k, o) in out.iter_mut().enumerate() {
        let mut a = m;
        for i in 0..3 {
            a[i][k] = r[i];
        }
        *o = det(a) / d;
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stroke_in_the_alpha_channel_is_ink_on_white() {
        // Black RGB everywhere; the stroke is the opaque part.
        let img = image::DynamicImage::ImageRgba8(image::RgbaImage::from_fn(96, 64, |x, y| {
            let a = if (20..76).contains(&x) && (26..38).contains(&y) { 255 } else { 0 };
            image::Rgba([0, 0, 0, a])
        }));
        let plain = img.to_luma32f().into_raw();
        assert!(matches!(mask_from_gray(plain, 96, 64, "t.png"), Err(PhotoError::AllInk { .. })));
        let grey = gray_on_white(&img);
        assert_eq!((grey[0], grey[32 * 96 + 48]), (1.0, 0.0));
        let mask = mask_from_gray(grey, 96, 64, "t.png").expect("the stroke is found");
        let n = mask.ink.iter().filter(|&&b| b).count();
        assert!((500..=800).contains(&n), "{n} ink pixels for a 56×12 stroke");
    }
}
