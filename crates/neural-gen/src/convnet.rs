//! A network of fully connected layers then 3×3 convolutions, any of them followed by a ReLU
//! and any convolution by a ×2 pixel shuffle, ending in a sigmoid image: inference and
//! training (MSE, AdamW) on the direct kernels of [`crate::InputVjp`] (`kernels`), for the
//! architectures whose convolutions are not each followed by a pixel shuffle (the
//! LearningToPaint-size network, [`crate::Ltp`]).
//!
//! The fully connected layers run on the whole batch as packed matrix products (forward
//! `x · Wᵀ`, input gradient `g · W`, weight gradient `gᵀ · x`, each output a fixed chain of
//! fused multiply–adds); the convolutions image by image in parallel, each correlation's
//! writeback adding the bias and applying the ReLU and the shuffle, the backward pass the
//! correlation with the flipped, transposed kernel, masked by the stored activations, then the
//! weight-gradient correlation. Every image's convolution gradients are computed on their own
//! and summed in image order: the results do not depend on the thread count.

use candle_nn::VarMap;
use pulp::{Simd, WithSimd};
use rayon::prelude::*;

use crate::NeuralGenError;
use crate::conv::flip_transpose;
use crate::direct::{adamw_step, conv_weight_grads};
use crate::kernels::{Conv3, Dense, Isa, padded_len};
use crate::vjp::{sigmoid, write_padded};

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

/// The architecture of a [`DirectNet`]: fully connected layers of `widths` (from 3 inputs),
/// a ReLU after each but maybe the last, the last layer's output viewed as `seed_channels`
/// planes of `seed_side²`, then the convolution `stages`; the last stage has 4 outputs, no
/// ReLU and a shuffle, and is followed by the sigmoid: one image plane.
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
}

/// One trainable tensor and its AdamW moments.
struct Param {
    name: String,
    w: Vec<f32>,
    g: Vec<f32>,
    m: Vec<f32>,
    v: Vec<f32>,
}

/// A fully connected layer's packed products.
struct Fc {
    /// `x · Wᵀ`.
    fwd: Dense,
    /// `g · W`.
    bwd: Dense,
    inp: usize,
    out: usize,
}

/// A convolution stage on the kernels.
struct Stage {
    spec: StageSpec,
    fwd: Conv3,
    /// The flipped, transposed kernel (the input gradient).
    bwd: Conv3,
    /// Side of the stage's input and of its convolution's output, px.
    n: usize,
}

/// A [`NetSpec`] network on the direct kernels, with its weights and AdamW state; see the
/// module documentation. Weights are candle's names and layouts (`fc{i}.weight` `[out, in]`,
/// `fc{i}.bias`, `conv{i}.weight` `[cout, cin, 3, 3]`, `conv{i}.bias`).
pub struct DirectNet {
    spec: NetSpec,
    isa: Isa,
    /// `fc0.weight, fc0.bias, …, conv0.weight, conv0.bias, …`.
    params: Vec<Param>,
    fcs: Vec<Fc>,
    stages: Vec<Stage>,
    size: usize,
    /// Values per image of the stages' padded inputs.
    per_image: usize,
    t: i32,
    batch: usize,
    /// Outputs of the fully connected layers (after their ReLU), `[batch, width]` each.
    hidden: Vec<Vec<f32>>,
    acts: Vec<f32>,
    images: Vec<f32>,
    up: Vec<f32>,
    /// Per image: the stages' weight and bias gradients, then the seed map's gradient.
    per_grads: Vec<f32>,
    /// The gradient at a fully connected layer's output and its transpose, `[batch, width]`.
    g: Vec<f32>,
    gt: Vec<f32>,
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

/// `v` where the activation `a` (after a ReLU) is positive, else 0.
#[inline(always)]
fn pass(v: f32, a: f32) -> f32 {
    if a > 0.0 { v } else { 0.0 }
}

impl DirectNet {
    /// The network `spec` with the weights of `varmap` (copied).
    ///
    /// # Errors
    /// [`NeuralGenError::Shape`] when the spec does not fit together or a tensor is missing or
    /// has the wrong size; [`NeuralGenError::Candle`].
    pub fn from_varmap(spec: &NetSpec, varmap: &VarMap) -> Result<Self, NeuralGenError> {
        let size = spec.validate()?;
        let data = varmap.data().lock().expect("varmap");
        let mut params = Vec::new();
        let mut want = Vec::new();
        for (i, w) in spec.widths.windows(2).enumerate() {
            want.push((format!("fc{i}.weight"), w[0] * w[1]));
            want.push((format!("fc{i}.bias"), w[1]));
        }
        for (i, st) in spec.stages.iter().enumerate() {
            want.push((format!("conv{i}.weight"), st.cout * st.cin * 9));
            want.push((format!("conv{i}.bias"), st.cout));
        }
        for (name, len) in want {
            let t = data.get(&name).ok_or_else(|| NeuralGenError::Shape(format!("no tensor {name}")))?;
            let w: Vec<f32> = t.as_tensor().flatten_all().and_then(|f| f.to_vec1()).map_err(NeuralGenError::Candle)?;
            if w.len() != len {
                return Err(NeuralGenError::Shape(format!("{name}: {} values, expected {len}", w.len())));
            }
            params.push(Param { name, g: vec![0.0; len], m: vec![0.0; len], v: vec![0.0; len], w });
        }
        drop(data);
        let isa = Isa::detect();
        let fcs = spec
            .widths
            .windows(2)
            .enumerate()
            .map(|(i, w)| {
                let wt = &params[2 * i].w;
                Fc {
                    fwd: Dense::new_transposed(wt, w[1], w[0], isa),
                    bwd: Dense::new(wt, w[1], w[0], isa),
                    inp: w[0],
                    out: w[1],
                }
            })
            .collect();
        let nfc = spec.widths.len() - 1;
        let mut n = spec.seed_side;
        let mut stages = Vec::new();
        let mut per_image = 0;
        for (i, st) in spec.stages.iter().enumerate() {
            let w = &params[2 * (nfc + i)].w;
            stages.push(Stage {
                spec: *st,
                fwd: Conv3::new(w, st.cout, st.cin, isa),
                bwd: Conv3::new(&flip_transpose(w, st.cout, st.cin, 3), st.cin, st.cout, isa),
                n,
            });
            per_image += padded_len(st.cin, n);
            if st.shuffle {
                n *= 2;
            }
        }
        Ok(DirectNet {
            spec: spec.clone(),
            isa,
            params,
            fcs,
            stages,
            size,
            per_image,
            t: 0,
            batch: 0,
            hidden: Vec::new(),
            acts: Vec::new(),
            images: Vec::new(),
            up: Vec::new(),
            per_grads: Vec::new(),
            g: Vec::new(),
            gt: Vec::new(),
        })
    }

