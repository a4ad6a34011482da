//! Helpers shared by the subcommands: brush selection and atomic file output.

use std::io::Write;
use std::path::Path;

use anyhow::{Context, Result};
use brush_model::BrushProfile;

/// Resolves `--brush`: a built-in name (`pen1`, `pen2`) or a profile JSON file.
pub fn load_brush(spec: &str) -> Result<BrushProfile> {
    if BrushProfile::BUILTINS.contains(&spec) {
        return Ok(BrushProfile::builtin(spec)?);
    }
    let path = Path::new(spec);
    if !path.exists() && !spec.ends_with(".json") {
        anyhow::bail!("--brush `{spec}`: not a built-in brush (pen1, pen2) nor an existing profile file");
    }
    Ok(BrushProfile::load(path)?)
}

/// Writes `bytes` to `path` atomically: into a temporary file in the same folder, then renamed,
/// so a failure never leaves a half-written output. Creates the parent folder if needed.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create folder {}", dir.display()))?;
    let mut tmp = tempfile::NamedTempFile::new_in(dir)
        .with_context(|| format!("cannot create a temporary file in {}", dir.display()))?;
    tmp.write_all(bytes).with_context(|| format!("cannot write {}", path.display()))?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        // Temporary files are created private; outputs get the usual permissions.
        let _ = tmp.as_file().set_permissions(std::fs::Permissions::from_mode(0o644));
    }
    tmp.persist(path).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}

/// Prints a value as pretty JSON on stdout.
pub fn print_json<T: serde::Serialize>(value: &T) -> Result<()> {
    println!("{}", serde_json::to_string_pretty(value)?);
    Ok(())
}

/// Loads an image file as coverage (ink = 1), naming the file on error.
pub fn load_image(path: &Path) -> Result<bezier_raster::Coverage> {
    Ok(bezier_raster::Coverage::load(path)?)
}

pub use maobi::pipeline::gray;

/// A progress bar on stderr (hidden when stderr is not a terminal).
pub fn progress(len: u64, what: &str) -> indicatif::ProgressBar {
    let pb = indicatif::ProgressBar::new(len);
    pb.set_style(
        indicatif::ProgressStyle::with_template("{msg:>10} [{bar:40}] {pos}/{len} ({per_sec}, {eta})")
            .expect("valid template")
            .progress_chars("=> "),
    );
    pb.set_message(what.to_string());
    pb
}

/// The `--brush` argument shared by most commands.
#[derive(clap::Args, Debug, Clone)]
pub struct BrushArg {
    /// Brush: pen1, pen2 or a profile JSON file.
    #[arg(long, default_value = "pen1")]
    pub brush: String,
}

/// The `--model` argument: a stroke model name.
pub fn parse_model(s: &str) -> std::result::Result<bezier_raster::ModelKind, String> {
    s.parse()
}

/// The `--from` argument: a centre-line method name.
pub fn parse_method(s: &str) -> std::result::Result<trajectory::Method, String> {
    s.parse()
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
    /// The press, angles converted to radians.
    pub fn press(&self) -> brush_model::Press {
        brush_model::Press::from_degrees(self.h_mm, self.alpha_deg, self.beta_deg)
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
    let name = path.display().to_string();
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

/// `--renderer analytic|neural` and `--generator`, shared by `stroke` and `write`.
#[derive(clap::Args, Debug, Clone)]
pub struct RendererArgs {
    /// `analytic` (the stroke model) or `neural` (the trained generator; for `stroke` PNG only,
    /// at the generator's own size and scale; for `write` batched along the track, and its brush
    /// must be the one written with).
    #[arg(long, default_value = "analytic", value_parser = ["analytic", "neural"])]
    pub renderer: String,
    /// Generator weights for `--renderer neural` (default: the committed pen1 model).
    #[arg(long)]
    pub generator: Option<std::path::PathBuf>,
}

impl RendererArgs {
    /// Whether the neural generator draws.
    pub fn neural(&self) -> bool {
        self.renderer == "neural"
    }

    /// The generator asked for (or the committed pen1 model).
    pub fn generator(&self) -> Result<neural_gen::Generator> {
        maobi::generator::load_generator(self.generator.as_deref())
    }
}
