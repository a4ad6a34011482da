//! The generator network, its checkpoints, inference and gradients.

use std::path::{Path, PathBuf};

use bezier_raster::Coverage;
use brush_model::Press;
use candle_core::{DType, Device, Module, Tensor, Var};
use candle_nn::{Conv2dConfig, Linear, VarBuilder, VarMap};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::NeuralGenError;
use crate::config::{CONFIG_VERSION, GeneratorConfig};
use crate::conv::{self, Conv2d};

/// A generator: the network and its configuration.
pub struct Generator {
    /// Configuration (architecture, normalisation, brush, canvas).
    pub config: GeneratorConfig,
    /// The trainable variables.
    pub varmap: VarMap,
    fcs: Vec<Linear>,
    convs: Vec<Conv2d>,
    device: Device,
}

fn cerr(e: candle_core::Error) -> NeuralGenError {
    NeuralGenError::Candle(e)
}

impl Generator {
    /// A new generator with weights initialised deterministically from `seed` (Kaiming-uniform
    /// weights, zero biases).
    ///
    /// # Errors
    /// [`NeuralGenError::Config`] for an inconsistent architecture.
    pub fn new(config: GeneratorConfig, seed: u64) -> Result<Self, NeuralGenError> {
        config
            .arch
            .validate()
            .map_err(|m| NeuralGenError::Config { source_name: "architecture".into(), message: m })?;
        let device = Device::Cpu;
        let varmap = VarMap::new();
        let vb = VarBuilder::from_varmap(&varmap, DType::F32, &device);
        let (fcs, convs) = build(&config, &vb).map_err(cerr)?;
        let g = Generator { config, varmap, fcs, convs, device };
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

    /// Forward pass on normalised inputs `[B, 3]` → images `[B, 1, S, S]` in [0, 1].
    ///
    /// # Errors
    /// [`NeuralGenError::Candle`] on shape errors.
    pub fn forward(&self, x: &Tensor) -> Result<Tensor, NeuralGenError> {
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
    /// footprint centred).
    ///
    /// # Errors
    /// [`NeuralGenError::Candle`].
    pub fn render(&self, presses: &[Press]) -> Result<Vec<Coverage>, NeuralGenError> {
        if presses.is_empty() {
            return Ok(Vec::new());
        }
        let y = self.forward(&self.inputs(presses)?)?;
        let s = self.config.size;
        let flat: Vec<f32> = y.flatten_all().and_then(|t| t.to_vec1()).map_err(cerr)?;
        Ok(flat.chunks((s * s) as usize).map(|c| Coverage::from_vec(s, s, c.to_vec()).expect("sized")).collect())
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
        let y = self.forward(x.as_tensor())?;
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

    /// Saves the weights (`path`, safetensors) and the config (`path` with extension `.json`),
    /// each written to a temporary file first and renamed.
    ///
    /// # Errors
    /// [`NeuralGenError::Io`].
    pub fn save(&self, path: &Path) -> Result<(), NeuralGenError> {
        let io = |p: &Path, context: &'static str| {
            let path = p.to_path_buf();
            move |source| NeuralGenError::Io { path, context, source }
        };
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(io(dir, "cannot create the folder"))?;
        }
        let tmp = path.with_extension("safetensors.tmp");
        self.varmap.save(&tmp).map_err(|source| NeuralGenError::Save { path: tmp.clone(), source })?;
        std::fs::rename(&tmp, path).map_err(io(path, "cannot rename the temporary file onto it"))?;
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let _ = std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o644));
        }
        let cfg = config_path(path);
        let tmp = cfg.with_extension("json.tmp");
        std::fs::write(&tmp, serde_json::to_string_pretty(&self.config).expect("serialises"))
            .map_err(io(&tmp, "cannot write"))?;
        std::fs::rename(&tmp, &cfg).map_err(io(&cfg, "cannot rename the temporary file onto it"))?;
        Ok(())
    }

    /// Loads weights and config, checking that they belong together: the config's version and
    /// architecture, the canvas size, and every tensor's name and shape.
    ///
    /// # Errors
    /// [`NeuralGenError::Io`], [`NeuralGenError::Config`] (mismatched or corrupted files).
    pub fn load(path: &Path) -> Result<Self, NeuralGenError> {
        let cfg_path = config_path(path);
        let name = cfg_path.display().to_string();
        let text = std::fs::read_to_string(&cfg_path).map_err(|source| NeuralGenError::Io {
            path: cfg_path.clone(),
            context: "cannot read the generator's config",
            source,
        })?;
        let bytes = std::fs::read(path).map_err(|source| NeuralGenError::Io {
            path: path.to_path_buf(),
            context: "cannot read the generator's weights",
            source,
        })?;
        Self::from_bytes(&bytes, &text, &path.display().to_string(), &name)
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
        let config: GeneratorConfig = serde_json::from_str(text)
            .map_err(|e| NeuralGenError::Config { source_name: name.clone(), message: e.to_string() })?;
        if config.version != CONFIG_VERSION {
            return Err(NeuralGenError::Config {
                source_name: name,
                message: format!("version {} (this build reads {CONFIG_VERSION})", config.version),
            });
        }
        if config.arch.output_side() as u32 != config.size {
            return Err(NeuralGenError::Config {
                source_name: name,
                message: format!(
                    "size {} does not match the architecture's output {}",
                    config.size,
                    config.arch.output_side()
                ),
            });
        }
        config
            .profile
            .validate(&name)
            .map_err(|e| NeuralGenError::Config { source_name: name.clone(), message: e.to_string() })?;
        config.arch.validate().map_err(|m| NeuralGenError::Config { source_name: name.clone(), message: m })?;
        if !(config.px_per_mm.is_finite() && config.px_per_mm > 0.0 && config.px_per_mm <= 1e4) {
            return Err(NeuralGenError::Config {
                source_name: name,
                message: format!("px_per_mm {}: expected a scale above 0 and at most 10000 px/mm", config.px_per_mm),
            });
        }
        let g = Generator::new(config, 0)?;
        let wname = weights_name.to_string();
        let tensors =
            candle_core::safetensors::load_buffer(weights, &g.device).map_err(|e| NeuralGenError::Config {
                source_name: wname.clone(),
                message: format!("not a readable safetensors file: {e}"),
            })?;
        {
            let data = g.varmap.data().lock().expect("varmap");
            if tensors.len() != data.len() {
                return Err(NeuralGenError::Config {
                    source_name: wname,
                    message: format!("{} tensors, the architecture has {}", tensors.len(), data.len()),
                });
            }
            for (k, var) in data.iter() {
                let t = tensors.get(k).ok_or_else(|| NeuralGenError::Config {
                    source_name: wname.clone(),
                    message: format!("tensor `{k}` missing"),
                })?;
                if t.shape() != var.shape() {
                    return Err(NeuralGenError::Config {
                        source_name: wname.clone(),
                        message: format!(
                            "tensor `{k}` has shape {:?}, the architecture needs {:?}",
                            t.dims(),
                            var.dims()
                        ),
                    });
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
                    return Err(NeuralGenError::Config {
                        source_name: wname.clone(),
                        message: format!("tensor `{k}` holds NaN or infinite weights"),
                    });
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
