//! Flags shared by several commands.

use std::path::Path;

use anyhow::{Context, Result, bail};

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

/// One row of a stroke-photo labels file.
pub struct StrokeLabel {
    /// Image file, relative to the labels' folder.
    pub file: String,
    /// The press that made the stroke.
    pub press: brush_model::Press,
    /// Scale of this photo, when given.
    pub px_per_mm: Option<f64>,
}

/// Reads `file,h_mm,alpha_deg,beta_deg[,px_per_mm]` (extra columns ignored); errors name the
/// file, line and column.
pub fn read_stroke_labels(path: &Path) -> Result<Vec<StrokeLabel>> {
    const MAX_BYTES: u64 = 64 << 20;
    const MAX_ROWS: usize = 100_000;
    let name = path.display().to_string();
    let len = std::fs::metadata(path).with_context(|| format!("{name}: cannot read"))?.len();
    if len > MAX_BYTES {
        bail!("{name}: {len} bytes; a labels file is at most {MAX_BYTES} bytes");
    }
    let mut rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(path)
        .with_context(|| format!("{name}: cannot read"))?;
    let header = rdr.headers().with_context(|| format!("{name}: cannot read the header"))?.clone();
    let col = |c: &str| header.iter().position(|h| h == c);
    let need = |c: &'static str| {
        col(c).with_context(|| format!("{name}: header has no column `{c}` (need file,h_mm,alpha_deg,beta_deg)"))
    };
    let (fi, hi, ai, bi) = (need("file")?, need("h_mm")?, need("alpha_deg")?, need("beta_deg")?);
    let si = col("px_per_mm");
    let mut out = Vec::new();
    for rec in rdr.records() {
        let rec = rec.with_context(|| format!("{name}: malformed CSV"))?;
        if out.len() == MAX_ROWS {
            bail!("{name}: more than {MAX_ROWS} rows");
        }
        let line = rec.position().map_or(0, |p| p.line());
        let num = |i: usize, c: &str| -> Result<f64> {
            let v = rec.get(i).unwrap_or("");
            v.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .with_context(|| format!("{name}: line {line}, column `{c}`: expected a number, got {v:?}"))
        };
        let px = match si {
            Some(i) if !rec.get(i).unwrap_or("").is_empty() => Some(num(i, "px_per_mm")?),
            _ => None,
        };
        out.push(StrokeLabel {
            file: rec.get(fi).unwrap_or("").to_string(),
            press: brush_model::Press::from_degrees(num(hi, "h_mm")?, num(ai, "alpha_deg")?, num(bi, "beta_deg")?),
            px_per_mm: px,
        });
    }
    if out.is_empty() {
        anyhow::bail!("{name}: no rows");
    }
    Ok(out)
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
