//! What `maobi observe` saw of a written sheet, as `write --observed` reads it back: a typed
//! `summary.json` with a version, naming the sheet it observed by an absolute path and a
//! fingerprint of that sheet's `track.json`, validated where it is parsed (docs/closed-loop.md).

use std::path::{Path, PathBuf};

use observe::{Diagnosis, Homography, MarkFit};
use serde::{Deserialize, Serialize};

use crate::readback::{ReadBackError, check_num, read_bounded};
use crate::{MAX_SHEET_CHARS, SheetTrack, Similarity};

/// The version of [`Observation`] this build writes and reads.
pub const OBSERVATION_VERSION: u32 = 1;

/// The largest observation `summary.json` read back, bytes.
pub const MAX_OBSERVATION_BYTES: u64 = 16 << 20;

/// The smallest and largest side of an observed character image, px (as `write --size`).
pub const OBSERVED_PX: [u32; 2] = [64, 4096];

/// A photo of a written sheet, observed (`maobi observe`'s `summary.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Observation {
    /// [`OBSERVATION_VERSION`].
    pub version: u32,
    /// The photo, as given.
    pub photo: String,
    /// The sheet observed.
    pub sheet: ObservedSheet,
    /// Its text.
    pub text: String,
    /// The brush it was written with (its profile's name).
    pub brush: String,
    /// How the photo was mapped onto the paper.
    pub registration: ObservedRegistration,
    /// Each character, in the sheet's order.
    pub chars: Vec<ObservedChar>,
}

/// Which sheet an observation is of.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ObservedSheet {
    /// The sheet's folder, absolute.
    pub path: PathBuf,
    /// [`crate::fingerprint`] of its `track.json`.
    pub track_fingerprint: String,
}

/// The photo → paper map and how well the marks fit it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ObservedRegistration {
    /// Root mean square of the marks' errors against the fit to all of them, mm.
    pub residual_rms_mm: f64,
    /// The largest such error, mm.
    pub residual_max_mm: f64,
    /// The largest error of a mark against the map fitted to the others, mm.
    pub leave_one_out_max_mm: f64,
    /// The marks' 10–90 % edge width, mm.
    pub edge_mm: f64,
    /// Photo px per paper mm at the sheet's centre.
    pub photo_px_per_mm: f64,
    /// The photo was reduced by this factor before it was looked at.
    pub photo_reduced_by: u32,
    /// Which way round the corner marks were found.
    pub corner_shift: usize,
    /// What of the lens is modelled.
    pub lens_distortion: String,
    /// Paper mm → photo px.
    pub paper_to_photo: Homography,
    /// Every mark as found.
    pub marks: Vec<MarkFit>,
}

/// CSIM, SSIM and IoU of observed ink against an image.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ObservedScores {
    /// Cosine similarity.
    pub csim: f64,
    /// Structural similarity.
    pub ssim: f64,
    /// Intersection over union at 0.5.
    pub iou: f64,
}

impl From<Similarity> for ObservedScores {
    fn from(s: Similarity) -> Self {
        ObservedScores { csim: s.csim, ssim: s.ssim, iou: s.iou }
    }
}

/// One character as observed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ObservedChar {
    /// The character.
    pub char: String,
    /// Its folder in the observation (`NN-<char>`, [`crate::char_folder`]), holding
    /// `observed.png`.
    pub folder: String,
    /// Side of `observed.png`, px (its box at the sheet's image scale).
    pub size_px: u32,
    /// The observed ink against the glyph.
    pub vs_glyph: ObservedScores,
    /// The observed ink against the plan.
    pub vs_plan: ObservedScores,
    /// What the brush did differently from the plan.
    pub diagnosis: Diagnosis,
    /// The diagnosis in one line.
    pub verdict: String,
}

const WHAT: &str = "the summary.json of `maobi observe`";

/// Bounds on the numbers an observation holds.
const MAX_MM: f64 = 10_000.0;
const MAX_STROKES: usize = 10_000;
const MAX_TEXT: usize = 64 << 10;

impl Observation {
    /// Reads and validates an observation's `summary.json` ([`Observation::parse`]).
    ///
    /// # Errors
    /// [`ReadBackError`] naming the file and the field.
    pub fn load(path: &Path) -> Result<Observation, ReadBackError> {
        let bytes = read_bounded(path, MAX_OBSERVATION_BYTES, WHAT)?;
        Self::parse(&bytes, path)
    }

