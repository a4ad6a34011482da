//! maobi's character pipeline: a character's glyph → its centre lines → a char box and corner
//! splits → a brush track → the robot program, checked and run as the controller would →
//! renders of the plan and of what the robot writes → CSIM, SSIM and IoU against the glyph;
//! and several characters laid out on a sheet.
//!
//! The pipeline is a library: it knows no command line, prints nothing and writes no file.
//! `maobi write` and `maobi evaluate`, `cargo xtask`'s gates and style tables, and the benches
//! all call it.
//!
//! Each public item has one path, at the crate root; the values the pipeline was tuned with
//! (analysis raster, char box search, sheet gaps, calibration sheet, registration marks, the
//! closed loop's brush fit) are gathered in [`tuning`].
//!
//! # Examples
//! ```
//! use pipeline::{BoxRule, WriteOptions, prepare, write_placed};
//!
//! let pen1 = brush_model::BrushProfile::builtin("pen1")?;
//! let glyph = trajectory::embedded_glyph('永')?;
//! let prepared = prepare(glyph, None)?;
//! let opts = WriteOptions { size: 128, ..WriteOptions::default() };
//! let written = write_placed(&prepared, &pen1, &opts, BoxRule::Auto)?;
//! let executed = written.report.executed.expect("executed by default");
//! assert!(executed.csim > 0.8, "executed CSIM {}", executed.csim);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod brush_choice;
mod calibration_photo;
mod calibration_sheet;
mod closed_loop;
mod error;
mod glyphs;
mod marks;
mod means;
mod model_scores;
mod next_attempt;
mod observation;
mod placement;
mod prepare;
mod readback;
mod registration;
mod sheet;
mod sheet_file;
mod sheet_folder;
mod sheet_run;
mod summary;
mod text;
pub mod tuning;
mod write;

pub use brush_choice::{BrushChoice, builtin_brushes, choose_brush};
pub use calibration_photo::{
    LeftOut, MAX_CELL_MM, MAX_LAYOUT_BYTES, MAX_PRESSES, PressReading, SheetReading, read_calibration_sheet,
};
pub use calibration_sheet::{
    CALIBRATION_LAYOUT_VERSION, CalibrationLayout, CalibrationPress, CalibrationSheet, CalibrationSheetError,
    calibration_sheet, calibration_sheet_image, press_stroke,
};
pub use closed_loop::{
    BrushCorrection, ClosedLoopError, LastAttempt, Residual, carry_correction, choose_corrected_brush, fit_brush,
    ilc_target, predict_attempt, refine_observed,
};
pub use error::{Error, Result};
pub use glyphs::{GlyphInput, image_folder, prepare_loaded};
pub use marks::{Mark, MarkError, MarkRole, mark_strokes, registration_marks};
pub use means::{RefineMeans, ReportMeans, SimilarityMeans, methods_used};
pub use model_scores::{ModelScores, ModelTarget, ReferenceError, load_reference_photos, score_models};
pub use next_attempt::{
    MAX_ROUNDS, MAX_SHEET_SUMMARY_BYTES, MIN_OBSERVED_INK_SHARE, NextAttempt, NextOptions, ObservedRun,
    ObservedRunError, Round, RoundChar, same_brush,
};
pub use observation::{
    MAX_OBSERVATION_BYTES, OBSERVATION_VERSION, OBSERVED_PX, Observation, ObservedChar, ObservedRegistration,
    ObservedScores, ObservedSheet,
};
pub use placement::{BoxRule, Placement, searched_placement, searched_splits, with_splits, write_placed};
pub use prepare::{Prepared, TemplateReport, prepare, prepare_with_template};
pub use readback::{ReadBackError, char_folder, fingerprint, read_bounded};
pub use registration::known_marks;
pub use sheet::{
    BrushFit, BrushMiss, Flow, Grid, Layout, MAX_SHEET_MM, Sheet, SheetChar, SheetError, SheetTrack, auto_layout,
    layout_on_sheet, parse_sheet, sheet_image, sheet_image_of, sheet_image_with_marks,
};
pub use sheet_file::{MAX_SHEET_CHARS, MAX_SHEET_TRACK_BYTES, SHEET_MAX_CHAR_MM, SHEET_MIN_CHAR_MM};
pub use sheet_folder::{PlannedChar, SheetFolder, SheetFolderError, plan_csim_mean};
pub use sheet_run::{
    RunSample, SheetRun, TimedFootprint, planned_samples, render_trace, run_footprints, run_sheet, run_sheet_with,
};
pub use summary::{Agreement, Figures, SheetSummary, TextSummary};
pub use text::{TextOptions, WrittenText, write_text, write_text_each};
pub use track_refine::RefineOptions;
#[cfg(feature = "generator")]
pub use write::rerender_with_generator;
pub use write::{
    BrushReport, CharReport, CharResult, ExecutedRun, Execution, PlanReport, RefineReport, Similarity, TimingMs,
    WriteOptions, execute_track, execute_track_with, level_frame_for, refine_target, render_char, render_states,
    side_by_side, similarity, write_char,
};

// The README's example runs as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