    /// Side of the images, px.
    pub fn size(&self) -> usize {
        self.size
    }

    /// The architecture.
    pub fn spec(&self) -> &NetSpec {
        &self.spec
    }

    /// The bias of fully connected layer `li` or (offset by the layers) of stage `si`.
    fn bias(&self, layer: usize) -> &[f32] {
        &self.params[2 * layer + 1].w
    }

    /// Values of the seed map per image.
    fn seed_len(&self) -> usize {
        self.spec.seed_channels * self.spec.seed_side * self.spec.seed_side
    }

    /// Values per image of the convolution stages' weight and bias gradients.
    fn conv_len(&self) -> usize {
        self.spec.stages.iter().map(|s| s.cout * s.cin * 9 + s.cout).sum()
    }

    /// The fully connected layers on the batch `x` (`[batch, 3]`) into `hidden` (every
    /// layer's output after its ReLU; the last is the seed maps).
    fn dense_forward(&self, x: &[f32], hidden: &mut Vec<Vec<f32>>) {
        let b = x.len() / 3;
        hidden.resize_with(self.fcs.len(), Vec::new);
        let last = self.fcs.len() - 1;
        for li in 0..self.fcs.len() {
            let (done, rest) = hidden.split_at_mut(li);
            let input: &[f32] = if li == 0 { x } else { &done[li - 1] };
            let y = &mut rest[0];
            y.resize(b * self.fcs[li].out, 0.0);
            self.fcs[li].fwd.apply_into(input, Some(self.bias(li)), y);
            if li < last || self.spec.relu_last_fc {
                y.iter_mut().for_each(|v| *v = v.max(0.0));
            }
        }
    }

    /// Images of a batch of normalised inputs `x` (`[batch, 3]`): `batch × size²` values in
    /// [0, 1], image after image. The same bits for any batch split and thread count.
    ///
    /// # Errors
    /// [`NeuralGenError::Shape`] when `x.len()` is not a multiple of 3.
    pub fn forward(&self, x: &[f32]) -> Result<Vec<f32>, NeuralGenError> {
        if x.len() % 3 != 0 {
            return Err(NeuralGenError::Shape(format!("{} inputs: they come in threes", x.len())));
        }
        let ss = self.size * self.size;
        let mut images = vec![0f32; x.len() / 3 * ss];
        if x.is_empty() {
            return Ok(images);
        }
        let mut hidden = Vec::new();
        self.dense_forward(x, &mut hidden);
        let seed = &hidden[self.fcs.len() - 1];
        images.par_chunks_mut(ss).zip(seed.par_chunks(self.seed_len())).for_each_init(
            || (vec![0f32; self.per_image], Vec::new()),
            |(buf, acc), (img, sd)| self.isa.dispatch(Forward { net: self, seed: sd, img, buf, acc }),
        );
        Ok(images)
    }

