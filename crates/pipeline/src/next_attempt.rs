//! One round of the closed loop (docs/closed-loop.md): the last attempt read back from what
//! `maobi observe` wrote ([`ObservedRun::load`]), the next attempt planned from it
//! ([`ObservedRun::plan`]: which brush writes it, which levers act, the residuals the tracks are
//! refined against), the tracks refined ([`NextAttempt::refine`], warm-started from the last
//! attempt's when the brush is the same) and the round's entry for the sheet's `summary.json`
//! ([`NextAttempt::round`]). The command line only writes and prints what these return.

use std::path::{Path, PathBuf};

use bezier_raster::{Coverage, ModelKind};
use brush_model::{BrushProfile, Stroke, Terms};
use serde::Serialize;
use thiserror::Error;
use track_refine::RefineOptions;
use trajectory::CharBox;

use crate::readback::{ReadBackError, read_bounded};
use crate::{
    BrushChoice, BrushCorrection, CharResult, ClosedLoopError, LastAttempt, Layout, Observation, ObservedScores,
    Prepared, Residual, SheetTrack, WriteOptions,
};

/// The most rounds a corrected sheet's summary.json may list.
pub const MAX_ROUNDS: usize = 100;

/// The largest summary.json of a sheet read back (for its rounds), bytes.
pub const MAX_SHEET_SUMMARY_BYTES: u64 = 16 << 20;

/// Below this share of its pixels at coverage ≥ ½, an observed character holds no ink.
pub const MIN_OBSERVED_INK_SHARE: f64 = 0.002;

/// Why the last attempt could not be read back, or the next one not planned. Every message
/// names the file (and the field) at fault.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ObservedRunError {
    /// The observation's `summary.json` or the sheet's `summary.json` was refused.
    #[error(transparent)]
    ReadBack(#[from] ReadBackError),
    /// The sheet the observation names could not be read back.
    #[error("{} observed the sheet {} (field `sheet.path` of {})", dir.display(), sheet.display(), summary.display())]
    Sheet {
        /// The observation's folder.
        dir: PathBuf,
        /// The sheet's folder.
        sheet: PathBuf,
        /// The observation's `summary.json`.
        summary: PathBuf,
        /// Why.
        #[source]
        source: Box<ReadBackError>,
    },
    /// The observed sheet holds other characters than the ones to write.
    #[error("{} observed the sheet of {seen:?} ({}), not {text:?}: give the same characters", dir.display(), sheet.display())]
    OtherText {
        /// The observation's folder.
        dir: PathBuf,
        /// The sheet's folder.
        sheet: PathBuf,
        /// The sheet's text.
        seen: String,
        /// The text to write.
        text: String,
    },
    /// The observed sheet was laid out otherwise than the sheet to write.
    #[error(
        "the sheet {} was laid out otherwise ({:.0}×{:.0} mm, {:.1} mm boxes; here {:.0}×{:.0} mm, {:.1} mm)",
        sheet.display(), was[0], was[1], was[2], here[0], here[1], here[2]
    )]
    OtherLayout {
        /// The sheet's folder.
        sheet: PathBuf,
        /// Its width, height and box side, mm.
        was: [f64; 3],
        /// The same of the sheet to write, mm.
        here: [f64; 3],
    },
    /// An observed image could not be read.
    #[error("cannot read {}", path.display())]
    Image {
        /// The image.
        path: PathBuf,
        /// Why.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// An observed image is not the size the observation says.
    #[error("{} is {width}×{height} px, expected {side}×{side} px (chars[{index}].size_px of {})", path.display(), summary.display())]
    ImageSize {
        /// The image.
        path: PathBuf,
        /// Its columns.
        width: u32,
        /// Its rows.
        height: u32,
        /// The side the observation gives.
        side: u32,
        /// The character's index.
        index: usize,
        /// The observation's `summary.json`.
        summary: PathBuf,
    },
    /// An observed image holds no ink.
    #[error(
        "{} holds no ink ({inked} inked px of {pixels}): no ink was seen of {ch:?} (was it written? is the photo of this sheet?)",
        path.display()
    )]
    NoInk {
        /// The image.
        path: PathBuf,
        /// Pixels at coverage ≥ ½.
        inked: usize,
        /// All its pixels.
        pixels: usize,
        /// The character.
        ch: String,
    },
    /// The correction or the refinement failed.
    #[error("{}: {what}", dir.display())]
    Correction {
        /// The observation's folder.
        dir: PathBuf,
        /// The step that failed.
        what: &'static str,
        /// Why.
        #[source]
        source: Box<ClosedLoopError>,
    },
}

