//! What the measuring commands share: writing a result file whole, and their progress bar.

use std::path::Path;

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};

/// Writes `bytes` to `path` through a temporary file beside it and a rename, creating the
/// folder; a reader never sees half a file (`safe_output::write_atomic`).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    Ok(safe_output::write_atomic(path, bytes)?)
}

/// A bar over `len` characters labelled `what`.
pub fn char_bar(len: usize, what: &str) -> ProgressBar {
    let pb = ProgressBar::new(len as u64);
    pb.set_style(
        ProgressStyle::with_template("{msg:>10} [{bar:40}] {pos}/{len} ({per_sec}, {eta})")
            .expect("valid template")
            .progress_chars("=> "),
    );
    pb.set_message(what.to_string());
    pb
}

/// `--lines A-B`: the 1-based, inclusive line range of a character set.
pub fn parse_lines(v: &str) -> Result<(usize, usize)> {
    let (x, y) = v.split_once('-').with_context(|| format!("--lines {v}: expected A-B"))?;
    let (x, y): (usize, usize) = (x.parse()?, y.parse()?);
    if x == 0 || y < x {
        anyhow::bail!("--lines {v}: expected 1 <= A <= B");
    }
    Ok((x, y))
}
