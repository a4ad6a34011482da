//! Training on the direct kernels, for the generator and for any [`NetSpec`] network (the
//! benchmarks' LearningToPaint-size one): per image in one pass (its activations stay in the
//! core's cache), the forward pass of [`Net`] with every stage's input and ReLU mask kept, the
//! squared error, the backward pass to the seed map (the input-gradient correlations of
//! [`Net`]) and a weight-gradient correlation per stage; then products for the fully connected
//! layers on the whole batch, and AdamW fused into one pass per tensor, on plain buffers
//! allocated once.
//!
//! Every image's gradients are computed on their own and summed over the batch in image order,
//! each sum a fixed chain of operations: the results do not depend on the thread count. The
//! weights live here during training; [`DirectTrainer::write_back`] copies them into the
//! generator's candle variables (checkpoints, the final weights).

// `DirectTrainer` is public through `crate::bench` only (the `bench` feature).
#![cfg_attr(not(feature = "bench"), allow(unreachable_pub))]

use std::sync::{Mutex, MutexGuard};

use candle_nn::VarMap;
use pulp::{Simd, WithSimd};
use rayon::prelude::*;

use crate::NeuralGenError;
use crate::kernels::{Dense, padded_len};
use crate::model::Generator;
use crate::net::{BackwardImage, ForwardImage, Net, NetSpec};

/// One trainable tensor and its AdamW moments.
struct Param {
    name: String,
    dims: Vec<usize>,
    w: Vec<f32>,
    g: Vec<f32>,
    m: Vec<f32>,
    v: Vec<f32>,
}

/// A network's training step on the direct kernels (AdamW with weight decay 0 on MSE): the
/// generator's ([`DirectTrainer::new`]) or any [`NetSpec`]'s ([`DirectTrainer::from_varmap`]).
/// [`crate::train()`] is the generator's entry point; public for the benchmarks.
pub struct DirectTrainer {
    /// `fc0.weight, fc0.bias, …, conv0.weight, conv0.bias, …`.
    params: Vec<Param>,
    net: Net,
    t: i32,
    /// Per image: the convolution stages' weight and bias gradients, then the seed-map gradient.
    per_image: Vec<f32>,
    /// The gradient at a fully connected layer's output, transposed (`[out, batch]`).
    gt: Vec<f32>,
    /// The fully connected layers' outputs (after their ReLU; the last: the seed maps).
    hid: Vec<Vec<f32>>,
    /// Each fully connected layer's input, packed for its weight gradient (`[batch, in]`).
    xin: Vec<Dense>,
    /// The gradients at a fully connected layer's output and input (`[batch, ·]`).
    g: Vec<f32>,
    gi: Vec<f32>,
    /// Scratch of the panel-parallel products; the images' squared errors.
    dense_t: Vec<f32>,
    sq: Vec<f64>,
    /// Per-thread scratch of the per-image passes (gradient planes with zero borders).
    pool: Vec<Mutex<Scratch>>,
    batch: usize,
}

/// One thread's scratch for the per-image pass (forward, loss, backward and weight gradients
/// of one image, so that its activations stay in the core's cache): the stages' padded inputs
/// and the padded gradient at every stage's output (zero borders kept), the ReLU masks, the
/// image and the loss's gradient, and the correlation's accumulators.
struct Scratch {
    acts: Vec<f32>,
    bufs: Vec<Vec<f32>>,
    masks: Vec<u8>,
    img: Vec<f32>,
    up: Vec<f32>,
    acc: Vec<f32>,
}

/// A thread's [`Scratch`] from the trainer's pool, or its own where that is in use.
struct ScratchRef<'a> {
    guard: Option<MutexGuard<'a, Scratch>>,
    own: Option<Scratch>,
}

impl Scratch {
    fn new(net: &Net) -> Self {
        let ss = net.size * net.size;
        Scratch {
            acts: vec![0f32; net.per_image],
            bufs: net.gradient_planes(),
            masks: vec![0u8; net.masks_per_image],
            img: vec![0f32; ss],
            up: vec![0f32; ss],
            acc: Vec::new(),
        }
    }

    /// The current thread's entry of `pool` (by rayon's thread index), when free.
    fn take(pool: &[Mutex<Scratch>]) -> ScratchRef<'_> {
        let i = rayon::current_thread_index().unwrap_or(0) % pool.len().max(1);
        ScratchRef { guard: pool.get(i).and_then(|m| m.try_lock().ok()), own: None }
    }
}

impl ScratchRef<'_> {
    fn get(&mut self, net: &Net) -> &mut Scratch {
        match &mut self.guard {
            Some(g) => g,
            None => self.own.get_or_insert_with(|| Scratch::new(net)),
        }
    }
}

