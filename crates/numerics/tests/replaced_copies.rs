//! The shared functions reproduce, bit for bit, the copies they replaced (kept here verbatim as
//! they were in stroke-fit's `fit.rs`, `synth.rs` and `photo.rs`, trajectory's `template.rs`,
//! `raster.rs`, `scan.rs` and `glyph/bitmap.rs`, and xtask's `rng.rs`): same values, same calls of the objective in the same
//! order, same random streams. Fixtures built with the old copies are compared byte for byte.

use numerics::{
    Edge, NelderMead, Normalise, OutsideContraction, SplitMix64, for_each_block, gaussian_blur, nelder_mead,
};

// ---- the old copies, verbatim (names suffixed) ----

/// stroke-fit `fit.rs`.
fn nelder_mead_fit(
    f: &mut impl FnMut(&[f64; 6]) -> f64,
    start: [f64; 6],
    step: [f64; 6],
    iters: usize,
) -> ([f64; 6], f64) {
    let mut pts: Vec<([f64; 6], f64)> = Vec::with_capacity(7);
    pts.push((start, f(&start)));
    for k in 0..6 {
        let mut p = start;
        p[k] += step[k];
        pts.push((p, f(&p)));
    }
    for _ in 0..iters {
        pts.sort_by(|a, b| a.1.total_cmp(&b.1));
        if (pts[6].1 - pts[0].1).abs() < 1e-9 {
            break;
        }
        let mut c = [0.0; 6];
        for (p, _) in &pts[..6] {
            for k in 0..6 {
                c[k] += p[k] / 6.0;
            }
        }
        let worst = pts[6].0;
        let along = |t: f64| {
            let mut q = [0.0; 6];
            for k in 0..6 {
                q[k] = c[k] + t * (worst[k] - c[k]);
            }
            q
        };
        let r = along(-1.0);
        let fr = f(&r);
        if fr < pts[0].1 {
            let e = along(-2.0);
            let fe = f(&e);
            pts[6] = if fe < fr { (e, fe) } else { (r, fr) };
        } else if fr < pts[5].1 {
            pts[6] = (r, fr);
        } else {
            let (cp, fc) = if fr < pts[6].1 {
                let q = along(-0.5);
                (q, f(&q))
            } else {
                let q = along(0.5);
                (q, f(&q))
            };
            if fc < pts[6].1.min(fr) {
                pts[6] = (cp, fc);
            } else {
                let best = pts[0].0;
                for p in pts.iter_mut().skip(1) {
                    for (x, b) in p.0.iter_mut().zip(best) {
                        *x = b + 0.5 * (*x - b);
                    }
                    p.1 = f(&p.0);
                }
            }
        }
    }
    pts.sort_by(|a, b| a.1.total_cmp(&b.1));
    pts[0]
}

/// trajectory `template.rs`.
fn nelder_mead_template(f: impl Fn(&[f64]) -> f64, x0: &[f64], steps: &[f64], iters: usize) -> (Vec<f64>, f64) {
    let d = x0.len();
    let mut simplex: Vec<(Vec<f64>, f64)> = Vec::with_capacity(d + 1);
    simplex.push((x0.to_vec(), f(x0)));
    for i in 0..d {
        let mut x = x0.to_vec();
        x[i] += steps[i];
        let v = f(&x);
        simplex.push((x, v));
    }
    let lerp = |a: &[f64], b: &[f64], t: f64| -> Vec<f64> { a.iter().zip(b).map(|(a, b)| a + t * (b - a)).collect() };
    for _ in 0..iters {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let mut centroid = vec![0.0; d];
        for (x, _) in &simplex[..d] {
            for (c, v) in centroid.iter_mut().zip(x) {
                *c += v / d as f64;
            }
        }
        let worst = simplex[d].clone();
        let refl = lerp(&centroid, &worst.0, -1.0);
        let fr = f(&refl);
        if fr < simplex[0].1 {
            let exp = lerp(&centroid, &worst.0, -2.0);
            let fe = f(&exp);
            simplex[d] = if fe < fr { (exp, fe) } else { (refl, fr) };
        } else if fr < simplex[d - 1].1 {
            simplex[d] = (refl, fr);
        } else {
            let con = if fr < worst.1 { lerp(&centroid, &refl, 0.5) } else { lerp(&centroid, &worst.0, 0.5) };
            let fc = f(&con);
            if fc < worst.1.min(fr) {
                simplex[d] = (con, fc);
            } else {
                let best = simplex[0].0.clone();
                for s in simplex.iter_mut().skip(1) {
                    let x = lerp(&best, &s.0, 0.5);
                    let v = f(&x);
                    *s = (x, v);
                }
            }
        }
    }
    simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    simplex.swap_remove(0)
}