    /// The stages of one image from its seed map; `buf` receives every stage's padded input
    /// (zero borders kept: write them once).
    #[inline(always)]
    fn forward_image(&self, seed: &[f32], img: &mut [f32], buf: &mut [f32], acc: &mut Vec<f32>) {
        let mut reg = regions(&self.stages, buf);
        write_padded(reg[0], seed, self.spec.seed_channels, self.spec.seed_side);
        let (nfc, last) = (self.fcs.len(), self.stages.len() - 1);
        for (si, st) in self.stages.iter().enumerate() {
            let (cur, next) = reg.split_at_mut(si + 1);
            let (x, n, bias, relu) = (&*cur[si], st.n, self.bias(nfc + si), st.spec.relu);
            if si == last {
                let s = 2 * n;
                st.fwd.run_pairs(x, n, acc, |o, y, r0, r1| {
                    let (ch, r, b0, b1) = (o / 4, 2 * y + (o / 2) % 2, bias[o], bias[o + 1]);
                    let d = &mut img[(ch * s + r) * s..(ch * s + r + 1) * s];
                    for (dd, (&v0, &v1)) in d.chunks_exact_mut(2).zip(r0.iter().zip(r1)) {
                        dd[0] = v0 + b0;
                        dd[1] = v1 + b1;
                    }
                });
                for v in img.iter_mut() {
                    *v = sigmoid(*v);
                }
            } else if st.spec.shuffle {
                let (dst, s) = (&mut *next[0], 2 * n);
                let wq = s + 2;
                st.fwd.run_pairs(x, n, acc, |o, y, r0, r1| {
                    let (ch, r, b0, b1) = (o / 4, 2 * y + (o / 2) % 2, bias[o], bias[o + 1]);
                    let d = &mut dst[ch * wq * wq + (r + 1) * wq + 1..ch * wq * wq + (r + 1) * wq + 1 + s];
                    for (dd, (&v0, &v1)) in d.chunks_exact_mut(2).zip(r0.iter().zip(r1)) {
                        let (a0, a1) = (v0 + b0, v1 + b1);
                        dd[0] = if relu { a0.max(0.0) } else { a0 };
                        dd[1] = if relu { a1.max(0.0) } else { a1 };
                    }
                });
            } else {
                let (dst, wq) = (&mut *next[0], n + 2);
                st.fwd.run(x, n, acc, |o, y, row| {
                    let d = &mut dst[o * wq * wq + (y + 1) * wq + 1..o * wq * wq + (y + 1) * wq + 1 + n];
                    let bo = bias[o];
                    for (dd, &v) in d.iter_mut().zip(row) {
                        let a = v + bo;
                        *dd = if relu { a.max(0.0) } else { a };
                    }
                });
            }
        }
    }

    /// Sizes the per-image buffers for `batch` images (only when the batch changes).
    fn size_for(&mut self, batch: usize) {
        if batch == self.batch {
            return;
        }
        let ss = self.size * self.size;
        self.acts = vec![0.0; batch * self.per_image];
        self.images = vec![0.0; batch * ss];
        self.up = vec![0.0; batch * ss];
        self.per_grads = vec![0.0; batch * (self.conv_len() + self.seed_len())];
        self.batch = batch;
    }

