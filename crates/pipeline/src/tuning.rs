//! The pipeline's tuning constants, in one place: the values that set how a character is
//! analysed and placed, how a sheet is laid out and judged against its brush, how the
//! calibration sheet and the registration marks are drawn, and how the closed loop fits a
//! brush correction to an observed sheet. Each says what it sets, in which units, and whether it
//! was tuned (on which set, with the measurements in docs/) or hand-set.
//!
//! They are defined beside the code that uses them and gathered here, so that each has one path
//! (`pipeline::tuning::FIT_PX`). The crate root keeps the constants that are not choices: the
//! file format versions and the bounds on inputs (`OBSERVATION_VERSION`, `MAX_SHEET_MM`,
//! `OBSERVED_PX`, …). trajectory's tuned constants are `trajectory::DEFAULT_ANALYSIS_PX` and
//! its kin, tabled in docs/trajectory.md ("Tuned constants", kept in step by `cargo xtask tidy`).

// Analysis and placement of one character.
pub use crate::placement::{CHAR_BOX_SEARCH_PX, CHAR_BOX_SEARCH_SCALES};
pub use crate::prepare::ANALYSIS_PX;

// A sheet's layout, and whether its brush suits the size.
pub use crate::sheet::{BRUSH_FIT_CLAMPED_SHARE, BRUSH_FIT_SIZE_FACTOR, GAP_FRACTION};

// The calibration sheet.
pub use crate::calibration_sheet::{
    CELL_GAP_MM, CELL_GROWTH, PRESS_ALPHA_LEVELS, PRESS_BETA_LEVELS, PRESS_H_LEVELS, PRESS_SLIDE_MM,
    PRESS_TOUCH_FRACTION,
};

// Which presses of a calibration sheet's photo are used.
pub use crate::calibration_photo::{MAX_PRESS_ROOT_MM, MAX_PRESS_TURN_RAD, MIN_MEASURED_SHARE};

// The registration marks.
pub use crate::marks::{
    MARK_CLEARANCE_MM, MARK_DEPTH_FRACTION, MARK_GAP_MM, MARK_MARGIN_MM, MARK_SPACING_MM, MARK_TRAVEL_MM,
};

// Whether a photo is of the sheet it is observed against.
pub use crate::sheet_folder::MIN_PLAN_CSIM;

// The closed loop's brush correction.
pub use crate::closed_loop::{
    CONTACT_CANDIDATES_MM, FACTOR_RANGE, FIT_PX, MIN_CORRECTION_GAIN, SPREAD_RANGE_MM, TRAIL_CANDIDATES,
};