/// The last attempt: `maobi observe`'s output, the sheet it observed, and each character's
/// observed ink.
#[derive(Clone, Debug)]
pub struct ObservedRun {
    /// The observation's folder.
    pub dir: PathBuf,
    /// The sheet folder it observed (absolute, as the observation records it).
    pub sheet_dir: PathBuf,
    /// The observation.
    pub observation: Observation,
    /// The observed sheet's `track.json`.
    pub track: SheetTrack,
    /// Each character's `observed.png`, in the sheet's order.
    pub observed: Vec<Coverage>,
    /// The rounds before this one (the observed sheet's `summary.json` `rounds`, when it was
    /// itself a corrected attempt), as written.
    pub earlier: Vec<serde_json::Value>,
}

/// How the next attempt is planned ([`ObservedRun::plan`]).
#[derive(Clone, Debug)]
pub struct NextOptions {
    /// The stroke model the brush is re-fitted and the residuals predicted with.
    pub model: ModelKind,
    /// The refinement asked for (`None`: the defaults, unless `brush_only`).
    pub refine: Option<RefineOptions>,
    /// Correct the brush only: no track refinement against the residual.
    pub brush_only: bool,
    /// The char box side, mm, when known: the next brush is then chosen among the built-ins
    /// (with the correction carried over) when the observed brush is one.
    pub char_mm: Option<f64>,
    /// Whether another brush may be chosen (false keeps the corrected one, e.g. for a renderer
    /// trained for one brush).
    pub choose_brush: bool,
    /// The brush tilt, rad.
    pub alpha_rad: f64,
}

/// The next attempt, planned from the last one.
#[derive(Debug)]
pub struct NextAttempt {
    /// The correction fitted to the observed ink.
    pub correction: BrushCorrection,
    /// The observed brush corrected, named after the round (`<root>+observedN`; its own name when
    /// the correction was not taken).
    pub corrected: BrushProfile,
    /// The brush the next attempt is written with: `corrected`, or the built-in chosen for the
    /// boxes with the correction carried over.
    pub brush: BrushProfile,
    /// The built-in chosen, when one was.
    pub choice: Option<BrushChoice>,
    /// Why no other brush was considered, when the observed brush is a built-in and the choice
    /// failed.
    pub kept_because: Option<ClosedLoopError>,
    /// The refinement of the tracks against the residual (`None`: brush only).
    pub refine: Option<RefineOptions>,
    /// Each character's residual under the corrected brush (with `refine`).
    pub residuals: Option<Vec<Residual>>,
}

/// One round's entry in a corrected sheet's `summary.json`.
#[derive(Clone, Debug, Serialize)]
pub struct Round {
    /// Rounds before it.
    pub round: usize,
    /// The sheet observed.
    pub sheet: String,
    /// The observation's folder.
    pub observed: String,
    /// The brush that wrote the observed sheet.
    pub brush: String,
    /// The observed ink against the glyphs, means over the characters.
    pub observed_vs_glyph_mean: ObservedScores,
    /// Each character as observed.
    pub chars: Vec<RoundChar>,
    /// The correction fitted.
    pub correction: BrushCorrection,
    /// The corrected brush's name.
    pub brush_after: String,
    /// The brush chosen for the next attempt.
    pub brush_choice: Option<BrushChoice>,
    /// How the next attempt's tracks were made, in words.
    pub track: &'static str,
}

