//! Calligraphy rules at the corners of a chain: which turns end a stroke (the upper left of 口,
//! box bottoms) and which stay inside one (横折, 竖提 and other 提, hooks 钩 at a chain's end).
//!
//! Frame: the analysis raster, px, y down (so "rising" is `y` decreasing). Turns are measured
//! between chords over [`GraphOptions::corner_reach`] local half-widths each way; every
//! returned piece is a sub-polyline of the chain, consecutive pieces sharing their cut point.

use kurbo::{Point, Vec2};

use super::options::GraphOptions;
use super::order::writing_direction;
use crate::polyline::{arc_lengths, nearly_horizontal};

/// Splits a chain at corners that cannot be inside one written stroke.
///
/// A corner is a point where the chain turns by more than `corner_rad`, measured between the
/// points [`CORNER_REACH`] local half-widths before and after it (a local maximum of the turn). With
/// the chain's two legs oriented as the chain runs, one stroke can turn there only if both legs
/// run the way they are written ([`writing_direction`]) or both against it; otherwise the
/// corner joins the starts of two strokes (the upper left of 口) or their ends (the lower
/// right); a leg rising to the right out of a downward one is 提 and stays (竖提). On a closed
/// chain, vertical-into-rightward corners split too when `split_box_corners` is set. Legs
/// shorter than two half-widths never split, nor do hooks at a chain's ends ([`HOOK_WIDTHS`],
/// [`HOOK_RATIO`]). A closed chain (a box drawn as one loop) is cut at its splitting corners.
pub(super) fn split_at_corners(
    p: &[Point],
    dt: &[f32],
    n: usize,
    opts: &GraphOptions,
    junctions: &[Point],
) -> Vec<Vec<Point>> {
    let m = p.len();
    if m < 5 {
        return vec![p.to_vec()];
    }
    let closed = p[0].distance(p[m - 1]) < 1.5;
    // Arc length, with the closing segment for loops.
    let s = arc_lengths(p);
    let total = s[m - 1] + if closed { p[m - 1].distance(p[0]) } else { 0.0 };
    let width = |q: Point| -> f64 {
        let (x, y) = (q.x.floor().clamp(0.0, (n - 1) as f64) as usize, q.y.floor().clamp(0.0, (n - 1) as f64) as usize);
        f64::from(dt[y * n + x]).max(1.0)
    };
    // The point at arc length `t` (wrapping for loops; clamped otherwise).
    let at = |t: f64| -> Point {
        let t = if closed { t.rem_euclid(total) } else { t.clamp(0.0, s[m - 1]) };
        let i = s.partition_point(|&x| x <= t).clamp(1, m) - 1;
        p[i]
    };
    let reach: Vec<f64> = p.iter().map(|&q| (opts.corner_reach * width(q)).max(3.0)).collect();
    let turn: Vec<f64> = (0..m)
        .map(|i| {
            if !closed && (s[i] < reach[i] || s[m - 1] - s[i] < reach[i]) {
                return 0.0;
            }
            let (a, b) = (p[i] - at(s[i] - reach[i]), at(s[i] + reach[i]) - p[i]);
            if a.hypot() < 1e-9 || b.hypot() < 1e-9 {
                return 0.0;
            }
            (a.dot(b) / (a.hypot() * b.hypot())).clamp(-1.0, 1.0).acos()
        })
        .collect();
    // Corners: local maxima of the turn above the threshold, one per neighbourhood.
    let mut corners: Vec<usize> = Vec::new();
    for i in 0..m {
        if turn[i] <= opts.corner_rad {
            continue;
        }
        let near = |j: usize| {
            let d = (s[j] - s[i]).abs();
            if closed { d.min(total - d) } else { d }
        };
        let is_max = (0..m).all(|j| near(j) > reach[i] || turn[j] < turn[i] || (turn[j] == turn[i] && j >= i));
        if is_max {
            corners.push(i);
        }
    }
    // Per corner: stays, splits, or an open box corner that splits if the horizontal leg's far
    // end (the neighbouring corner's index or the chain's end) lies against other strokes: a
    // splitting corner or a junction.
    enum Verdict {
        Stay,
        Split,
        OpenBox(usize),
    }
    let decide = |i: usize| -> Verdict {
        let d_in = p[i] - at(s[i] - reach[i]);
        let d_out = at(s[i] + reach[i]) - p[i];
        let (w_in, w_out) = (writing_direction(d_in), writing_direction(d_out));
        let forward_in = w_in.dot(d_in) > 0.0;
        let forward_out = w_out.dot(d_out) > 0.0;
        // The legs up to the neighbouring corners (or the chain's ends).
        let prev =
            corners.iter().rev().find(|&&c| c < i).map_or(if closed { None } else { Some(0.0) }, |&c| Some(s[c]));
        let next = corners.iter().find(|&&c| c > i).map_or(if closed { None } else { Some(s[m - 1]) }, |&c| Some(s[c]));
        let min_leg = 2.0 * width(p[i]);
        let long = prev.is_none_or(|a| s[i] - a >= min_leg) && next.is_none_or(|b| b - s[i] >= min_leg);
        if !long {
            return Verdict::Stay;
        }
        // A hook: a chain's first or last leg that is much shorter than the leg it turns
        // from, or short and rising away from the corner (every 钩 points up).
        if !closed {
            let (len_in, len_out) = (s[i] - prev.unwrap_or(0.0), next.unwrap_or(s[m - 1]) - s[i]);
            let w = width(p[i]);
            let hook = |len: f64, other: f64, outward: Vec2| {
                len < opts.hook_widths * w && (len < opts.hook_ratio * other || outward.y < -0.2 * outward.hypot())
            };
            let first = corners.first() == Some(&i);
            let last = corners.last() == Some(&i);
            if (first && hook(len_in, len_out, -d_in)) || (last && hook(len_out, len_in, d_out)) {
                return Verdict::Stay;
            }
        }
        // 提 rises to the right out of a downward leg (竖提, 横折提): one stroke, whichever
        // way the chain runs.
        let down = |v: Vec2| !nearly_horizontal(v) && v.y > 0.0;
        let rising = |v: Vec2| v.x > 0.0 && v.y < -opts.ti_min_rise * v.x;
        if (down(d_in) && rising(d_out)) || (down(-d_out) && rising(-d_in)) {
            return Verdict::Stay;
        }
        if forward_in != forward_out {
            return Verdict::Split;
        }
        // As written: which leg comes first. A vertical leg turning right is a box corner.
        let (first, second) = if forward_in { (d_in, d_out) } else { (-d_out, -d_in) };
        let vertical = |v: Vec2| v.y > 2.0 * v.x.abs();
        let right = |v: Vec2| nearly_horizontal(v) && v.x > 0.0;
        if !(vertical(first) && right(second)) {
            return Verdict::Stay;
        }
        if closed {
            return if opts.split_box_corners { Verdict::Split } else { Verdict::Stay };
        }
        // The legs as written: the vertical one, then the horizontal one, which must run to
        // the chain's end and end there against other strokes (the bottom of 口 ending at
        // the right side), not at a free end or another corner.
        let (len_in, len_out) = (s[i] - prev.unwrap_or(0.0), next.unwrap_or(s[m - 1]) - s[i]);
        let (len_v, len_h) = if forward_in { (len_in, len_out) } else { (len_out, len_in) };
        // A box side is upright and its bottom level (撇折 in 纟 and 幺 slants and rises).
        let upright = first.x.abs() <= 0.3 * first.y && second.y >= -0.15 * second.x;
        if !(opts.open_box_min_ratio > 0.0 && upright && len_v >= opts.open_box_min_ratio * len_h) {
            return Verdict::Stay;
        }
        let far = if forward_in {
            corners.iter().copied().find(|&c| c > i).unwrap_or(m - 1)
        } else {
            corners.iter().rev().copied().find(|&c| c < i).unwrap_or(0)
        };
        Verdict::OpenBox(far)
    };
    let verdicts: Vec<Verdict> = corners.iter().map(|&i| decide(i)).collect();
    let base: Vec<usize> =
        corners.iter().zip(&verdicts).filter(|(_, v)| matches!(v, Verdict::Split)).map(|(&c, _)| c).collect();
    let splits: Vec<usize> = corners
        .iter()
        .zip(&verdicts)
        .filter(|(_, v)| match v {
            Verdict::Split => true,
            Verdict::OpenBox(far) => {
                base.contains(far)
                    || ((*far == 0 || *far == m - 1) && junctions.iter().any(|j| j.distance(p[*far]) < 1.5))
            }
            Verdict::Stay => false,
        })
        .map(|(&c, _)| c)
        .collect();
    if splits.is_empty() {
        return vec![p.to_vec()];
    }
    let mut out = Vec::new();
    if closed {
        // Rotate the loop to start at the first split, then cut at the others.
        let start = splits[0];
        let ring: Vec<Point> = p[start..m - 1].iter().chain(&p[..=start]).copied().collect();
        let cuts: Vec<usize> = splits.iter().map(|&c| (c + (m - 1) - start) % (m - 1)).collect();
        let mut from = 0;
        for &c in cuts.iter().skip(1).chain(std::iter::once(&(ring.len() - 1))) {
            out.push(ring[from..=c].to_vec());
            from = c;
        }
    } else {
        let mut from = 0;
        for &c in splits.iter().chain(std::iter::once(&(m - 1))) {
            out.push(p[from..=c].to_vec());
            from = c;
        }
    }
    out
}