impl DirectTrainer {
    /// The generator's network with `g`'s weights (copied).
    ///
    /// # Errors
    /// [`NeuralGenError::Candle`].
    pub fn new(g: &Generator) -> Result<Self, NeuralGenError> {
        Self::from_varmap(&NetSpec::of_arch(&g.config.arch), &g.varmap)
    }

    /// The network `spec` with the weights of `varmap` (copied; candle's names and layouts:
    /// `fc{i}.weight` `[out, in]`, `fc{i}.bias`, `conv{i}.weight` `[cout, cin, 3, 3]`,
    /// `conv{i}.bias`).
    ///
    /// # Errors
    /// [`NeuralGenError::Shape`] when the spec does not fit together or a tensor is missing or
    /// has the wrong size; [`NeuralGenError::Candle`].
    pub fn from_varmap(spec: &NetSpec, varmap: &VarMap) -> Result<Self, NeuralGenError> {
        spec.validate()?;
        let data = varmap.data().lock().expect("varmap");
        let mut params = Vec::new();
        for (name, dims) in spec.tensors() {
            let t = data.get(&name).ok_or_else(|| NeuralGenError::Shape(format!("no tensor {name}")))?;
            let w: Vec<f32> = t.as_tensor().flatten_all().and_then(|f| f.to_vec1()).map_err(NeuralGenError::Candle)?;
            let len: usize = dims.iter().product();
            if w.len() != len {
                return Err(NeuralGenError::Shape(format!("{name}: {} values, expected {len}", w.len())));
            }
            params.push(Param { name, dims, w, g: vec![0.0; len], m: vec![0.0; len], v: vec![0.0; len] });
        }
        drop(data);
        let net =
            Net::new(spec, |name| Ok(params.iter().find(|p| p.name == name).map(|p| p.w.clone()).unwrap_or_default()))?;
        Ok(DirectTrainer {
            params,
            net,
            t: 0,
            per_image: Vec::new(),
            gt: Vec::new(),
            hid: Vec::new(),
            xin: Vec::new(),
            g: Vec::new(),
            gi: Vec::new(),
            dense_t: Vec::new(),
            sq: Vec::new(),
            pool: Vec::new(),
            batch: 0,
        })
    }

    /// Side of the images, px.
    #[cfg(any(test, feature = "bench"))]
    pub fn size(&self) -> usize {
        self.net.size
    }

    /// Sizes the per-image buffers for `batch` images (only when the batch changes).
    fn size_for(&mut self, batch: usize) {
        if batch == self.batch {
            return;
        }
        let net = &self.net;
        self.per_image = vec![0.0; batch * (net.conv_len() + net.seed_len())];
        self.hid = net.fcs.iter().map(|fc| vec![0.0; batch * fc.out]).collect();
        let mut inp = 3;
        self.xin = net
            .fcs
            .iter()
            .map(|fc| {
                let d = Dense::new(&vec![0.0; batch * inp], batch, inp, net.isa);
                inp = fc.out;
                d
            })
            .collect();
        let threads = rayon::current_num_threads().max(1);
        self.pool = (0..threads).map(|_| Mutex::new(Scratch::new(net))).collect();
        self.batch = batch;
    }

    /// The MSE of the network's images of normalised inputs `x` (`[B, 3]`) against `target`
    /// (`B × size²`), and every parameter's gradient of it (kept for [`DirectTrainer::update`]).
    ///
    /// # Errors
    /// [`NeuralGenError::Shape`] when `x` is empty or not in threes, or `target` is not
    /// `B × size²` long.
    pub fn gradients(&mut self, x: &[f32], target: &[f32]) -> Result<f64, NeuralGenError> {
        let b = x.len() / 3;
        let ss = self.net.size * self.net.size;
        if b == 0 || x.len() % 3 != 0 || target.len() != b * ss {
            return Err(NeuralGenError::Shape(format!(
                "{} inputs and {} target values: expected threes and {ss} values per image",
                x.len(),
                target.len()
            )));
        }
        self.size_for(b);
        let loss = self.image_gradients(x, target);
        self.sum_conv_gradients(b);
        self.dense_gradients(x, b);
        Ok(loss)
    }