    /// Parses and validates an observation: its version, the sheet's path (absolute) and
    /// fingerprint, every number finite and within its range, at most [`MAX_SHEET_CHARS`]
    /// characters, each one character, its folder [`crate::char_folder`]'s name and its image
    /// side within [`OBSERVED_PX`], and the text the characters joined. `path` names the file.
    ///
    /// # Errors
    /// [`ReadBackError::Json`] (not JSON, truncated, a field missing or of another type) or
    /// [`ReadBackError::Field`].
    ///
    /// # Examples
    /// ```
    /// let e = pipeline::Observation::parse(br#"{"photo": "p.jpg"}"#, "summary.json".as_ref()).unwrap_err();
    /// assert!(e.to_string().contains("field `version`"), "{e}");
    /// ```
    pub fn parse(bytes: &[u8], path: &Path) -> Result<Observation, ReadBackError> {
        let json = |source| ReadBackError::Json { path: path.to_path_buf(), what: WHAT, source };
        // The version first: an older or newer file says so instead of naming a field it lacks.
        let head: serde_json::Map<String, serde_json::Value> = serde_json::from_slice(bytes).map_err(json)?;
        match head.get("version").and_then(serde_json::Value::as_u64) {
            Some(v) if v == OBSERVATION_VERSION as u64 => {}
            Some(v) => {
                return Err(ReadBackError::field(
                    path,
                    "version",
                    format!("{v}: this build reads version {OBSERVATION_VERSION} (observe the photo again)"),
                ));
            }
            None => {
                return Err(ReadBackError::field(
                    path,
                    "version",
                    format!(
                        "missing: written by an older maobi (or not by `maobi observe`); observe the photo again (version {OBSERVATION_VERSION})"
                    ),
                ));
            }
        }
        let o: Observation = serde_json::from_value(serde_json::Value::Object(head)).map_err(json)?;
        o.validate(path)?;
        Ok(o)
    }

