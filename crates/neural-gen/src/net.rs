//! A network on the direct kernels (`kernels`): fully connected layers, then 3×3
//! convolutions each followed or not by a ReLU and a ×2 pixel shuffle, then a sigmoid image.
//! The definitions and the per-image passes that inference, the input VJP ([`crate::InputVjp`])
//! and training ([`crate::direct`]) share.
//!
//! The generator ([`crate::Arch`]) is one such network ([`NetSpec::of_arch`]: every
//! convolution followed by a shuffle, a ReLU after every layer but the last of each kind); the
//! LearningToPaint-size network of the benchmarks is another.
//!
//! The fully connected layers run on the whole batch as packed matrix products; the
//! convolutions image by image, each correlation's writeback adding the bias and applying the
//! ReLU (keeping its mask, one byte per activation, where a backward pass needs it), the pixel
//! shuffle and the sigmoid in the pass that writes the next layer's padded input. The backward
//! pass to the input is the correlation with the flipped, transposed kernel, masked by the ReLU
//! and un-shuffled onto the previous layer; the forward-mode tangent reuses the masks. Every
//! image is computed on its own, every sum in a fixed order of fused multiply–adds: the results
//! do not depend on the batch size, the thread count or the vector width.

// `NetSpec` and `StageSpec` are public through `crate::bench` only (the `bench` feature).
#![cfg_attr(not(feature = "bench"), allow(unreachable_pub))]

use pulp::{Simd, WithSimd};
use rayon::prelude::*;

use crate::NeuralGenError;
use crate::config::Arch;
use crate::conv::flip_transpose;
use crate::kernels::{Conv3, Dense, Isa, padded_len};

/// One 3×3 convolution (padding 1, with bias) of a [`NetSpec`] and what follows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StageSpec {
    /// Input channels.
    pub cin: usize,
    /// Output channels (a multiple of 4 when `shuffle`).
    pub cout: usize,
    /// A ReLU after the convolution.
    pub relu: bool,
    /// A ×2 pixel shuffle after it (and after the ReLU): `cout / 4` channels of twice the side.
    pub shuffle: bool,
}

/// The architecture of a network on the direct kernels: fully connected layers of `widths`
/// (from 3 inputs), a ReLU after each but maybe the last, the last layer's output viewed as
/// `seed_channels` planes of `seed_side²`, then the convolution `stages`; the last stage has 4
/// outputs, no ReLU and a shuffle, and is followed by the sigmoid: one image plane. Weights
/// have candle's names and layouts (`fc{i}.weight` `[out, in]`, `fc{i}.bias`,
/// `conv{i}.weight` `[cout, cin, 3, 3]`, `conv{i}.bias`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NetSpec {
    /// Widths of the fully connected layers' inputs and outputs, from 3 to
    /// `seed_channels · seed_side²`.
    pub widths: Vec<usize>,
    /// Whether the last fully connected layer is followed by a ReLU.
    pub relu_last_fc: bool,
    /// Channels of the seed map.
    pub seed_channels: usize,
    /// Side of the seed map, px.
    pub seed_side: usize,
    /// The convolutions, in order.
    pub stages: Vec<StageSpec>,
}

impl NetSpec {
    /// The generator's network: a ReLU after every hidden fully connected layer and every
    /// convolution but the last, every convolution followed by a ×2 pixel shuffle.
    pub(crate) fn of_arch(a: &Arch) -> Self {
        let last = a.stages.len().saturating_sub(1);
        NetSpec {
            widths: std::iter::once(3)
                .chain(a.hidden.iter().copied())
                .chain([a.seed_channels * a.seed_side * a.seed_side])
                .collect(),
            relu_last_fc: false,
            seed_channels: a.seed_channels,
            seed_side: a.seed_side,
            stages: a
                .stages
                .iter()
                .enumerate()
                .map(|(i, &(cin, cout))| StageSpec { cin, cout, relu: i < last, shuffle: true })
                .collect(),
        }
    }

    /// Checks that the layers fit together; returns the side of the image, px.
    ///
    /// # Errors
    /// [`NeuralGenError::Shape`] naming the first layer that does not fit.
    pub fn validate(&self) -> Result<usize, NeuralGenError> {
        let bad = |m: String| Err(NeuralGenError::Shape(m));
        if self.widths.len() < 2 || self.widths[0] != 3 || self.widths.contains(&0) {
            return bad(format!(
                "fully connected widths {:?}: expected 3, then at least one positive width",
                self.widths
            ));
        }
        let seed = self.seed_channels * self.seed_side * self.seed_side;
        if self.widths.last() != Some(&seed) || seed == 0 {
            return bad(format!(
                "the last fully connected width {:?} is not the seed map's {} × {}²",
                self.widths.last(),
                self.seed_channels,
                self.seed_side
            ));
        }
        let (mut c, mut n) = (self.seed_channels, self.seed_side);
        for (i, st) in self.stages.iter().enumerate() {
            if st.cin != c || st.cout == 0 || (st.shuffle && st.cout % 4 != 0) {
                return bad(format!(
                    "stage {i} ({} → {}, shuffle {}): expected {c} inputs and, with a shuffle, a multiple of 4 outputs",
                    st.cin, st.cout, st.shuffle
                ));
            }
            (c, n) = if st.shuffle { (st.cout / 4, 2 * n) } else { (st.cout, n) };
        }
        match self.stages.last() {
            Some(st) if st.cout == 4 && st.shuffle && !st.relu => Ok(n),
            _ => bad("the last stage must have 4 outputs, no ReLU and a pixel shuffle (one image plane)".into()),
        }
    }

