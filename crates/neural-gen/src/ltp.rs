//! The LearningToPaint-sized renderer network, kept as a speed reference.
//!
//! Huang et al.'s LearningToPaint neural renderer with a 3-number input: fully connected
//! 3 → 512 → 1024 → 2048 → 4096 (ReLU), viewed as a 16-channel 16 × 16 map, then six 3 × 3
//! convolutions, every second one followed by a ×2 pixel shuffle, to a 128 × 128 image with a
//! sigmoid. 11.0 M parameters, 20.5 M multiply–adds per image. It is much larger than the
//! generator maobi trains ([`crate::Arch::default_128`]); it exists so that candle's speed on
//! the paper-scale network can be measured against PyTorch (`benches/ltp.rs`,
//! `benches/ltp_torch.py`, docs/neural-gen.md) with either convolution kernel.

use candle_core::backprop::GradStore;
use candle_core::{DType, Device, Module, Result, Tensor};
use candle_nn::{AdamW, Linear, Optimizer, ParamsAdamW, VarBuilder, VarMap};

use crate::adam::FusedAdamW;
use crate::conv;
use crate::net::{NetSpec, StageSpec};

/// Which kernels the network trains with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kernels {
    /// Stock candle: `candle_nn::Conv2d` (and its backward) and `candle_nn::AdamW`.
    Candle,
    /// maobi's: the crate's direct convolution (forward and backward) and fused AdamW.
    Maobi,
}

enum Opt {
    Candle(AdamW),
    Fused(FusedAdamW),
}

/// The network and its optimiser.
pub struct Ltp {
    fcs: Vec<Linear>,
    convs: Vec<candle_nn::Conv2d>,
    fast: Vec<conv::Conv2d>,
    kernels: Kernels,
    opt: Opt,
    /// The variables (for counting or saving).
    pub varmap: VarMap,
}

/// `(input channels, output channels, pixel shuffle after)` of the six convolutions.
const CONVS: [(usize, usize, bool); 6] =
    [(16, 32, false), (32, 32, true), (8, 16, false), (16, 16, true), (4, 8, false), (8, 4, true)];

impl Ltp {
    /// Multiply–accumulates per image in a forward pass (fully connected layers and
    /// convolutions).
    pub const MACS_PER_IMAGE: usize = 3 * 512
        + 512 * 1024
        + 1024 * 2048
        + 2048 * 4096
        + 16 * 16 * (16 * 32 + 32 * 32) * 9
        + 32 * 32 * (8 * 16 + 16 * 16) * 9
        + 64 * 64 * (4 * 8 + 8 * 4) * 9;

    /// The architecture as a [`NetSpec`], for [`crate::bench::DirectTrainer::from_varmap`] on
    /// [`Ltp::varmap`] (the network on the direct kernels).
    pub fn spec() -> NetSpec {
        NetSpec {
            widths: vec![3, 512, 1024, 2048, 4096],
            relu_last_fc: true,
            seed_channels: 16,
            seed_side: 16,
            stages: CONVS
                .iter()
                .map(|&(cin, cout, shuffle)| StageSpec { cin, cout, relu: !shuffle, shuffle })
                .collect(),
        }
    }

    /// A network with candle's default (random) initialisation and Adam at learning rate `lr`
    /// (candle's AdamW with weight decay 0).
    ///
    /// # Errors
    /// A candle error.
    pub fn new(kernels: Kernels, lr: f64) -> Result<Self> {
        let device = Device::Cpu;
        let varmap = VarMap::new();
        let vb = VarBuilder::from_varmap(&varmap, DType::F32, &device);
        let widths = [3, 512, 1024, 2048, 4096];
        let fcs = widths
            .windows(2)
            .enumerate()
            .map(|(i, w)| candle_nn::linear(w[0], w[1], vb.pp(format!("fc{i}"))))
            .collect::<Result<Vec<_>>>()?;
        let cfg = candle_nn::Conv2dConfig { padding: 1, ..Default::default() };
        let convs = CONVS
            .iter()
            .enumerate()
            .map(|(i, &(cin, cout, _))| candle_nn::conv2d(cin, cout, 3, cfg, vb.pp(format!("conv{i}"))))
            .collect::<Result<Vec<_>>>()?;
        let fast = convs
            .iter()
            .zip(CONVS)
            .map(|(c, (_, _, shuffle))| {
                let f = conv::Conv2d::from_candle(c)?;
                Ok(if shuffle { f } else { f.with_relu() })
            })
            .collect::<Result<Vec<_>>>()?;
        let params = ParamsAdamW { lr, weight_decay: 0.0, ..Default::default() };
        let opt = match kernels {
            Kernels::Candle => Opt::Candle(AdamW::new(varmap.all_vars(), params)?),
            Kernels::Maobi => Opt::Fused(FusedAdamW::new(varmap.all_vars(), params)?),
        };
        Ok(Ltp { fcs, convs, fast, kernels, opt, varmap })
    }

    /// Number of trainable parameters.
    pub fn parameters(&self) -> usize {
        self.varmap.all_vars().iter().map(|v| v.elem_count()).sum()
    }

    /// Forward pass: `[B, 3]` → `[B, 1, 128, 128]` in (0, 1).
    ///
    /// # Errors
    /// A candle error on shape mismatch.
    pub fn forward(&self, x: &Tensor) -> Result<Tensor> {
        let mut h = x.clone();
        for fc in &self.fcs {
            h = fc.forward(&h)?.relu()?;
        }
        let mut h = h.reshape((x.dim(0)?, 16, 16, 16))?;
        for (i, &(_, _, shuffle)) in CONVS.iter().enumerate() {
            h = match self.kernels {
                Kernels::Candle => {
                    let y = self.convs[i].forward(&h)?;
                    if shuffle { candle_nn::ops::pixel_shuffle(&y, 2)? } else { y.relu()? }
                }
                // ReLU fused into the convolution.
                Kernels::Maobi if shuffle => conv::pixel_shuffle(&self.fast[i].forward(&h)?, 2)?,
                Kernels::Maobi => self.fast[i].forward(&h)?,
            };
        }
        candle_nn::ops::sigmoid(&h)
    }

    /// One training step on `x` `[B, 3]` against `target` `[B, 1, 128, 128]` (MSE); returns
    /// the loss before the step.
    ///
    /// # Errors
    /// A candle error on shape mismatch.
    pub fn step(&mut self, x: &Tensor, target: &Tensor) -> Result<f32> {
        let loss = candle_nn::loss::mse(&self.forward(x)?, target)?;
        self.update(&loss.backward()?)?;
        loss.to_scalar::<f32>()
    }

    /// The optimiser step alone, for gradients from `loss.backward()`.
    ///
    /// # Errors
    /// A candle error.
    pub fn update(&mut self, grads: &GradStore) -> Result<()> {
        match &mut self.opt {
            Opt::Candle(o) => o.step(grads),
            Opt::Fused(o) => o.step(grads),
        }
    }
}