    /// The MSE of the images of normalised inputs `x` (`[B, 3]`) against `target` (`B ×
    /// size²`), and every parameter's gradient of it (kept for [`DirectNet::update`]).
    ///
    /// # Errors
    /// [`NeuralGenError::Shape`] when `x` is empty or not in threes, or `target` is not
    /// `B × size²` long.
    pub fn gradients(&mut self, x: &[f32], target: &[f32]) -> Result<f64, NeuralGenError> {
        let ss = self.size * self.size;
        let b = x.len() / 3;
        if b == 0 || x.len() % 3 != 0 || target.len() != b * ss {
            return Err(NeuralGenError::Shape(format!(
                "{} inputs and {} target values: expected threes and {ss} values per image",
                x.len(),
                target.len()
            )));
        }
        self.size_for(b);
        let mut hidden = std::mem::take(&mut self.hidden);
        self.dense_forward(x, &mut hidden);
        let (pi, sl, cl) = (self.per_image, self.seed_len(), self.conv_len());
        {
            let (mut images, mut acts) = (std::mem::take(&mut self.images), std::mem::take(&mut self.acts));
            let net = &*self;
            let seed = &hidden[net.fcs.len() - 1];
            images
                .par_chunks_mut(ss)
                .zip(acts.par_chunks_mut(pi))
                .zip(seed.par_chunks(sl))
                .for_each_init(Vec::new, |acc, ((img, buf), sd)| {
                    net.isa.dispatch(Forward { net, seed: sd, img, buf, acc })
                });
            self.images = images;
            self.acts = acts;
        }
        // MSE and its gradient.
        let k = 2.0 / (b * ss) as f32;
        let mut loss = 0f64;
        for ((u, &y), &t) in self.up.iter_mut().zip(&self.images).zip(target) {
            let d = y - t;
            loss += (d as f64) * (d as f64);
            *u = k * d;
        }
        loss /= (b * ss) as f64;
        // Per image: back through the stages, each stage's weight gradients on the way.
        let mut per_grads = std::mem::take(&mut self.per_grads);
        {
            let net = &*self;
            let bufs = || -> Vec<Vec<f32>> {
                net.stages.iter().map(|st| vec![0f32; padded_len(st.spec.cout, st.n)]).collect()
            };
            per_grads
                .par_chunks_mut(cl + sl)
                .zip(net.up.par_chunks(ss))
                .zip(net.images.par_chunks(ss))
                .zip(net.acts.par_chunks(pi))
                .for_each_init(
                    || (bufs(), Vec::new()),
                    |(bufs, acc), (((out, up), img), acts)| {
                        net.isa.dispatch(Backward { net, out, up, img, acts, bufs, acc })
                    },
                );
        }
        // The convolution gradients summed over the images, in image order.
        let nfc = self.fcs.len();
        let mut off = 0;
        for p in &mut self.params[2 * nfc..] {
            let len = p.g.len();
            let per = &per_grads;
            p.g.par_chunks_mut(1024).enumerate().for_each(|(ci, gch)| {
                let base = off + ci * 1024;
                gch.fill(0.0);
                for i in 0..b {
                    let src = &per[i * (cl + sl) + base..i * (cl + sl) + base + gch.len()];
                    gch.iter_mut().zip(src).for_each(|(a, v)| *a += v);
                }
            });
            off += len;
        }
        // Back through the fully connected layers, on the whole batch.
        let mut g = std::mem::take(&mut self.g);
        let mut gt = std::mem::take(&mut self.gt);
        g.clear();
        for i in 0..b {
            g.extend_from_slice(&per_grads[i * (cl + sl) + cl..(i + 1) * (cl + sl)]);
        }
        self.per_grads = per_grads;
        for li in (0..nfc).rev() {
            let (inp, out) = (self.fcs[li].inp, self.fcs[li].out);
            let input: &[f32] = if li == 0 { x } else { &hidden[li - 1] };
            // dW = gᵀ · input ([out, inp], candle's layout); db = Σ_b g.
            gt.resize(out * b, 0.0);
            gt.par_chunks_mut(b).enumerate().for_each(|(o, row)| {
                for (i, v) in row.iter_mut().enumerate() {
                    *v = g[i * out + o];
                }
            });
            let xin = Dense::new(input, b, inp, self.isa);
            let (wp, rest) = self.params[2 * li..].split_at_mut(1);
            xin.apply_into(&gt, None, &mut wp[0].g);
            rest[0].g.par_iter_mut().zip(gt.par_chunks(b)).for_each(|(bo, row)| *bo = row.iter().sum());
            if li > 0 {
                let mut gi = self.fcs[li].bwd.apply(&g, None);
                gi.par_iter_mut().zip(input.par_iter()).for_each(|(v, &a)| *v = pass(*v, a));
                g = gi;
            }
        }
        self.g = g;
        self.gt = gt;
        self.hidden = hidden;
        Ok(loss)
    }

    /// One AdamW step (candle's rule, weight decay 0) on the gradients of the last
    /// [`DirectNet::gradients`], at learning rate `lr`; the kernels then run on the new
    /// weights.
    pub fn update(&mut self, lr: f64) {
        self.t += 1;
        for p in &mut self.params {
            adamw_step(&mut p.w, &p.g, &mut p.m, &mut p.v, lr, self.t);
        }
        let nfc = self.fcs.len();
        for (li, fc) in self.fcs.iter_mut().enumerate() {
            fc.fwd.repack_transposed(&self.params[2 * li].w);
            fc.bwd.repack(&self.params[2 * li].w);
        }
        for (si, st) in self.stages.iter_mut().enumerate() {
            let (w, s) = (&self.params[2 * (nfc + si)].w, st.spec);
            st.fwd = Conv3::new(w, s.cout, s.cin, self.isa);
            st.bwd = Conv3::new(&flip_transpose(w, s.cout, s.cin, 3), s.cin, s.cout, self.isa);
        }
    }

