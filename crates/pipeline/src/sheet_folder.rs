//! A written sheet's folder read back to be observed: its validated `track.json`, its
//! registration marks in the order [`observe::register`] takes them, and each character's
//! frame on the paper, inking paths and images; then one character's ink observed against its
//! glyph and its plan, and the [`Observation`] of the whole photo (docs/closed-loop.md).
//!
//! The folder is untrusted input (it travels): every image's size is read from its header and
//! checked before anything is decoded, and every error names the file.

use std::path::{Path, PathBuf};

use bezier_raster::{Coverage, ImageFileError, RasterError};
use observe::{Frame, InkMap, KnownMark, Photo, Registration, diagnose, rectify};
use thiserror::Error;

use crate::readback::ReadBackError;
use crate::{
    OBSERVATION_VERSION, OBSERVED_PX, Observation, ObservedChar, ObservedRegistration, ObservedSheet, SheetTrack,
    char_folder, fingerprint, known_marks, similarity,
};

/// Below this CSIM of the observed ink against the plan (mean over the characters, see
/// [`plan_csim_mean`]) a photo is taken to be of another sheet. Hand-set, not swept.
pub const MIN_PLAN_CSIM: f64 = 0.5;

/// Why a sheet folder could not be read back or observed. Every message names the file.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum SheetFolderError {
    /// The folder cannot be read (missing, not a folder, no permission).
    #[error("cannot read the folder {}", path.display())]
    Folder {
        /// The folder as given.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// Its `track.json` is refused.
    #[error(transparent)]
    Track(#[from] ReadBackError),
    /// The sheet was written without registration marks.
    #[error("{} has no registration marks: write the sheet again with marks", path.display())]
    NoMarks {
        /// Its `track.json`.
        path: PathBuf,
    },
    /// A corner mark is missing.
    #[error("{} lacks one of the four corner registration marks", path.display())]
    NoCorner {
        /// Its `track.json`.
        path: PathBuf,
    },
    /// Only the four corner marks (the photo's orientation needs a fifth).
    #[error("{} has only the four corner registration marks (a sheet has six)", path.display())]
    CornersOnly {
        /// Its `track.json`.
        path: PathBuf,
    },
    /// A character image's header cannot be read.
    #[error("cannot read {}", path.display())]
    ImageHeader {
        /// The image.
        path: PathBuf,
        /// Why.
        #[source]
        source: ImageFileError,
    },
    /// A character image cannot be decoded.
    #[error("cannot read {}", path.display())]
    Image {
        /// The image.
        path: PathBuf,
        /// Why.
        #[source]
        source: RasterError,
    },
    /// A character image is not a square of [`OBSERVED_PX`].
    #[error(
        "{} is {width}×{height} px: expected a square of {}..={} px (a character image of the sheet)",
        path.display(), OBSERVED_PX[0], OBSERVED_PX[1]
    )]
    NotSquare {
        /// The image.
        path: PathBuf,
        /// Its width, px.
        width: u32,
        /// Its height, px.
        height: u32,
    },
    /// A character image's header differs in size from the first character's reference.
    #[error(
        "{} is not the size of {} ({side}×{side} px): every character image of a sheet has one size",
        path.display(), first.display()
    )]
    OtherSize {
        /// The image.
        path: PathBuf,
        /// The first character's `reference.png`.
        first: PathBuf,
        /// Its side, px.
        side: u32,
    },
    /// A decoded character image is not the size of the character's frame (changed since its
    /// header was read).
    #[error(
        "{} is {width}×{height} px, expected {side}×{side} px (the size of the sheet's first reference.png)",
        path.display()
    )]
    FrameSize {
        /// The image.
        path: PathBuf,
        /// Its width, px.
        width: u32,
        /// Its height, px.
        height: u32,
        /// The frame's side, px.
        side: u32,
    },
    /// Scoring the observed ink failed.
    #[error(transparent)]
    Score(Box<crate::Error>),
}

/// One character of a sheet as planned: where its images are, its frame on the paper and the
/// inking part of each stroke.
#[derive(Clone, Debug)]
pub struct PlannedChar {
    /// Its folder's name in the sheet's output and the observation's (`NN-<char>`,
    /// [`char_folder`]).
    pub folder: String,
    /// The folder holding its `reference.png` and `render.png` (the sheet's own for a sheet of
    /// one character).
    pub dir: PathBuf,
    /// Its character box on the paper at its images' scale.
    pub frame: Frame,
    /// Each stroke's points where the brush presses at least the profile's shallowest
    /// calibrated depth (the entry glide, only the tip touching, leaves nothing), paper mm.
    pub paths: Vec<Vec<[f64; 2]>>,
}

