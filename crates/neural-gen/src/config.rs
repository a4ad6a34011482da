//! The generator's configuration: architecture, input normalisation, brush, canvas, training
//! recipe and final metrics. Saved as JSON beside the safetensors weights.

use brush_model::{BrushProfile, Press, PressRanges};
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// The format version of the config file.
pub const CONFIG_VERSION: u32 = 1;

/// The network's shape.
///
/// Fully connected layers from the 3 normalised inputs (ReLU between) to a
/// `seed_channels × seed_side × seed_side` feature map; then, per stage `(c_in, c_out)`, a 3×3
/// convolution `c_in → c_out` (padding 1), ReLU (not after the last), and a pixel shuffle by 2
/// (`c_out → c_out/4` channels, side doubled). The last stage ends with one channel; a sigmoid
/// gives ink in [0, 1].
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Arch {
    /// Widths of the hidden fully connected layers.
    pub hidden: Vec<usize>,
    /// Channels of the first feature map.
    pub seed_channels: usize,
    /// Side of the first feature map.
    pub seed_side: usize,
    /// Convolution stages `(c_in, c_out)`.
    pub stages: Vec<(usize, usize)>,
}

impl Arch {
    /// The default for 128² on 2 CPU cores: FC 3→128→512→16·8·8, then stages 16→64, 16→32,
    /// 8→32, 8→4 (8² → 16² → 32² → 64² → 128²).
    pub fn default_128() -> Self {
        Self {
            hidden: vec![128, 512],
            seed_channels: 16,
            seed_side: 8,
            stages: vec![(16, 64), (16, 32), (8, 32), (8, 4)],
        }
    }

    /// A tiny network for 32² images, for tests.
    pub fn tiny_32() -> Self {
        Self { hidden: vec![32], seed_channels: 8, seed_side: 4, stages: vec![(8, 16), (4, 16), (4, 4)] }
    }

    /// Output side, px.
    pub fn output_side(&self) -> usize {
        self.seed_side.saturating_mul(1usize.checked_shl(self.stages.len() as u32).unwrap_or(usize::MAX))
    }

    /// Checks that consecutive stages fit together and end in one channel, and that the
    /// network stays within the bounds (at most 8 stages, a 64² seed, a 1024² output, 16
    /// hidden layers of at most 8192, 4096 channels per layer, 50 million parameters).
    ///
    /// # Errors
    /// The first inconsistency, as an [`ArchError`].
    pub fn validate(&self) -> Result<(), ArchError> {
        if self.stages.is_empty() || self.seed_side == 0 || self.seed_channels == 0 {
            return Err(ArchError::Empty);
        }
        // Bounds before any size is computed or allocated: output side, widths and the
        // parameter count stay far above any useful generator and far below memory limits.
        if self.stages.len() > 8 || self.seed_side > 64 || self.output_side() > 1024 {
            return Err(ArchError::TooLarge { stages: self.stages.len(), seed_side: self.seed_side });
        }
        if self.hidden.len() > 16 || self.hidden.iter().any(|&h| h == 0 || h > 8192) {
            return Err(ArchError::Hidden);
        }
        if self.seed_channels > 4096 || self.stages.iter().any(|&(a, b)| a > 4096 || b > 4096) {
            return Err(ArchError::Channels);
        }
        if self.parameter_count() > 50_000_000 {
            return Err(ArchError::Parameters { count: self.parameter_count() });
        }
        let mut c = self.seed_channels;
        for (i, &(cin, cout)) in self.stages.iter().enumerate() {
            if cin != c {
                return Err(ArchError::StageInput { stage: i + 1, takes: cin, gets: c });
            }
            if cout % 4 != 0 {
                return Err(ArchError::NotShufflable { stage: i + 1, channels: cout });
            }
            c = cout / 4;
        }
        if c != 1 {
            return Err(ArchError::LastChannels { channels: c });
        }
        Ok(())
    }

    /// Trainable parameters.
    pub fn parameter_count(&self) -> usize {
        let mut n = 0;
        let mut w = 3;
        for &h in &self.hidden {
            n += w * h + h;
            w = h;
        }
        let seed = self.seed_channels * self.seed_side * self.seed_side;
        n += w * seed + seed;
        for &(cin, cout) in &self.stages {
            n += cin * cout * 9 + cout;
        }
        n
    }

    /// Multiply-accumulates per image in a forward pass.
    pub fn macs_per_image(&self) -> usize {
        let mut n = 0;
        let mut w = 3;
        for &h in &self.hidden {
            n += w * h;
            w = h;
        }
        n += w * self.seed_channels * self.seed_side * self.seed_side;
        let mut side = self.seed_side;
        for &(cin, cout) in &self.stages {
            n += side * side * cin * cout * 9;
            side *= 2;
        }
        n
    }
}

