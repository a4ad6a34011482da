//! Photos and scans of a character: the paper's uneven light divided out, Otsu threshold and
//! cleaning.

use std::path::Path;

use bezier_raster::{connected_components, fill_holes, otsu_threshold};
use image::GrayImage;

use super::{Glyph, GlyphError, GlyphSource, Shape};

/// Loads, thresholds and cleans an image; returns the square side and the binary ink (1/0).
pub(crate) fn load_clean(path: &Path) -> Result<(u32, Vec<f32>), GlyphError> {
    let name = path.display().to_string();
    // Size-checked before decoding (bezier_raster::MAX_LOAD_PIXELS).
    let img = bezier_raster::decode_image(path)
        .map_err(|source| GlyphError::Image { path: path.to_path_buf(), source: std::sync::Arc::new(source) })?;
    clean_gray(&name, on_white(&img))
}

/// An image's grey levels as printed on white paper: transparency composited on white, so ink
/// drawn only in the alpha channel (black or any colour, alpha = ink) reads as ink, as it does
/// in every viewer; an opaque image is its plain grey.
fn on_white(img: &image::DynamicImage) -> GrayImage {
    if !img.color().has_alpha() {
        return img.to_luma8();
    }
    let la = img.to_luma_alpha8();
    let (w, h) = la.dimensions();
    let grey = la.pixels().map(|p| {
        let (l, a) = (p.0[0] as u32, p.0[1] as u32);
        ((l * a + 255 * (255 - a) + 127) / 255) as u8
    });
    GrayImage::from_raw(w, h, grey.collect()).expect("one grey byte per pixel")
}

/// A glyph from an 8-bit grey photo or scan already in memory (dark ink on light paper), cleaned
/// as [`crate::glyph_from_image`] cleans a file; `name` labels the source in messages and in
/// [`GlyphSource::Image`].
///
/// # Errors
/// [`GlyphError::BadImage`] for an image too small, without contrast, or with no usable ink.
pub fn glyph_from_gray(ch: char, name: &str, gray: &GrayImage) -> Result<Glyph, GlyphError> {
    let (size, ink) = clean_gray(name, gray.clone())?;
    Ok(Glyph {
        ch,
        source: GlyphSource::Image(name.to_string()),
        shape: Shape::Bitmap { size, ink },
        stroke_outlines: None,
        medians: None,
    })
}

/// The paper's brightness under each pixel of a `w × h` grey image: per block (1/32 of the
/// longer side) the 90th percentile, the brightest within ±2 blocks (so ink up to about four
/// blocks wide is bridged), smoothed, never below 0.45 of the whole image's 90th percentile,
/// interpolated bilinearly between block centres.
fn paper_level(raw: &[u8], w: usize, h: usize) -> Vec<f32> {
    let b = (w.max(h) / 32).max(4);
    let (gw, gh) = (w.div_ceil(b), h.div_ceil(b));
    let pct90 = |vals: &mut [u8]| -> f32 {
        vals.sort_unstable();
        vals[((vals.len() - 1) as f64 * 0.9).round() as usize] as f32
    };
    let floor = 0.45 * pct90(&mut raw.to_vec());
    let mut grid = vec![0.0f32; gw * gh];
    numerics::for_each_block(raw, w, h, b, |gx, gy, vals| grid[gy * gw + gx] = pct90(vals));
    let filt = |g: &[f32], r: i64, max: bool| -> Vec<f32> {
        let mut out = vec![0.0f32; gw * gh];
        for y in 0..gh as i64 {
            for x in 0..gw as i64 {
                let (mut acc, mut k) = (0.0f32, 0);
                for yy in (y - r).max(0)..=(y + r).min(gh as i64 - 1) {
                    for xx in (x - r).max(0)..=(x + r).min(gw as i64 - 1) {
                        let v = g[yy as usize * gw + xx as usize];
                        if max {
                            acc = acc.max(v)
                        } else {
                            acc += v
                        }
                        k += 1;
                    }
                }
                out[y as usize * gw + x as usize] = if max { acc } else { acc / k as f32 };
            }
        }
        out
    };
    let grid = filt(&filt(&filt(&grid, 2, true), 1, false), 1, false);
    let mut out = Vec::with_capacity(w * h);
    for y in 0..h {
        let fy = ((y as f64 + 0.5) / b as f64 - 0.5).clamp(0.0, (gh - 1) as f64);
        let (y0, ty) = (fy.floor() as usize, fy - fy.floor());
        let y1 = (y0 + 1).min(gh - 1);
        for x in 0..w {
            let fx = ((x as f64 + 0.5) / b as f64 - 0.5).clamp(0.0, (gw - 1) as f64);
            let (x0, tx) = (fx.floor() as usize, fx - fx.floor());
            let x1 = (x0 + 1).min(gw - 1);
            let at = |i: usize, j: usize| grid[j * gw + i] as f64;
            let v = (at(x0, y0) * (1.0 - tx) + at(x1, y0) * tx) * (1.0 - ty)
                + (at(x0, y1) * (1.0 - tx) + at(x1, y1) * tx) * ty;
            out.push((v as f32).max(floor).max(1.0));
        }
    }
    out
}

