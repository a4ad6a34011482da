//! A photo as luminance, the sheet found in it, the paper's brightness flattened and the ink
//! separated.

use bezier_raster::{connected_components, fill_holes, otsu_threshold};
use image::DynamicImage;

use crate::ObserveError;

/// Photos with a longer side are reduced (by an integer factor, averaging) to at most this, px.
pub const MAX_PHOTO_SIDE: u32 = 3200;

/// A photo as luminance in `[0, 1]` (0 = black), row major.
#[derive(Clone, Debug)]
pub struct Photo {
    /// Width, px.
    pub width: usize,
    /// Height, px.
    pub height: usize,
    /// Luminance, `width × height`.
    pub luma: Vec<f32>,
    /// How many original pixels one pixel here spans along each side (1 unless reduced).
    pub reduced_by: u32,
}

impl Photo {
    /// The luminance of an image (Rec. 601 weights of its 8-bit RGB), reduced to at most
    /// [`MAX_PHOTO_SIDE`] a side.
    ///
    /// # Errors
    /// [`ObserveError::TooSmall`] below 200 px a side.
    pub fn from_image(img: &DynamicImage) -> Result<Self, ObserveError> {
        let (w, h) = (img.width(), img.height());
        if w < 200 || h < 200 {
            return Err(ObserveError::TooSmall { width: w, height: h });
        }
        let gray = img.to_luma8();
        let k = w.max(h).div_ceil(MAX_PHOTO_SIDE).max(1);
        let (ow, oh) = ((w / k) as usize, (h / k) as usize);
        let mut luma = vec![0f32; ow * oh];
        let inv = 1.0 / (255.0 * (k * k) as f32);
        for y in 0..oh {
            for x in 0..ow {
                let mut s = 0u32;
                for dy in 0..k {
                    for dx in 0..k {
                        s += gray.get_pixel(x as u32 * k + dx, y as u32 * k + dy)[0] as u32;
                    }
                }
                luma[y * ow + x] = s as f32 * inv;
            }
        }
        Ok(Photo { width: ow, height: oh, luma, reduced_by: k })
    }
}

/// The ink of a photo: coverage in `[0, 1]` per photo pixel (1 = ink, 0 = bare paper or off
/// the sheet), and the sheet's mask.
#[derive(Clone, Debug)]
pub struct InkMap {
    /// Width, px.
    pub width: usize,
    /// Height, px.
    pub height: usize,
    /// Ink coverage, `width × height`.
    pub ink: Vec<f32>,
    /// Whether each pixel is on the sheet.
    pub paper: Vec<bool>,
    /// The ink's brightness as a fraction of the paper's around it.
    pub ink_level: f32,
}

impl InkMap {
    /// Bilinear coverage at photo point `(x, y)` px (pixel centres at `i + 0.5`); 0 off the image.
    pub fn sample(&self, x: f64, y: f64) -> f32 {
        let (fx, fy) = (x - 0.5, y - 0.5);
        if !(fx >= 0.0 && fy >= 0.0) {
            return 0.0;
        }
        let (x0, y0) = (fx.floor() as usize, fy.floor() as usize);
        if x0 + 1 >= self.width || y0 + 1 >= self.height {
            return 0.0;
        }
        let (tx, ty) = ((fx - x0 as f64) as f32, (fy - y0 as f64) as f32);
        let i = y0 * self.width + x0;
        let a = self.ink[i] * (1.0 - tx) + self.ink[i + 1] * tx;
        let b = self.ink[i + self.width] * (1.0 - tx) + self.ink[i + self.width + 1] * tx;
        a * (1.0 - ty) + b * ty
    }
}

/// A box blur of radius `r` (two passes of running sums, edges clamped).
fn box_blur(src: &[f32], w: usize, h: usize, r: usize) -> Vec<f32> {
    let pass = |src: &[f32], len: usize, count: usize, stride: usize, step: usize| -> Vec<f32> {
        let mut out = vec![0f32; src.len()];
        for line in 0..count {
            let at = |i: isize| src[line * stride + (i.clamp(0, len as isize - 1) as usize) * step];
            let mut s: f32 = (-(r as isize)..=r as isize).map(at).sum();
            let n = (2 * r + 1) as f32;
            for i in 0..len {
                out[line * stride + i * step] = s / n;
                s += at(i as isize + r as isize + 1) - at(i as isize - r as isize);
            }
        }
        out
    };
    let a = pass(src, w, h, w, 1);
    pass(&a, h, w, 1, w)
}

