//! A faster CPU 2-D convolution for candle, with bias and ReLU fused in, and a pixel shuffle
//! with a direct backward pass.
//!
//! candle 0.11 runs the forward convolution on the CPU as im2col + gemm, but its backward pass
//! uses `conv_transpose2d` (a direct loop) for the input gradient and a convolution whose
//! "kernel" is the whole output gradient for the weight gradient; with the few channels and
//! large images of a footprint generator those dominate a training step, and the bias add,
//! ReLU and pixel shuffle around each convolution add several more full passes with
//! allocations each way.
//!
//! Here a convolution (square kernel, stride 1, zero padding smaller than the kernel) is one
//! candle custom op on `(x, weight, bias)` computed directly on zero-padded planes laid out on
//! rows of the padded width (the "padded stride" layout): every kernel tap is then one long contiguous
//! `axpy` (forward and input gradient) or `dot` (weight gradient), which the compiler
//! vectorises for the CPU found at run time ([`pulp`] dispatch). The input gradient is the same
//! correlation of the output gradient with the flipped, transposed kernel. An optional ReLU is
//! applied in the same pass and its mask used in the backward pass. No column matrix is built:
//! for few channels im2col's 9× larger buffer costs more memory traffic than the arithmetic.
//!
//! [`Conv2d`] is a drop-in [`Module`] over the same weight and bias tensors as
//! `candle_nn::Conv2d` (so checkpoints are shared); on other devices or dtypes, or with a
//! padding of at least the kernel size, it falls back to candle's kernel. The module depends
//! on nothing but candle, rayon and pulp so that it could move upstream. Tested against
//! candle's own kernel in value and in every gradient (`conv_tests.rs`).

use candle_core::{CpuStorage, CustomOp1, CustomOp3, DType, Layout, Module, Result, Shape, Tensor, bail};
use rayon::prelude::*;

fn contiguous_f32<'a>(storage: &'a CpuStorage, layout: &Layout, op: &str) -> Result<&'a [f32]> {
    let data = storage.as_slice::<f32>()?;
    match layout.contiguous_offsets() {
        Some((a, b)) => Ok(&data[a..b]),
        None => bail!("{op}: the input must be contiguous"),
    }
}

fn cpu_f32<'a>(storage: &'a candle_core::Storage, layout: &Layout, op: &str) -> Result<&'a [f32]> {
    match storage {
        candle_core::Storage::Cpu(s) => contiguous_f32(s, layout, op),
        _ => bail!("{op}: CPU tensors only"),
    }
}

/// Every image of `x` (`[B·C, H, W]` planes) copied into a zero-padded `[Hp, Wp]` plane.
pub(crate) fn pad_planes(x: &[f32], planes: usize, (h, w): (usize, usize), p: usize) -> Vec<f32> {
    let (hp, wp) = (h + 2 * p, w + 2 * p);
    let mut out = vec![0f32; planes * hp * wp];
    out.par_chunks_mut(hp * wp).zip(x.par_chunks(h * w)).for_each(|(dst, src)| {
        for y in 0..h {
            dst[(y + p) * wp + p..(y + p) * wp + p + w].copy_from_slice(&src[y * w..(y + 1) * w]);
        }
    });
    out
}

/// `out += a · x`, element-wise (vectorised under [`pulp::Arch::dispatch`]).
#[inline(always)]
fn axpy(out: &mut [f32], a: f32, x: &[f32]) {
    for (d, s) in out.iter_mut().zip(x) {
        *d += a * s;
    }
}

/// `Σ a·b` with eight independent accumulators (so that it vectorises).
#[inline(always)]
fn dot(a: &[f32], b: &[f32]) -> f32 {
    let mut acc = [0f32; 8];
    let (ca, cb) = (a.chunks_exact(8), b.chunks_exact(8));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for i in 0..8 {
            acc[i] += x[i] * y[i];
        }
    }
    let tail: f32 = ra.iter().zip(rb).map(|(x, y)| x * y).sum();
    acc.iter().sum::<f32>() + tail
}

