//! Small rules on polylines shared by the skeleton, the medians pipeline and track building:
//! arc-length prefix sums and the "nearly horizontal" test.
//!
//! Frame-free: any frame whose y axis points down (em units, analysis px or paper mm); lengths
//! come out in the frame's unit.

use kurbo::{Point, Vec2};

/// A direction is nearly horizontal when it rises or falls by at most this much per unit run
/// (about 31°). Hand-set with the stroke rules of the skeleton method (docs/trajectory.md,
/// "Skeleton rules"): 横 in kaishu rises a little to the right, and a box's bottom too, while
/// 撇 and 捺 run well past it. Hand-set (docs/trajectory.md, Tuned constants).
pub(crate) const NEARLY_HORIZONTAL_SLOPE: f64 = 0.6;

/// Whether `v` is nearly horizontal ([`NEARLY_HORIZONTAL_SLOPE`]), either sign.
pub(crate) fn nearly_horizontal(v: Vec2) -> bool {
    v.y.abs() <= NEARLY_HORIZONTAL_SLOPE * v.x.abs()
}

/// Arc length at each point of a polyline (`s[0] = 0`, ascending), `dist` measuring one segment.
pub(crate) fn arc_lengths_by<T: Copy>(p: &[T], dist: impl Fn(T, T) -> f64) -> Vec<f64> {
    let mut s = Vec::with_capacity(p.len());
    let mut acc = 0.0;
    for (i, &q) in p.iter().enumerate() {
        if i > 0 {
            acc += dist(q, p[i - 1]);
        }
        s.push(acc);
    }
    s
}

/// Arc length at each point of an em-frame or pixel polyline ([`arc_lengths_by`]).
pub(crate) fn arc_lengths(p: &[Point]) -> Vec<f64> {
    arc_lengths_by(p, Point::distance)
}

/// A polyline's length.
pub(crate) fn length(p: &[Point]) -> f64 {
    p.windows(2).map(|w| w[0].distance(w[1])).sum()
}