    /// [`DirectNet::gradients`] then [`DirectNet::update`]: one training step; returns the
    /// MSE before it.
    ///
    /// # Errors
    /// As [`DirectNet::gradients`].
    pub fn step(&mut self, x: &[f32], target: &[f32], lr: f64) -> Result<f64, NeuralGenError> {
        let loss = self.gradients(x, target)?;
        self.update(lr);
        Ok(loss)
    }

    /// The gradient of the last [`DirectNet::gradients`] for the tensor `name`.
    pub fn gradient(&self, name: &str) -> Option<&[f32]> {
        self.params.iter().find(|p| p.name == name).map(|p| &p.g[..])
    }

    /// The current weights of the tensor `name`.
    pub fn weight(&self, name: &str) -> Option<&[f32]> {
        self.params.iter().find(|p| p.name == name).map(|p| &p.w[..])
    }

    /// The backward pass of one image: the gradient at the last convolution's output from the
    /// upstream gradient `up` of the image `img`, then stage by stage (last first) the weight
    /// and bias gradients into `out` and the gradient of the stage's input, masked by the
    /// stored activations `acts`; the seed map's gradient at the end of `out`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn backward_image<S: Simd>(
        &self,
        simd: S,
        out: &mut [f32],
        up: &[f32],
        img: &[f32],
        acts: &[f32],
        bufs: &mut [Vec<f32>],
        acc: &mut Vec<f32>,
    ) {
        let last = self.stages.len() - 1;
        // Through the sigmoid, un-shuffled onto the last convolution's padded output: row yy
        // of the image interleaves rows yy / 2 of channels 2(yy % 2) + {0, 1}.
        let st = &self.stages[last];
        let (n, s, wp) = (st.n, 2 * st.n, st.n + 2);
        let q2 = wp * wp;
        let gl = &mut bufs[last];
        for yy in 0..s {
            let base = 2 * (yy % 2) * q2 + (yy / 2 + 1) * wp + 1;
            let (lo, hi) = gl.split_at_mut(base + q2);
            let (d0, d1) = (&mut lo[base..base + n], &mut hi[..n]);
            let row = yy * s..(yy + 1) * s;
            let (u, y) = (&up[row.clone()], &img[row]);
            for ((e0, e1), (uu, yv)) in d0.iter_mut().zip(d1.iter_mut()).zip(u.chunks_exact(2).zip(y.chunks_exact(2))) {
                *e0 = uu[0] * yv[0] * (1.0 - yv[0]);
                *e1 = uu[1] * yv[1] * (1.0 - yv[1]);
            }
        }
        // Offsets of the stages' inputs in `acts` and of their gradients in `out`.
        let mut aoffs = Vec::with_capacity(self.stages.len());
        let mut goffs = Vec::with_capacity(self.stages.len());
        let (mut ao, mut go) = (0, 0);
        for st in &self.stages {
            aoffs.push(ao);
            goffs.push(go);
            ao += padded_len(st.spec.cin, st.n);
            go += st.spec.cout * st.spec.cin * 9 + st.spec.cout;
        }
        let (grads, gs) = out.split_at_mut(go);
        for (si, st) in self.stages.iter().enumerate().rev() {
            let (n, sp) = (st.n, st.spec);
            let (lo, hi) = bufs.split_at_mut(si);
            let gy = &hi[0];
            let a = &acts[aoffs[si]..aoffs[si] + padded_len(sp.cin, n)];
            let (gw, rest) = grads[goffs[si]..].split_at_mut(sp.cout * sp.cin * 9);
            conv_weight_grads(simd, a, gy, (sp.cin, sp.cout, n), gw, &mut rest[..sp.cout]);
            let wa = n + 2;
            if si == 0 {
                // The seed map's gradient, through the last fully connected layer's ReLU.
                let relu = self.spec.relu_last_fc;
                st.bwd.run(gy, n, acc, |c, y, row| {
                    let d = &mut gs[(c * n + y) * n..(c * n + y + 1) * n];
                    let ar = &a[c * wa * wa + (y + 1) * wa + 1..c * wa * wa + (y + 1) * wa + 1 + n];
                    for ((dd, &v), &av) in d.iter_mut().zip(row).zip(ar) {
                        *dd = if relu { pass(v, av) } else { v };
                    }
                });
                continue;
            }
            let prev = self.stages[si - 1].spec;
            let dst = &mut lo[si - 1];
            if prev.shuffle {
                // Row y of channel c de-interleaves into rows y / 2 of channels
                // 4c + 2(y % 2) + {0, 1} of the previous convolution's output.
                let (h, wq) = (n / 2, n / 2 + 2);
                let q2 = wq * wq;
                st.bwd.run(gy, n, acc, |c, y, row| {
                    let base = (4 * c + 2 * (y % 2)) * q2 + (y / 2 + 1) * wq + 1;
                    let (dlo, dhi) = dst.split_at_mut(base + q2);
                    let (d0, d1) = (&mut dlo[base..base + h], &mut dhi[..h]);
                    let ar = &a[c * wa * wa + (y + 1) * wa + 1..c * wa * wa + (y + 1) * wa + 1 + n];
                    for ((e0, e1), (v, av)) in
                        d0.iter_mut().zip(d1.iter_mut()).zip(row.chunks_exact(2).zip(ar.chunks_exact(2)))
                    {
                        *e0 = if prev.relu { pass(v[0], av[0]) } else { v[0] };
                        *e1 = if prev.relu { pass(v[1], av[1]) } else { v[1] };
                    }
                });
            } else {
                st.bwd.run(gy, n, acc, |c, y, row| {
                    let r = c * wa * wa + (y + 1) * wa + 1..c * wa * wa + (y + 1) * wa + 1 + n;
                    let ar = &a[r.clone()];
                    for ((dd, &v), &av) in dst[r].iter_mut().zip(row).zip(ar) {
                        *dd = if prev.relu { pass(v, av) } else { v };
                    }
                });
            }
        }
    }

