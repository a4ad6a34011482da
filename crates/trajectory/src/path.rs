//! One stroke's centre line in the em frame ([`StrokePath`], em units, y down) and its sharp
//! corners ([`find_corners`]).
//!
//! The skeleton method has a second corner test (`skeleton::corners`) on purpose: it runs on
//! pixel chains before strokes exist, with a reach in local half-widths and rules about which
//! corners end a stroke; this one runs on finished centre lines (of every method) in em units
//! with a fixed reach, and only marks where track building starts a fresh press. Invariant:
//! `corners` are ascending indices into `points`, never the first or last point.

use kurbo::{Point, Vec2};

use crate::polyline::arc_lengths;

/// One stroke's centre line in the em frame with the glyph's half-width at each point (em).
#[derive(Clone, Debug, PartialEq)]
pub struct StrokePath {
    /// Points in writing order, em frame.
    pub points: Vec<Point>,
    /// Half-width of the glyph at each point, em units.
    pub half_widths: Vec<f64>,
    /// Indices into `points` of sharp corners (折), ascending: [`crate::build_track`] ends a piece there
    /// and starts the next with a fresh entry press, as a calligrapher lifts slightly and presses
    /// again.
    pub corners: Vec<usize>,
}

impl StrokePath {
    /// A path whose corners are found by [`find_corners`].
    pub fn new(points: Vec<Point>, half_widths: Vec<f64>) -> Self {
        let corners = find_corners(&points);
        Self { points, half_widths, corners }
    }
}

/// Turn (radians) above which a centre line has a corner. Chosen on the tuning set
/// (docs/trajectory.md, Tuned constants).
pub const CORNER_RAD: f64 = 0.7;
/// The turn is measured between the directions over this arc length before and after a point,
/// em units (about a stroke width, so the rounded bends of hand-drawn medians still count).
/// Hand-set (docs/trajectory.md, Tuned constants).
pub const CORNER_REACH_EM: f64 = 50.0;

/// The sharp corners of a centre line (em frame): for every point at least
/// [`CORNER_REACH_EM`] from both ends, the turn between the chords to the points that far before
/// and after it; of each run of points turning more than [`CORNER_RAD`], the sharpest. Returns
/// ascending indices into `points`.
pub fn find_corners(points: &[Point]) -> Vec<usize> {
    corner_turns(points).into_iter().map(|(i, _)| i).collect()
}

/// [`find_corners`] with each corner's unit chord directions in and out.
pub(crate) fn corner_turns(p: &[Point]) -> Vec<(usize, (Vec2, Vec2))> {
    if p.len() < 3 {
        return Vec::new();
    }
    let s = arc_lengths(p);
    let total = s[s.len() - 1];
    let reach = CORNER_REACH_EM;
    let dirs = |i: usize| {
        let a = p[(0..=i).rev().find(|&j| s[i] - s[j] >= reach).unwrap_or(0)];
        let b = p[(i..p.len()).find(|&j| s[j] - s[i] >= reach).unwrap_or(p.len() - 1)];
        let (u, v) = (p[i] - a, b - p[i]);
        let (nu, nv) = (u.hypot(), v.hypot());
        if nu < 1e-9 || nv < 1e-9 { None } else { Some((u / nu, v / nv)) }
    };
    let mut out = Vec::new();
    let mut run: Option<(usize, f64, (Vec2, Vec2))> = None;
    for (i, &si) in s.iter().enumerate() {
        let d = if si >= reach && si <= total - reach { dirs(i) } else { None };
        match d.map(|(u, v)| (u.dot(v).clamp(-1.0, 1.0).acos(), (u, v))) {
            Some((a, uv)) if a > CORNER_RAD => {
                if run.is_none_or(|(_, best, _)| a > best) {
                    run = Some((i, a, uv));
                }
            }
            _ => {
                if let Some((c, _, uv)) = run.take() {
                    out.push((c, uv));
                }
            }
        }
    }
    if let Some((c, _, uv)) = run {
        out.push((c, uv));
    }
    out
}