    /// Multiply–adds per image of a forward pass.
    #[cfg(any(test, feature = "bench"))]
    pub fn macs_per_image(&self) -> usize {
        let fc: usize = self.widths.windows(2).map(|w| w[0] * w[1]).sum();
        let mut n = self.seed_side;
        let mut conv = 0;
        for st in &self.stages {
            conv += n * n * st.cin * st.cout * 9;
            if st.shuffle {
                n *= 2;
            }
        }
        fc + conv
    }

    /// The trainable tensors in order (`fc0.weight, fc0.bias, …, conv0.weight, conv0.bias, …`)
    /// with their shapes.
    pub(crate) fn tensors(&self) -> Vec<(String, Vec<usize>)> {
        let mut out = Vec::new();
        for (i, w) in self.widths.windows(2).enumerate() {
            out.push((format!("fc{i}.weight"), vec![w[1], w[0]]));
            out.push((format!("fc{i}.bias"), vec![w[1]]));
        }
        for (i, st) in self.stages.iter().enumerate() {
            out.push((format!("conv{i}.weight"), vec![st.cout, st.cin, 3, 3]));
            out.push((format!("conv{i}.bias"), vec![st.cout]));
        }
        out
    }
}

/// One fully connected layer `y = W·x + b`.
#[derive(Clone)]
pub(crate) struct Fc {
    /// `· Wᵀ`: the forward products (`x` `[batch, in]`).
    pub(crate) fwd: Dense,
    /// `· W`: the backward product (`g` `[batch, out]`).
    pub(crate) bwd: Dense,
    pub(crate) b: Vec<f32>,
    pub(crate) out: usize,
}

/// One convolution stage on the kernels.
#[derive(Clone)]
pub(crate) struct Stage {
    pub(crate) spec: StageSpec,
    pub(crate) fwd: Conv3,
    /// The flipped, transposed kernel: the correlation that gives the input gradient.
    pub(crate) bwd: Conv3,
    pub(crate) b: Vec<f32>,
    /// Side of the stage's input (and of its convolution's output), px.
    pub(crate) n: usize,
    /// Where the ReLU mask of the stage's input starts in an image's masks, when its input
    /// comes out of a ReLU.
    mask: Option<usize>,
}

/// A [`NetSpec`] network on the direct kernels with its weights (see the module doc).
#[derive(Clone)]
pub(crate) struct Net {
    pub(crate) spec: NetSpec,
    pub(crate) fcs: Vec<Fc>,
    pub(crate) stages: Vec<Stage>,
    /// Values per image of the stages' padded inputs.
    pub(crate) per_image: usize,
    /// Mask bytes per image (at least one, so that per-image chunks are never empty).
    pub(crate) masks_per_image: usize,
    /// Side of the images, px.
    pub(crate) size: usize,
    pub(crate) isa: Isa,
}

/// What a forward pass keeps for its backward pass: the ReLU masks of every layer but the last
/// and the images.
pub struct Tape {
    batch: usize,
    /// Outputs (after the ReLU) of the fully connected layers but the last, `[batch, width]`
    /// (their signs are the masks).
    hidden: Vec<Vec<f32>>,
    /// Per image, the ReLU masks (1 where positive) of the inputs of the stages that have one,
    /// `[c, y, x]`, stage after stage.
    masks: Vec<u8>,
    images: Vec<f32>,
}

impl Tape {
    /// Number of images.
    pub fn len(&self) -> usize {
        self.batch
    }

    /// Whether the batch was empty.
    pub fn is_empty(&self) -> bool {
        self.batch == 0
    }

    /// All images, `len() × size²` values in [0, 1], image after image, row-major.
    pub fn images(&self) -> &[f32] {
        &self.images
    }

    /// All images, as [`Tape::images`], without a copy (the tape cannot go backward after).
    pub fn into_images(self) -> Vec<f32> {
        self.images
    }

    /// Image `i` (`size²` values).
    ///
    /// # Panics
    /// When `i ≥ len()`.
    pub fn image(&self, i: usize) -> &[f32] {
        let n = self.images.len() / self.batch.max(1);
        &self.images[i * n..(i + 1) * n]
    }
}

/// `eˣ` without a libm call, so that the loops around it vectorise: `x = k·ln 2 + r` with
/// `|r| ≤ ln 2 / 2`, `eʳ` by its Taylor polynomial to degree 7, `2ᵏ` built in the exponent
/// bits. Relative error below 1e-7 (a few ulp of f32) for `x` in [−87, 88]; clamped there.
/// Plain IEEE operations only (no fused multiply–adds), so every instruction set gives the
/// same bits.
#[inline(always)]
fn exp_f32(x: f32) -> f32 {
    const LOG2E: f32 = std::f32::consts::LOG2_E;
    const LN2_HI: f32 = 0.693_145_75;
    const LN2_LO: f32 = 1.428_606_8e-6;
    // Adding and subtracting 1.5·2²³ rounds to the nearest integer (|x·log₂e| < 2²²).
    const ROUND: f32 = 12_582_912.0;
    let x = x.clamp(-87.0, 88.0);
    let y = x * LOG2E + ROUND;
    let k = y - ROUND;
    let r = (x - k * LN2_HI) - k * LN2_LO;
    let p = 1.0
        + r * (1.0
            + r * (1.0 / 2.0
                + r * (1.0 / 6.0 + r * (1.0 / 24.0 + r * (1.0 / 120.0 + r * (1.0 / 720.0 + r * (1.0 / 5040.0)))))));
    // The bits of `y` are those of 1.5·2²³ plus k: 2ᵏ's exponent field is k + 127 (no
    // float-to-integer conversion, which does not vectorise).
    p * f32::from_bits(y.to_bits().wrapping_sub(0x4B40_0000 - 127) << 23)
}

