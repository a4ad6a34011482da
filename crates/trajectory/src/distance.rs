//! Exact Euclidean distance transform (Felzenszwalb & Huttenlocher, separable).

/// For each pixel of a `w × h` mask, the Euclidean distance (px) from its centre to the centre
/// of the nearest pixel outside the mask (0 outside). Pixels beyond the image count as outside.
pub(crate) fn distance_to_background(mask: &[bool], w: usize, h: usize) -> Vec<f32> {
    const INF: f64 = 1e20;
    // Pad by one pixel of background on every side so the image edge counts as outside.
    let (pw, ph) = (w + 2, h + 2);
    let mut f = vec![0.0f64; pw * ph];
    for y in 0..h {
        for x in 0..w {
            if mask[y * w + x] {
                f[(y + 1) * pw + x + 1] = INF;
            }
        }
    }
    let mut buf = vec![0.0f64; pw.max(ph)];
    let mut out = vec![0.0f64; pw.max(ph)];
    let mut v = vec![0usize; pw.max(ph)];
    let mut z = vec![0.0f64; pw.max(ph) + 1];
    // Columns, then rows.
    for x in 0..pw {
        for y in 0..ph {
            buf[y] = f[y * pw + x];
        }
        dt1d(&buf[..ph], &mut out[..ph], &mut v, &mut z);
        for y in 0..ph {
            f[y * pw + x] = out[y];
        }
    }
    for y in 0..ph {
        buf[..pw].copy_from_slice(&f[y * pw..(y + 1) * pw]);
        dt1d(&buf[..pw], &mut out[..pw], &mut v, &mut z);
        f[y * pw..(y + 1) * pw].copy_from_slice(&out[..pw]);
    }
    let mut d = vec![0.0f32; w * h];
    for y in 0..h {
        for x in 0..w {
            d[y * w + x] = f[(y + 1) * pw + x + 1].sqrt() as f32;
        }
    }
    d
}

/// 1D squared distance transform of `f` into `d` (lower envelope of parabolas).
fn dt1d(f: &[f64], d: &mut [f64], v: &mut [usize], z: &mut [f64]) {
    let n = f.len();
    let mut k = 0usize;
    v[0] = 0;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    for q in 1..n {
        loop {
            let p = v[k];
            let s = ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64)) / (2.0 * q as f64 - 2.0 * p as f64);
            if s <= z[k] && k > 0 {
                k -= 1;
                continue;
            }
            if s <= z[k] {
                // k == 0 and the new parabola dominates everywhere.
                v[0] = q;
                z[0] = f64::NEG_INFINITY;
                z[1] = f64::INFINITY;
                break;
            }
            k += 1;
            v[k] = q;
            z[k] = s;
            z[k + 1] = f64::INFINITY;
            break;
        }
    }
    k = 0;
    for (q, dq) in d.iter_mut().enumerate().take(n) {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let p = v[k];
        *dq = (q as f64 - p as f64).powi(2) + f[p];
    }
}

/// Bilinear sample of a `w × h` field at pixel coordinates `(x, y)` (pixel centres at `i + 0.5`),
/// clamped at the edges.
pub(crate) fn sample(field: &[f32], w: usize, h: usize, x: f64, y: f64) -> f64 {
    let fx = (x - 0.5).clamp(0.0, (w - 1) as f64);
    let fy = (y - 0.5).clamp(0.0, (h - 1) as f64);
    let (x0, y0) = (fx.floor() as usize, fy.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (tx, ty) = (fx - x0 as f64, fy - y0 as f64);
    let at = |x: usize, y: usize| field[y * w + x] as f64;
    (at(x0, y0) * (1.0 - tx) + at(x1, y0) * tx) * (1.0 - ty) + (at(x0, y1) * (1.0 - tx) + at(x1, y1) * tx) * ty
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_brute_force() {
        let (w, h) = (23, 17);
        let mask: Vec<bool> = (0..w * h).map(|i| ((i * 7919) % 13) > 3 && (i % w) != 0).collect();
        let d = distance_to_background(&mask, w, h);
        for y in 0..h {
            for x in 0..w {
                let mut best = f64::INFINITY;
                for yy in -1..=h as i64 {
                    for xx in -1..=w as i64 {
                        let outside = xx < 0
                            || yy < 0
                            || xx >= w as i64
                            || yy >= h as i64
                            || !mask[yy as usize * w + xx as usize];
                        if outside {
                            best = best.min(((xx - x as i64).pow(2) + (yy - y as i64).pow(2)) as f64);
                        }
                    }
                }
                let want = if mask[y * w + x] { best.sqrt() } else { 0.0 };
                assert!((d[y * w + x] as f64 - want).abs() < 1e-5, "({x},{y}) {} vs {want}", d[y * w + x]);
            }
        }
    }
}
