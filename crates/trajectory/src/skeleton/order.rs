//! Stroke orientation and order by the usual writing rules: nearly horizontal strokes run left
//! to right, all others top to bottom; strokes are ordered top before bottom (in bands of a
//! twelfth of the glyph's extent), left before right, and a horizontal before a vertical it
//! crosses.
//!
//! Frame: any frame with y down (the analysis raster here, px); only directions and the
//! extent's scale matter.

use kurbo::{Point, Vec2};

use crate::polyline::nearly_horizontal;

/// Strokes starting in the same horizontal band (of this many across the glyph's extent) are
/// ordered left to right; bands top to bottom. Hand-set.
const ORDER_BANDS: f64 = 12.0;

/// The direction a line of direction `v` (either sign; raster y down) is written in: rightward
/// if it is nearly horizontal, otherwise downward (撇 and 捺 both go down; 提, the rising
/// stroke, is short and rarely meets another at a corner).
pub(super) fn writing_direction(v: Vec2) -> Vec2 {
    if runs_backwards(v) { -v } else { v }
}

/// Whether a line of direction `v` runs against the way it is written ([`writing_direction`]):
/// leftward when nearly horizontal, otherwise upward.
fn runs_backwards(v: Vec2) -> bool {
    if nearly_horizontal(v) { v.x < 0.0 } else { v.y < 0.0 }
}

pub(super) fn is_horizontal(s: &[Point]) -> bool {
    nearly_horizontal(s[s.len() - 1] - s[0])
}

/// Orients each stroke (horizontal-ish ones left to right, others top to bottom) and orders
/// them: top before bottom (in bands of 1/12 of the raster), left before right, and a
/// horizontal before a vertical it crosses.
pub(super) fn order_strokes(strokes: Vec<Vec<Point>>) -> Vec<Vec<Point>> {
    let mut s: Vec<Vec<Point>> = strokes
        .into_iter()
        .map(|mut p| {
            if runs_backwards(p[p.len() - 1] - p[0]) {
                p.reverse();
            }
            p
        })
        .collect();
    let extent = s.iter().flatten().fold(1.0f64, |m, p| m.max(p.x).max(p.y));
    let band = extent / ORDER_BANDS;
    s.sort_by(|a, b| {
        let ka = ((a[0].y / band).floor() as i64, a[0].x);
        let kb = ((b[0].y / band).floor() as i64, b[0].x);
        ka.0.cmp(&kb.0).then(ka.1.total_cmp(&kb.1))
    });
    // Horizontal before a crossing vertical.
    for _ in 0..s.len() * s.len() {
        let mut moved = false;
        'outer: for i in 0..s.len() {
            for j in i + 1..s.len() {
                if !is_horizontal(&s[i]) && is_horizontal(&s[j]) && crosses(&s[i], &s[j]) {
                    let h = s.remove(j);
                    s.insert(i, h);
                    moved = true;
                    break 'outer;
                }
            }
        }
        if !moved {
            break;
        }
    }
    s
}

fn crosses(a: &[Point], b: &[Point]) -> bool {
    let seg = |p: Point, q: Point, r: Point, s: Point| {
        let d = |a: Point, b: Point, c: Point| (b - a).cross(c - a);
        let (d1, d2, d3, d4) = (d(p, q, r), d(p, q, s), d(r, s, p), d(r, s, q));
        d1 * d2 <= 0.0 && d3 * d4 <= 0.0 && (d1 != 0.0 || d2 != 0.0)
    };
    a.windows(2).any(|x| b.windows(2).any(|y| seg(x[0], x[1], y[0], y[1])))
}