    /// The fully connected layers forward on the whole batch, then per image in one pass
    /// (its activations stay in the core's cache): the stages, the squared error and its
    /// gradient, back through the stages, the weight gradients of each, into `per_image`.
    /// Returns the MSE, the squared errors summed image by image, then over the images in
    /// order.
    fn image_gradients(&mut self, x: &[f32], target: &[f32]) -> f64 {
        let b = x.len() / 3;
        let net = &self.net;
        let ss = net.size * net.size;
        let nfc = net.fcs.len();
        // The fully connected layers on the whole batch, into the kept buffers (the same
        // products as `Net::dense_forward`).
        for li in 0..nfc {
            let (prev, cur) = self.hid.split_at_mut(li);
            let input: &[f32] = if li == 0 { x } else { &prev[li - 1] };
            let fc = &net.fcs[li];
            fc.fwd.apply_scratch(input, Some(&fc.b), &mut cur[0], &mut self.dense_t);
            if net.fc_relu(li) {
                cur[0].iter_mut().for_each(|v| *v = v.max(0.0));
            }
        }
        let seed = &self.hid[nfc - 1];
        let sl = net.seed_len();
        let pool = &self.pool;
        let k = 2.0 / (b * ss) as f32;
        let cl = net.conv_len();
        self.sq.resize(b, 0.0);
        self.per_image
            .par_chunks_mut(cl + sl)
            .zip(self.sq.par_iter_mut())
            .zip(seed.par_chunks(sl))
            .zip(target.par_chunks(ss))
            .for_each_init(
                || Scratch::take(pool),
                |sc, (((out, sq), sd), t)| {
                    let Scratch { acts, bufs, masks, img, up, acc } = sc.get(net);
                    net.isa.dispatch(ForwardImage { net, seed: sd, img, masks: Some(&mut masks[..]), buf: acts, acc });
                    let mut e = 0f64;
                    for ((u, &y), &t) in up.iter_mut().zip(img.iter()).zip(t) {
                        let d = y - t;
                        e += (d as f64) * (d as f64);
                        *u = k * d;
                    }
                    *sq = e;
                    let (grads, gs) = out.split_at_mut(cl);
                    net.isa.dispatch(BackwardImage { net, gs, up, img, masks, bufs, acc });
                    net.isa.dispatch(WeightGrads { net, bufs, acts, grads });
                },
            );
        self.sq.iter().sum::<f64>() / (b * ss) as f64
    }