/// The logistic function `1 / (1 + e⁻ˣ)` (through [`exp_f32`]).
#[inline(always)]
fn sigmoid(x: f32) -> f32 {
    1.0 / (1.0 + exp_f32(-x))
}

/// `v` where the mask byte is 1, 0 where it is 0 (branch-free, so that the loops vectorise).
#[inline(always)]
fn masked(v: f32, m: u8) -> f32 {
    f32::from_bits(v.to_bits() & u32::from(m).wrapping_neg())
}

/// The activation after a convolution: the ReLU or nothing.
#[inline(always)]
fn act<const RELU: bool>(v: f32) -> f32 {
    if RELU { v.max(0.0) } else { v }
}

/// `row` into `dst`, masked where `m` is given.
#[inline(always)]
fn put(dst: &mut [f32], row: &[f32], m: Option<&[u8]>) {
    match m {
        Some(m) => dst.iter_mut().zip(row.iter().zip(m)).for_each(|(d, (&v, &mm))| *d = masked(v, mm)),
        None => dst.copy_from_slice(row),
    }
}

/// `row` de-interleaved into `d0` (even columns) and `d1` (odd), masked where `m` is given:
/// the gradient of a row of a pixel-shuffled layer on the two rows it came from.
#[inline(always)]
fn put_unshuffled(d0: &mut [f32], d1: &mut [f32], row: &[f32], m: Option<&[u8]>) {
    match m {
        Some(m) => {
            for ((e0, e1), (v, mm)) in d0.iter_mut().zip(d1.iter_mut()).zip(row.chunks_exact(2).zip(m.chunks_exact(2)))
            {
                *e0 = masked(v[0], mm[0]);
                *e1 = masked(v[1], mm[1]);
            }
        }
        None => {
            for ((e0, e1), v) in d0.iter_mut().zip(d1.iter_mut()).zip(row.chunks_exact(2)) {
                *e0 = v[0];
                *e1 = v[1];
            }
        }
    }
}

/// Copies `c` planes of `n × n` into the interior of zero-bordered padded planes.
fn write_padded(dst: &mut [f32], src: &[f32], c: usize, n: usize) {
    let wp = n + 2;
    for ch in 0..c {
        for y in 0..n {
            let d = ch * wp * wp + (y + 1) * wp + 1;
            dst[d..d + n].copy_from_slice(&src[(ch * n + y) * n..(ch * n + y + 1) * n]);
        }
    }
}

/// Splits an image's activations into the padded inputs of the stages.
fn regions<'a>(stages: &[Stage], mut buf: &'a mut [f32]) -> Vec<&'a mut [f32]> {
    let mut out = Vec::with_capacity(stages.len());
    for st in stages {
        let (a, rest) = std::mem::take(&mut buf).split_at_mut(padded_len(st.spec.cin, st.n));
        out.push(a);
        buf = rest;
    }
    out
}

/// Sets every value of `v` to 0 where the activation beside it is not positive (the backward
/// pass of a ReLU, on its output).
fn relu_back(v: &mut [f32], activations: &[f32]) {
    v.iter_mut().zip(activations).for_each(|(v, &a)| {
        if a <= 0.0 {
            *v = 0.0;
        }
    });
}

impl Stage {
    /// The stage's input mask in an image's masks `m`, when it has one.
    fn mask_in<'a>(&self, m: &'a [u8]) -> Option<&'a [u8]> {
        self.mask.map(|off| &m[off..off + self.spec.cin * self.n * self.n])
    }

    /// The convolution of the padded input `x` with bias and activation, pixel-shuffled into
    /// the next stage's padded input `dst`, the ReLU's mask into `m` where given.
    #[inline(always)]
    fn shuffled_into<const RELU: bool>(
        &self,
        x: &[f32],
        acc: &mut Vec<f32>,
        dst: &mut [f32],
        mut m: Option<&mut [u8]>,
    ) {
        let (n, s) = (self.n, 2 * self.n);
        let wq = s + 2;
        self.fwd.run_pairs(x, n, acc, |o, y, r0, r1| {
            let (ch, r, b0, b1) = (o / 4, 2 * y + (o / 2) % 2, self.b[o], self.b[o + 1]);
            let d = &mut dst[ch * wq * wq + (r + 1) * wq + 1..ch * wq * wq + (r + 1) * wq + 1 + s];
            for (dd, (&v0, &v1)) in d.chunks_exact_mut(2).zip(r0.iter().zip(r1)) {
                dd[0] = act::<RELU>(v0 + b0);
                dd[1] = act::<RELU>(v1 + b1);
            }
            if let Some(m) = m.as_deref_mut() {
                for (mm, &v) in m[(ch * s + r) * s..(ch * s + r + 1) * s].iter_mut().zip(d.iter()) {
                    *mm = u8::from(v > 0.0);
                }
            }
        });
    }

    /// As [`Stage::shuffled_into`], without the shuffle.
    #[inline(always)]
    fn plain_into<const RELU: bool>(&self, x: &[f32], acc: &mut Vec<f32>, dst: &mut [f32], mut m: Option<&mut [u8]>) {
        let (n, wq) = (self.n, self.n + 2);
        self.fwd.run(x, n, acc, |o, y, row| {
            let d = &mut dst[o * wq * wq + (y + 1) * wq + 1..o * wq * wq + (y + 1) * wq + 1 + n];
            let bo = self.b[o];
            for (dd, &v) in d.iter_mut().zip(row) {
                *dd = act::<RELU>(v + bo);
            }
            if let Some(m) = m.as_deref_mut() {
                for (mm, &v) in m[(o * n + y) * n..(o * n + y + 1) * n].iter_mut().zip(d.iter()) {
                    *mm = u8::from(v > 0.0);
                }
            }
        });
    }
}