/// Thresholds and cleans a grey image (see [`load_clean`]).
fn clean_gray(name: &str, gray: GrayImage) -> Result<(u32, Vec<f32>), GlyphError> {
    let name = std::path::PathBuf::from(name);
    let gray = if gray.width().max(gray.height()) > 1024 {
        // Longer side to 1024 px, aspect kept (as `DynamicImage::resize` does).
        let k = 1024.0 / gray.width().max(gray.height()) as f64;
        let (nw, nh) =
            (((gray.width() as f64 * k).round() as u32).max(1), ((gray.height() as f64 * k).round() as u32).max(1));
        image::imageops::resize(&gray, nw, nh, image::imageops::FilterType::Triangle)
    } else {
        gray
    };
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
    // Divide out uneven light (a lamp to one side, a vignette) so one threshold fits the page.
    let paper = paper_level(&raw, w, h);
    let raw: Vec<u8> = raw.iter().zip(&paper).map(|(&v, &p)| (255.0 * (v as f32 / p).min(1.0)).round() as u8).collect();
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
    let (label, sizes) = connected_components(&ink, w, h, true);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A 64×64 RGBA image of black (or white) RGB everywhere, alpha 255 on a bar and `bg_alpha`
    /// elsewhere.
    fn bar(rgb: u8, bg_alpha: u8) -> image::DynamicImage {
        image::DynamicImage::ImageRgba8(image::RgbaImage::from_fn(64, 64, |x, y| {
            let a = if (28..36).contains(&x) && (8..56).contains(&y) { 255 } else { bg_alpha };
            image::Rgba([rgb, rgb, rgb, a])
        }))
    }

    #[test]
    fn ink_in_the_alpha_channel_is_ink_on_white() {
        // Black RGB, alpha = ink: plain grey conversion sees an all-black image.
        let img = bar(0, 0);
        assert!(matches!(clean_gray("t", img.to_luma8()), Err(GlyphError::BadImage { .. })));
        let (side, ink) = clean_gray("t", on_white(&img)).unwrap();
        assert_eq!(side, 64);
        let on = |x: usize, y: usize| ink[y * 64 + x] > 0.5;
        assert!(on(32, 32) && on(29, 10), "the bar is ink");
        assert!(!on(5, 5) && !on(60, 32), "the transparent background is paper");
        let frac = ink.iter().filter(|&&v| v > 0.5).count() as f64 / ink.len() as f64;
        assert!((frac - 8.0 * 48.0 / 4096.0).abs() < 0.03, "ink share {frac}");
    }

    #[test]
    fn compositing_on_white_follows_alpha() {
        let table: &[(u8, u8, u8)] = &[(0, 255, 0), (0, 0, 255), (0, 128, 127), (200, 255, 200), (255, 0, 255)];
        for &(l, a, want) in table {
            let img = image::DynamicImage::ImageLumaA8(image::GrayAlphaImage::from_pixel(1, 1, image::LumaA([l, a])));
            assert_eq!(on_white(&img).get_pixel(0, 0).0[0], want, "grey {l} alpha {a}");
        }
        // An opaque image is its plain grey.
        let rgb = image::DynamicImage::ImageRgb8(image::RgbImage::from_pixel(2, 2, image::Rgb([10, 20, 30])));
        assert_eq!(on_white(&rgb), rgb.to_luma8());
        // White RGB: white on white, still no ink.
        assert!(clean_gray("t", on_white(&bar(255, 0))).is_err());
    }
}