    /// The convolution gradients of `per_image` summed over the `b` images, in image order,
    /// into the parameters.
    fn sum_conv_gradients(&mut self, b: usize) {
        let nfc = self.net.fcs.len();
        let (cl, sl) = (self.net.conv_len(), self.net.seed_len());
        let mut off = 0;
        for p in &mut self.params[2 * nfc..] {
            let len = p.g.len();
            let per = &self.per_image;
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
    }

    /// Back through the fully connected layers on the whole batch of `b` inputs `x`, from the
    /// seed maps' gradients in `per_image`: their weight and bias gradients into the
    /// parameters.
    fn dense_gradients(&mut self, x: &[f32], b: usize) {
        let net = &self.net;
        let nfc = net.fcs.len();
        let (cl, sl) = (net.conv_len(), net.seed_len());
        let hidden = &self.hid;
        let (mut g, mut gi) = (std::mem::take(&mut self.g), std::mem::take(&mut self.gi));
        g.clear();
        for i in 0..b {
            g.extend_from_slice(&self.per_image[i * (cl + sl) + cl..(i + 1) * (cl + sl)]);
        }
        for li in (0..nfc).rev() {
            let fc = &net.fcs[li];
            let input: &[f32] = if li == 0 { x } else { &hidden[li - 1] };
            let inp = input.len() / b.max(1);
            let (wp, rest) = self.params[2 * li..].split_at_mut(1);
            let (gw, gb) = (&mut wp[0].g, &mut rest[0].g);
            // dW = gᵀ · input ([out, inp], candle's layout), a packed product (each value a
            // chain of fused multiply–adds over the batch in order); db[o] = Σ_b g[b, o].
            let out = fc.out;
            self.gt.resize(out * b, 0.0);
            self.gt.par_chunks_mut(b).enumerate().for_each(|(o, row)| {
                for (i, v) in row.iter_mut().enumerate() {
                    *v = g[i * out + o];
                }
            });
            let xin = &mut self.xin[li];
            xin.repack(input);
            xin.apply_scratch(&self.gt, None, gw, &mut self.dense_t);
            gb.par_iter_mut().zip(self.gt.par_chunks(b)).for_each(|(bo, row)| *bo = row.iter().fold(0.0, |a, v| a + v));
            if li > 0 {
                gi.resize(b * inp, 0.0);
                fc.bwd.apply_scratch(&g, None, &mut gi, &mut self.dense_t);
                gi.iter_mut().zip(&hidden[li - 1]).for_each(|(v, &a)| {
                    if a <= 0.0 {
                        *v = 0.0;
                    }
                });
                std::mem::swap(&mut g, &mut gi);
            }
        }
        self.g = g;
        self.gi = gi;
    }

    /// One AdamW step (candle's `AdamW` rule, weight decay 0) on the gradients of the last
    /// [`DirectTrainer::gradients`], at learning rate `lr`; the kernels then run on the new
    /// weights.
    pub fn update(&mut self, lr: f64) {
        self.t += 1;
        for p in &mut self.params {
            adamw_step(&mut p.w, &p.g, &mut p.m, &mut p.v, lr, self.t);
        }
        self.repack();
    }

    /// Packs the parameters into the kernels' layouts, in place.
    fn repack(&mut self) {
        let params = &self.params;
        self.net.set_weights(|k| &params[k].w);
    }

    /// [`DirectTrainer::gradients`] then [`DirectTrainer::update`]: one training step; returns
    /// the MSE before it.
    ///
    /// # Errors
    /// As [`DirectTrainer::gradients`].
    pub fn step(&mut self, x: &[f32], target: &[f32], lr: f64) -> Result<f64, NeuralGenError> {
        let loss = self.gradients(x, target)?;
        self.update(lr);
        Ok(loss)
    }

    /// The gradient of the last [`DirectTrainer::gradients`] for the tensor `name`.
    #[cfg(any(test, feature = "bench"))]
    pub fn gradient(&self, name: &str) -> Option<&[f32]> {
        self.params.iter().find(|p| p.name == name).map(|p| &p.g[..])
    }

    /// The current weights of the tensor `name`.
    #[cfg(any(test, feature = "bench"))]
    pub fn weight(&self, name: &str) -> Option<&[f32]> {
        self.params.iter().find(|p| p.name == name).map(|p| &p.w[..])
    }

    /// Images of normalised inputs `x` (`[B, 3]`) on the current weights: `B × size²` values
    /// in [0, 1], image after image; the same bits for any batch split and thread count.
    ///
    /// # Errors
    /// [`NeuralGenError::Shape`] when `x.len()` is not a multiple of 3.
    pub fn images(&self, x: &[f32]) -> Result<Vec<f32>, NeuralGenError> {
        if x.len() % 3 != 0 {
            return Err(NeuralGenError::Shape(format!("{} inputs: they come in threes", x.len())));
        }
        Ok(self.net.images(x))
    }

    /// The current weights, by name.
    pub(crate) fn snapshot(&self) -> Vec<Vec<f32>> {
        self.params.iter().map(|p| p.w.clone()).collect()
    }

    /// Restores weights from [`DirectTrainer::snapshot`].
    pub(crate) fn restore(&mut self, w: Vec<Vec<f32>>) {
        for (p, w) in self.params.iter_mut().zip(w) {
            p.w = w;
        }
        self.repack();
    }

    /// Copies the current weights into `g`'s candle variables.
    ///
    /// # Errors
    /// As [`DirectTrainer::write_varmap`].
    pub fn write_back(&self, g: &mut Generator) -> Result<(), NeuralGenError> {
        self.write_varmap(&g.varmap)?;
        g.weights_changed();
        Ok(())
    }

    /// Copies the current weights into `varmap`'s variables of the same names.
    ///
    /// # Errors
    /// [`NeuralGenError::Shape`] when a variable is missing; [`NeuralGenError::Candle`].
    pub fn write_varmap(&self, varmap: &VarMap) -> Result<(), NeuralGenError> {
        let data = varmap.data().lock().expect("varmap");
        for p in &self.params {
            let var = data.get(&p.name).ok_or_else(|| NeuralGenError::Shape(format!("no variable {}", p.name)))?;
            let t = candle_core::Tensor::from_vec(p.w.clone(), p.dims.clone(), var.device())
                .map_err(NeuralGenError::Candle)?;
            var.set(&t).map_err(NeuralGenError::Candle)?;
        }
        Ok(())
    }
}

/// The weight and bias gradients of every stage of one image: `bufs[si]` the padded gradient
/// at stage `si`'s output (from [`BackwardImage`]), `acts` the stages' padded inputs.
struct WeightGrads<'a> {
    net: &'a Net,
    bufs: &'a [Vec<f32>],
    acts: &'a [f32],
    grads: &'a mut [f32],
}

impl WithSimd for WeightGrads<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let (mut aoff, mut goff) = (0, 0);
        for (si, st) in self.net.stages.iter().enumerate() {
            let (cin, cout) = (st.spec.cin, st.spec.cout);
            let x = &self.acts[aoff..aoff + padded_len(cin, st.n)];
            let (gw, rest) = self.grads[goff..].split_at_mut(cout * cin * 9);
            conv_weight_grads(simd, x, &self.bufs[si], (cin, cout, st.n), gw, &mut rest[..cout]);
            aoff += padded_len(cin, st.n);
            goff += cout * cin * 9 + cout;
        }
    }
}

