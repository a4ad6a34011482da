//! Binary-image helpers shared by glyph and stroke-photo analysis: Otsu's threshold and
//! connected components.

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
    for (t, &count) in hist.iter().enumerate() {
        w0 += count as f64;
        sum0 += t as f64 * count as f64;
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
pub fn connected_components(mask: &[bool], w: usize, h: usize, value: bool) -> (Vec<u32>, Vec<usize>) {
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

/// Fills holes: paper components of a `w × h` mask that do not touch the border and are smaller
/// than `max_px` become ink (`usize::MAX`: every enclosed hole).
pub fn fill_holes(mask: &mut [bool], w: usize, h: usize, max_px: usize) {
    let (label, sizes) = connected_components(mask, w, h, false);
    let mut border = vec![false; sizes.len()];
    for x in 0..w {
        border[label[x] as usize] = true;
        border[label[(h - 1) * w + x] as usize] = true;
    }
    for y in 0..h {
        border[label[y * w] as usize] = true;
        border[label[y * w + w - 1] as usize] = true;
    }
    for (i, v) in mask.iter_mut().enumerate() {
        let l = label[i] as usize;
        if !*v && !border[l] && sizes[l] < max_px {
            *v = true;
        }
    }
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
        let (_, sizes) = connected_components(&m, 3, 3, true);
        assert_eq!(sizes[1..].to_vec(), vec![3, 1]);
    }
}