    /// Copies the current weights into `varmap`'s variables of the same names.
    ///
    /// # Errors
    /// [`NeuralGenError::Shape`] when a variable is missing; [`NeuralGenError::Candle`].
    pub fn write_back(&self, varmap: &VarMap) -> Result<(), NeuralGenError> {
        let data = varmap.data().lock().expect("varmap");
        for p in &self.params {
            let var = data.get(&p.name).ok_or_else(|| NeuralGenError::Shape(format!("no variable {}", p.name)))?;
            let t =
                candle_core::Tensor::from_vec(p.w.clone(), var.dims(), var.device()).map_err(NeuralGenError::Candle)?;
            var.set(&t).map_err(NeuralGenError::Candle)?;
        }
        Ok(())
    }
}

/// [`DirectNet::forward_image`] on the detected vectors.
struct Forward<'a> {
    net: &'a DirectNet,
    seed: &'a [f32],
    img: &'a mut [f32],
    buf: &'a mut [f32],
    acc: &'a mut Vec<f32>,
}

impl WithSimd for Forward<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: Simd>(self, _simd: S) {
        self.net.forward_image(self.seed, self.img, self.buf, self.acc);
    }
}

/// [`DirectNet::backward_image`] on the detected vectors.
struct Backward<'a> {
    net: &'a DirectNet,
    out: &'a mut [f32],
    up: &'a [f32],
    img: &'a [f32],
    acts: &'a [f32],
    bufs: &'a mut [Vec<f32>],
    acc: &'a mut Vec<f32>,
}

impl WithSimd for Backward<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        self.net.backward_image(simd, self.out, self.up, self.img, self.acts, self.bufs, self.acc);
    }
}

#[cfg(test)]
mod tests {
    use super::{DirectNet, NetSpec, StageSpec};
    use crate::{Ltp, LtpKernels};
    use candle_core::{DType, Device, Tensor};
    use candle_nn::{AdamW, Optimizer, ParamsAdamW, VarBuilder, VarMap};