/// The weight (`gw`, `[cout, cin, 3, 3]`) and bias (`gb`, `[cout]`) gradients of one 3×3
/// convolution (padding 1) of one image of `n × n` pixels (`(cin, cout, n)`): `x` its padded
/// input planes, `gy` the padded gradient at its output (zero borders). Each sum a fixed
/// order of operations (vectors of positions, the last one partial, then their lanes, as
/// [`Simd::reduce_sum_f32s`] adds them); output
/// channels are taken four at a time (three at a time, then one, for the rest) and kernel rows
/// one at a time, so that each vector of the input is loaded once for several output
/// channels and taps; the blocking does not change any sum.
#[inline(always)]
fn conv_weight_grads<S: Simd>(
    simd: S,
    x: &[f32],
    gy: &[f32],
    (cin, cout, n): (usize, usize, usize),
    gw: &mut [f32],
    gb: &mut [f32],
) {
    let mut o = 0;
    while o + 4 <= cout {
        wgrad_block::<S, 4>(simd, x, gy, (cin, o, n), gw, gb);
        o += 4;
    }
    while o + 2 <= cout {
        wgrad_block::<S, 2>(simd, x, gy, (cin, o, n), gw, gb);
        o += 2;
    }
    while o < cout {
        wgrad_block::<S, 1>(simd, x, gy, (cin, o, n), gw, gb);
        o += 1;
    }
}

/// Output channels `o0 .. o0 + OB` of [`conv_weight_grads`].
#[inline(always)]
fn wgrad_block<S: Simd, const OB: usize>(
    simd: S,
    x: &[f32],
    gy: &[f32],
    (cin, o0, n): (usize, usize, usize),
    gw: &mut [f32],
    gb: &mut [f32],
) {
    let l = S::F32_LANES;
    let wp = n + 2;
    let q2 = wp * wp;
    // Positions q of the padded plane whose 3×3 neighbourhood lies inside it; the
    // gradient is zero on the border, so these are all that count.
    let (q0, q1) = (wp + 1, q2 - wp - 1);
    let full = (q1 - q0) / l * l;
    let tail = q1 - q0 - full;
    let load = |v: &[f32], at: usize| -> S::f32s {
        pulp::bytemuck::pod_read_unaligned(pulp::bytemuck::cast_slice(&v[at..at + l]))
    };
    let g: [&[f32]; OB] = std::array::from_fn(|j| &gy[(o0 + j) * q2..(o0 + j + 1) * q2]);
    // The bias sums: vectors of positions over the whole plane (the last one partial), then
    // their lanes.
    let mut sb = [simd.splat_f32s(0.0); OB];
    let mut q = 0;
    while q + l <= q2 {
        for (s, gj) in sb.iter_mut().zip(&g) {
            *s = simd.add_f32s(*s, load(gj, q));
        }
        q += l;
    }
    if q < q2 {
        for (s, gj) in sb.iter_mut().zip(&g) {
            *s = simd.add_f32s(*s, simd.partial_load_f32s(&gj[q..q2]));
        }
    }
    for (b, s) in gb[o0..o0 + OB].iter_mut().zip(sb) {
        *b = simd.reduce_sum_f32s(s);
    }
    for c in 0..cin {
        let xc = &x[c * q2..(c + 1) * q2];
        for ky in 0..3 {
            let mut acc = [[simd.splat_f32s(0.0); 3]; OB];
            let mut q = q0;
            while q < q0 + full {
                let gv: [S::f32s; OB] = std::array::from_fn(|j| load(g[j], q));
                for kx in 0..3 {
                    let xv = load(xc, q + ky * wp + kx - wp - 1);
                    for (aj, &gj) in acc.iter_mut().zip(&gv) {
                        aj[kx] = simd.mul_add_f32s(gj, xv, aj[kx]);
                    }
                }
                q += l;
            }
            if tail > 0 {
                // The last positions as one partial vector (zeros past the end).
                let gv: [S::f32s; OB] = std::array::from_fn(|j| simd.partial_load_f32s(&g[j][q..q1]));
                for kx in 0..3 {
                    let s = q + ky * wp + kx - wp - 1;
                    let xv = simd.partial_load_f32s(&xc[s..s + tail]);
                    for (aj, &gj) in acc.iter_mut().zip(&gv) {
                        aj[kx] = simd.mul_add_f32s(gj, xv, aj[kx]);
                    }
                }
            }
            for (j, aj) in acc.iter().enumerate() {
                let o = o0 + j;
                let w = &mut gw[(o * cin + c) * 9..(o * cin + c + 1) * 9];
                for (kx, &a) in aj.iter().enumerate() {
                    w[ky * 3 + kx] = simd.reduce_sum_f32s(a);
                }
            }
        }
    }
}