/// One character of a [`Round`].
#[derive(Clone, Debug, Serialize)]
pub struct RoundChar {
    /// Its folder in the observation.
    pub char: String,
    /// The observed ink against the glyph.
    pub vs_glyph: ObservedScores,
    /// The observed ink against the plan.
    pub vs_plan: ObservedScores,
    /// [`observe::Diagnosis::width_ratio`].
    pub width_ratio: Option<f64>,
    /// [`observe::Diagnosis::end_beyond_mm`].
    pub end_beyond_mm: Option<f64>,
    /// [`observe::Diagnosis::lateral_mm`].
    pub lateral_mm: Option<f64>,
    /// The diagnosis in one line.
    pub verdict: String,
}

impl ObservedRun {
    /// Reads the observation in `dir` and the sheet it observed; refuses when the sheet is not
    /// the one observed (its fingerprint), when `chars` or `layout` (the sheet to write, when
    /// known) differ from it, or when an observed image is unreadable, of another size or blank.
    ///
    /// # Errors
    /// [`ObservedRunError`] naming the file and field.
    pub fn load(dir: &Path, chars: &[char], layout: Option<&Layout>) -> Result<ObservedRun, ObservedRunError> {
        let sp = dir.join("summary.json");
        let observation = Observation::load(&sp)?;
        let sheet_dir = observation.sheet.path.clone();
        let tp = observation.track_path();
        let (track, bytes) = SheetTrack::load(&tp).map_err(|source| ObservedRunError::Sheet {
            dir: dir.to_path_buf(),
            sheet: sheet_dir.clone(),
            summary: sp.clone(),
            source: Box::new(source),
        })?;
        observation.check_sheet(&sp, &track, &tp, &bytes)?;
        let text: String = chars.iter().collect();
        let seen: String = track.chars.iter().map(|c| c.char.as_str()).collect();
        if seen != text {
            return Err(ObservedRunError::OtherText { dir: dir.to_path_buf(), sheet: sheet_dir, seen, text });
        }
        if let Some(lay) = layout {
            check_layout(&track, lay, &sheet_dir)?;
        }
        let observed = observation
            .chars
            .iter()
            .enumerate()
            .map(|(i, c)| observed_image(&dir.join(&c.folder).join("observed.png"), i, c, &sp))
            .collect::<Result<_, _>>()?;
        let earlier = earlier_rounds(&sheet_dir.join("summary.json"))?;
        Ok(ObservedRun { dir: dir.to_path_buf(), sheet_dir, observation, track, observed, earlier })
    }