/// trajectory `raster.rs`.
#[derive(Clone, Copy)]
enum OldEdge {
    Zero,
    Clamp,
}
fn blur_trajectory(src: &[f32], n: usize, sigma: f64, edge: OldEdge) -> Vec<f32> {
    if sigma <= 0.0 {
        return src.to_vec();
    }
    let r = (3.0 * sigma).ceil() as i64;
    let k: Vec<f64> = (-r..=r).map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp()).collect();
    let norm: f64 = k.iter().sum();
    let at = |i: i64| -> Option<usize> {
        match edge {
            OldEdge::Zero => (0..n as i64).contains(&i).then_some(i as usize),
            OldEdge::Clamp => Some(i.clamp(0, n as i64 - 1) as usize),
        }
    };
    let pass = |from: &[f32], horizontal: bool| -> Vec<f32> {
        let mut to = vec![0.0f32; n * n];
        for y in 0..n {
            for x in 0..n {
                let mut acc = 0.0;
                for (j, w) in k.iter().enumerate() {
                    let (along, other) = if horizontal { (x, y) } else { (y, x) };
                    if let Some(i) = at(along as i64 + j as i64 - r) {
                        acc += w * from[if horizontal { other * n + i } else { i * n + other }] as f64;
                    }
                }
                to[y * n + x] = (acc / norm) as f32;
            }
        }
        to
    };
    pass(&pass(src, true), false)
}

/// stroke-fit `synth.rs`.
fn blur_synth(v: &[f64], w: usize, h: usize, sigma: f64) -> Vec<f64> {
    let r = (3.0 * sigma).ceil() as isize;
    let k: Vec<f64> = (-r..=r).map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp()).collect();
    let s: f64 = k.iter().sum();
    let k: Vec<f64> = k.iter().map(|x| x / s).collect();
    let rows = blur_pass(v, w, h, &k, true);
    blur_pass(&rows, w, h, &k, false)
}
fn blur_pass(v: &[f64], w: usize, h: usize, k: &[f64], horizontal: bool) -> Vec<f64> {
    let r = (k.len() / 2) as isize;
    let mut out = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let (pos, len) = if horizontal { (x as isize, w as isize) } else { (y as isize, h as isize) };
            let mut a = 0.0;
            for (j, kk) in k.iter().enumerate() {
                let q = (pos + j as isize - r).clamp(0, len - 1);
                let idx = if horizontal { y * w + q as usize } else { q as usize * w + x };
                a += kk * v[idx];
            }
            out[y * w + x] = a;
        }
    }
    out
}