/// One AdamW step (candle's rule, weight decay 0) at step `t` (from 1) on weights `w` with
/// gradients `g` and moments `m`, `v`, in parallel over fixed chunks.
fn adamw_step(w: &mut [f32], g: &[f32], m: &mut [f32], v: &mut [f32], lr: f64, t: i32) {
    let (b1, b2, eps) = (0.9f64, 0.999f64, 1e-8f64);
    let (sm, sv) = ((1.0 / (1.0 - b1.powi(t))) as f32, (1.0 / (1.0 - b2.powi(t))) as f32);
    let (lr, b1, b2, eps) = (lr as f32, b1 as f32, b2 as f32, eps as f32);
    w.par_chunks_mut(1 << 14)
        .zip(m.par_chunks_mut(1 << 14))
        .zip(v.par_chunks_mut(1 << 14))
        .zip(g.par_chunks(1 << 14))
        .for_each(|(((th, m), v), g)| {
            for i in 0..th.len() {
                let gi = g[i];
                m[i] = b1 * m[i] + (1.0 - b1) * gi;
                v[i] = b2 * v[i] + (1.0 - b2) * gi * gi;
                let step = (m[i] * sm) / ((v[i] * sv).sqrt() + eps);
                th[i] -= lr * step;
            }
        });
}

#[cfg(test)]
mod tests {
    use super::DirectTrainer;
    use crate::train::NetworkStep;
    use crate::{Arch, Generator, GeneratorConfig};
    use brush_model::{BrushProfile, Press};
    use candle_core::Tensor;

    fn presses(n: usize) -> Vec<Press> {
        (0..n)
            .map(|i| {
                let f = i as f64 / n as f64;
                Press::from_degrees(11.0 + 9.0 * f, 10.0 * ((7 * i) % n) as f64 / n as f64, 5.0 * f)
            })
            .collect()
    }

    /// Gradients of every tensor and one AdamW step against candle's autograd and the fused
    /// AdamW on the candle graph (`NetworkStep`).
    fn check(arch: Arch, batch: usize, what: &str) {
        let profile = BrushProfile::builtin("pen1").unwrap();
        let mut g = Generator::new(GeneratorConfig::new(profile.clone(), arch.clone()), 3).unwrap();
        let ps = presses(batch);
        let s = g.config.size as usize;
        let x: Vec<f32> = ps.iter().flat_map(|p| g.config.normalise(p)).collect();
        let t: Vec<f32> = (0..batch * s * s).map(|i| ((i * 7919) % 113) as f32 / 113.0).collect();
        let mut tr = DirectTrainer::new(&g).unwrap();
        let loss = tr.gradients(&x, &t).unwrap();
        // candle: the same loss through the graph.
        let xs = g.inputs(&ps).unwrap();
        let ts = Tensor::from_vec(t.clone(), (batch, 1, s, s), g.device()).unwrap();
        let l = (g.forward_autograd(&xs).unwrap() - &ts).unwrap().sqr().unwrap().mean_all().unwrap();
        let lc = l.to_scalar::<f32>().unwrap() as f64;
        assert!((loss - lc).abs() < 1e-5 * lc.max(1e-3), "{what}: loss {loss} vs candle {lc}");
        let grads = l.backward().unwrap();
        let data = g.varmap.data().lock().unwrap();
        for (name, var) in data.iter() {
            let want: Vec<f32> = grads.get(var).unwrap().flatten_all().unwrap().to_vec1().unwrap();
            let got = tr.gradient(name).unwrap();
            assert_eq!(want.len(), got.len());
            let scale = want.iter().fold(0f32, |m, v| m.max(v.abs())).max(1e-12);
            let worst = want.iter().zip(got).fold(0f32, |m, (a, b)| m.max((a - b).abs()));
            assert!(worst <= 1e-3 * scale, "{what} {name}: worst {worst} of {scale}");
            assert!(scale > 1e-9 || name.ends_with("bias"), "{what} {name}: a zero gradient tests nothing");
        }
        drop(data);
        // One AdamW step each way: the same weights.
        let mut gc = Generator::new(GeneratorConfig::new(profile, arch), 3).unwrap();
        let mut ns = NetworkStep::new(&gc, 1e-3).unwrap();
        ns.step(&mut gc, &xs, &ts, 1e-3).unwrap();
        tr.update(1e-3);
        tr.write_back(&mut g).unwrap();
        let (a, b) = (g.weights().unwrap(), gc.weights().unwrap());
        for (name, ta) in &a {
            let va: Vec<f32> = ta.flatten_all().unwrap().to_vec1().unwrap();
            let vb: Vec<f32> = b[name].flatten_all().unwrap().to_vec1().unwrap();
            // Adam moves each weight by about lr; a gradient near zero may flip the sign of a
            // step, so compare to a fraction of the step.
            let worst = va.iter().zip(&vb).fold(0f32, |m, (p, q)| m.max((p - q).abs()));
            assert!(worst < 2.1e-3, "{what} {name}: weights differ by {worst} after one step");
            let moved = va.iter().zip(&vb).filter(|(p, q)| (*p - *q).abs() < 1e-5).count();
            assert!(moved * 10 >= va.len() * 9, "{what} {name}: {moved} of {} weights agree", va.len());
        }
        // The generator renders with the written-back weights.
        assert_eq!(g.render(&ps).unwrap().len(), batch);
    }