    /// Each character's last attempt (its strokes in the observed sheet, its observed ink).
    pub fn attempts(&self) -> Vec<LastAttempt<'_>> {
        self.track
            .chars
            .iter()
            .zip(&self.observed)
            .map(|(c, img)| LastAttempt {
                ch: &c.char,
                char_box: CharBox { x0_mm: c.char_box_mm[0], y0_mm: c.char_box_mm[1], size_mm: c.char_box_mm[2] },
                strokes: &self.track.strokes[c.strokes[0]..c.strokes[1]],
                observed: img,
            })
            .collect()
    }

    /// Plans the next attempt of `prepared` (the same characters, in order): the brush the
    /// observed sheet was written with re-fitted to its ink ([`crate::fit_brush`]); with
    /// `opts.char_mm` and a built-in base brush, the built-in whose corrected footprints suit
    /// the boxes ([`crate::choose_corrected_brush`]); both levers unless `opts.brush_only`: the
    /// tracks refined (with `opts.refine`, or its defaults) against the glyph shifted by the
    /// residual the corrected brush leaves.
    ///
    /// # Errors
    /// [`ObservedRunError::Correction`] when the brush cannot be re-fitted or a residual
    /// predicted.
    ///
    /// # Examples
    /// ```no_run
    /// use pipeline::{NextOptions, ObservedRun};
    /// # let prepared: Vec<pipeline::Prepared> = Vec::new();
    /// let run = ObservedRun::load("obs".as_ref(), &['永'], None)?;
    /// let opts = NextOptions {
    ///     model: bezier_raster::ModelKind::Bsm,
    ///     refine: None,
    ///     brush_only: false,
    ///     char_mm: Some(40.0),
    ///     choose_brush: true,
    ///     alpha_rad: 0.0,
    /// };
    /// let next = run.plan(&prepared, &opts)?;
    /// println!("next brush: {}", next.brush.name);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn plan(&self, prepared: &[Prepared], opts: &NextOptions) -> Result<NextAttempt, ObservedRunError> {
        let fail =
            |what| move |source| ObservedRunError::Correction { dir: self.dir.clone(), what, source: Box::new(source) };
        let base = &self.track.brush;
        let correction = crate::fit_brush(&self.attempts(), base, opts.model).map_err(fail("re-fitting the brush"))?;
        let root = base.name.split('+').next().unwrap_or(&base.name);
        let name = match correction.not_taken {
            None => format!("{root}+observed{}", self.earlier.len() + 1),
            Some(_) => base.name.clone(),
        };
        let corrected = correction.apply(base, &name).map_err(fail("the corrected brush"))?;
        let refine = match opts.refine {
            Some(r) => Some(r),
            None if !opts.brush_only => Some(RefineOptions::default()),
            None => None,
        };
        let residuals = match refine {
            Some(_) => Some(self.residuals(&corrected, opts.model).map_err(fail("the residual"))?),
            None => None,
        };
        let (choice, kept_because) = match opts.char_mm {
            Some(mm) if opts.choose_brush => next_brush(prepared, &corrected, mm, opts.alpha_rad),
            _ => (None, None),
        };
        let brush = choice.as_ref().map_or_else(|| corrected.clone(), |c| c.profile.clone());
        Ok(NextAttempt { correction, corrected, brush, choice, kept_because, refine, residuals })
    }

    /// Each character's residual: observed ink minus the last attempt through `profile`.
    fn residuals(&self, profile: &BrushProfile, model: ModelKind) -> Result<Vec<Residual>, ClosedLoopError> {
        self.attempts().iter().map(|a| Residual::of(a, profile, model)).collect()
    }
}

impl NextAttempt {
    /// Refines the written `results` (in `prepared`'s order, written with [`NextAttempt::brush`])
    /// against the glyphs shifted by the residuals ([`crate::refine_observed`]); when the brush is
    /// the one the last attempt was written with, each refinement starts from the last attempt's
    /// track. Returns whether it did (a warm start); does nothing without [`NextAttempt::refine`].
    ///
    /// # Errors
    /// [`ObservedRunError::Correction`] for the first character that fails.
    pub fn refine(
        &self,
        run: &ObservedRun,
        results: &mut [CharResult],
        prepared: &[Prepared],
        opts: &WriteOptions,
    ) -> Result<bool, ObservedRunError> {
        let (Some(residuals), Some(ro)) = (&self.residuals, self.refine) else {
            return Ok(false);
        };
        let opts = WriteOptions { refine: Some(ro), ..opts.clone() };
        let last = same_brush(&run.track.brush, &self.brush).then(|| run.attempts());
        let starts: Option<Vec<&[Stroke]>> = last.as_ref().map(|a| a.iter().map(|a| a.strokes).collect());
        crate::refine_observed(results, prepared, residuals, starts.as_deref(), &self.brush, &opts, &ro).map_err(
            |source| ObservedRunError::Correction {
                dir: run.dir.clone(),
                what: "refining against the observed residual",
                source: Box::new(source),
            },
        )?;
        Ok(last.is_some())
    }

