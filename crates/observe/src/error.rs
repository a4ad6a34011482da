//! The crate's one error type.

use thiserror::Error;

/// Why a photo could not be observed. Each names what was not found or not good enough.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ObserveError {
    /// The photo file cannot be read or decoded ([`crate::read_sheet_photo`]).
    #[error(transparent)]
    Image(#[from] bezier_raster::ImageFileError),
    /// The photo is too small to hold a sheet.
    #[error("the photo is {width}×{height} px: too small to see a sheet of paper (need at least 200 px a side)")]
    TooSmall {
        /// Width, px.
        width: u32,
        /// Height, px.
        height: u32,
    },
    /// No sheet of paper stands out from the background.
    #[error("found no sheet of paper in the photo: no bright region covers a tenth of it")]
    NoPaper,
    /// Fewer than four blobs of ink where the corner marks should be.
    #[error(
        "found {found} blob(s) of ink on the paper, not the four corner registration marks (is the whole sheet in the photo, and was it written with marks?)"
    )]
    TooFewBlobs {
        /// Blobs found.
        found: usize,
    },
    /// A registration mark was not where the others put it.
    #[error(
        "the {role} registration mark was not found where the corner marks put it (the photo may be of another sheet, or the sheet was written without marks)"
    )]
    MarkNotFound {
        /// Which mark.
        role: String,
    },
    /// The marks fit the sheet more than one way round.
    #[error(
        "the registration marks fit the sheet {ways} ways round: ambiguous (is something else inked near the corners?)"
    )]
    Ambiguous {
        /// How many orientations fit.
        ways: usize,
    },
    /// A mark's ink is far from the size it should have.
    #[error(
        "the ink at the {role} registration mark covers {area_mm2:.0} mm², a mark covers about {expected_mm2:.0} mm²: not a mark (a photo of another sheet?)"
    )]
    MarkSize {
        /// Which mark.
        role: String,
        /// What was found, mm².
        area_mm2: f64,
        /// What a mark covers, mm².
        expected_mm2: f64,
    },
    /// The marks do not fit one homography.
    #[error(
        "the registration marks do not fit the sheet: the {role} mark is {error_mm:.2} mm off (limit {limit_mm} mm; a photo of a sheet of another size, or paper that is not flat?)"
    )]
    Residual {
        /// The worst mark.
        role: String,
        /// Its error, mm.
        error_mm: f64,
        /// The limit, mm.
        limit_mm: f64,
    },
    /// A mark is not where the other marks put it.
    #[error(
        "the {role} registration mark is {error_mm:.2} mm from where the other marks put it (limit {limit_mm} mm): a mark out of place (did the paper move while the marks were written?), or paper that is not flat"
    )]
    Misplaced {
        /// The mark farthest from where the others put it.
        role: String,
        /// Its distance, mm.
        error_mm: f64,
        /// The limit, mm.
        limit_mm: f64,
    },
    /// The marks' edges are too soft.
    #[error(
        "the photo is blurred: the registration marks' edges are {edge_mm:.2} mm wide (10–90 %), over the {limit_mm} mm limit (hold the camera still and focus on the paper)"
    )]
    Blurred {
        /// Measured edge width, mm.
        edge_mm: f64,
        /// The limit, mm.
        limit_mm: f64,
    },
    /// The homography could not be fitted (the marks lie on a line).
    #[error("the registration marks give no homography (they lie on one line in the photo)")]
    Degenerate,
    /// A calibration press's window holds no ink.
    #[error(
        "found no footprint in the paper box ({:.1}, {:.1})–({:.1}, {:.1}) mm where a press should be",
        window_mm[0], window_mm[1], window_mm[2], window_mm[3]
    )]
    NoFootprint {
        /// The window searched, `[x0, y0, x1, y1]` paper mm.
        window_mm: [f64; 4],
    },
    /// A calibration press's window holds more than one blob of ink.
    #[error(
        "the paper box ({:.1}, {:.1})–({:.1}, {:.1}) mm holds several blobs of ink (the second is {:.0} % of the largest), not one footprint",
        window_mm[0], window_mm[1], window_mm[2], window_mm[3], 100.0 * share
    )]
    SeveralFootprints {
        /// The window searched, `[x0, y0, x1, y1]` paper mm.
        window_mm: [f64; 4],
        /// The second blob's size over the largest's.
        share: f64,
    },
}