    #[test]
    fn gradients_and_steps_match_candle_for_the_shipped_architecture() {
        check(Arch::default_128(), 3, "pen1");
    }

    #[test]
    fn gradients_and_steps_match_candle_for_odd_architectures() {
        check(Arch::tiny_32(), 5, "tiny");
        check(
            Arch { hidden: vec![24, 40], seed_channels: 12, seed_side: 3, stages: vec![(12, 20), (5, 12), (3, 4)] },
            4,
            "odd",
        );
    }

    /// After steps, the kernels repacked in place give the same images, bit for bit, as
    /// kernels packed afresh from the written-back weights.
    #[test]
    fn repacked_kernels_equal_fresh_ones() {
        let arch =
            Arch { hidden: vec![24, 40], seed_channels: 12, seed_side: 3, stages: vec![(12, 20), (5, 12), (3, 4)] };
        let mut g = Generator::new(GeneratorConfig::new(BrushProfile::builtin("pen1").unwrap(), arch), 4).unwrap();
        let ps = presses(5);
        let x: Vec<f32> = ps.iter().flat_map(|p| g.config.normalise(p)).collect();
        let s = g.config.size as usize;
        let t: Vec<f32> = (0..5 * s * s).map(|i| ((i * 31) % 17) as f32 / 17.0).collect();
        let mut tr = DirectTrainer::new(&g).unwrap();
        let before = tr.images(&x).unwrap();
        for _ in 0..2 {
            tr.step(&x, &t, 1e-2).unwrap();
        }
        tr.write_back(&mut g).unwrap();
        let fresh = g.kernels().unwrap().images_normalised(&x);
        let repacked = tr.images(&x).unwrap();
        assert_ne!(before, repacked, "the steps changed nothing");
        assert_eq!(fresh, repacked);
    }