/// trajectory `scan.rs`.
struct ScanSplitMix(u64);
impl ScanSplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// stroke-fit `synth.rs`.
struct SynthRng(u64);
impl SynthRng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn normal(&mut self) -> f64 {
        let (u, v) = (self.next().max(1e-12), self.next());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

/// xtask `rng.rs`.
struct XtaskSplitMix(u64);
impl XtaskSplitMix {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn normal(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

// ---- the comparisons ----

/// Objectives with curvature, coupling, ripples and a NaN region, so every branch of the
/// method (expansion, both contractions, shrink) runs.
fn objective(kind: usize, p: &[f64]) -> f64 {
    let q: f64 = p.iter().enumerate().map(|(k, x)| (k as f64 + 1.0) * (x - 0.3 * k as f64).powi(2)).sum();
    match kind {
        0 => q,
        1 => q + 0.3 * (5.0 * p[0]).sin() * (3.0 * p[p.len() - 1]).cos(),
        2 => (1.0 - p[0]).powi(2) + 100.0 * (p[1] - p[0] * p[0]).powi(2) + 0.1 * q,
        3 => {
            if p[0] > 2.5 {
                f64::NAN
            } else {
                q.sqrt() + (p[0] * p[1]).abs()
            }
        }
        _ => (q + 1e-3).ln() + 0.05 * p.iter().map(|x| (7.0 * x).sin()).sum::<f64>(),
    }
}

/// stroke-fit `photo.rs` (`flatten_background`'s blocks): each block's centre and 90th
/// percentile (truncated index).
fn blocks_stroke_fit(g: &[f32], w: usize, h: usize) -> Vec<(f64, f64, f64)> {
    const B: usize = 32;
    let (bw, bh) = (w.div_ceil(B), h.div_ceil(B));
    let mut blocks = Vec::with_capacity(bw * bh);
    let mut vals = Vec::with_capacity(B * B);
    for by in 0..bh {
        for bx in 0..bw {
            vals.clear();
            for y in by * B..((by + 1) * B).min(h) {
                vals.extend_from_slice(&g[y * w + bx * B..y * w + ((bx + 1) * B).min(w)]);
            }
            vals.sort_by(f32::total_cmp);
            let cx = ((bx * B + ((bx + 1) * B).min(w)) as f64) / 2.0;
            let cy = ((by * B + ((by + 1) * B).min(h)) as f64) / 2.0;
            blocks.push((cx, cy, vals[((vals.len() - 1) as f32 * 0.9) as usize] as f64));
        }
    }
    blocks
}

/// trajectory `glyph/bitmap.rs` (`paper_level`'s grid): each block's 90th percentile (rounded
/// index).
fn grid_trajectory(raw: &[u8], w: usize, h: usize) -> Vec<f32> {
    let b = (w.max(h) / 32).max(4);
    let (gw, gh) = (w.div_ceil(b), h.div_ceil(b));
    let pct90 = |vals: &mut Vec<u8>| -> f32 {
        vals.sort_unstable();
        vals[((vals.len() - 1) as f64 * 0.9).round() as usize] as f32
    };
    let mut grid = vec![0.0f32; gw * gh];
    let mut vals = Vec::with_capacity(b * b);
    for gy in 0..gh {
        for gx in 0..gw {
            vals.clear();
            for y in gy * b..((gy + 1) * b).min(h) {
                vals.extend_from_slice(&raw[y * w + gx * b..y * w + ((gx + 1) * b).min(w)]);
            }
            grid[gy * gw + gx] = pct90(&mut vals);
        }
    }
    grid
}

#[test]
fn nelder_mead_reproduces_stroke_fit_and_template_bit_for_bit() {
    let mut rng = SplitMix64(0xF17);
    for case in 0..40 {
        let kind = case % 5;
        let start: [f64; 6] = std::array::from_fn(|_| 4.0 * rng.next_f64() - 2.0);
        let step: [f64; 6] = std::array::from_fn(|_| 0.05 + rng.next_f64());
        let iters = [0, 1, 7, 60, 160, 400][case % 6];
        // stroke-fit: FnMut, early stop at 1e-9, outside contraction from the worst vertex.
        let (mut old_calls, mut new_calls) = (Vec::new(), Vec::new());
        let old = nelder_mead_fit(
            &mut |p: &[f64; 6]| {
                old_calls.push(*p);
                objective(kind, p)
            },
            start,
            step,
            iters,
        );
        let opts = NelderMead { min_spread: Some(1e-9), ..NelderMead::new(step, iters) };
        let new = nelder_mead(
            |p: &[f64; 6]| {
                new_calls.push(*p);
                objective(kind, p)
            },
            start,
            &opts,
        );
        assert_eq!(old.0.map(f64::to_bits), new.0.map(f64::to_bits), "fit case {case}");
        assert_eq!(old.1.to_bits(), new.1.to_bits(), "fit case {case}");
        assert_eq!(old_calls.len(), new_calls.len(), "fit case {case}");
        assert!(old_calls.iter().zip(&new_calls).all(|(a, b)| a.map(f64::to_bits) == b.map(f64::to_bits)));
        // template: no early stop, outside contraction from the reflected point.
        let old = nelder_mead_template(|p| objective(kind, p), &start, &step, iters);
        let opts = NelderMead { outside: OutsideContraction::FromReflected, ..NelderMead::new(step, iters) };
        let new = nelder_mead(|p: &[f64; 6]| objective(kind, p), start, &opts);
        assert_eq!(
            old.0.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            new.0.map(f64::to_bits),
            "template case {case}"
        );
        assert_eq!(old.1.to_bits(), new.1.to_bits(), "template case {case}");
    }
    // The template's version at another dimension (its unit test ran in 2-D).
    let f = |x: &[f64]| (x[0] - 3.0).powi(2) + 2.0 * (x[1] + 1.0).powi(2) + 1.0;
    let old = nelder_mead_template(f, &[0.0, 0.0], &[1.0, 1.0], 200);
    let opts = NelderMead { outside: OutsideContraction::FromReflected, ..NelderMead::new([1.0, 1.0], 200) };
    let new = nelder_mead(|x: &[f64; 2]| f(x), [0.0, 0.0], &opts);
    assert_eq!(old.0.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), new.0.map(f64::to_bits));
}

#[test]
fn the_blur_reproduces_trajectory_and_stroke_fit_bit_for_bit() {
    let mut rng = SplitMix64(0xB1);
    for (case, &sigma) in [0.0, 0.4, 0.9, 1.0, 1.2, 1.5, 2.7, 4.0, 6.3].iter().enumerate() {
        for n in [1, 5, 17, 64] {
            let img: Vec<f32> =
                (0..n * n).map(|_| if rng.next_f64() < 0.3 { 1.0 } else { rng.next_f64() as f32 }).collect();
            for (old_edge, edge) in [(OldEdge::Zero, Edge::Zero), (OldEdge::Clamp, Edge::Clamp)] {
                let old = blur_trajectory(&img, n, sigma, old_edge);
                let new = gaussian_blur(&img, n, n, sigma, edge, Normalise::Sum);
                assert_eq!(
                    old.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                    new.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                    "trajectory case {case}, n {n}"
                );
            }
        }
        if sigma > 0.0 {
            for (w, h) in [(1, 1), (3, 9), (40, 23), (64, 64)] {
                let img: Vec<f64> = (0..w * h).map(|_| rng.next_f64()).collect();
                let old = blur_synth(&img, w, h, sigma);
                let new = gaussian_blur(&img, w, h, sigma, Edge::Clamp, Normalise::Kernel);
                assert_eq!(
                    old.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                    new.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                    "synth case {case}, {w}×{h}"
                );
            }
        }
    }
}

#[test]
fn splitmix_streams_are_unchanged() {
    for seed in [0, 1, 0x5CA7_5CA7, 0x5EED_0015, 0x6d61_6f62_6931, u64::MAX] {
        let (mut scan, mut synth, mut xtask) = (ScanSplitMix(seed), SynthRng(seed), XtaskSplitMix(seed));
        let (mut a, mut b, mut c) = (SplitMix64(seed), SplitMix64(seed), SplitMix64(seed));
        for i in 0..500 {
            assert_eq!(scan.unit().to_bits(), a.next_f64().to_bits());
            if i % 3 == 0 {
                assert_eq!(synth.next().to_bits(), b.next_f64().to_bits());
            } else {
                // synth's normal: half-open uniforms with the first floored at 1e-12.
                let (u, v) = (b.next_f64().max(1e-12), b.next_f64());
                let want = (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos();
                assert_eq!(synth.normal().to_bits(), want.to_bits());
            }
            match i % 3 {
                0 => assert_eq!(xtask.next_u64(), c.next_u64()),
                1 => assert_eq!(xtask.uniform().to_bits(), c.uniform().to_bits()),
                _ => assert_eq!(xtask.normal().to_bits(), c.normal().to_bits()),
            }
        }
    }
}

#[test]
fn the_blocks_reproduce_stroke_fit_and_trajectory_bit_for_bit() {
    let mut rng = SplitMix64(0xB10C);
    for (w, h) in [(1, 1), (31, 33), (32, 64), (65, 40), (200, 7), (130, 129)] {
        let g: Vec<f32> = (0..w * h).map(|_| rng.next_f64() as f32).collect();
        const B: usize = 32;
        let mut blocks = Vec::new();
        for_each_block(&g, w, h, B, |bx, by, vals| {
            vals.sort_by(f32::total_cmp);
            let cx = ((bx * B + ((bx + 1) * B).min(w)) as f64) / 2.0;
            let cy = ((by * B + ((by + 1) * B).min(h)) as f64) / 2.0;
            blocks.push((cx, cy, vals[((vals.len() - 1) as f32 * 0.9) as usize] as f64));
        });
        let bits = |v: &[(f64, f64, f64)]| v.iter().map(|b| [b.0, b.1, b.2].map(f64::to_bits)).collect::<Vec<_>>();
        assert_eq!(bits(&blocks_stroke_fit(&g, w, h)), bits(&blocks), "stroke-fit {w}×{h}");

        let raw: Vec<u8> = (0..w * h).map(|_| (rng.next_u64() >> 56) as u8).collect();
        let b = (w.max(h) / 32).max(4);
        let gw = w.div_ceil(b);
        let mut grid = vec![0.0f32; gw * h.div_ceil(b)];
        for_each_block(&raw, w, h, b, |gx, gy, vals| {
            vals.sort_unstable();
            grid[gy * gw + gx] = vals[((vals.len() - 1) as f64 * 0.9).round() as usize] as f32;
        });
        assert_eq!(grid_trajectory(&raw, w, h), grid, "trajectory {w}×{h}");
    }
}