    fn values(n: usize, seed: u64, scale: f32) -> Vec<f32> {
        let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        (0..n)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                scale * ((s >> 40) as f32 / (1u64 << 23) as f32 - 1.0)
            })
            .collect()
    }

    /// Sets every variable of `varmap` to reproducible values of the size candle's default
    /// initialisation has (uniform, ±1/√fan-in), biases included so that every ReLU sees
    /// both signs.
    fn fill(varmap: &VarMap) {
        let data = varmap.data().lock().unwrap();
        let mut names: Vec<&String> = data.keys().collect();
        names.sort();
        for (i, name) in names.into_iter().enumerate() {
            let var = &data[name];
            let dims = var.dims().to_vec();
            let fan_in: usize = if dims.len() > 1 { dims[1..].iter().product() } else { 8 };
            let v = values(var.elem_count(), 11 + i as u64, 1.0 / (fan_in as f32).sqrt());
            var.set(&Tensor::from_vec(v, dims, &Device::Cpu).unwrap()).unwrap();
        }
    }

    /// Variables for `spec` with candle's layers' names and shapes.
    fn varmap_for(spec: &NetSpec) -> VarMap {
        let varmap = VarMap::new();
        let vb = VarBuilder::from_varmap(&varmap, DType::F32, &Device::Cpu);
        for (i, w) in spec.widths.windows(2).enumerate() {
            candle_nn::linear(w[0], w[1], vb.pp(format!("fc{i}"))).unwrap();
        }
        let cfg = candle_nn::Conv2dConfig { padding: 1, ..Default::default() };
        for (i, st) in spec.stages.iter().enumerate() {
            candle_nn::conv2d(st.cin, st.cout, 3, cfg, vb.pp(format!("conv{i}"))).unwrap();
        }
        fill(&varmap);
        varmap
    }

    /// `spec` as a candle graph on `varmap`'s variables (autograd through it).
    fn candle_forward(spec: &NetSpec, varmap: &VarMap, x: &Tensor) -> Tensor {
        let data = varmap.data().lock().unwrap();
        let get = |n: String| data[&n].as_tensor().clone();
        let nfc = spec.widths.len() - 1;
        let mut h = x.clone();
        for i in 0..nfc {
            h = h
                .matmul(&get(format!("fc{i}.weight")).t().unwrap())
                .unwrap()
                .broadcast_add(&get(format!("fc{i}.bias")))
                .unwrap();
            if i + 1 < nfc || spec.relu_last_fc {
                h = h.relu().unwrap();
            }
        }
        let mut h = h.reshape((x.dim(0).unwrap(), spec.seed_channels, spec.seed_side, spec.seed_side)).unwrap();
        for (i, st) in spec.stages.iter().enumerate() {
            let b = get(format!("conv{i}.bias")).reshape((1, st.cout, 1, 1)).unwrap();
            h = h.conv2d(&get(format!("conv{i}.weight")), 1, 1, 1, 1).unwrap().broadcast_add(&b).unwrap();
            if st.relu {
                h = h.relu().unwrap();
            }
            if st.shuffle {
                h = candle_nn::ops::pixel_shuffle(&h, 2).unwrap();
            }
        }
        candle_nn::ops::sigmoid(&h).unwrap()
    }

    fn flat(t: &Tensor) -> Vec<f32> {
        t.flatten_all().unwrap().to_vec1().unwrap()
    }

    fn inputs(batch: usize) -> Vec<f32> {
        values(batch * 3, 5, 1.0)
    }

    /// Images, every gradient and one AdamW step of the direct kernels against candle's graph
    /// (`forward` on `varmap`), its autograd and candle's `AdamW`.
    fn check(spec: &NetSpec, varmap: &VarMap, forward: &dyn Fn(&Tensor) -> Tensor, batch: usize, what: &str) {
        let mut net = DirectNet::from_varmap(spec, varmap).unwrap();
        let s = net.size();
        let x = inputs(batch);
        let xs = Tensor::from_vec(x.clone(), (batch, 3), &Device::Cpu).unwrap();
        let t: Vec<f32> = (0..batch * s * s).map(|i| ((i * 7919) % 113) as f32 / 113.0).collect();
        let ts = Tensor::from_vec(t.clone(), (batch, 1, s, s), &Device::Cpu).unwrap();
        // Images.
        let y = forward(&xs);
        let (want, got) = (flat(&y), net.forward(&x).unwrap());
        assert_eq!(want.len(), got.len(), "{what}: image size");
        let worst = want.iter().zip(&got).fold(0f32, |m, (a, b)| m.max((a - b).abs()));
        assert!(worst < 1e-5, "{what}: images differ by {worst}");
        let spread = want.iter().fold(0f32, |m, v| m.max((v - 0.5).abs()));
        assert!(spread > 1e-3, "{what}: a flat image tests little");
        // Loss and gradients.
        let l = (y - &ts).unwrap().sqr().unwrap().mean_all().unwrap();
        let lc = l.to_scalar::<f32>().unwrap() as f64;
        let loss = net.gradients(&x, &t).unwrap();
        assert!((loss - lc).abs() < 1e-5 * lc, "{what}: loss {loss} vs candle {lc}");
        let grads = l.backward().unwrap();
        {
            let data = varmap.data().lock().unwrap();
            assert_eq!(data.len(), 2 * (spec.widths.len() - 1 + spec.stages.len()));
            for (name, var) in data.iter() {
                let want = flat(grads.get(var).unwrap());
                let got = net.gradient(name).unwrap();
                assert_eq!(want.len(), got.len(), "{what} {name}");
                let scale = want.iter().fold(0f32, |m, v| m.max(v.abs()));
                let worst = want.iter().zip(got).fold(0f32, |m, (a, b)| m.max((a - b).abs()));
                assert!(scale > 1e-9, "{what} {name}: a zero gradient tests nothing");
                assert!(worst <= 1e-3 * scale, "{what} {name}: worst {worst} of {scale}");
            }
        }
        // One AdamW step each way: the same weights.
        let mut opt =
            AdamW::new(varmap.all_vars(), ParamsAdamW { lr: 1e-3, weight_decay: 0.0, ..Default::default() }).unwrap();
        opt.step(&grads).unwrap();
        net.update(1e-3);
        let data = varmap.data().lock().unwrap();
        for (name, var) in data.iter() {
            let (vc, vd) = (flat(var.as_tensor()), net.weight(name).unwrap());
            // Adam moves each weight by about lr; a gradient near zero may flip the sign of a
            // step, so compare to a fraction of the step.
            let worst = vc.iter().zip(vd).fold(0f32, |m, (p, q)| m.max((p - q).abs()));
            assert!(worst < 2.1e-3, "{what} {name}: weights differ by {worst} after one step");
            let agree = vc.iter().zip(vd).filter(|(p, q)| (*p - *q).abs() < 1e-5).count();
            assert!(agree * 10 >= vc.len() * 9, "{what} {name}: {agree} of {} weights agree", vc.len());
        }
        drop(data);
        // The updated network's images are candle's on the written-back weights.
        net.write_back(varmap).unwrap();
        let (want, got) = (flat(&forward(&xs)), net.forward(&x).unwrap());
        let worst = want.iter().zip(&got).fold(0f32, |m, (a, b)| m.max((a - b).abs()));
        assert!(worst < 1e-5, "{what}: images after the step differ by {worst}");
    }

    fn st(cin: usize, cout: usize, relu: bool, shuffle: bool) -> StageSpec {
        StageSpec { cin, cout, relu, shuffle }
    }

    /// Convolutions with and without shuffles and ReLUs, odd sides and channel counts.
    fn odd() -> NetSpec {
        NetSpec {
            widths: vec![3, 24, 45],
            relu_last_fc: true,
            seed_channels: 5,
            seed_side: 3,
            stages: vec![
                st(5, 8, true, false),
                st(8, 12, false, true),
                st(3, 7, true, false),
                st(7, 8, true, true),
                st(2, 4, false, true),
            ],
        }
    }

    /// The generator's pattern (every convolution followed by a shuffle, no ReLU after the
    /// last fully connected layer).
    fn generator_like() -> NetSpec {
        NetSpec {
            widths: vec![3, 16, 64],
            relu_last_fc: false,
            seed_channels: 4,
            seed_side: 4,
            stages: vec![st(4, 8, true, true), st(2, 12, true, true), st(3, 4, false, true)],
        }
    }

    #[test]
    fn odd_architectures_match_candle() {
        for (spec, what) in [(odd(), "odd"), (generator_like(), "generator-like")] {
            let vm = varmap_for(&spec);
            check(&spec, &vm, &|x: &Tensor| candle_forward(&spec, &vm, x), 5, what);
        }
    }

    /// The LearningToPaint-size network against its own candle implementation (`Ltp`).
    #[test]
    fn learning_to_paint_network_matches_candle() {
        let ltp = Ltp::new(LtpKernels::Candle, 1e-3).unwrap();
        fill(&ltp.varmap);
        let spec = Ltp::spec();
        assert_eq!(spec.macs_per_image(), Ltp::MACS_PER_IMAGE);
        check(&spec, &ltp.varmap, &|x: &Tensor| ltp.forward(x).unwrap(), 2, "LearningToPaint");
    }

    /// Images do not depend on the batch split; gradients and steps not on the thread count.
    #[test]
    fn results_do_not_depend_on_batch_or_threads() {
        let spec = odd();
        let vm = varmap_for(&spec);
        let x = inputs(6);
        let s = DirectNet::from_varmap(&spec, &vm).unwrap().size();
        let t = vec![0.25f32; 6 * s * s];
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let mut net = DirectNet::from_varmap(&spec, &vm).unwrap();
                let whole = net.forward(&x).unwrap();
                let parts: Vec<f32> = x.chunks(9).flat_map(|c| net.forward(c).unwrap()).collect();
                assert_eq!(whole, parts, "a batch against its parts");
                net.step(&x, &t, 1e-3).unwrap();
                net.gradients(&x, &t).unwrap();
                net.params.iter().map(|p| (p.g.clone(), p.w.clone())).collect::<Vec<_>>()
            })
        };
        assert_eq!(run(1), run(2));
    }

    #[test]
    fn bad_specs_and_inputs_are_errors() {
        let mut spec = odd();
        spec.stages[1].cout = 10;
        assert!(spec.validate().is_err(), "a shuffle of 10 channels");
        let mut spec = odd();
        spec.widths[2] = 44;
        assert!(spec.validate().is_err(), "seed size");
        let mut spec = odd();
        spec.stages[4].shuffle = false;
        assert!(spec.validate().is_err(), "the last stage without a shuffle");
        let spec = odd();
        let vm = varmap_for(&generator_like());
        assert!(DirectNet::from_varmap(&spec, &vm).is_err(), "weights of another architecture");
        let vm = varmap_for(&spec);
        let mut net = DirectNet::from_varmap(&spec, &vm).unwrap();
        assert!(net.forward(&[0.0; 4]).is_err());
        assert!(net.gradients(&[0.0; 3], &[0.0; 5]).is_err());
        assert!(net.gradients(&[], &[]).is_err());
    }
}
