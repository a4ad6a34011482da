//! The generator network, its checkpoints, inference and gradients.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use bezier_raster::Coverage;
use brush_model::Press;
use candle_core::{DType, Device, Module, Tensor, Var};
use candle_nn::{Conv2dConfig, Linear, VarBuilder, VarMap};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::config::{CONFIG_VERSION, GeneratorConfig};
use crate::conv::{self, Conv2d};
use crate::vjp::InputVjp;
use crate::{ConfigError, NeuralGenError};

/// The largest generator config [`Generator::load`] reads, bytes.
const MAX_CONFIG_BYTES: u64 = 1 << 20;
/// The largest generator weights file [`Generator::load`] reads, bytes (the committed pen1
/// checkpoint is a few MB).
const MAX_WEIGHTS_BYTES: u64 = 1 << 30;

/// A generator: the network and its configuration.
///
/// Inference ([`Generator::forward`], [`Generator::render`]) runs on the crate's direct
/// kernels (the network of [`InputVjp`], built from the weights on first use), and so does
/// training ([`crate::train()`]); the candle graph ([`Generator::forward_autograd`]) is there
/// for checks against candle's autograd.
pub struct Generator {
    /// Configuration (architecture, normalisation, brush, canvas).
    pub config: GeneratorConfig,
    /// The trainable variables. Private: inference caches a copy of them ([`Generator::kernels`]),
    /// so every change goes through this crate (training, loading), which drops the copy.
    pub(crate) varmap: VarMap,
    fcs: Vec<Linear>,
    convs: Vec<Conv2d>,
    device: Device,
    /// The weights on the direct kernels, built on first use, dropped when they change.
    kernels: OnceLock<InputVjp>,
}

fn cerr(e: candle_core::Error) -> NeuralGenError {
    NeuralGenError::Candle(e)
}

/// Images of side `s`, one after another in `images`, as coverages.
fn coverages(images: &[f32], s: usize) -> Vec<Coverage> {
    images.chunks_exact(s * s).map(|c| Coverage::from_vec(s as u32, s as u32, c.to_vec()).expect("sized")).collect()
}

/// A tensor's values as f32, flattened.
fn tensor_vec(t: &Tensor) -> Result<Vec<f32>, NeuralGenError> {
    t.flatten_all().and_then(|f| f.to_dtype(DType::F32)).and_then(|f| f.to_vec1::<f32>()).map_err(cerr)
}

impl Generator {
    /// A new generator with weights initialised deterministically from `seed` (Kaiming-uniform
    /// weights, zero biases).
    ///
    /// # Errors
    /// [`NeuralGenError::Config`] for an inconsistent architecture.
    pub fn new(config: GeneratorConfig, seed: u64) -> Result<Self, NeuralGenError> {
        config.arch.validate().map_err(|e| NeuralGenError::Config {
            source_name: "architecture".into(),
            problem: ConfigError::Arch(e),
        })?;
        let device = Device::Cpu;
        let varmap = VarMap::new();
        let vb = VarBuilder::from_varmap(&varmap, DType::F32, &device);
        let (fcs, convs) = build(&config, &vb).map_err(cerr)?;
        let g = Generator { config, varmap, fcs, convs, device, kernels: OnceLock::new() };
        g.init(seed)?;
        Ok(g)
    }

