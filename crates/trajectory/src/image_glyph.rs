//! Photos and scans of a character: Otsu threshold and cleaning.

use std::path::Path;

use crate::glyph::GlyphError;

/// The Otsu threshold of 8-bit gray values: the level `t` maximising the between-class variance
/// of `{v ≤ t}` and `{v > t}`.
pub fn otsu_threshold(gray: &[u8]) -> u8 {
    let mut hist = [0u64; 256];
    for &v in gray {
        hist[v as usize] += 1;
    }
    let total = gray.len() as f64;
    let sum_all: f64 = hist.iter().enumerate().map(|(i, &c)| i as f64 * c as f64).sum();
    let (mut w0, mut sum0) = (0.0f64, 0.0f64);
    let (mut best, mut best_t) = (-1.0f64, 127u8);
    for t in 0..256 {
        w0 += hist[t] as f64;
        sum0 += t as f64 * hist[t] as f64;
        let w1 = total - w0;
        if w0 == 0.0 || w1 == 0.0 {
            continue;
        }
        let (m0, m1) = (sum0 / w0, (sum_all - sum0) / w1);
        let between = w0 * w1 * (m0 - m1) * (m0 - m1);
        if between > best {
            best = between;
            best_t = t as u8;
        }
    }
    best_t
}

/// 4-connected components of `mask == value`: a label per pixel (0 = other value) and the size
/// of each label (index 0 unused).
pub fn components(mask: &[bool], w: usize, h: usize, value: bool) -> (Vec<u32>, Vec<usize>) {
    let mut label = vec![0u32; w * h];
    let mut sizes = vec![0usize];
    let mut stack = Vec::new();
    for start in 0..w * h {
        if mask[start] != value || label[start] != 0 {
            continue;
        }
        let id = sizes.len() as u32;
        let mut n = 0;
        label[start] = id;
        stack.push(start);
        while let Some(i) = stack.pop() {
            n += 1;
            let (x, y) = (i % w, i / w);
            let mut visit = |j: usize| {
                if mask[j] == value && label[j] == 0 {
                    label[j] = id;
                    stack.push(j);
                }
            };
            if x > 0 {
                visit(i - 1);
            }
            if x + 1 < w {
                visit(i + 1);
            }
            if y > 0 {
                visit(i - w);
            }
            if y + 1 < h {
                visit(i + w);
            }
        }
        sizes.push(n);
    }
    (label, sizes)
}

/// Loads, thresholds and cleans an image; returns the square side and the binary ink (1/0).
pub fn load_clean(path: &Path) -> Result<(u32, Vec<f32>), GlyphError> {
    let name = path.display().to_string();
    let img = image::ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| GlyphError::Io { path: name.clone(), message: e.to_string() })?
        .decode()
        .map_err(|e| GlyphError::Io { path: name.clone(), message: e.to_string() })?;
    let img = if img.width().max(img.height()) > 1024 { img.resize(1024, 1024, image::imageops::FilterType::Triangle) } else { img };
    let gray = img.to_luma8();
    let (w, h) = (gray.width() as usize, gray.height() as usize);
    if w < 16 || h < 16 {
        return Err(GlyphError::BadImage { path: name, message: format!("image is {w}×{h} px; need at least 16×16") });
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
        return Err(GlyphError::BadImage { path: name, message: format!("{:.0}% of the image is ink; expected dark ink on light paper", 100.0 * frac) });
    }
    // Remove specks: ink components under 0.5 % of all ink.
    let total: usize = ink.iter().filter(|&&b| b).count();
    let (label, sizes) = components(&ink, w, h, true);
    for (i, v) in ink.iter_mut().enumerate() {
        if *v && (sizes[label[i] as usize] as f64) < 0.005 * total as f64 {
            *v = false;
        }
    }
    // Fill pinholes: paper components not touching the border, under 0.05 % of the image.
    let (label, sizes) = components(&ink, w, h, false);
    let mut touches = vec![false; sizes.len()];
    for x in 0..w {
        touches[label[x] as usize] = true;
        touches[label[(h - 1) * w + x] as usize] = true;
    }
    for y in 0..h {
        touches[label[y * w] as usize] = true;
        touches[label[y * w + w - 1] as usize] = true;
    }
    for (i, v) in ink.iter_mut().enumerate() {
        let l = label[i] as usize;
        if !*v && !touches[l] && (sizes[l] as f64) < 0.0005 * (w * h) as f64 {
            *v = true;
        }
    }
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

    #[test]
    fn otsu_splits_two_levels() {
        let mut v = vec![30u8; 100];
        v.extend(vec![220u8; 300]);
        let t = otsu_threshold(&v);
        assert!((30..220).contains(&t));
    }

    #[test]
    fn components_are_counted() {
        // Two separate ink blobs.
        let m = [true, true, false, false, true, false, false, false, true]; // (0,0),(1,0),(1,1) and (2,2)
        let (_, sizes) = components(&m, 3, 3, true);
        assert_eq!(sizes[1..].to_vec(), vec![3, 1]);
    }
}