    /// The same gradients on one thread and on two.
    #[test]
    fn gradients_do_not_depend_on_the_thread_count() {
        let g =
            Generator::new(GeneratorConfig::new(BrushProfile::builtin("pen1").unwrap(), Arch::tiny_32()), 5).unwrap();
        let ps = presses(6);
        let x: Vec<f32> = ps.iter().flat_map(|p| g.config.normalise(p)).collect();
        let t = vec![0.25f32; 6 * 32 * 32];
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let mut tr = DirectTrainer::new(&g).unwrap();
                tr.step(&x, &t, 1e-3).unwrap();
                tr.gradients(&x, &t).unwrap();
                tr.params.iter().map(|p| (p.g.clone(), p.w.clone())).collect::<Vec<_>>()
            })
        };
        assert_eq!(run(1), run(2));
    }

    /// The weight and bias gradients of one convolution against a naive f64 sum, on every
    /// instruction set (AVX-512, AVX2 and scalar where the CPU has them), for odd channel
    /// counts (blocks of four, two and one output channel) and sides whose positions end in a
    /// partial vector.
    #[test]
    fn convolution_weight_gradients_match_naive_sums() {
        use crate::kernels::{Isa, padded_len};
        use pulp::{Simd, WithSimd};
        struct Grads<'a> {
            x: &'a [f32],
            gy: &'a [f32],
            dims: (usize, usize, usize),
            gw: &'a mut [f32],
            gb: &'a mut [f32],
        }
        impl WithSimd for Grads<'_> {
            type Output = ();
            #[inline(always)]
            fn with_simd<S: Simd>(self, simd: S) {
                super::conv_weight_grads(simd, self.x, self.gy, self.dims, self.gw, self.gb);
            }
        }
        let mut state = 0x2545_F491_4F6C_DD1Du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 23) as f32 - 1.0
        };
        for &(cin, cout, n) in &[(3, 5, 1), (2, 7, 5), (4, 9, 8), (3, 6, 17), (2, 4, 40), (1, 3, 64)] {
            let wp = n + 2;
            let q2 = wp * wp;
            // Padded input planes (borders zero, as the stages write them) and a gradient that
            // is zero on the border.
            let mut x = vec![0f32; padded_len(cin, n)];
            let mut gy = vec![0f32; padded_len(cout, n)];
            for (planes, v) in [(cin, &mut x), (cout, &mut gy)] {
                for p in 0..planes {
                    for y in 1..=n {
                        for xx in 1..=n {
                            v[p * q2 + y * wp + xx] = next();
                        }
                    }
                }
            }
            let mut want_w = vec![0f64; cout * cin * 9];
            let mut scale_w = vec![0f64; cout * cin * 9];
            let mut want_b = vec![0f64; cout];
            for o in 0..cout {
                for y in 0..n {
                    for xx in 0..n {
                        let g = f64::from(gy[o * q2 + (y + 1) * wp + xx + 1]);
                        want_b[o] += g;
                        for c in 0..cin {
                            for ky in 0..3 {
                                for kx in 0..3 {
                                    let v = g * f64::from(x[c * q2 + (y + ky) * wp + xx + kx]);
                                    want_w[((o * cin + c) * 3 + ky) * 3 + kx] += v;
                                    scale_w[((o * cin + c) * 3 + ky) * 3 + kx] += v.abs();
                                }
                            }
                        }
                    }
                }
            }
            for isa in Isa::all_for_tests() {
                let (mut gw, mut gb) = (vec![f32::NAN; cout * cin * 9], vec![f32::NAN; cout]);
                isa.dispatch(Grads { x: &x, gy: &gy, dims: (cin, cout, n), gw: &mut gw, gb: &mut gb });
                for (i, (g, w)) in gw.iter().zip(&want_w).enumerate() {
                    assert!(
                        (f64::from(*g) - w).abs() <= 1e-5 * (1.0 + scale_w[i]),
                        "{isa:?} {cin}→{cout}@{n} weight [{i}]: {g} vs {w}"
                    );
                }
                for (o, (g, w)) in gb.iter().zip(&want_b).enumerate() {
                    assert!(
                        (f64::from(*g) - w).abs() <= 1e-5 * (1.0 + n as f64 * n as f64),
                        "{isa:?} {cin}→{cout}@{n} bias [{o}]: {g} vs {w}"
                    );
                }
            }
        }
    }
}

/// Networks other than the generator's ([`NetSpec`]s with and without shuffles and ReLUs, the
/// LearningToPaint-size one) against candle.
#[cfg(test)]
mod spec_tests {
    use super::DirectTrainer;
    use crate::ltp::{Kernels as LtpKernels, Ltp};
    use crate::net::{NetSpec, StageSpec};
    use candle_core::{DType, Device, Tensor};
    use candle_nn::{AdamW, Optimizer, ParamsAdamW, VarBuilder, VarMap};

    use crate::kernels::test_values as values;

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
        let mut net = DirectTrainer::from_varmap(spec, varmap).unwrap();
        let s = net.size();
        let x = inputs(batch);
        let xs = Tensor::from_vec(x.clone(), (batch, 3), &Device::Cpu).unwrap();
        let t: Vec<f32> = (0..batch * s * s).map(|i| ((i * 7919) % 113) as f32 / 113.0).collect();
        let ts = Tensor::from_vec(t.clone(), (batch, 1, s, s), &Device::Cpu).unwrap();
        // Images.
        let y = forward(&xs);
        let (want, got) = (flat(&y), net.images(&x).unwrap());
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
        net.write_varmap(varmap).unwrap();
        let (want, got) = (flat(&forward(&xs)), net.images(&x).unwrap());
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
        let s = DirectTrainer::from_varmap(&spec, &vm).unwrap().size();
        let t = vec![0.25f32; 6 * s * s];
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let mut net = DirectTrainer::from_varmap(&spec, &vm).unwrap();
                let whole = net.images(&x).unwrap();
                let parts: Vec<f32> = x.chunks(9).flat_map(|c| net.images(c).unwrap()).collect();
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
        assert!(DirectTrainer::from_varmap(&spec, &vm).is_err(), "weights of another architecture");
        let vm = varmap_for(&spec);
        let mut net = DirectTrainer::from_varmap(&spec, &vm).unwrap();
        assert!(net.images(&[0.0; 4]).is_err());
        assert!(net.gradients(&[0.0; 3], &[0.0; 5]).is_err());
        assert!(net.gradients(&[], &[]).is_err());
    }
}