    /// This round's entry (what was observed, what was corrected); `warm_started` as
    /// [`NextAttempt::refine`] returned.
    pub fn round(&self, run: &ObservedRun, warm_started: bool) -> Round {
        let chars = &run.observation.chars;
        let mean = |f: fn(&ObservedScores) -> f64| {
            chars.iter().map(|c| f(&c.vs_glyph)).sum::<f64>() / chars.len().max(1) as f64
        };
        Round {
            round: run.earlier.len(),
            sheet: run.sheet_dir.display().to_string(),
            observed: run.dir.display().to_string(),
            brush: run.track.brush.name.clone(),
            observed_vs_glyph_mean: ObservedScores {
                csim: mean(|s| s.csim),
                ssim: mean(|s| s.ssim),
                iou: mean(|s| s.iou),
            },
            chars: chars
                .iter()
                .map(|c| RoundChar {
                    char: c.folder.clone(),
                    vs_glyph: c.vs_glyph,
                    vs_plan: c.vs_plan,
                    width_ratio: c.diagnosis.width_ratio,
                    end_beyond_mm: c.diagnosis.end_beyond_mm,
                    lateral_mm: c.diagnosis.lateral_mm,
                    verdict: c.verdict.clone(),
                })
                .collect(),
            correction: self.correction,
            brush_after: self.brush.name.clone(),
            brush_choice: self.choice.clone(),
            track: match (self.refine.is_some(), warm_started) {
                (true, true) => {
                    "refined from the last attempt's track against the glyph shifted by the observed residual (ILC)"
                }
                (true, false) => "refined against the glyph shifted by the observed residual (ILC)",
                (false, _) => "built with the corrected brush",
            },
        }
    }

    /// Every round so far: the earlier ones as written, then `this`.
    pub fn rounds(run: &ObservedRun, this: &Round) -> Vec<serde_json::Value> {
        let mut all = run.earlier.clone();
        all.push(serde_json::to_value(this).expect("a round serialises"));
        all
    }
}

/// Refuses a sheet laid out otherwise than `lay`.
fn check_layout(track: &SheetTrack, lay: &Layout, sheet_dir: &Path) -> Result<(), ObservedRunError> {
    let same =
        (track.sheet_mm[0] - lay.sheet.width_mm).abs() < 1e-6
            && (track.sheet_mm[1] - lay.sheet.height_mm).abs() < 1e-6
            && track.chars.iter().zip(&lay.boxes).all(|(c, b)| {
                [b.x0_mm, b.y0_mm, b.size_mm].iter().zip(&c.char_box_mm).all(|(a, b)| (a - b).abs() < 1e-6)
            });
    if same {
        return Ok(());
    }
    Err(ObservedRunError::OtherLayout {
        sheet: sheet_dir.to_path_buf(),
        was: [track.sheet_mm[0], track.sheet_mm[1], track.char_mm],
        here: [lay.sheet.width_mm, lay.sheet.height_mm, lay.char_mm],
    })
}

/// One character's `observed.png`: the size the observation gives (from its header, before
/// decoding), holding ink.
fn observed_image(
    p: &Path,
    index: usize,
    c: &crate::ObservedChar,
    summary: &Path,
) -> Result<Coverage, ObservedRunError> {
    let image =
        |source: Box<dyn std::error::Error + Send + Sync>| ObservedRunError::Image { path: p.to_path_buf(), source };
    let (width, height) = bezier_raster::image_header(p).map_err(|e| image(Box::new(e)))?;
    if (width, height) != (c.size_px, c.size_px) {
        return Err(ObservedRunError::ImageSize {
            path: p.to_path_buf(),
            width,
            height,
            side: c.size_px,
            index,
            summary: summary.to_path_buf(),
        });
    }
    let img = Coverage::load(p).map_err(|e| image(Box::new(e)))?;
    let inked = img.data().iter().filter(|&&v| v >= 0.5).count();
    if (inked as f64) < MIN_OBSERVED_INK_SHARE * img.data().len() as f64 {
        return Err(ObservedRunError::NoInk {
            path: p.to_path_buf(),
            inked,
            pixels: img.data().len(),
            ch: c.char.clone(),
        });
    }
    Ok(img)
}