impl PlannedChar {
    /// Its `reference.png` (the glyph) and `render.png` (the plan), each decoded only after its
    /// size was found to be the frame's.
    ///
    /// # Errors
    /// [`SheetFolderError::Image`], [`SheetFolderError::FrameSize`].
    pub fn images(&self) -> Result<(Coverage, Coverage), SheetFolderError> {
        let load = |f: &str| -> Result<Coverage, SheetFolderError> {
            let path = self.dir.join(f);
            let img = Coverage::load(&path).map_err(|source| SheetFolderError::Image { path: path.clone(), source })?;
            if (img.width(), img.height()) != (self.frame.width, self.frame.height) {
                return Err(SheetFolderError::FrameSize {
                    path,
                    width: img.width(),
                    height: img.height(),
                    side: self.frame.width,
                });
            }
            Ok(img)
        };
        Ok((load("reference.png")?, load("render.png")?))
    }
}

/// A sheet folder (`maobi write … --sheet …`'s output) read back: its validated `track.json`
/// (and that file's bytes, for [`fingerprint`]), its marks in [`observe::register`]'s order and
/// each character as planned. Images are read one character at a time ([`PlannedChar::images`]).
#[derive(Clone, Debug)]
pub struct SheetFolder {
    /// The folder, absolute.
    pub dir: PathBuf,
    /// Its `track.json`, validated.
    pub track: SheetTrack,
    /// That file's bytes.
    pub track_bytes: Vec<u8>,
    /// The registration marks, the four corners first ([`known_marks`]).
    pub marks: Vec<KnownMark>,
    /// Each character, in the sheet's order.
    pub chars: Vec<PlannedChar>,
}

impl SheetFolder {
    /// Reads and validates the sheet folder `dir`: its `track.json` ([`SheetTrack::load`]), the
    /// four corner marks and at least one more, and every character's `reference.png` and
    /// `render.png` a square of one side within [`OBSERVED_PX`] (from their headers).
    ///
    /// # Errors
    /// [`SheetFolderError`] naming the folder or file at fault.
    ///
    /// # Examples
    /// ```
    /// let e = pipeline::SheetFolder::load("no/such/sheet".as_ref()).unwrap_err();
    /// assert!(e.to_string().starts_with("cannot read the folder no/such/sheet"), "{e}");
    /// ```
    pub fn load(dir: &Path) -> Result<SheetFolder, SheetFolderError> {
        let dir = std::fs::canonicalize(dir)
            .map_err(|source| SheetFolderError::Folder { path: dir.to_path_buf(), source })?;
        let path = dir.join("track.json");
        let (track, track_bytes) = SheetTrack::load(&path)?;
        if track.marks.is_empty() {
            return Err(SheetFolderError::NoMarks { path });
        }
        let Some(marks) = known_marks(&track.marks) else {
            return Err(SheetFolderError::NoCorner { path });
        };
        if marks.len() < 5 {
            return Err(SheetFolderError::CornersOnly { path });
        }
        let single = track.chars.len() == 1;
        let h_min = track.brush.ranges.h_mm.min;
        // Every character's images have the first one's size (one size for the sheet), read from
        // its header before anything is decoded.
        let first = if single { dir.clone() } else { dir.join(char_folder(0, &track.chars[0].char)) };
        let first = first.join("reference.png");
        let side = image_side(&first)?;
        let mut chars = Vec::new();
        for (i, c) in track.chars.iter().enumerate() {
            let folder = char_folder(i, &c.char);
            let cdir = if single { dir.clone() } else { dir.join(&folder) };
            let [x0, y0, size] = c.char_box_mm;
            for f in ["reference.png", "render.png"] {
                let p = cdir.join(f);
                if image_side(&p)? != side {
                    return Err(SheetFolderError::OtherSize { path: p, first: first.clone(), side });
                }
            }
            let frame = Frame { x0_mm: x0, y0_mm: y0, px_per_mm: side as f64 / size, width: side, height: side };
            let paths = track.strokes[c.strokes[0]..c.strokes[1]]
                .iter()
                .map(|s| s.points.iter().filter(|p| p.h_mm >= h_min).map(|p| [p.x_mm, p.y_mm]).collect())
                .collect();
            chars.push(PlannedChar { folder, dir: cdir, frame, paths });
        }
        Ok(SheetFolder { dir, track, track_bytes, marks, chars })
    }

