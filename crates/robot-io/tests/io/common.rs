//! What the test modules share: the pen1 profile, a level sheet in front of the arm, and a small
//! two-stroke track.

use brush_model::{BrushProfile, Stroke, Track, TrackPoint};
use robot_io::PaperFrame;

/// The built-in pen1 profile.
pub(crate) fn pen1() -> BrushProfile {
    BrushProfile::builtin("pen1").unwrap()
}

/// A level 200 × 200 mm sheet at base (0.35, 0.15, 0.05) m.
pub(crate) fn paper() -> PaperFrame {
    PaperFrame::level([0.35, 0.15, 0.05], [200.0, 200.0])
}

/// Two short strokes, pressed at 15 mm, tilted 0.05 rad.
pub(crate) fn small_track() -> Track {
    let line = |pts: &[(f64, f64)], beta: f64| Stroke {
        points: pts
            .iter()
            .map(|&(x, y)| TrackPoint { x_mm: x, y_mm: y, h_mm: 15.0, alpha_rad: 0.05, beta_rad: beta })
            .collect(),
    };
    Track {
        strokes: vec![
            line(&[(40.0, 60.0), (50.0, 60.0), (60.0, 61.0), (70.0, 62.0)], std::f64::consts::PI),
            line(&[(55.0, 40.0), (55.0, 55.0), (55.0, 70.0), (55.5, 85.0)], -std::f64::consts::FRAC_PI_2),
        ],
    }
}