/// The "padded stride" trick: on zero-padded input planes of width `Wp`, output pixel
/// `(oy, ox)` of a stride-1 correlation is `Σ w[ky, kx] · in[(oy + ky)·Wp + ox + kx]`, so with
/// the output also laid out on rows of `Wp` (the last `k − 1` columns of each row are junk)
/// every kernel tap is one long contiguous `axpy` or `dot` over `len = Ho·Wp − (k − 1)`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Padded {
    pub(crate) c: usize,
    pub(crate) hp: usize,
    pub(crate) wp: usize,
    pub(crate) k: usize,
}

impl Padded {
    fn ho(&self) -> usize {
        self.hp + 1 - self.k
    }
    fn wo(&self) -> usize {
        self.wp + 1 - self.k
    }
    fn len(&self) -> usize {
        self.ho() * self.wp - (self.k - 1)
    }
}

/// Output channels computed together: each input value loaded feeds this many accumulators.
const OB: usize = 4;
/// Output positions per register tile.
const TILE: usize = 16;

/// Direct correlation `y = w ⋆ x` (no bias) of padded planes `xp` (`[B, C, Hp, Wp]`) with
/// `w` (`[O, C, k, k]`): `[B, O, Ho, Wo]`. Parallel over images and blocks of [`OB`] output
/// channels; within a block, [`TILE`] output positions × [`OB`] channels are accumulated in
/// registers over every input channel and kernel tap.
pub(crate) fn direct_forward(pd: Padded, b: usize, o: usize, xp: &[f32], w: &[f32]) -> Vec<f32> {
    let (plane_in, taps, len) = (pd.c * pd.hp * pd.wp, pd.c * pd.k * pd.k, pd.len());
    let (ho, wo, wp, k, hpwp) = (pd.ho(), pd.wo(), pd.wp, pd.k, pd.hp * pd.wp);
    let blocks = o.div_ceil(OB);
    // Weights by block, tap-major: wb[blk][tap][j] (zero for channels past `o`).
    let mut wb = vec![0f32; blocks * taps * OB];
    for oi in 0..o {
        for tap in 0..taps {
            wb[((oi / OB) * taps + tap) * OB + oi % OB] = w[oi * taps + tap];
        }
    }
    let mut y = vec![0f32; b * o * ho * wo];
    let arch = pulp::Arch::new();
    y.par_chunks_mut(o * ho * wo).enumerate().for_each(|(bi, img_out)| {
        let xi = &xp[bi * plane_in..(bi + 1) * plane_in];
        img_out.par_chunks_mut(OB * ho * wo).enumerate().for_each_init(
            || vec![0f32; OB * ho * wp],
            |acc, (blk, out)| {
                let wv = &wb[blk * taps * OB..(blk + 1) * taps * OB];
                let stride = ho * wp;
                arch.dispatch(|| {
                    let full = len - len % TILE;
                    for t in (0..full).step_by(TILE) {
                        let a = tile_sums(pd, xi, wv, t);
                        for (j, aj) in a.iter().enumerate() {
                            acc[j * stride + t..j * stride + t + TILE].copy_from_slice(aj);
                        }
                    }
                    for j in 0..OB {
                        acc[j * stride + full..j * stride + len].fill(0.0);
                    }
                    for c in 0..pd.c {
                        let plane = &xi[c * hpwp..(c + 1) * hpwp];
                        for ky in 0..k {
                            for kx in 0..k {
                                let off = ky * wp + kx;
                                let ws = &wv[((c * k + ky) * k + kx) * OB..][..OB];
                                for j in 0..OB {
                                    let dst = &mut acc[j * stride + full..j * stride + len];
                                    axpy(dst, ws[j], &plane[off + full..off + len]);
                                }
                            }
                        }
                    }
                });
                for (j, plane_out) in out.chunks_exact_mut(ho * wo).enumerate() {
                    for (dst, src) in plane_out.chunks_exact_mut(wo).zip(acc[j * stride..].chunks(wp)) {
                        dst.copy_from_slice(&src[..wo]);
                    }
                }
            },
        );
    });
    y
}

