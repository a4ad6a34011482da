//! `track.json` read back ([`TrackFile`]), and what `maobi robot` does first with one: its
//! program built and checked on a paper frame, timed on the nominal arm, or placed on a level
//! sheet when a plotter writes it.

use std::path::Path;

use brush_model::{BrushProfile, Stroke, Track};
use serde::{Deserialize, Serialize};

use crate::config::RobotConfig;
use crate::exec::level_frame_in_front;
use crate::frame::PaperFrame;
use crate::kinematics::DhParams;
use crate::program::{CheckReport, Program, build_program_chars};
use crate::timing::{ProgramTiming, time_program};
use crate::{MAX_FILE_BYTES, RobotError, load_json};

/// A sheet `track.json`'s characters, as far as [`TrackFile::load`] checks them.
#[derive(Deserialize)]
struct SheetChars {
    #[serde(default)]
    chars: Option<Vec<SheetCharRange>>,
}

/// One character's stroke range in a sheet `track.json`.
#[derive(Deserialize)]
struct SheetCharRange {
    #[serde(default)]
    strokes: Option<[usize; 2]>,
}

/// `track.json` as `maobi write` writes it for one character and reads it back: the brush
/// profile and the strokes, with where the character sits. A sheet's `track.json` (more fields,
/// which this type ignores) reads through it too.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct TrackFile {
    /// The character, if recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub char: Option<String>,
    /// The char box on the paper, `[x0, y0, size]` mm, if recorded (as read: see
    /// [`TrackFile::char_box`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub char_box_mm: Option<[f64; 3]>,
    /// The sheet the character was laid out on, `[width, height]` mm, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sheet_mm: Option<[f64; 2]>,
    /// The brush profile the track was made for.
    pub brush: BrushProfile,
    /// The strokes.
    pub strokes: Vec<Stroke>,
    /// For a sheet: the character (index) of each stroke, which the ink reload rule
    /// `before_each_char` needs (absent for a single character).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stroke_chars: Option<Vec<usize>>,
}

impl TrackFile {
    /// Loads and validates `track.json`.
    ///
    /// # Errors
    /// [`RobotError::Read`] or [`RobotError::Json`] naming the file; [`RobotError::Profile`]
    /// (naming the file) for an invalid brush profile; [`RobotError::Config`] naming the file
    /// and the field for `stroke_chars` that do not fit the strokes. The char box is checked
    /// where it is needed ([`TrackFile::char_box`]).
    pub fn load(path: &Path) -> Result<Self, RobotError> {
        let t: TrackFile = load_json(path)?;
        t.brush.validate(&path.display().to_string())?;
        let chars: SheetChars = load_json(path)?;
        t.checked(chars, path)
    }

    /// As [`TrackFile::load`], from the text of a `track.json` (`name` labels errors: a file
    /// name, or what the text came from), with the same validation.
    ///
    /// # Errors
    /// As [`TrackFile::load`].
    pub fn from_json(text: &str, name: &str) -> Result<Self, RobotError> {
        let path = Path::new(name);
        let json = |source| RobotError::Json { path: path.to_path_buf(), source };
        if text.len() as u64 > MAX_FILE_BYTES {
            return Err(RobotError::Config {
                file: path.to_path_buf(),
                message: format!("larger than {} MiB: not a track file maobi writes", MAX_FILE_BYTES >> 20),
            });
        }
        let t: TrackFile = serde_json::from_str(text).map_err(json)?;
        t.brush.validate(name)?;
        let chars: SheetChars = serde_json::from_str(text).map_err(json)?;
        t.checked(chars, path)
    }

    /// A sheet's character boundaries, checked against what they index: `stroke_chars` (the
    /// ink reload rule's) against the strokes and the sheet's `chars`.
    fn checked(self, chars: SheetChars, path: &Path) -> Result<Self, RobotError> {
        self.check_stroke_chars(chars.chars.as_deref()).map_err(|message| RobotError::Config {
            file: path.to_path_buf(),
            message: format!("field `stroke_chars`: {message}"),
        })?;
        Ok(self)
    }

    /// `stroke_chars`, when there: one entry per stroke, the characters in writing order (each
    /// the last one or the next, from 0); with the sheet's `chars`, each entry one of them and
    /// each character's stroke range its own (the marks' strokes before them count as the
    /// first character's).
    fn check_stroke_chars(&self, chars: Option<&[SheetCharRange]>) -> Result<(), String> {
        let Some(sc) = &self.stroke_chars else { return Ok(()) };
        let n = self.strokes.len();
        if sc.len() != n {
            return Err(format!("{} entries for {n} strokes: expected one per stroke", sc.len()));
        }
        let mut last = 0;
        for (s, &c) in sc.iter().enumerate() {
            if c != last && c != last + 1 || (s == 0 && c != 0) {
                return Err(format!(
                    "stroke {s} is given character {c} after character {last}: expected the characters in writing order from 0"
                ));
            }
            last = c;
        }
        let Some(chars) = chars else { return Ok(()) };
        if let Some(s) = sc.iter().position(|&c| c >= chars.len()) {
            return Err(format!("stroke {s} names character {}, the sheet has {}", sc[s], chars.len()));
        }
        for (i, c) in chars.iter().enumerate() {
            let Some([a, b]) = c.strokes else { continue };
            if a > b || b > n || sc[a..b].iter().any(|&x| x != i) {
                return Err(format!("character {i}'s strokes [{a}, {b}) are not all its own (of {n} strokes)"));
            }
        }
        Ok(())
    }

