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
