//! Stroke photos as flags give them: the scale (a flag or a column, else the file's
//! metadata) and the footprint fitted at it (`fit-stroke` and `calibrate`'s photo path).

use std::path::Path;

use anyhow::Result;
use stroke_fit::{PhotoError, StrokeFit, fit_footprint, load_ink, scale_from_metadata};

use super::{MAX_PX_PER_MM, MIN_PX_PER_MM, check_range};

/// The scale of a photo: given (by the flag or column `what`), or from its metadata; either
/// must lie in [`MIN_PX_PER_MM`]..=[`MAX_PX_PER_MM`].
pub fn scale_for(photo: &Path, given: Option<f64>, what: &str) -> Result<f64> {
    match given {
        Some(s) => check_range(what, s, MIN_PX_PER_MM, MAX_PX_PER_MM, "px/mm"),
        None => {
            let s = scale_from_metadata(photo).ok_or_else(|| {
                let e = PhotoError::NoScale { path: photo.display().to_string() };
                anyhow::anyhow!("{e}; give the scale ({what})")
            })?;
            check_range(
                &format!("{}: the resolution in the file,", photo.display()),
                s,
                MIN_PX_PER_MM,
                MAX_PX_PER_MM,
                "px/mm",
            )
        }
    }
}

/// Fits one photo at the scale given or stored in the file. A missing, empty or non-image file
/// says so first (not "no scale"), then the scale is checked, then the ink.
pub fn fit_photo(photo: &Path, given: Option<f64>, what: &str) -> Result<(StrokeFit, stroke_fit::InkMask, f64)> {
    bezier_raster::image_header(photo).map_err(|source| PhotoError::Image { path: photo.to_path_buf(), source })?;
    let scale = scale_for(photo, given, what)?;
    let mask = load_ink(photo)?;
    Ok((fit_footprint(&mask, scale), mask, scale))
}