impl Net {
    /// The network `spec` with the weights `get(name)` returns (candle's names and layouts,
    /// [`NetSpec::tensors`]).
    ///
    /// # Errors
    /// [`NeuralGenError::Shape`] when the spec does not fit together or a tensor has the wrong
    /// size; what `get` returns for a missing tensor.
    pub(crate) fn new(
        spec: &NetSpec,
        get: impl Fn(&str) -> Result<Vec<f32>, NeuralGenError>,
    ) -> Result<Self, NeuralGenError> {
        let size = spec.validate()?;
        let tensor = |name: &str, dims: &[usize]| -> Result<Vec<f32>, NeuralGenError> {
            let w = get(name)?;
            let len: usize = dims.iter().product();
            if w.len() != len {
                return Err(NeuralGenError::Shape(format!("{name}: {} values, expected {len}", w.len())));
            }
            Ok(w)
        };
        let isa = Isa::detect();
        let mut fcs = Vec::new();
        for (i, w) in spec.widths.windows(2).enumerate() {
            let (inp, out) = (w[0], w[1]);
            let wt = tensor(&format!("fc{i}.weight"), &[out, inp])?;
            fcs.push(Fc {
                fwd: Dense::new_transposed(&wt, out, inp, isa),
                bwd: Dense::new(&wt, out, inp, isa),
                b: tensor(&format!("fc{i}.bias"), &[out])?,
                out,
            });
        }
        let mut stages = Vec::new();
        let (mut n, mut per_image, mut moff) = (spec.seed_side, 0, 0);
        let mut relu_before = spec.relu_last_fc;
        for (i, st) in spec.stages.iter().enumerate() {
            let (cin, cout) = (st.cin, st.cout);
            let w = tensor(&format!("conv{i}.weight"), &[cout, cin, 9])?;
            let mask = relu_before.then_some(moff);
            if relu_before {
                moff += cin * n * n;
            }
            stages.push(Stage {
                spec: *st,
                fwd: Conv3::new(&w, cout, cin, isa),
                bwd: Conv3::new(&flip_transpose(&w, cout, cin, 3), cin, cout, isa),
                b: tensor(&format!("conv{i}.bias"), &[cout])?,
                n,
                mask,
            });
            per_image += padded_len(cin, n);
            relu_before = st.relu;
            if st.shuffle {
                n *= 2;
            }
        }
        Ok(Net { spec: spec.clone(), fcs, stages, per_image, masks_per_image: moff.max(1), size, isa })
    }

