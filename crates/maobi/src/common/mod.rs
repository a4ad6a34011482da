//! Helpers shared by the subcommands: brush selection, atomic file output, output folders
//! (staging, lock, interrupt-safe swap), stdout that ends quietly when the reader goes away,
//! Ctrl-C clean-up, and numeric flag ranges.

use std::io::Write;
use std::path::Path;

use anyhow::{Result, bail};
use brush_model::BrushProfile;

mod args;
mod glyph_args;
mod interrupt;
mod output;
mod photo_args;
mod progress;

pub use args::*;
pub use glyph_args::*;
pub use interrupt::*;
pub use output::*;
pub use photo_args::*;
pub use progress::*;

/// The smallest image scale a flag may ask for, px per mm (a 25-dpi scan is 1 px/mm).
pub const MIN_PX_PER_MM: f64 = 0.1;
/// The largest image scale a flag may ask for, px per mm (a 250 000-dpi microscope).
pub const MAX_PX_PER_MM: f64 = 10_000.0;

/// Checks a numeric flag against a closed range (NaN is outside every range); the error names
/// the flag, the value and the range with its unit.
pub fn check_range<T: PartialOrd + std::fmt::Display + Copy>(flag: &str, v: T, lo: T, hi: T, unit: &str) -> Result<T> {
    if lo <= v && v <= hi {
        Ok(v)
    } else {
        let unit = if unit.is_empty() { String::new() } else { format!(" {unit}") };
        bail!("{flag} {}: expected {lo}..={hi}{unit}", short_number(&v.to_string()))
    }
}

/// A number as typed, or in exponent form when that is long (`1e300`, not 301 digits).
pub fn short_number(s: &str) -> String {
    match s.parse::<f64>() {
        Ok(v) if s.len() > 16 => format!("{v:e}"),
        _ => s.to_string(),
    }
}

/// Writes one line to stdout. A reader that went away (`maobi … | head`) is an error that
/// [`is_broken_pipe`] recognises, so `main` ends quietly instead of panicking as `println!` does.
#[macro_export]
macro_rules! outln {
    ($($t:tt)*) => { $crate::common::out_fmt(format_args!("{}\n", format_args!($($t)*))) };
}

/// Writes to stdout without a newline; see [`outln!`].
#[macro_export]
macro_rules! out {
    ($($t:tt)*) => { $crate::common::out_fmt(format_args!($($t)*)) };
}

/// The writer behind [`outln!`] and [`out!`].
pub fn out_fmt(args: std::fmt::Arguments<'_>) -> Result<()> {
    let mut o = std::io::stdout().lock();
    o.write_fmt(args).and_then(|()| o.flush()).map_err(anyhow::Error::from)
}

/// Whether an error (anywhere in its chain) is a write to a closed pipe.
pub fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| c.downcast_ref::<std::io::Error>().is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe))
}

/// Resolves `--brush`: a built-in name (`pen1`, `pen2`) or a profile JSON file.
pub fn load_brush(spec: &str) -> Result<BrushProfile> {
    if BrushProfile::BUILTINS.contains(&spec) {
        return Ok(BrushProfile::builtin(spec)?);
    }
    let path = Path::new(spec);
    if !path.exists() && !spec.ends_with(".json") {
        anyhow::bail!(
            "--brush `{spec}`: not a built-in brush (pen1, pen2, pen1-s84 … pen1-s25) nor an existing profile file"
        );
    }
    Ok(BrushProfile::load(path)?)
}

/// `profile.predict` for a command with `--extrapolate`: outside the calibrated range the error
/// names the flag (`hint`: what to say, e.g. "give --extrapolate to use it anyway").
pub fn predict_or_hint(
    profile: &BrushProfile,
    press: &brush_model::Press,
    ex: brush_model::Extrapolation,
    hint: &str,
) -> Result<brush_model::Footprint> {
    profile.predict(press, ex).map_err(|e| match e {
        brush_model::ProfileError::OutOfRange { profile, quantity, value, min, max } => anyhow::anyhow!(
            "{quantity} = {value:.4} is outside the calibrated range [{min:.4}, {max:.4}] of profile `{profile}` ({hint})"
        ),
        e => e.into(),
    })
}

/// Prints a value as pretty JSON on stdout.
pub fn print_json<T: serde::Serialize>(value: &T) -> Result<()> {
    outln!("{}", serde_json::to_string_pretty(value)?)
}

/// Loads an image file as coverage (ink = 1), naming the file on error.
pub fn load_image(path: &Path) -> Result<bezier_raster::Coverage> {
    Ok(bezier_raster::Coverage::load(path)?)
}

/// The table `models` and `eval-generator` print: per model, CSIM and SSIM best, worst and mean,
/// in %.
pub fn print_model_table<'a>(
    rows: impl IntoIterator<Item = (&'a str, stroke_metrics::Summary, stroke_metrics::Summary)>,
) -> Result<()> {
    crate::outln!(
        "{:<8} {:>9} {:>9} {:>9}   {:>9} {:>9} {:>9}",
        "model",
        "CSIM best",
        "worst",
        "mean",
        "SSIM best",
        "worst",
        "mean"
    )?;
    for (name, c, s) in rows {
        crate::outln!(
            "{:<8} {:>9.2} {:>9.2} {:>9.2}   {:>9.2} {:>9.2} {:>9.2}",
            name,
            100.0 * c.best,
            100.0 * c.worst,
            100.0 * c.mean,
            100.0 * s.best,
            100.0 * s.worst,
            100.0 * s.mean
        )?;
    }
    Ok(())
}
