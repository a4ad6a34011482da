//! The committed pen1 generator, compiled into the binary, and loading others.

use std::path::Path;

use anyhow::{Context, Result};
use neural_gen::Generator;

/// The generator at `path` (a `.safetensors` with its `.json` beside), or the committed pen1
/// checkpoint when `None`.
///
/// # Errors
/// When the files are unreadable, corrupted or do not match each other.
pub fn load_generator(path: Option<&Path>) -> Result<Generator> {
    match path {
        Some(p) => Generator::load(p).with_context(|| format!("loading the generator {}", p.display())),
        None => Ok(Generator::pen1()?),
    }
}

/// The committed pen1 generator prepared for refinement (`--gradients generator`), loaded once.
///
/// # Errors
/// When the embedded files do not load (a broken build).
pub fn committed_gen_model() -> Result<std::sync::Arc<track_refine::GenModel>> {
    static CELL: std::sync::OnceLock<std::sync::Arc<track_refine::GenModel>> = std::sync::OnceLock::new();
    if let Some(m) = CELL.get() {
        return Ok(m.clone());
    }
    let g = load_generator(None)?;
    let m = track_refine::GenModel::new(&g).context("the committed generator")?;
    Ok(CELL.get_or_init(|| std::sync::Arc::new(m)).clone())
}