    /// Packs new weights into the kernels' layouts, in place (the same values as
    /// [`Net::new`] would pack): `w(k)` is tensor `k` of [`NetSpec::tensors`].
    pub(crate) fn set_weights<'a>(&mut self, w: impl Fn(usize) -> &'a [f32]) {
        let nfc = self.fcs.len();
        for (li, fc) in self.fcs.iter_mut().enumerate() {
            fc.fwd.repack_transposed(w(2 * li));
            fc.bwd.repack(w(2 * li));
            fc.b.copy_from_slice(w(2 * li + 1));
        }
        for (si, st) in self.stages.iter_mut().enumerate() {
            st.fwd.repack(w(2 * (nfc + si)));
            st.bwd.repack_flipped(w(2 * (nfc + si)));
            st.b.copy_from_slice(w(2 * (nfc + si) + 1));
        }
    }

    /// Values of the seed map (the last fully connected layer's output) per image.
    pub(crate) fn seed_len(&self) -> usize {
        let s = &self.stages[0];
        s.spec.cin * s.n * s.n
    }

    /// Weight and bias values of the convolution stages.
    pub(crate) fn conv_len(&self) -> usize {
        self.stages.iter().map(|s| s.spec.cout * s.spec.cin * 9 + s.spec.cout).sum()
    }

    /// Whether the fully connected layer `li` is followed by a ReLU.
    pub(crate) fn fc_relu(&self, li: usize) -> bool {
        li + 1 < self.fcs.len() || self.spec.relu_last_fc
    }

    /// The fully connected layers on the whole batch of inputs `x` (`[batch, 3]`): the outputs
    /// of every layer but the last (after the ReLU) and the seed maps.
    pub(crate) fn dense_forward(&self, x: &[f32]) -> (Vec<Vec<f32>>, Vec<f32>) {
        let mut hidden: Vec<Vec<f32>> = Vec::new();
        let mut seed = Vec::new();
        for (li, fc) in self.fcs.iter().enumerate() {
            let input = if li == 0 { x } else { &hidden[li - 1] };
            let mut y = fc.fwd.apply(input, Some(&fc.b));
            if self.fc_relu(li) {
                y.iter_mut().for_each(|v| *v = v.max(0.0));
            }
            if li + 1 < self.fcs.len() {
                hidden.push(y);
            } else {
                seed = y;
            }
        }
        (hidden, seed)
    }

    /// The gradient at the inputs of the fully connected layers from the gradient `g` at the
    /// seed maps (already through the last layer's ReLU), `hidden` the layers' outputs as
    /// [`Net::dense_forward`] gives them: `[batch, 3]`.
    fn dense_backward(&self, mut g: Vec<f32>, hidden: &[Vec<f32>]) -> Vec<f32> {
        for (li, fc) in self.fcs.iter().enumerate().rev() {
            let mut gi = fc.bwd.apply(&g, None);
            if li > 0 {
                relu_back(&mut gi, &hidden[li - 1]);
            }
            g = gi;
        }
        g
    }

    /// Images for a batch of inputs `x` (`[batch, 3]`): `batch × size²` values in [0, 1],
    /// image after image, without keeping a tape.
    ///
    /// # Panics
    /// When `x.len()` is not a multiple of 3.
    pub(crate) fn images(&self, x: &[f32]) -> Vec<f32> {
        assert_eq!(x.len() % 3, 0, "inputs come in threes");
        let ss = self.size * self.size;
        let mut images = vec![0f32; x.len() / 3 * ss];
        if images.is_empty() {
            return images;
        }
        let (_, seed) = self.dense_forward(x);
        images.par_chunks_mut(ss).zip(seed.par_chunks(self.seed_len())).for_each_init(
            || (vec![0f32; self.per_image], Vec::new()),
            |(buf, acc), (img, sd)| self.isa.dispatch(ForwardImage { net: self, seed: sd, img, masks: None, buf, acc }),
        );
        images
    }

    /// As [`Net::images`], each image in a vector of its own (`size²` values), written where
    /// the image is computed (no copy out of a batch buffer). The vectors are allocated by the
    /// calling thread, which usually frees them too (so that the allocator reuses their
    /// memory), and filled in parallel.
    ///
    /// # Panics
    /// When `x.len()` is not a multiple of 3.
    pub(crate) fn images_each(&self, x: &[f32]) -> Vec<Vec<f32>> {
        assert_eq!(x.len() % 3, 0, "inputs come in threes");
        let ss = self.size * self.size;
        let mut out: Vec<Vec<f32>> = (0..x.len() / 3).map(|_| Vec::with_capacity(ss)).collect();
        if out.is_empty() {
            return out;
        }
        let (_, seed) = self.dense_forward(x);
        out.par_iter_mut().zip(seed.par_chunks(self.seed_len())).for_each_init(
            || (vec![0f32; self.per_image], Vec::new()),
            |(buf, acc), (img, sd)| {
                img.resize(ss, 0.0);
                self.isa.dispatch(ForwardImage { net: self, seed: sd, img, masks: None, buf, acc })
            },
        );
        out
    }

    /// The forward pass for a batch of inputs `x` (`[batch, 3]`), keeping what
    /// [`Net::input_gradient`] and [`Net::jacobian`] need.
    ///
    /// # Panics
    /// When `x.len()` is not a multiple of 3.
    pub(crate) fn forward_taped(&self, x: &[f32]) -> Tape {
        assert_eq!(x.len() % 3, 0, "inputs come in threes");
        let b = x.len() / 3;
        let (hidden, seed) = self.dense_forward(x);
        let ss = self.size * self.size;
        let mp = self.masks_per_image;
        let mut masks = vec![0u8; b * mp];
        let mut images = vec![0f32; b * ss];
        images.par_chunks_mut(ss).zip(masks.par_chunks_mut(mp)).zip(seed.par_chunks(self.seed_len())).for_each_init(
            || (vec![0f32; self.per_image], Vec::new()),
            |(buf, acc), ((img, m), sd)| {
                self.isa.dispatch(ForwardImage { net: self, seed: sd, img, masks: Some(m), buf, acc })
            },
        );
        Tape { batch: b, hidden, masks, images }
    }

    /// The gradient of `Σ upstream · image` with respect to every input of the tape's batch
    /// (`[batch, 3]`), `upstream` holding `size²` values per image.
    ///
    /// # Panics
    /// When `upstream` does not hold `size²` values per image of the tape.
    pub(crate) fn input_gradient(&self, tape: &Tape, upstream: &[f32]) -> Vec<f32> {
        let (b, ss) = (tape.batch, self.size * self.size);
        assert_eq!(upstream.len(), b * ss, "upstream gradient");
        if b == 0 {
            return Vec::new();
        }
        // The convolution stages image by image, to the seed map.
        let (sl, mp) = (self.seed_len(), self.masks_per_image);
        let mut g = vec![0f32; b * sl];
        g.par_chunks_mut(sl)
            .zip(upstream.par_chunks(ss))
            .zip(tape.images.par_chunks(ss))
            .zip(tape.masks.par_chunks(mp))
            .for_each_init(
                || (self.gradient_planes(), Vec::new()),
                |(bufs, acc), (((gs, up), img), masks)| {
                    self.isa.dispatch(BackwardImage { net: self, gs, up, img, masks, bufs, acc })
                },
            );
        // Back through the fully connected layers, on the whole batch.
        self.dense_backward(g, &tape.hidden)
    }

    /// Zeroed planes for the padded gradient at every stage's output (the scratch of
    /// [`BackwardImage`]).
    pub(crate) fn gradient_planes(&self) -> Vec<Vec<f32>> {
        self.stages.iter().map(|st| vec![0f32; padded_len(st.spec.cout, st.n)]).collect()
    }

    /// The Jacobian of each image of the tape with respect to its inputs by forward-mode
    /// differentiation (one tangent through the network per input marked in `which`, the
    /// forward pass's ReLU masks reused): `len() × 3 × size²` values, per image the derivative
    /// along `steps[k]` of input `k` for k = 0, 1, 2; the columns of unmarked inputs are zero.
    pub(crate) fn jacobian(&self, tape: &Tape, which: [bool; 3], steps: [f32; 3]) -> Vec<f32> {
        let b = tape.batch;
        let sel: Vec<usize> = (0..3).filter(|&k| which[k]).collect();
        let ss = self.size * self.size;
        let ns = sel.len();
        if b == 0 || ns == 0 {
            return vec![0f32; b * 3 * ss];
        }
        let t = ns * b;
        // Tangent rows (image r / ns, input sel[r % ns]): the step of that input.
        let mut x = vec![0f32; t * 3];
        for r in 0..t {
            let k = sel[r % ns];
            x[r * 3 + k] = steps[k];
        }
        for (li, fc) in self.fcs.iter().enumerate() {
            let mut y = fc.fwd.apply(&x, None);
            if li + 1 < self.fcs.len() {
                let h = &tape.hidden[li];
                y.par_chunks_mut(fc.out).enumerate().for_each(|(r, row)| {
                    relu_back(row, &h[(r / ns) * fc.out..(r / ns + 1) * fc.out]);
                });
            }
            x = y;
        }
        let (sl, mp) = (self.seed_len(), self.masks_per_image);
        let mut out = vec![0f32; b * 3 * ss];
        out.par_chunks_mut(3 * ss).enumerate().for_each_init(
            || (vec![0f32; self.per_image], Vec::new()),
            |(buf, acc), (i, cols)| {
                for (q, &k) in sel.iter().enumerate() {
                    let r = i * ns + q;
                    let masks = &tape.masks[i * mp..(i + 1) * mp];
                    let col = &mut cols[k * ss..(k + 1) * ss];
                    let seed = &x[r * sl..(r + 1) * sl];
                    let img = tape.image(i);
                    self.isa.dispatch(TangentImage { net: self, seed, masks, img, col, buf, acc });
                }
            },
        );
        out
    }

    /// The convolution stages of one image, from its seed map: the image into `img`, the ReLU
    /// masks into `masks` where given (training and VJPs; inference does without); `buf`
    /// holds the stages' padded inputs (zero borders kept), `acc` scratch.
    #[inline(always)]
    fn forward_image(
        &self,
        seed: &[f32],
        img: &mut [f32],
        mut masks: Option<&mut [u8]>,
        buf: &mut [f32],
        acc: &mut Vec<f32>,
    ) {
        let mut reg = regions(&self.stages, buf);
        let first = &self.stages[0];
        write_padded(reg[0], seed, first.spec.cin, first.n);
        if let (Some(m), Some(off)) = (masks.as_deref_mut(), first.mask) {
            for (mm, &v) in m[off..off + seed.len()].iter_mut().zip(seed) {
                *mm = u8::from(v > 0.0);
            }
        }
        let last = self.stages.len() - 1;
        for (si, st) in self.stages.iter().enumerate() {
            let (cur, next) = reg.split_at_mut(si + 1);
            let x = &*cur[si];
            if si == last {
                // Bias and the pixel shuffle into the image, then the sigmoid on the row while
                // it is in cache (each call writes one whole row of the image).
                let (n, s) = (st.n, 2 * st.n);
                st.fwd.run_pairs(x, n, acc, |o, y, r0, r1| {
                    let (ch, r, b0, b1) = (o / 4, 2 * y + (o / 2) % 2, st.b[o], st.b[o + 1]);
                    let d = &mut img[(ch * s + r) * s..(ch * s + r + 1) * s];
                    for (dd, (&v0, &v1)) in d.chunks_exact_mut(2).zip(r0.iter().zip(r1)) {
                        dd[0] = v0 + b0;
                        dd[1] = v1 + b1;
                    }
                    for v in d.iter_mut() {
                        *v = sigmoid(*v);
                    }
                });
                continue;
            }
            // Bias, activation and (maybe) the shuffle into the next stage's padded input, with
            // its mask where the next stage's input has one.
            let nx = &self.stages[si + 1];
            let m = match (masks.as_deref_mut(), nx.mask) {
                (Some(m), Some(off)) => Some(&mut m[off..off + nx.spec.cin * nx.n * nx.n]),
                _ => None,
            };
            let dst = &mut *next[0];
            match (st.spec.shuffle, st.spec.relu) {
                (true, true) => st.shuffled_into::<true>(x, acc, dst, m),
                (true, false) => st.shuffled_into::<false>(x, acc, dst, m),
                (false, true) => st.plain_into::<true>(x, acc, dst, m),
                (false, false) => st.plain_into::<false>(x, acc, dst, m),
            }
        }
    }

    /// One tangent of one image through the stages: `seed` the tangent of the seed map,
    /// `masks` and `img` the image's ReLU masks and image from the forward pass, the tangent
    /// of the image into `col`; `buf` scratch for the stages' padded inputs (zero borders kept).
    #[inline(always)]
    fn tangent_image(
        &self,
        seed: &[f32],
        masks: &[u8],
        img: &[f32],
        col: &mut [f32],
        buf: &mut [f32],
        acc: &mut Vec<f32>,
    ) {
        let mut reg = regions(&self.stages, buf);
        let first = &self.stages[0];
        write_padded(reg[0], seed, first.spec.cin, first.n);
        if let Some(m) = first.mask_in(masks) {
            let (n, wp) = (first.n, first.n + 2);
            for ch in 0..first.spec.cin {
                for y in 0..n {
                    let d = &mut reg[0][ch * wp * wp + (y + 1) * wp + 1..][..n];
                    d.iter_mut().zip(&m[(ch * n + y) * n..][..n]).for_each(|(v, &mm)| *v = masked(*v, mm));
                }
            }
        }
        let last = self.stages.len() - 1;
        for (si, st) in self.stages.iter().enumerate() {
            let (cur, next) = reg.split_at_mut(si + 1);
            let (x, n) = (&*cur[si], st.n);
            if si == last {
                let s = 2 * n;
                st.fwd.run_pairs(x, n, acc, |o, y, r0, r1| {
                    let (ch, r) = (o / 4, 2 * y + (o / 2) % 2);
                    let row = (ch * s + r) * s..(ch * s + r + 1) * s;
                    let (d, im) = (&mut col[row.clone()], &img[row]);
                    for ((dd, yy), (&v0, &v1)) in d.chunks_exact_mut(2).zip(im.chunks_exact(2)).zip(r0.iter().zip(r1)) {
                        dd[0] = v0 * (yy[0] * (1.0 - yy[0]));
                        dd[1] = v1 * (yy[1] * (1.0 - yy[1]));
                    }
                });
                continue;
            }
            let nx = &self.stages[si + 1];
            let m = nx.mask_in(masks);
            let dst = &mut *next[0];
            if st.spec.shuffle {
                let (s, wq) = (2 * n, 2 * n + 2);
                st.fwd.run_pairs(x, n, acc, |o, y, r0, r1| {
                    let (ch, r) = (o / 4, 2 * y + (o / 2) % 2);
                    let d = &mut dst[ch * wq * wq + (r + 1) * wq + 1..ch * wq * wq + (r + 1) * wq + 1 + s];
                    match m {
                        Some(m) => {
                            let mr = &m[(ch * s + r) * s..(ch * s + r + 1) * s];
                            for ((dd, mm), (&v0, &v1)) in
                                d.chunks_exact_mut(2).zip(mr.chunks_exact(2)).zip(r0.iter().zip(r1))
                            {
                                dd[0] = masked(v0, mm[0]);
                                dd[1] = masked(v1, mm[1]);
                            }
                        }
                        None => {
                            for (dd, (&v0, &v1)) in d.chunks_exact_mut(2).zip(r0.iter().zip(r1)) {
                                dd[0] = v0;
                                dd[1] = v1;
                            }
                        }
                    }
                });
            } else {
                let wq = n + 2;
                st.fwd.run(x, n, acc, |o, y, row| {
                    let d = &mut dst[o * wq * wq + (y + 1) * wq + 1..o * wq * wq + (y + 1) * wq + 1 + n];
                    put(d, row, m.map(|m| &m[(o * n + y) * n..(o * n + y + 1) * n]));
                });
            }
        }
    }

    /// The backward pass of one image through the stages to its inputs: `up` the upstream
    /// gradient of the image `img`, `masks` its ReLU masks from the forward pass; the gradient
    /// of the seed map into `gs` (through the last fully connected layer's ReLU, where there is
    /// one). `bufs[si]` receives the padded gradient at stage `si`'s convolution output (zero
    /// borders kept: what the weight gradients read), `acc` scratch.
    #[inline(always)]
    fn backward_image(
        &self,
        gs: &mut [f32],
        up: &[f32],
        img: &[f32],
        masks: &[u8],
        bufs: &mut [Vec<f32>],
        acc: &mut Vec<f32>,
    ) {
        let last = self.stages.len() - 1;
        // Through the sigmoid, un-shuffled onto the last convolution's padded output: row yy
        // of image channel ch interleaves rows yy / 2 of channels 4ch + 2(yy % 2) + {0, 1}.
        let st = &self.stages[last];
        let (n, s, wp) = (st.n, 2 * st.n, st.n + 2);
        let q2 = wp * wp;
        let gl = &mut bufs[last];
        for ch in 0..st.spec.cout / 4 {
            for yy in 0..s {
                let base = (4 * ch + 2 * (yy % 2)) * q2 + (yy / 2 + 1) * wp + 1;
                let (lo, hi) = gl.split_at_mut(base + q2);
                let (d0, d1) = (&mut lo[base..base + n], &mut hi[..n]);
                let row = (ch * s + yy) * s..(ch * s + yy + 1) * s;
                let (u, y) = (&up[row.clone()], &img[row]);
                for ((e0, e1), (uu, yv)) in
                    d0.iter_mut().zip(d1.iter_mut()).zip(u.chunks_exact(2).zip(y.chunks_exact(2)))
                {
                    *e0 = uu[0] * yv[0] * (1.0 - yv[0]);
                    *e1 = uu[1] * yv[1] * (1.0 - yv[1]);
                }
            }
        }
        for (si, st) in self.stages.iter().enumerate().rev() {
            let n = st.n;
            let (lo, hi) = bufs.split_at_mut(si);
            let gy = &hi[0];
            // The gradient at this stage's input is the previous layer's output after its ReLU
            // (and shuffle): mask it (and un-shuffle it).
            let m = st.mask_in(masks);
            let row_mask = |c: usize, y: usize| m.map(|m| &m[(c * n + y) * n..(c * n + y + 1) * n]);
            if si == 0 {
                st.bwd.run(gy, n, acc, |c, y, row| {
                    put(&mut gs[(c * n + y) * n..(c * n + y + 1) * n], row, row_mask(c, y))
                });
            } else if self.stages[si - 1].spec.shuffle {
                // Row y of channel c de-interleaves into rows y / 2 of channels
                // 4c + 2(y % 2) + {0, 1} of the previous convolution's output.
                let dst = &mut lo[si - 1];
                let (h, wq) = (n / 2, n / 2 + 2);
                let q2 = wq * wq;
                st.bwd.run(gy, n, acc, |c, y, row| {
                    let base = (4 * c + 2 * (y % 2)) * q2 + (y / 2 + 1) * wq + 1;
                    let (dlo, dhi) = dst.split_at_mut(base + q2);
                    put_unshuffled(&mut dlo[base..base + h], &mut dhi[..h], row, row_mask(c, y));
                });
            } else {
                let (dst, wq) = (&mut lo[si - 1], n + 2);
                st.bwd.run(gy, n, acc, |c, y, row| {
                    let d = &mut dst[c * wq * wq + (y + 1) * wq + 1..c * wq * wq + (y + 1) * wq + 1 + n];
                    put(d, row, row_mask(c, y));
                });
            }
        }
    }
}