/// One register tile of [`direct_forward`]: the sums over every input channel and kernel tap
/// for the [`TILE`] output positions from `t` and the [`OB`] channels of one block (`wv`: the
/// block's weights, tap-major).
#[inline(always)]
fn tile_sums(pd: Padded, xi: &[f32], wv: &[f32], t: usize) -> [[f32; TILE]; OB] {
    let (wp, k, hpwp) = (pd.wp, pd.k, pd.hp * pd.wp);
    let mut a = [[0f32; TILE]; OB];
    for c in 0..pd.c {
        let plane = &xi[c * hpwp..(c + 1) * hpwp];
        for ky in 0..k {
            for kx in 0..k {
                let off = ky * wp + kx + t;
                let src: &[f32; TILE] = plane[off..off + TILE].try_into().expect("tile");
                let ws = &wv[((c * k + ky) * k + kx) * OB..][..OB];
                for j in 0..OB {
                    for i in 0..TILE {
                        a[j][i] += ws[j] * src[i];
                    }
                }
            }
        }
    }
    a
}

/// The weight gradient `dw[o, c, ky, kx] = Σ_b Σ_p dy[b, o, p] · x[b, c, p + (ky, kx)]` on
/// padded input planes, accumulated per thread over images and summed.
fn direct_weight_grad(pd: Padded, b: usize, o: usize, xp: &[f32], dy: &[f32]) -> Vec<f32> {
    let (ho, wo, wp, k, len) = (pd.ho(), pd.wo(), pd.wp, pd.k, pd.len());
    let (plane_in, hpwp) = (pd.c * pd.hp * wp, pd.hp * wp);
    let n = o * pd.c * k * k;
    let arch = pulp::Arch::new();
    // Fixed groups of images, each summed in order and the groups summed in order: the result
    // does not depend on how rayon schedules the work (training stays deterministic).
    let groups = b.clamp(1, 16);
    let per = b.div_ceil(groups);
    let partial: Vec<Vec<f32>> = (0..groups)
        .into_par_iter()
        .map(|grp| {
            let (mut acc, mut d) = (vec![0f32; n], vec![0f32; ho * wp]);
            for bi in grp * per..((grp + 1) * per).min(b) {
                let xi = &xp[bi * plane_in..(bi + 1) * plane_in];
                for oi in 0..o {
                    // The output gradient of (bi, oi) on rows of Wp, junk columns zero.
                    let src = &dy[(bi * o + oi) * ho * wo..(bi * o + oi + 1) * ho * wo];
                    for (dst, row) in d.chunks_exact_mut(wp).zip(src.chunks_exact(wo)) {
                        dst[..wo].copy_from_slice(row);
                        dst[wo..].fill(0.0);
                    }
                    // Two planes of at most (64 + 2)² values: both stay in L1 over the taps.
                    arch.dispatch(|| {
                        for c in 0..pd.c {
                            let plane = &xi[c * hpwp..(c + 1) * hpwp];
                            for ky in 0..k {
                                for kx in 0..k {
                                    let off = ky * wp + kx;
                                    acc[((oi * pd.c + c) * k + ky) * k + kx] += dot(&d[..len], &plane[off..off + len]);
                                }
                            }
                        }
                    });
                }
            }
            acc
        })
        .collect();
    let mut total = vec![0f32; n];
    for p in &partial {
        total.iter_mut().zip(p).for_each(|(t, v)| *t += v);
    }
    total
}