    fn init(&self, seed: u64) -> Result<(), NeuralGenError> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let data = self.varmap.data().lock().expect("varmap");
        let mut names: Vec<&String> = data.keys().collect();
        names.sort();
        for name in names {
            let var = &data[name];
            let shape = var.shape().clone();
            let n = shape.elem_count();
            let values: Vec<f32> = if name.ends_with(".bias") {
                vec![0.0; n]
            } else {
                let fan_in: usize = shape.dims()[1..].iter().product();
                let bound = (6.0 / fan_in as f64).sqrt();
                (0..n).map(|_| rng.random_range(-bound..bound) as f32).collect()
            };
            var.set(&Tensor::from_vec(values, shape, &self.device).map_err(cerr)?).map_err(cerr)?;
        }
        Ok(())
    }

    /// The device (CPU).
    pub fn device(&self) -> &Device {
        &self.device
    }

    /// The trainable tensors by name (`fc0.weight`, `conv2.bias`, …), copies: for inspection
    /// and comparison; changes go through [`crate::train()`] or [`Generator::load`].
    ///
    /// # Errors
    /// [`NeuralGenError::Candle`].
    pub fn weights(&self) -> Result<BTreeMap<String, Tensor>, NeuralGenError> {
        let data = self.varmap.data().lock().expect("varmap");
        data.iter().map(|(k, v)| Ok((k.clone(), v.as_tensor().copy().map_err(cerr)?))).collect()
    }

    /// The network on the direct kernels (weights copied on first use, kept until the weights
    /// change): what [`Generator::forward`] and [`Generator::render`] run on.
    ///
    /// # Errors
    /// [`NeuralGenError::Candle`] when the weights cannot be read.
    pub fn kernels(&self) -> Result<&InputVjp, NeuralGenError> {
        if let Some(k) = self.kernels.get() {
            return Ok(k);
        }
        let data = self.varmap.data().lock().expect("varmap");
        let built = InputVjp::new(&self.config, |name| {
            let v = data.get(name).ok_or_else(|| NeuralGenError::Config {
                source_name: "generator".into(),
                problem: ConfigError::MissingTensor { name: name.to_string() },
            })?;
            tensor_vec(v.as_tensor())
        })?;
        drop(data);
        // Another thread may have built it meanwhile: the same weights, either copy will do.
        let _ = self.kernels.set(built);
        Ok(self.kernels.get().expect("just set"))
    }

    /// Drops the kernels' copy of the weights (after the weights changed).
    pub(crate) fn weights_changed(&mut self) {
        self.kernels.take();
    }

    /// Forward pass on normalised inputs `[B, 3]` → images `[B, 1, S, S]` in [0, 1], on the
    /// direct kernels ([`Generator::kernels`]): deterministic, the same bits for any batch
    /// size and thread count, and no autograd graph (for gradients with respect to the
    /// weights use [`Generator::forward_autograd`]).
    ///
    /// # Errors
    /// [`NeuralGenError::Shape`] when `x` is not `[B, 3]`; [`NeuralGenError::Candle`].
    pub fn forward(&self, x: &Tensor) -> Result<Tensor, NeuralGenError> {
        let b = match x.dims() {
            &[b, 3] => b,
            d => return Err(NeuralGenError::Shape(format!("generator input of shape {d:?}, expected [batch, 3]"))),
        };
        let v: Vec<f32> =
            x.flatten_all().and_then(|t| t.to_dtype(DType::F32)).and_then(|t| t.to_vec1()).map_err(cerr)?;
        let s = self.config.size as usize;
        let y = self.kernels()?.images_normalised(&v);
        Tensor::from_vec(y, (b, 1, s, s), &self.device).map_err(cerr)
    }

    /// The same forward pass as [`Generator::forward`] as a candle graph (autograd through the
    /// weights and the input): for checking the direct kernels against autograd. Equal to
    /// [`Generator::forward`] within floating-point rounding.
    ///
    /// # Errors
    /// [`NeuralGenError::Candle`] on shape errors.
    pub fn forward_autograd(&self, x: &Tensor) -> Result<Tensor, NeuralGenError> {
        self.forward_inner(x).map_err(cerr)
    }

    fn forward_inner(&self, x: &Tensor) -> candle_core::Result<Tensor> {
        let a = &self.config.arch;
        let mut h = x.clone();
        for (i, fc) in self.fcs.iter().enumerate() {
            h = fc.forward(&h)?;
            if i + 1 < self.fcs.len() {
                h = h.relu()?;
            }
        }
        let b = x.dim(0)?;
        let mut h = h.reshape((b, a.seed_channels, a.seed_side, a.seed_side))?;
        // Each convolution (ReLU fused in, except the last) is followed by a ×2 pixel shuffle.
        for conv in &self.convs {
            h = conv::pixel_shuffle(&conv.forward(&h)?, 2)?;
        }
        candle_nn::ops::sigmoid(&h)
    }

    /// The inputs of a batch of presses, `[B, 3]`.
    ///
    /// # Errors
    /// [`NeuralGenError::Candle`].
    pub fn inputs(&self, presses: &[Press]) -> Result<Tensor, NeuralGenError> {
        let v: Vec<f32> = presses.iter().flat_map(|p| self.config.normalise(p)).collect();
        Tensor::from_vec(v, (presses.len(), 3), &self.device).map_err(cerr)
    }

    /// Footprint images for a batch of presses (the `maobi stroke` canvas convention: same scale,
    /// footprint centred), on the direct kernels as [`Generator::forward`]: the convolutions of
    /// the images run in parallel (rayon), the bits do not depend on the batch or the thread
    /// count.
    ///
    /// # Errors
    /// [`NeuralGenError::Candle`].
    pub fn render(&self, presses: &[Press]) -> Result<Vec<Coverage>, NeuralGenError> {
        if presses.is_empty() {
            return Ok(Vec::new());
        }
        let x: Vec<f32> = presses.iter().flat_map(|p| self.config.normalise(p)).collect();
        let s = self.config.size;
        Ok(self
            .kernels()?
            .images_normalised_each(&x)
            .into_iter()
            .map(|img| Coverage::from_vec(s, s, img).expect("sized"))
            .collect())
    }

    /// The image for one press and the gradient of `Σ upstream · image` with respect to the
    /// press `(h [per mm], α [per rad], β [per rad])`: a vector–Jacobian product, exact by
    /// reverse-mode differentiation through the network. With `upstream = ∂L/∂image` it gives
    /// `∂L/∂(h, α, β)` for any loss `L` of the image: what track optimisation needs.
    ///
    /// # Errors
    /// [`NeuralGenError::Shape`] if `upstream` is not `size²` long; [`NeuralGenError::Candle`].
    pub fn image_and_vjp(&self, press: &Press, upstream: &[f32]) -> Result<(Coverage, [f64; 3]), NeuralGenError> {
        let s = self.config.size as usize;
        if upstream.len() != s * s {
            return Err(NeuralGenError::Shape(format!(
                "upstream gradient has {} values, expected {}",
                upstream.len(),
                s * s
            )));
        }
        let x = Var::from_tensor(&self.inputs(std::slice::from_ref(press))?).map_err(cerr)?;
        let y = self.forward_autograd(x.as_tensor())?;
        let w = Tensor::from_vec(upstream.to_vec(), (1, 1, s, s), &self.device).map_err(cerr)?;
        let l = (&y * &w).and_then(|t| t.sum_all()).map_err(cerr)?;
        let grads = l.backward().map_err(cerr)?;
        let gx: Vec<f32> = grads
            .get(x.as_tensor())
            .ok_or_else(|| NeuralGenError::Candle(candle_core::Error::Msg("no gradient for the input".into())))?
            .flatten_all()
            .and_then(|t| t.to_vec1())
            .map_err(cerr)?;
        let k = self.config.normalise_slopes();
        let img: Vec<f32> = y.flatten_all().and_then(|t| t.to_vec1()).map_err(cerr)?;
        Ok((
            Coverage::from_vec(s as u32, s as u32, img).expect("sized"),
            [gx[0] as f64 * k[0], gx[1] as f64 * k[1], gx[2] as f64 * k[2]],
        ))
    }

    /// The images' side, px, after checking that `upstream` holds `size²` values for each of
    /// `n` presses.
    fn upstream_side(&self, n: usize, upstream: &[f32]) -> Result<usize, NeuralGenError> {
        let s = self.config.size as usize;
        if upstream.len() != n * s * s {
            return Err(NeuralGenError::Shape(format!(
                "upstream gradient has {} values, expected {} ({n} presses × {s}²)",
                upstream.len(),
                n * s * s
            )));
        }
        Ok(s)
    }

    /// Images for a batch of presses and, for each, the gradient of `Σ upstream_i · image_i`
    /// with respect to its press `(h [per mm], α [per rad], β [per rad])`. `upstream` holds
    /// `size²` values per press, press after press. One forward and one backward pass through
    /// the network (direct kernels, input gradient only: [`InputVjp`]); the same numbers as
    /// [`Generator::image_and_vjp`] press by press (the kernels of [`Generator::kernels`]).
    ///
    /// # Errors
    /// [`NeuralGenError::Shape`] when `upstream` is not `presses.len() × size²` long;
    /// [`NeuralGenError::Candle`].
    pub fn images_and_vjps(
        &self,
        presses: &[Press],
        upstream: &[f32],
    ) -> Result<(Vec<Coverage>, Vec<[f64; 3]>), NeuralGenError> {
        let s = self.upstream_side(presses.len(), upstream)?;
        let net = self.kernels()?;
        let tape = net.forward(presses);
        let grads = net.vjp(&tape, upstream)?;
        Ok((coverages(tape.images(), s), grads))
    }

    /// As [`Generator::images_and_vjps`], through candle's autograd (one forward and one
    /// backward of the whole batch; weight gradients are computed too). Kept for the speed
    /// comparison and as a cross-check.
    ///
    /// # Errors
    /// As [`Generator::images_and_vjps`].
    pub fn images_and_vjps_candle(
        &self,
        presses: &[Press],
        upstream: &[f32],
    ) -> Result<(Vec<Coverage>, Vec<[f64; 3]>), NeuralGenError> {
        let s = self.upstream_side(presses.len(), upstream)?;
        let b = presses.len();
        if b == 0 {
            return Ok((Vec::new(), Vec::new()));
        }
        let x = candle_core::Var::from_tensor(&self.inputs(presses)?).map_err(cerr)?;
        let y = self.forward_autograd(x.as_tensor())?;
        let w = Tensor::from_vec(upstream.to_vec(), (b, 1, s, s), self.device()).map_err(cerr)?;
        let l = (&y * &w).and_then(|t| t.sum_all()).map_err(cerr)?;
        let grads = l.backward().map_err(cerr)?;
        let gx = tensor_vec(
            grads
                .get(x.as_tensor())
                .ok_or_else(|| NeuralGenError::Candle(candle_core::Error::Msg("no gradient for the input".into())))?,
        )?;
        let k = self.config.normalise_slopes();
        let img = tensor_vec(&y)?;
        Ok((
            coverages(&img, s),
            gx.chunks_exact(3).map(|v| [v[0] as f64 * k[0], v[1] as f64 * k[1], v[2] as f64 * k[2]]).collect(),
        ))
    }

    /// Saves the weights (`path`, safetensors) and the config (`path` with extension `.json`),
    /// each written whole to a temporary file first and renamed (`safe_output::write_atomic`:
    /// the folder is created, a symlink is written through).
    ///
    /// # Errors
    /// [`NeuralGenError::Save`] (the weights cannot be serialised), [`NeuralGenError::Write`].
    pub fn save(&self, path: &Path) -> Result<(), NeuralGenError> {
        let (weights, config) = self.serialise(path)?;
        safe_output::write_atomic(path, &weights)?;
        safe_output::write_atomic(&config_path(path), config.as_bytes())?;
        Ok(())
    }

    /// Adds the weights (`path`) and the config (`path` with extension `.json`) to `files`, a
    /// set of files replaced together when it is installed (with the caller's other outputs,
    /// say a loss curve): as [`Generator::save`], but both files are replaced or neither.
    ///
    /// # Errors
    /// [`NeuralGenError::Save`] (the weights cannot be serialised); the writes themselves fail
    /// in [`safe_output::FileSet::install`].
    ///
    /// # Examples
    /// ```
    /// use neural_gen::{Arch, Generator, GeneratorConfig};
    /// let profile = neural_gen::brush_model::BrushProfile::builtin("pen1")?;
    /// let g = Generator::new(GeneratorConfig::new(profile, Arch::tiny_32()), 1)?;
    /// let dir = std::env::temp_dir().join(format!("neural-gen-doc-save-into-{}", std::process::id()));
    /// let mut files = neural_gen::safe_output::FileSet::new();
    /// g.save_into(&mut files, &dir.join("g.safetensors"))?;
    /// files.add(dir.join("notes.txt"), b"trained for a doc test\n".to_vec());
    /// files.install("save")?;
    /// assert_eq!(Generator::load(&dir.join("g.safetensors"))?.config, g.config);
    /// # std::fs::remove_dir_all(&dir)?;
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn save_into(&self, files: &mut safe_output::FileSet<'_>, path: &Path) -> Result<(), NeuralGenError> {
        let (weights, config) = self.serialise(path)?;
        files.add(path, weights);
        files.add(config_path(path), config.into_bytes());
        Ok(())
    }

    /// The weights as safetensors and the config as pretty JSON (`path` names errors).
    fn serialise(&self, path: &Path) -> Result<(Vec<u8>, String), NeuralGenError> {
        let weights = {
            let data = self.varmap.data().lock().expect("varmap");
            safetensors::tensor::serialize(data.iter().map(|(k, v)| (k, v.as_tensor())), None)
                .map_err(|e| NeuralGenError::Save { path: path.to_path_buf(), source: e.into() })?
        };
        Ok((weights, serde_json::to_string_pretty(&self.config).expect("serialises")))
    }

    /// Loads weights and config, checking that they belong together: the config's version and
    /// architecture, the canvas size, and every tensor's name and shape.
    ///
    /// # Errors
    /// [`NeuralGenError::Io`], [`NeuralGenError::Config`] (mismatched or corrupted files).
    pub fn load(path: &Path) -> Result<Self, NeuralGenError> {
        let cfg_path = config_path(path);
        let name = cfg_path.display().to_string();
        let read = |p: &Path, max: u64, context: &'static str| {
            let io = |source| NeuralGenError::Io { path: p.to_path_buf(), context, source };
            let over = || io(std::io::Error::new(std::io::ErrorKind::InvalidData, format!("more than {max} bytes")));
            brush_model::read_regular(p, max).map_err(io)?.ok_or_else(over)
        };
        let text = String::from_utf8(read(&cfg_path, MAX_CONFIG_BYTES, "cannot read the generator's config")?)
            .map_err(|e| NeuralGenError::Io {
                path: cfg_path.clone(),
                context: "cannot read the generator's config",
                source: std::io::Error::new(std::io::ErrorKind::InvalidData, format!("not UTF-8 text: {e}")),
            })?;
        let bytes = read(path, MAX_WEIGHTS_BYTES, "cannot read the generator's weights")?;
        Self::from_bytes(&bytes, &text, &path.display().to_string(), &name)
    }

    /// The committed pen1 generator (`data/pen1.safetensors` with its `pen1.json`, trained by
    /// `cargo xtask train-fixture`; docs/neural-gen.md), compiled in with the `pen1` feature.
    ///
    /// # Errors
    /// As [`Generator::from_bytes`] (only for a broken build).
    ///
    /// # Examples
    /// ```
    /// # #[cfg(feature = "pen1")] {
    /// let g = neural_gen::Generator::pen1()?;
    /// assert_eq!(g.config.profile.name, "pen1");
    /// # }
    /// # Ok::<(), neural_gen::NeuralGenError>(())
    /// ```
    #[cfg(feature = "pen1")]
    pub fn pen1() -> Result<Self, NeuralGenError> {
        static WEIGHTS: &[u8] = include_bytes!("../data/pen1.safetensors");
        static CONFIG: &str = include_str!("../data/pen1.json");
        Self::from_bytes(WEIGHTS, CONFIG, "the committed pen1.safetensors", "the committed pen1.json")
    }

    /// As [`Generator::load`], from the weights' bytes and the config's text (for checkpoints
    /// compiled into a binary); the names label errors.
    ///
    /// # Errors
    /// As [`Generator::load`].
    pub fn from_bytes(
        weights: &[u8],
        config_json: &str,
        weights_name: &str,
        config_name: &str,
    ) -> Result<Self, NeuralGenError> {
        let name = config_name.to_string();
        let text = config_json;
        let bad = |problem| NeuralGenError::Config { source_name: name.clone(), problem };
        let config: GeneratorConfig = serde_json::from_str(text).map_err(|e| bad(ConfigError::Json(e)))?;
        if config.version != CONFIG_VERSION {
            return Err(bad(ConfigError::Version { found: config.version, supported: CONFIG_VERSION }));
        }
        if config.arch.output_side() as u32 != config.size {
            return Err(bad(ConfigError::Size { size: config.size, output: config.arch.output_side() }));
        }
        config.profile.validate(&name).map_err(|e| bad(ConfigError::Profile(e)))?;
        config.arch.validate().map_err(|e| bad(ConfigError::Arch(e)))?;
        if !(config.px_per_mm.is_finite() && config.px_per_mm > 0.0 && config.px_per_mm <= 1e4) {
            return Err(bad(ConfigError::Scale { px_per_mm: config.px_per_mm }));
        }
        let g = Generator::new(config, 0)?;
        let bad = |problem| NeuralGenError::Config { source_name: weights_name.to_string(), problem };
        let tensors =
            candle_core::safetensors::load_buffer(weights, &g.device).map_err(|e| bad(ConfigError::Safetensors(e)))?;
        {
            let data = g.varmap.data().lock().expect("varmap");
            if tensors.len() != data.len() {
                return Err(bad(ConfigError::TensorCount { found: tensors.len(), expected: data.len() }));
            }
            for (k, var) in data.iter() {
                let t = tensors.get(k).ok_or_else(|| bad(ConfigError::MissingTensor { name: k.clone() }))?;
                if t.shape() != var.shape() {
                    return Err(bad(ConfigError::TensorShape {
                        name: k.clone(),
                        found: t.dims().to_vec(),
                        expected: var.dims().to_vec(),
                    }));
                }
                // NaN or infinite weights draw blank images and SSIM of ±inf: refuse them.
                let finite = t
                    .flatten_all()
                    .and_then(|f| f.to_dtype(candle_core::DType::F32))
                    .and_then(|f| f.to_vec1::<f32>())
                    .map_err(cerr)?
                    .iter()
                    .all(|v| v.is_finite());
                if !finite {
                    return Err(bad(ConfigError::NonFinite { name: k.clone() }));
                }
                var.set(t).map_err(cerr)?;
            }
        }
        Ok(g)
    }
}