/// Finds the sheet (the largest bright region, its holes filled), flattens the paper's
/// brightness and separates the ink.
///
/// The paper's brightness is the 90th percentile of the sheet's pixels in cells of a
/// 24-cell grid along the longer side, interpolated bilinearly; the ink's level is the median
/// brightness, relative to the paper, of the pixels darker than 0.55 of it; coverage is
/// `(1 − L/paper) / (1 − ink level)`, clamped to `[0, 1]`, and 0 within a few px of the
/// sheet's outline.
///
/// # Errors
/// [`ObserveError::NoPaper`] when no bright region covers a tenth of the photo.
pub fn ink_map(photo: &Photo) -> Result<InkMap, ObserveError> {
    let (w, h) = (photo.width, photo.height);
    // The sheet: bright against its background.
    let r = (w.max(h) / 400).max(1);
    let smooth = box_blur(&photo.luma, w, h, r);
    let bytes: Vec<u8> = smooth.iter().map(|v| (v.clamp(0.0, 1.0) * 255.0) as u8).collect();
    let t = otsu_threshold(&bytes);
    let bright: Vec<bool> = bytes.iter().map(|&v| v > t).collect();
    let (label, sizes) = connected_components(&bright, w, h, true);
    let (best, &size) = sizes.iter().enumerate().skip(1).max_by_key(|(_, s)| **s).ok_or(ObserveError::NoPaper)?;
    if size * 10 < w * h {
        return Err(ObserveError::NoPaper);
    }
    let mut paper: Vec<bool> = label.iter().map(|&l| l as usize == best).collect();
    fill_holes(&mut paper, w, h, usize::MAX);
    // The paper's brightness on a coarse grid.
    let cell = (w.max(h) / 24).max(8);
    let (gw, gh) = (w.div_ceil(cell), h.div_ceil(cell));
    let mut grid: Vec<Option<f32>> = vec![None; gw * gh];
    let mut vals = Vec::with_capacity(cell * cell);
    for gy in 0..gh {
        for gx in 0..gw {
            vals.clear();
            for y in gy * cell..((gy + 1) * cell).min(h) {
                for x in gx * cell..((gx + 1) * cell).min(w) {
                    if paper[y * w + x] && !bright_edge(&bright, w, h, x, y) {
                        vals.push(photo.luma[y * w + x]);
                    }
                }
            }
            if vals.len() * 4 >= cell * cell {
                let k = ((vals.len() * 9) / 10).min(vals.len() - 1);
                let (_, v, _) = vals.select_nth_unstable_by(k, |a, b| a.total_cmp(b));
                grid[gy * gw + gx] = Some(v.max(1e-3));
            }
        }
    }
    let grid = fill_grid(grid, gw, gh);
    let bg = |x: usize, y: usize| -> f32 {
        let fx = ((x as f32 + 0.5) / cell as f32 - 0.5).clamp(0.0, (gw - 1) as f32);
        let fy = ((y as f32 + 0.5) / cell as f32 - 0.5).clamp(0.0, (gh - 1) as f32);
        let (x0, y0) = (fx.floor() as usize, fy.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(gw - 1), (y0 + 1).min(gh - 1));
        let (tx, ty) = (fx - x0 as f32, fy - y0 as f32);
        let a = grid[y0 * gw + x0] * (1.0 - tx) + grid[y0 * gw + x1] * tx;
        let b = grid[y1 * gw + x0] * (1.0 - tx) + grid[y1 * gw + x1] * tx;
        a * (1.0 - ty) + b * ty
    };
    let mut rel = vec![1f32; w * h];
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            if paper[i] {
                rel[i] = photo.luma[i] / bg(x, y);
            }
        }
    }
    let mut dark: Vec<f32> = rel.iter().zip(&paper).filter(|(v, p)| **p && **v < 0.55).map(|(v, _)| *v).collect();
    let ink_level = if dark.is_empty() {
        0.1
    } else {
        let k = dark.len() / 2;
        *dark.select_nth_unstable_by(k, |a, b| a.total_cmp(b)).1
    }
    .clamp(0.0, 0.5);
    // No ink within a few px of the sheet's outline: there the background bleeds in.
    let inside = box_blur(&paper.iter().map(|&p| if p { 1.0 } else { 0.0 }).collect::<Vec<f32>>(), w, h, 2 * r + 2);
    let ink = rel
        .iter()
        .zip(&inside)
        .map(|(v, p)| if *p > 0.999 { ((1.0 - v) / (1.0 - ink_level)).clamp(0.0, 1.0) } else { 0.0 })
        .collect();
    Ok(InkMap { width: w, height: h, ink, paper, ink_level })
}

/// Whether `(x, y)` lies within 2 px of the sheet's outline (its brightness mixes with the
/// background's there).
fn bright_edge(bright: &[bool], w: usize, h: usize, x: usize, y: usize) -> bool {
    let (x0, x1, y0, y1) = (x.saturating_sub(2), (x + 2).min(w - 1), y.saturating_sub(2), (y + 2).min(h - 1));
    (y0..=y1).any(|yy| (x0..=x1).any(|xx| !bright[yy * w + xx])) && bright[y * w + x]
}

/// Fills the cells without enough paper from their neighbours, nearest first.
fn fill_grid(mut grid: Vec<Option<f32>>, gw: usize, gh: usize) -> Vec<f32> {
    if grid.iter().all(Option::is_none) {
        return vec![1.0; gw * gh];
    }
    while grid.iter().any(Option::is_none) {
        let prev = grid.clone();
        for y in 0..gh {
            for x in 0..gw {
                if prev[y * gw + x].is_some() {
                    continue;
                }
                let mut s = 0.0;
                let mut n = 0;
                for (dx, dy) in [(-1i32, 0i32), (1, 0), (0, -1), (0, 1)] {
                    let (nx, ny) = (x as i32 + dx, y as i32 + dy);
                    if nx >= 0 && ny >= 0 && (nx as usize) < gw && (ny as usize) < gh {
                        if let Some(v) = prev[ny as usize * gw + nx as usize] {
                            s += v;
                            n += 1;
                        }
                    }
                }
                if n > 0 {
                    grid[y * gw + x] = Some(s / n as f32);
                }
            }
        }
    }
    grid.into_iter().map(|v| v.unwrap_or(1.0)).collect()
}