/// The rounds a corrected sheet's summary.json lists (none when the sheet has no summary.json
/// or lists none): a summary that is there must be whole JSON, its `rounds` a list of at most
/// [`MAX_ROUNDS`] objects.
fn earlier_rounds(p: &Path) -> Result<Vec<serde_json::Value>, ReadBackError> {
    if !p.exists() {
        return Ok(Vec::new());
    }
    let what = "the summary.json of `maobi write` (cut short, or not JSON)";
    let bytes = read_bounded(p, MAX_SHEET_SUMMARY_BYTES, "a sheet's summary.json")?;
    let v: serde_json::Value =
        serde_json::from_slice(&bytes).map_err(|source| ReadBackError::Json { path: p.to_path_buf(), what, source })?;
    let rounds = match v.get("rounds") {
        None | Some(serde_json::Value::Null) => return Ok(Vec::new()),
        Some(serde_json::Value::Array(r)) => r,
        Some(_) => return Err(ReadBackError::field(p, "rounds", "expected a list of rounds")),
    };
    if rounds.len() > MAX_ROUNDS {
        return Err(ReadBackError::field(
            p,
            "rounds",
            format!("{} rounds, expected at most {MAX_ROUNDS}", rounds.len()),
        ));
    }
    if let Some(i) = rounds.iter().position(|r| !r.is_object()) {
        return Err(ReadBackError::field(p, format!("rounds[{i}]"), "expected an object"));
    }
    Ok(rounds.clone())
}

/// The brush for the next attempt when `corrected`'s base is a built-in: among the built-ins,
/// each with the correction carried over, the one whose footprints suit `char_mm` boxes;
/// `None` with the reason when the base is not a built-in (a calibrated brush of the user's
/// own is kept, silently) or the choice failed.
fn next_brush(
    prepared: &[Prepared],
    corrected: &BrushProfile,
    char_mm: f64,
    alpha_rad: f64,
) -> (Option<BrushChoice>, Option<ClosedLoopError>) {
    let root = corrected.name.split('+').next().unwrap_or(&corrected.name);
    let Ok(base) = BrushProfile::builtin(root) else {
        return (None, None);
    };
    let suffix = corrected.name.strip_prefix(root).unwrap_or("");
    match crate::choose_corrected_brush(
        prepared,
        &base,
        corrected,
        &crate::builtin_brushes(),
        suffix,
        char_mm,
        alpha_rad,
    ) {
        Ok(c) => (Some(c), None),
        Err(e) => (None, Some(e)),
    }
}

/// Whether two profiles are the same brush: the same name, brush and ranges, and footprint
/// models equal to 1e-9 mm (a correction carried back onto its own base rounds).
pub fn same_brush(a: &BrushProfile, b: &BrushProfile) -> bool {
    let terms = |x: Terms, y: Terms| {
        let close = |u: f64, v: f64| (u - v).abs() <= 1e-9 * (1.0 + u.abs());
        let opt = |u: Option<f64>, v: Option<f64>| close(u.unwrap_or(0.0), v.unwrap_or(0.0));
        close(x.intercept, y.intercept)
            && opt(x.h_mm, y.h_mm)
            && opt(x.alpha_rad, y.alpha_rad)
            && opt(x.beta_rad, y.beta_rad)
    };
    let (m, n) = (&a.model, &b.model);
    a.name == b.name
        && a.brush == b.brush
        && a.ranges == b.ranges
        && terms(m.lt_mm, n.lt_mm)
        && terms(m.lh_mm, n.lh_mm)
        && terms(m.lr_mm, n.lr_mm)
}