/// [`Net::forward_image`] on the detected vectors (a struct, not a closure, so that the
/// method is inlined where the target features are enabled).
pub(crate) struct ForwardImage<'a> {
    pub(crate) net: &'a Net,
    pub(crate) seed: &'a [f32],
    pub(crate) img: &'a mut [f32],
    pub(crate) masks: Option<&'a mut [u8]>,
    pub(crate) buf: &'a mut [f32],
    pub(crate) acc: &'a mut Vec<f32>,
}

impl WithSimd for ForwardImage<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: Simd>(self, _simd: S) {
        self.net.forward_image(self.seed, self.img, self.masks, self.buf, self.acc);
    }
}

/// [`Net::tangent_image`] on the detected vectors.
struct TangentImage<'a> {
    net: &'a Net,
    seed: &'a [f32],
    masks: &'a [u8],
    img: &'a [f32],
    col: &'a mut [f32],
    buf: &'a mut [f32],
    acc: &'a mut Vec<f32>,
}

impl WithSimd for TangentImage<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: Simd>(self, _simd: S) {
        self.net.tangent_image(self.seed, self.masks, self.img, self.col, self.buf, self.acc);
    }
}

/// [`Net::backward_image`] on the detected vectors.
pub(crate) struct BackwardImage<'a> {
    pub(crate) net: &'a Net,
    pub(crate) gs: &'a mut [f32],
    pub(crate) up: &'a [f32],
    pub(crate) img: &'a [f32],
    pub(crate) masks: &'a [u8],
    pub(crate) bufs: &'a mut [Vec<f32>],
    pub(crate) acc: &'a mut Vec<f32>,
}

impl WithSimd for BackwardImage<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: Simd>(self, _simd: S) {
        self.net.backward_image(self.gs, self.up, self.img, self.masks, self.bufs, self.acc);
    }
}

#[cfg(test)]
mod tests {
    use super::{exp_f32, sigmoid};

    /// The vectorisable exponential against libm's, over the range the clamp keeps, and the
    /// sigmoid at its ends.
    #[test]
    fn exp_f32_is_within_a_few_ulp() {
        let mut worst = 0f64;
        for i in 0..=200_000 {
            let x = -87.0 + 175.0 * i as f32 / 200_000.0;
            let (got, want) = (exp_f32(x) as f64, (x as f64).exp());
            worst = worst.max((got - want).abs() / want);
        }
        assert!(worst < 5e-7, "worst relative error {worst}");
        assert_eq!(exp_f32(0.0), 1.0);
        assert_eq!(sigmoid(0.0), 0.5);
        assert_eq!(sigmoid(1e4), 1.0);
        assert!(sigmoid(-1e4) >= 0.0 && sigmoid(-1e4) < 1e-37);
        assert!((sigmoid(2.0) as f64 - 1.0 / (1.0 + (-2f64).exp())).abs() < 1e-7);
    }
}