/// The flipped, transposed kernel: `wf[c, o, ky, kx] = w[o, c, k−1−ky, k−1−kx]`.
pub(crate) fn flip_transpose(w: &[f32], o: usize, c: usize, k: usize) -> Vec<f32> {
    let mut wf = vec![0f32; w.len()];
    for oi in 0..o {
        for ci in 0..c {
            for ky in 0..k {
                for kx in 0..k {
                    wf[((ci * o + oi) * k + ky) * k + kx] = w[((oi * c + ci) * k + (k - 1 - ky)) * k + (k - 1 - kx)];
                }
            }
        }
    }
    wf
}

/// Convolution + bias (+ ReLU) as one candle custom op on `(x, w, bias)`.
#[derive(Debug, Clone, Copy)]
struct DirectConv {
    padding: usize,
    relu: bool,
}

impl CustomOp3 for DirectConv {
    fn name(&self) -> &'static str {
        "maobi-direct-conv2d"
    }

    fn cpu_fwd(
        &self,
        s1: &CpuStorage,
        l1: &Layout,
        s2: &CpuStorage,
        l2: &Layout,
        s3: &CpuStorage,
        l3: &Layout,
    ) -> Result<(CpuStorage, Shape)> {
        let (b, c, h, w) = l1.shape().dims4()?;
        let (o, c2, k, _) = l2.shape().dims4()?;
        if c != c2 || l3.shape().dims() != [o] {
            bail!("direct conv2d: input {:?}, weight {:?}, bias {:?}", l1.shape(), l2.shape(), l3.shape());
        }
        let p = self.padding;
        let pd = Padded { c, hp: h + 2 * p, wp: w + 2 * p, k };
        if pd.hp < k || pd.wp < k {
            bail!("direct conv2d: a {h}×{w} image is smaller than the {k}×{k} kernel");
        }
        let xp = pad_planes(contiguous_f32(s1, l1, "direct conv2d")?, b * c, (h, w), p);
        let mut y = direct_forward(pd, b, o, &xp, contiguous_f32(s2, l2, "direct conv2d")?);
        let bias = contiguous_f32(s3, l3, "direct conv2d")?;
        let plane = pd.ho() * pd.wo();
        let relu = self.relu;
        y.par_chunks_mut(plane).enumerate().for_each(|(bo, out)| {
            let bv = bias[bo % o];
            if relu {
                out.iter_mut().for_each(|v| *v = (*v + bv).max(0.0));
            } else {
                out.iter_mut().for_each(|v| *v += bv);
            }
        });
        Ok((CpuStorage::F32(y), Shape::from((b, o, pd.ho(), pd.wo()))))
    }

    fn bwd(
        &self,
        x: &Tensor,
        w: &Tensor,
        _bias: &Tensor,
        res: &Tensor,
        dy: &Tensor,
    ) -> Result<(Option<Tensor>, Option<Tensor>, Option<Tensor>)> {
        let (b, c, h, wd) = x.dims4()?;
        let (o, _, k, _) = w.dims4()?;
        let (ho, wo) = (res.dim(2)?, res.dim(3)?);
        let (x, w, res, dy) = (x.contiguous()?, w.contiguous()?, res.contiguous()?, dy.contiguous()?);
        let (xs, xl) = x.storage_and_layout();
        let (ws, wl) = w.storage_and_layout();
        let (rs, rl) = res.storage_and_layout();
        let (ds, dl) = dy.storage_and_layout();
        let op = "direct conv2d backward";
        let (xv, wv, rv, dv) =
            (cpu_f32(&xs, xl, op)?, cpu_f32(&ws, wl, op)?, cpu_f32(&rs, rl, op)?, cpu_f32(&ds, dl, op)?);
        // The gradient at the pre-activation: ReLU passes it where the output is positive.
        let g: std::borrow::Cow<'_, [f32]> = if self.relu {
            dv.par_iter().zip(rv).map(|(&d, &r)| if r > 0.0 { d } else { 0.0 }).collect::<Vec<_>>().into()
        } else {
            dv.into()
        };
        let plane = ho * wo;
        let mut db = vec![0f32; o];
        for (bo, chunk) in g.chunks_exact(plane).enumerate() {
            db[bo % o] += chunk.iter().sum::<f32>();
        }
        // dx = g ⋆ flip(wᵀ) with padding k − 1 − p (a "full" correlation).
        let q = k - 1 - self.padding;
        let pg = Padded { c: o, hp: ho + 2 * q, wp: wo + 2 * q, k };
        let gp = pad_planes(&g, b * o, (ho, wo), q);
        let dx = direct_forward(pg, b, c, &gp, &flip_transpose(wv, o, c, k));
        // dw on the padded input.
        let p = self.padding;
        let pd = Padded { c, hp: h + 2 * p, wp: wd + 2 * p, k };
        let xp = pad_planes(xv, b * c, (h, wd), p);
        let dw = direct_weight_grad(pd, b, o, &xp, &g);
        let dev = x.device();
        Ok((
            Some(Tensor::from_vec(dx, (b, c, h, wd), dev)?),
            Some(Tensor::from_vec(dw, (o, c, k, k), dev)?),
            Some(Tensor::from_vec(db, o, dev)?),
        ))
    }
}