    /// The char box `[x0, y0, size]` mm, for a caller that places the character by it (a
    /// render of what the arm wrote): recorded, finite and with a positive size. `path` names
    /// the file in the error.
    ///
    /// # Errors
    /// [`RobotError::Config`] naming `path` and the field when no char box is recorded, or its
    /// size is not positive.
    pub fn char_box(&self, path: &Path) -> Result<[f64; 3], RobotError> {
        let shape = "field `char_box_mm` must be [x0, y0, size]";
        let config = |message: String| RobotError::Config { file: path.to_path_buf(), message };
        let b = self.char_box_mm.ok_or_else(|| config(shape.into()))?;
        if !(b.iter().all(|v| v.is_finite()) && b[2] > 0.0) {
            return Err(config(format!("{shape} with size > 0")));
        }
        Ok(b)
    }

    /// The strokes as a [`Track`].
    pub fn track(&self) -> Track {
        Track { strokes: self.strokes.clone() }
    }

    /// The title a program made from this track carries: the character, or `track`.
    pub fn title(&self) -> String {
        self.char.clone().unwrap_or_else(|| "track".into())
    }

    /// The level sheet in front of the nominal arm ([`level_frame_in_front`]) that a plotter's
    /// program is checked and timed on, as `maobi write` places a character for its executed
    /// figure: the whole sheet when the track was laid out on one, else the char box with one
    /// box size around it, else the strokes' extent and 10 mm (a track without points: a 1 mm
    /// square at the origin). A plotter moves in the paper's own millimetres: only the checks
    /// and the speeds come from this frame.
    pub fn level_frame(&self) -> PaperFrame {
        let [x0, y0, x1, y1] = match (self.sheet_mm, self.char_box_mm) {
            (Some([w, h]), _) => [0.0, 0.0, w, h],
            (None, Some([x, y, s])) => [x - s, y - s, x + 2.0 * s, y + 2.0 * s],
            (None, None) => {
                let mut b = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
                for p in self.strokes.iter().flat_map(|s| &s.points) {
                    b = [b[0].min(p.x_mm), b[1].min(p.y_mm), b[2].max(p.x_mm), b[3].max(p.y_mm)];
                }
                if b[0] > b[2] { [0.0, 0.0, 1.0, 1.0] } else { [b[0] - 10.0, b[1] - 10.0, b[2] + 10.0, b[3] + 10.0] }
            }
        };
        level_frame_in_front([(x0 + x1) / 2.0, (y0 + y1) / 2.0], [x0, y0, x1, y1])
    }

    /// The writing program of this track on `frame` with `cfg`, checked against the safety
    /// envelope ([`build_program_chars`], with the sheet's character boundaries).
    ///
    /// # Errors
    /// As [`build_program_chars`].
    pub fn build_program(&self, frame: &PaperFrame, cfg: &RobotConfig) -> Result<(Program, CheckReport), RobotError> {
        build_program_chars(&self.track(), self.stroke_chars.as_deref(), &self.brush, frame, cfg)
    }

    /// Checks this track's program on `frame` with `cfg` and times it on the nominal AUBO-i5
    /// (the simulator's arm; a controller's run times it again on the arm's own parameters
    /// before anything moves): `maobi robot check`'s verdict.
    ///
    /// # Examples
    /// ```
    /// use robot_io::brush_model::{BrushProfile, Stroke, TrackPoint};
    /// use robot_io::{RobotConfig, TrackFile};
    /// let pt = |x: f64| TrackPoint { x_mm: x, y_mm: 60.0, h_mm: 12.0, alpha_rad: 0.0, beta_rad: 0.0 };
    /// let tf = TrackFile {
    ///     char: Some("一".into()),
    ///     char_box_mm: Some([20.0, 20.0, 80.0]),
    ///     sheet_mm: None,
    ///     brush: BrushProfile::builtin("pen1").unwrap(),
    ///     strokes: vec![Stroke { points: (0..=30).map(|i| pt(30.0 + 2.0 * f64::from(i))).collect() }],
    ///     stroke_chars: None,
    /// };
    /// let check = tf.check(&tf.level_frame(), &RobotConfig::default()).unwrap();
    /// assert_eq!((check.report.strokes, check.timing.strokes.len()), (1, 1));
    /// assert!(check.timing.writing_s > 0.0);
    /// ```
    ///
    /// # Errors
    /// As [`TrackFile::build_program`] and [`time_program`].
    pub fn check(&self, frame: &PaperFrame, cfg: &RobotConfig) -> Result<TrackCheck, RobotError> {
        let (program, report) = self.build_program(frame, cfg)?;
        let timing = time_program(&program, &DhParams::AUBO_I5, cfg)?;
        Ok(TrackCheck { report, timing })
    }
}

/// A track's program checked and timed ([`TrackFile::check`]); as JSON, the report's fields
/// with the timing beside them (`timing`).
#[derive(Clone, Debug, Serialize)]
pub struct TrackCheck {
    /// The safety envelope's report.
    #[serde(flatten)]
    pub report: CheckReport,
    /// The timing on the nominal AUBO-i5.
    pub timing: ProgramTiming,
}
