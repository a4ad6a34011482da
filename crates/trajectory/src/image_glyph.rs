//! Photos and scans of a character: Otsu threshold and cleaning.

use std::path::Path;

use bezier_raster::binary::{components, fill_holes, otsu_threshold};

use crate::glyph::GlyphError;

/// Loads, thresholds and cleans an image; returns the square side and the binary ink (1/0).
pub fn load_clean(path: &Path) -> Result<(u32, Vec<f32>), GlyphError> {
    let name = path.display().to_string();
    // Size-checked before decoding (bezier_raster::coverage::MAX_LOAD_PIXELS).
    let img =
        bezier_raster::coverage::open_image(path).map_err(|message| GlyphError::Io { path: name.clone(), message })?;
    let img = if img.width().max(img.height()) > 1024 {
        img.resize(1024, 1024, image::imageops::FilterType::Triangle)
    } else {
        img
    };
    let gray = img.to_luma8();
    let (w, h) = (gray.width() as usize, gray.height() as usize);
    if w < 16 || h < 16 {
        return Err(GlyphError::BadImage {
            path: name, message: format!("image is {w}×{h} px; need at least 16×16")
        });
    }
    let raw = gray.into_raw();
    let (lo, hi) = (raw.iter().min().copied().unwrap_or(0), raw.iter().max().copied().unwrap_or(0));
    if hi - lo < 32 {
        return Err(GlyphError::BadImage { path: name, message: "no ink: the image has almost no contrast".into() });
    }
    let t = otsu_threshold(&raw);
    let mut ink: Vec<bool> = raw.iter().map(|&v| v <= t).collect();
    let frac = ink.iter().filter(|&&b| b).count() as f64 / (w * h) as f64;
    if frac > 0.6 {
        return Err(GlyphError::BadImage {
            path: name,
            message: format!("{:.0}% of the image is ink; expected dark ink on light paper", 100.0 * frac),
        });
    }
    // Remove specks: ink components under 0.5 % of all ink.
    let total: usize = ink.iter().filter(|&&b| b).count();
    let (label, sizes) = components(&ink, w, h, true);
    for (i, v) in ink.iter_mut().enumerate() {
        if *v && (sizes[label[i] as usize] as f64) < 0.005 * total as f64 {
            *v = false;
        }
    }
    // Fill pinholes: enclosed paper under 0.05 % of the image.
    fill_holes(&mut ink, w, h, (0.0005 * (w * h) as f64).ceil() as usize);
    if !ink.iter().any(|&b| b) {
        return Err(GlyphError::BadImage { path: name, message: "no ink left after removing specks".into() });
    }
    // Pad to a square, centred.
    let side = w.max(h);
    let (ox, oy) = ((side - w) / 2, (side - h) / 2);
    let mut out = vec![0.0f32; side * side];
    for y in 0..h {
        for x in 0..w {
            if ink[y * w + x] {
                out[(y + oy) * side + x + ox] = 1.0;
            }
        }
    }
    Ok((side as u32, out))
}