/// Pixel shuffle `[B, C·r², H, W]` → `[B, C, H·r, W·r]` as a custom op with a direct inverse
/// for its backward pass (candle's is a reshape, a permute and a strided copy each way).
#[derive(Debug, Clone, Copy)]
struct PixelShuffle {
    r: usize,
    inverse: bool,
}

impl CustomOp1 for PixelShuffle {
    fn name(&self) -> &'static str {
        if self.inverse { "maobi-pixel-unshuffle" } else { "maobi-pixel-shuffle" }
    }

    fn cpu_fwd(&self, storage: &CpuStorage, layout: &Layout) -> Result<(CpuStorage, Shape)> {
        let r = self.r;
        let (b, c_in, h_in, w_in) = layout.shape().dims4()?;
        let src = contiguous_f32(storage, layout, self.name())?;
        // Work in terms of the shuffled (large) geometry: c channels of (h·r) × (w·r).
        let (c, h, w) = if self.inverse {
            if h_in % r != 0 || w_in % r != 0 {
                bail!("pixel unshuffle: {h_in}×{w_in} is not divisible by {r}");
            }
            (c_in, h_in / r, w_in / r)
        } else {
            if c_in % (r * r) != 0 {
                bail!("pixel shuffle: {c_in} channels are not divisible by {}", r * r);
            }
            (c_in / (r * r), h_in, w_in)
        };
        let mut dst = vec![0f32; src.len()];
        let big = h * r * w * r;
        let (inverse, small) = (self.inverse, h * w);
        // One chunk per (image, large channel): r² small planes ↔ one large plane.
        dst.par_chunks_mut(big).enumerate().for_each(|(bc, out)| {
            for dy in 0..r {
                for dx in 0..r {
                    let sp = (bc * r + dy) * r + dx; // small plane index
                    for y in 0..h {
                        for x in 0..w {
                            let (si, li) = (sp * small + y * w + x, (y * r + dy) * w * r + x * r + dx);
                            if inverse {
                                // out is laid out as small planes here
                                out[(dy * r + dx) * small + y * w + x] = src[bc * big + li];
                            } else {
                                out[li] = src[si];
                            }
                        }
                    }
                }
            }
        });
        let shape = if self.inverse { (b, c * r * r, h, w) } else { (b, c, h * r, w * r) };
        Ok((CpuStorage::F32(dst), Shape::from(shape)))
    }

    fn bwd(&self, _arg: &Tensor, _res: &Tensor, grad_res: &Tensor) -> Result<Option<Tensor>> {
        let inv = PixelShuffle { r: self.r, inverse: !self.inverse };
        Ok(Some(grad_res.contiguous()?.apply_op1_no_bwd(&inv)?))
    }
}