    /// Character `i`'s ink observed: the photo's ink rectified into its frame (returned, for
    /// `observed.png`), scored against its glyph and its plan, and diagnosed against the plan's
    /// strokes with the sheet's brush named in the verdict.
    ///
    /// # Errors
    /// [`SheetFolderError`] from reading its images.
    ///
    /// # Panics
    /// When `i` is not a character of the sheet.
    pub fn observe_char(
        &self,
        i: usize,
        ink: &InkMap,
        reg: &Registration,
    ) -> Result<(ObservedChar, Coverage), SheetFolderError> {
        let c = &self.chars[i];
        let (reference, plan) = c.images()?;
        let observed = rectify(ink, reg, &c.frame);
        let score = |image: &Coverage| similarity(image, &observed).map_err(|e| SheetFolderError::Score(Box::new(e)));
        let (vs_glyph, vs_plan) = (score(&reference)?, score(&plan)?);
        let diagnosis = diagnose(&observed, &plan, &c.frame, &c.paths);
        let char = ObservedChar {
            char: self.track.chars[i].char.clone(),
            folder: c.folder.clone(),
            size_px: c.frame.width,
            vs_glyph: vs_glyph.into(),
            vs_plan: vs_plan.into(),
            verdict: diagnosis.verdict(&self.track.brush.name),
            diagnosis,
        };
        Ok((char, observed))
    }

    /// The observation of this sheet that `photo_name` (the photo as given) shows, registered
    /// by `reg` after the photo was reduced as `photo` says, with its characters observed.
    pub fn observation(
        &self,
        photo_name: &str,
        photo: &Photo,
        reg: &Registration,
        chars: Vec<ObservedChar>,
    ) -> Observation {
        Observation {
            version: OBSERVATION_VERSION,
            photo: photo_name.to_string(),
            sheet: ObservedSheet { path: self.dir.clone(), track_fingerprint: fingerprint(&self.track_bytes) },
            text: self.track.chars.iter().map(|c| c.char.as_str()).collect(),
            brush: self.track.brush.name.clone(),
            registration: ObservedRegistration {
                residual_rms_mm: reg.residual_rms_mm,
                residual_max_mm: reg.residual_max_mm,
                leave_one_out_max_mm: reg.leave_one_out_max_mm,
                edge_mm: reg.edge_mm,
                photo_px_per_mm: reg.px_per_mm,
                photo_reduced_by: photo.reduced_by,
                corner_shift: reg.corner_shift,
                lens_distortion: "not modelled".into(),
                paper_to_photo: reg.paper_to_photo,
                marks: reg.marks.clone(),
            },
            chars,
        }
    }
}

/// The mean CSIM of observed characters against their plans (0 for none): below
/// [`MIN_PLAN_CSIM`] the photo is not of the sheet.
///
/// # Examples
/// ```
/// assert_eq!(pipeline::plan_csim_mean(&[]), 0.0);
/// ```
pub fn plan_csim_mean(chars: &[ObservedChar]) -> f64 {
    chars.iter().map(|o| o.vs_plan.csim).sum::<f64>() / chars.len().max(1) as f64
}

/// The side of a character image of the sheet, from its header: square and within
/// [`OBSERVED_PX`].
fn image_side(path: &Path) -> Result<u32, SheetFolderError> {
    let (width, height) = bezier_raster::image_header(path)
        .map_err(|source| SheetFolderError::ImageHeader { path: path.to_path_buf(), source })?;
    let [lo, hi] = OBSERVED_PX;
    if width != height || !(lo..=hi).contains(&width) {
        return Err(SheetFolderError::NotSquare { path: path.to_path_buf(), width, height });
    }
    Ok(width)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_that_is_not_there_is_named() {
        let e = SheetFolder::load(Path::new("/no/such/sheet")).unwrap_err();
        assert!(matches!(e, SheetFolderError::Folder { .. }), "{e:?}");
        assert_eq!(e.to_string(), "cannot read the folder /no/such/sheet");
    }

    #[test]
    fn a_folder_without_a_track_says_which_file() {
        let dir = tempfile::tempdir().unwrap();
        let e = SheetFolder::load(dir.path()).unwrap_err();
        assert!(matches!(e, SheetFolderError::Track(ReadBackError::Read { .. })), "{e:?}");
        assert!(e.to_string().contains("track.json"), "{e}");
    }
}