    /// The checks of [`Observation::parse`] after the types.
    ///
    /// # Errors
    /// [`ReadBackError::Field`] for the first field at fault.
    pub fn validate(&self, path: &Path) -> Result<(), ReadBackError> {
        let bad = |field: &str, expected: String| Err(ReadBackError::field(path, field, expected));
        if !self.sheet.path.is_absolute() {
            return bad("sheet.path", format!("{}: expected an absolute path", self.sheet.path.display()));
        }
        let fp = &self.sheet.track_fingerprint;
        let hex = fp.strip_prefix("fnv1a64:");
        if !hex.is_some_and(|h| h.len() == 16 && h.bytes().all(|b| b.is_ascii_hexdigit())) {
            return bad("sheet.track_fingerprint", format!("{fp:?}: expected fnv1a64: and 16 hex digits"));
        }
        for (f, s) in [("photo", &self.photo), ("text", &self.text), ("brush", &self.brush)] {
            if s.len() > MAX_TEXT {
                return bad(f, format!("{} bytes: expected at most {MAX_TEXT}", s.len()));
            }
        }
        let r = &self.registration;
        for (f, v) in [
            ("registration.residual_rms_mm", r.residual_rms_mm),
            ("registration.residual_max_mm", r.residual_max_mm),
            ("registration.leave_one_out_max_mm", r.leave_one_out_max_mm),
            ("registration.edge_mm", r.edge_mm),
        ] {
            check_num(path, f, v, 0.0, MAX_MM, "mm")?;
        }
        check_num(path, "registration.photo_px_per_mm", r.photo_px_per_mm, 0.0, 1e6, "px/mm")?;
        if r.paper_to_photo.m.iter().flatten().any(|v| !v.is_finite()) {
            return bad("registration.paper_to_photo", "expected finite numbers".into());
        }
        if r.marks.len() > 6 {
            return bad("registration.marks", format!("{} marks: a sheet has at most 6", r.marks.len()));
        }
        for (i, m) in r.marks.iter().enumerate() {
            let all = [m.photo_px[0], m.photo_px[1], m.error_mm[0], m.error_mm[1], m.leave_one_out_mm, m.area_mm2];
            if all.iter().any(|v| !v.is_finite()) || m.role.len() > 64 {
                return bad(&format!("registration.marks[{i}]"), "expected finite numbers and a role".into());
            }
        }
        let n = self.chars.len();
        if n == 0 || n > MAX_SHEET_CHARS {
            return bad("chars", format!("{n} characters: expected 1..={MAX_SHEET_CHARS}"));
        }
        let mut text = String::new();
        for (i, c) in self.chars.iter().enumerate() {
            let at = |f: &str| format!("chars[{i}].{f}");
            let mut it = c.char.chars();
            if !matches!((it.next(), it.next()), (Some(_), None)) {
                return bad(&at("char"), format!("{:?}: expected one character", c.char));
            }
            text.push_str(&c.char);
            let folder = crate::char_folder(i, &c.char);
            if c.folder != folder {
                return bad(&at("folder"), format!("{:?}: expected {folder:?}", c.folder));
            }
            if !(OBSERVED_PX[0]..=OBSERVED_PX[1]).contains(&c.size_px) {
                return bad(
                    &at("size_px"),
                    format!("{}: expected {}..={} px", c.size_px, OBSERVED_PX[0], OBSERVED_PX[1]),
                );
            }
            for (f, s) in [("vs_glyph", c.vs_glyph), ("vs_plan", c.vs_plan)] {
                check_num(path, &at(&format!("{f}.csim")), s.csim, 0.0, 1.0, "")?;
                check_num(path, &at(&format!("{f}.ssim")), s.ssim, -1.0, 1.0, "")?;
                check_num(path, &at(&format!("{f}.iou")), s.iou, 0.0, 1.0, "")?;
            }
            let d = &c.diagnosis;
            if d.strokes.len() > MAX_STROKES {
                return bad(
                    &at("diagnosis.strokes"),
                    format!("{} strokes: expected at most {MAX_STROKES}", d.strokes.len()),
                );
            }
            let opt = |f: String, v: Option<f64>, lo: f64, hi: f64| match v {
                Some(v) => check_num(path, &f, v, lo, hi, ""),
                None => Ok(()),
            };
            opt(at("diagnosis.width_ratio"), d.width_ratio, 0.0, 1000.0)?;
            opt(at("diagnosis.end_beyond_mm"), d.end_beyond_mm, -MAX_MM, MAX_MM)?;
            opt(at("diagnosis.lateral_mm"), d.lateral_mm, -MAX_MM, MAX_MM)?;
            for (k, s) in d.strokes.iter().enumerate() {
                let f = |g: &str| at(&format!("diagnosis.strokes[{k}].{g}"));
                opt(f("width_ratio"), s.width_ratio, 0.0, 1000.0)?;
                opt(f("start_beyond_mm"), s.start_beyond_mm, -MAX_MM, MAX_MM)?;
                opt(f("end_beyond_mm"), s.end_beyond_mm, -MAX_MM, MAX_MM)?;
                opt(f("lateral_mm"), s.lateral_mm, -MAX_MM, MAX_MM)?;
            }
            if c.verdict.len() > MAX_TEXT {
                return bad(&at("verdict"), format!("{} bytes: expected at most {MAX_TEXT}", c.verdict.len()));
            }
        }
        if text != self.text {
            return bad("text", format!("{:?}: expected the characters' {text:?}", self.text));
        }
        Ok(())
    }

    /// Checks that `track` (read from `track_path`, whose bytes are `track_bytes`) is the sheet
    /// this observation is of: the same fingerprint, the same characters. `path` is the
    /// observation's file, for the errors.
    ///
    /// # Errors
    /// [`ReadBackError::Field`] naming `sheet.track_fingerprint` or `chars`.
    pub fn check_sheet(
        &self,
        path: &Path,
        track: &SheetTrack,
        track_path: &Path,
        track_bytes: &[u8],
    ) -> Result<(), ReadBackError> {
        let now = crate::fingerprint(track_bytes);
        if now != self.sheet.track_fingerprint {
            return Err(ReadBackError::field(
                path,
                "sheet.track_fingerprint",
                format!(
                    "{}: the sheet's {} is now {now}: not the sheet that was observed (written again, edited or replaced since); observe a photo of it again",
                    self.sheet.track_fingerprint,
                    track_path.display()
                ),
            ));
        }
        let seen: Vec<&str> = track.chars.iter().map(|c| c.char.as_str()).collect();
        let here: Vec<&str> = self.chars.iter().map(|c| c.char.as_str()).collect();
        if seen != here {
            return Err(ReadBackError::field(
                path,
                "chars",
                format!("{:?}: the sheet {} holds {:?}", self.text, track_path.display(), track.char),
            ));
        }
        Ok(())
    }

    /// The sheet's `track.json`.
    pub fn track_path(&self) -> PathBuf {
        self.sheet.path.join("track.json")
    }
}