/// Pixel shuffle by `r`: `[B, C·r², H, W]` → `[B, C, H·r, W·r]`, the same arrangement as
/// `candle_nn::ops::pixel_shuffle` (and PyTorch's), differentiable. f32 CPU tensors use a
/// direct kernel; others candle's.
///
/// # Errors
/// A candle error for a non-4-D input or channels not divisible by `r²`.
pub(crate) fn pixel_shuffle(x: &Tensor, r: usize) -> Result<Tensor> {
    if x.device().is_cpu() && x.dtype() == DType::F32 && r > 0 {
        x.contiguous()?.apply_op1(PixelShuffle { r, inverse: false })
    } else {
        candle_nn::ops::pixel_shuffle(x, r)
    }
}

/// A 2-D convolution (square kernel, stride 1, dilation 1, one group) with its bias and an
/// optional ReLU fused into one direct kernel, forward and backward. Holds the same tensors as
/// `candle_nn::Conv2d`.
#[derive(Debug, Clone)]
pub(crate) struct Conv2d {
    weight: Tensor,
    bias: Tensor,
    padding: usize,
    relu: bool,
}

impl Conv2d {
    /// A convolution from a weight `[O, C, k, k]`, an optional bias `[O]` (zero if `None`) and
    /// the zero padding on every side (pixels); no activation.
    ///
    /// # Errors
    /// A candle error when the weight is not 4-D with a square kernel, or the bias is not `[O]`.
    pub(crate) fn new(weight: Tensor, bias: Option<Tensor>, padding: usize) -> Result<Self> {
        let (o, _, kh, kw) = weight.dims4()?;
        if kh != kw {
            bail!("fast conv2d: the kernel must be square, got {kh}×{kw}");
        }
        let bias = match bias {
            Some(b) if b.dims() != [o] => bail!("fast conv2d: bias shape {:?}, expected [{o}]", b.dims()),
            Some(b) => b,
            None => Tensor::zeros(o, weight.dtype(), weight.device())?,
        };
        Ok(Conv2d { weight, bias, padding, relu: false })
    }

    /// Takes over the weight, bias and padding of a `candle_nn::Conv2d` (stride, dilation and
    /// groups must be 1).
    ///
    /// # Errors
    /// A candle error for strided, dilated or grouped convolutions.
    pub(crate) fn from_candle(conv: &candle_nn::Conv2d) -> Result<Self> {
        let cfg = conv.config();
        if cfg.stride != 1 || cfg.dilation != 1 || cfg.groups != 1 {
            bail!("fast conv2d: only stride 1, dilation 1 and one group are supported");
        }
        Self::new(conv.weight().clone(), conv.bias().cloned(), cfg.padding)
    }

    /// The same convolution followed by a ReLU, computed in the same pass.
    pub(crate) fn with_relu(mut self) -> Self {
        self.relu = true;
        self
    }
}

impl Module for Conv2d {
    fn forward(&self, x: &Tensor) -> Result<Tensor> {
        let (o, c, k, _) = self.weight.dims4()?;
        if x.dim(1)? != c {
            bail!("fast conv2d: input has {} channels, the weight expects {c}", x.dim(1)?);
        }
        let direct = x.device().is_cpu()
            && x.dtype() == DType::F32
            && self.weight.dtype() == DType::F32
            && self.bias.dtype() == DType::F32
            && self.padding < k;
        if direct {
            let op = DirectConv { padding: self.padding, relu: self.relu };
            return x.contiguous()?.apply_op3(&self.weight.contiguous()?, &self.bias.contiguous()?, op);
        }
        let y = x.conv2d(&self.weight, self.padding, 1, 1, 1)?.broadcast_add(&self.bias.reshape((1, o, 1, 1))?)?;
        if self.relu { y.relu() } else { Ok(y) }
    }
}