/// What is wrong with an [`Arch`] ([`Arch::validate`]).
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[non_exhaustive]
pub enum ArchError {
    /// No stage, or an empty seed map.
    #[error("need at least one stage and a non-empty seed map")]
    Empty,
    /// Too many stages or too large an output.
    #[error("{stages} stages from a {seed_side}² seed: at most 8 stages and a 1024² output")]
    TooLarge {
        /// Stages.
        stages: usize,
        /// Side of the seed map, px.
        seed_side: usize,
    },
    /// Too many or too wide hidden layers.
    #[error("hidden layers: at most 16, each 1..=8192 wide")]
    Hidden,
    /// Too many channels in a layer.
    #[error("channels: at most 4096 per layer")]
    Channels,
    /// Too many parameters.
    #[error("{count} parameters: at most 50 million")]
    Parameters {
        /// Trainable parameters.
        count: usize,
    },
    /// A stage's input channels differ from what the previous layer gives.
    #[error("stage {stage} takes {takes} channels but gets {gets}")]
    StageInput {
        /// Stage, 1-based.
        stage: usize,
        /// Channels it takes.
        takes: usize,
        /// Channels it gets.
        gets: usize,
    },
    /// A stage's output channels are not a multiple of 4.
    #[error("stage {stage}: {channels} output channels cannot be pixel-shuffled by 2")]
    NotShufflable {
        /// Stage, 1-based.
        stage: usize,
        /// Its output channels.
        channels: usize,
    },
    /// The last stage does not end in one channel.
    #[error("the last stage must end in 1 channel, not {channels}")]
    LastChannels {
        /// Channels after the last shuffle.
        channels: usize,
    },
}

/// How the checkpoint was trained.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Recipe {
    /// Steps run.
    pub steps: usize,
    /// Batch size.
    pub batch: usize,
    /// Peak learning rate (AdamW, weight decay 0).
    pub lr: f64,
    /// Seed.
    pub seed: u64,
    /// Loss.
    pub loss: String,
    /// Learning-rate schedule.
    pub schedule: String,
    /// Wall time, s.
    pub wall_seconds: f64,
    /// Threads.
    pub threads: usize,
}

/// Quality of the checkpoint against the analytic B-BSM.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// Held-out presses.
    pub n: usize,
    /// Mean SSIM.
    pub ssim_mean: f64,
    /// Worst SSIM.
    pub ssim_worst: f64,
    /// Mean CSIM.
    pub csim_mean: f64,
    /// Final validation MSE.
    pub val_mse: f64,
}

/// Everything needed to rebuild and check a generator.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GeneratorConfig {
    /// [`CONFIG_VERSION`].
    pub version: u32,
    /// The network.
    pub arch: Arch,
    /// Image side, px (equals `arch.output_side()`).
    pub size: u32,
    /// Canvas scale, px per mm (the `maobi stroke` convention for this brush and size).
    pub px_per_mm: f64,
    /// Input normalisation ranges (the profile's calibrated ranges).
    pub ranges: PressRanges,
    /// The brush the generator imitates.
    pub profile: BrushProfile,
    /// How it was trained (absent before training).
    #[serde(default)]
    pub recipe: Option<Recipe>,
    /// How good it is (absent before evaluation).
    #[serde(default)]
    pub metrics: Option<Metrics>,
}

impl GeneratorConfig {
    /// A fresh config for a profile and architecture; the canvas is the profile's default for
    /// the architecture's output side.
    pub fn new(profile: BrushProfile, arch: Arch) -> Self {
        let size = arch.output_side() as u32;
        let canvas = bezier_raster::StrokeCanvas::for_profile(&profile, size);
        Self {
            version: CONFIG_VERSION,
            ranges: profile.ranges,
            arch,
            size,
            px_per_mm: canvas.px_per_mm,
            profile,
            recipe: None,
            metrics: None,
        }
    }

    /// The press normalised to [−1, 1] per input (0 for a degenerate range).
    pub fn normalise(&self, p: &Press) -> [f32; 3] {
        let n = |v: f64, r: brush_model::Range| {
            if r.max > r.min { (2.0 * (v - r.min) / (r.max - r.min) - 1.0) as f32 } else { 0.0 }
        };
        [n(p.h_mm, self.ranges.h_mm), n(p.alpha_rad, self.ranges.alpha_rad), n(p.beta_rad, self.ranges.beta_rad)]
    }

    /// d(normalised input)/d(physical input) for h, α, β.
    pub fn normalise_slopes(&self) -> [f64; 3] {
        let s = |r: brush_model::Range| if r.max > r.min { 2.0 / (r.max - r.min) } else { 0.0 };
        [s(self.ranges.h_mm), s(self.ranges.alpha_rad), s(self.ranges.beta_rad)]
    }
}