/// The config file of a checkpoint: `MODEL.safetensors` → `MODEL.json`.
pub fn config_path(weights: &Path) -> PathBuf {
    weights.with_extension("json")
}

fn build(config: &GeneratorConfig, vb: &VarBuilder<'_>) -> candle_core::Result<(Vec<Linear>, Vec<Conv2d>)> {
    let a = &config.arch;
    let mut fcs = Vec::new();
    let mut w = 3;
    for (i, &h) in a.hidden.iter().enumerate() {
        fcs.push(candle_nn::linear(w, h, vb.pp(format!("fc{i}")))?);
        w = h;
    }
    fcs.push(candle_nn::linear(
        w,
        a.seed_channels * a.seed_side * a.seed_side,
        vb.pp(format!("fc{}", a.hidden.len())),
    )?);
    let cfg = Conv2dConfig { padding: 1, ..Default::default() };
    let n = a.stages.len();
    let convs = a
        .stages
        .iter()
        .enumerate()
        .map(|(i, &(cin, cout))| {
            let c = Conv2d::from_candle(&candle_nn::conv2d(cin, cout, 3, cfg, vb.pp(format!("conv{i}")))?)?;
            Ok(if i + 1 < n { c.with_relu() } else { c })
        })
        .collect::<candle_core::Result<_>>()?;
    Ok((fcs, convs))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Arch;

    #[test]
    fn saved_weights_are_the_bytes_candle_writes() {
        let profile = brush_model::BrushProfile::builtin("pen1").unwrap();
        let g = Generator::new(GeneratorConfig::new(profile, Arch::tiny_32()), 3).unwrap();
        let dir = std::env::temp_dir().join(format!("neural-gen-save-{}", std::process::id()));
        g.save(&dir.join("g.safetensors")).unwrap();
        g.varmap.save(dir.join("candle.safetensors")).unwrap();
        assert_eq!(
            std::fs::read(dir.join("g.safetensors")).unwrap(),
            std::fs::read(dir.join("candle.safetensors")).unwrap()
        );
        let config: GeneratorConfig = serde_json::from_slice(&std::fs::read(dir.join("g.json")).unwrap()).unwrap();
        assert_eq!(config.arch, g.config.arch);
        // Nothing else is left in the folder (no temporary file).
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 3);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_set_of_files_gets_the_bytes_save_writes() {
        let profile = brush_model::BrushProfile::builtin("pen1").unwrap();
        let g = Generator::new(GeneratorConfig::new(profile, Arch::tiny_32()), 4).unwrap();
        let dir = std::env::temp_dir().join(format!("neural-gen-save-into-{}", std::process::id()));
        g.save(&dir.join("a.safetensors")).unwrap();
        let mut files = safe_output::FileSet::new();
        g.save_into(&mut files, &dir.join("b.safetensors")).unwrap();
        files.install("test").unwrap();
        let read = |name: &str| std::fs::read(dir.join(name)).unwrap();
        assert_eq!(read("a.safetensors"), read("b.safetensors"));
        assert_eq!(read("a.json"), read("b.json"));
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 4);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
