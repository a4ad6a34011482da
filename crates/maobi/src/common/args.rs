//! Flags shared by several commands.

use anyhow::Result;

use brush_model::BrushProfile;

use super::check_range;

/// The `--brush` argument shared by most commands.
#[derive(clap::Args, Debug, Clone)]
pub struct BrushArg {
    /// Brush: pen1, pen2, a scaled pen1 (pen1-s84 … pen1-s25) or a profile JSON file.
    #[arg(long, default_value = "pen1")]
    pub brush: String,
}

/// A flag value parsed by its type's `FromStr` (whose error message is kept), with the names
/// that parse listed by `--help` as the possible values.
#[derive(Clone)]
pub struct Named<T> {
    names: Vec<&'static str>,
    _t: std::marker::PhantomData<fn() -> T>,
}

impl<T: std::str::FromStr> Named<T> {
    /// The parser; of `candidates`, `--help` lists the ones `T` accepts.
    pub fn new(candidates: &[&'static str]) -> Self {
        Named { names: candidates.iter().copied().filter(|n| n.parse::<T>().is_ok()).collect(), _t: Default::default() }
    }
}

impl<T> clap::builder::TypedValueParser for Named<T>
where
    T: std::str::FromStr<Err = String> + Clone + Send + Sync + 'static,
{
    type Value = T;

    fn parse_ref(
        &self,
        _cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &std::ffi::OsStr,
    ) -> std::result::Result<T, clap::Error> {
        let flag = arg.map_or_else(|| "the value".to_string(), |a| format!("'{a}'"));
        let s = value.to_str().ok_or_else(|| {
            clap::Error::raw(clap::error::ErrorKind::InvalidUtf8, format!("invalid UTF-8 in {flag}\n"))
        })?;
        s.parse().map_err(|e| {
            clap::Error::raw(clap::error::ErrorKind::InvalidValue, format!("invalid value '{s}' for {flag}: {e}\n"))
        })
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = clap::builder::PossibleValue> + '_>> {
        Some(Box::new(self.names.iter().map(|n| clap::builder::PossibleValue::new(*n))))
    }
}

/// The `--model` argument: a stroke model name (help lists `ModelKind::ALL`).
pub fn parse_model() -> Named<bezier_raster::ModelKind> {
    let names: Vec<&'static str> = bezier_raster::ModelKind::ALL.iter().map(|m| m.name()).collect();
    Named::new(&names)
}

/// The `--from` argument: a centre-line method name (help lists those this build knows).
pub fn parse_method() -> Named<trajectory::Method> {
    Named::new(&["medians", "skeleton", "template"])
}

/// The press arguments shared by `footprint` and `stroke`: depth in mm, angles in degrees.
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct PressArgs {
    /// Press depth h, mm.
    #[arg(long = "h", value_name = "MM", allow_negative_numbers = true)]
    pub h_mm: f64,
    /// Tilt α, degrees.
    #[arg(long = "alpha", value_name = "DEG", allow_negative_numbers = true)]
    pub alpha_deg: f64,
    /// Rotation β, degrees.
    #[arg(long = "beta", value_name = "DEG", default_value_t = 0.0, allow_negative_numbers = true)]
    pub beta_deg: f64,
}

impl PressArgs {
    /// The press, angles converted to radians, after checking each value against what the
    /// brush can physically do (even with `--extrapolate`): depth 0 up to the bundle's length,
    /// tilt within ±90°, rotation within ±360°.
    pub fn press(&self, profile: &BrushProfile) -> Result<brush_model::Press> {
        check_range("--h", self.h_mm, 0.0, profile.brush.length_mm, "mm (up to the brush's length)")?;
        check_range("--alpha", self.alpha_deg, -90.0, 90.0, "degrees")?;
        check_range("--beta", self.beta_deg, -360.0, 360.0, "degrees")?;
        Ok(brush_model::Press::from_degrees(self.h_mm, self.alpha_deg, self.beta_deg))
    }
}

/// `--renderer analytic|neural` and `--generator` of `maobi write`.
#[derive(clap::Args, Debug, Clone)]
pub struct RendererArgs {
    /// Who draws the character: `analytic` (the --model stroke model) or `neural` (the trained
    /// generator, batched along the track; it must have been trained for --brush).
    #[arg(long, default_value = "analytic", value_parser = ["analytic", "neural"])]
    pub renderer: String,
    /// Generator weights (`.safetensors`, its `.json` config beside) for `--renderer neural`
    /// (default: the committed pen1 generator).
    #[arg(long, value_name = "FILE")]
    pub generator: Option<std::path::PathBuf>,
}

impl RendererArgs {
    /// Whether the neural generator draws.
    pub fn neural(&self) -> bool {
        self.renderer == "neural"
    }

    /// The generator asked for (or the committed pen1 model).
    pub fn generator(&self) -> Result<neural_gen::Generator> {
        crate::generator::load_generator(self.generator.as_deref())
    }
}

/// `--renderer analytic|neural` and `--generator` of `maobi stroke`.
#[derive(clap::Args, Debug, Clone)]
pub struct StrokeRendererArgs {
    /// Who draws the footprint: `analytic` (the --model stroke model, PNG or SVG at any size and
    /// scale) or `neural` (the trained generator: PNG only, at its own size and scale, inside its
    /// training range).
    #[arg(long, default_value = "analytic", value_parser = ["analytic", "neural"])]
    pub renderer: String,
    /// Generator weights (`.safetensors`, its `.json` config beside) for `--renderer neural`
    /// (default: the committed pen1 generator).
    #[arg(long, value_name = "FILE")]
    pub generator: Option<std::path::PathBuf>,
}

impl StrokeRendererArgs {
    /// Whether the neural generator draws.
    pub fn neural(&self) -> bool {
        self.renderer == "neural"
    }

    /// The generator asked for (or the committed pen1 model).
    pub fn generator(&self) -> Result<neural_gen::Generator> {
        crate::generator::load_generator(self.generator.as_deref())
    }
}
