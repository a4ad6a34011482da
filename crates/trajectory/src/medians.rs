//! The centre-line pipeline behind [`crate::centre_lines`]: hanzi-writer medians re-centred on
//! the distance ridge ([`from_medians`]) or the skeleton's strokes ([`from_skeleton`]), then
//! both ends run out into the end caps and sharp corners out into their knobs.
//!
//! Frames and units: the output is in the em frame (1024 units, y down), half-widths in em
//! units. Distance transforms are on the `analysis_px²` raster of the em box (px, pixel
//! centres at `i + 0.5`); `px_to_em` converts. Invariants: every returned path has one
//! half-width per point, and its corners are ascending indices of knob tips.

use kurbo::{Point, Vec2};

use crate::skeleton::{GraphOptions, Skeleton};
use crate::{Glyph, StrokePath, TrajectoryError, distance, glyph, raster};

/// Medians are densified to at most this spacing (em units) before they are re-centred: a few
/// analysis pixels at 512² (2 px), fine against a stroke's width. Hand-set (docs/trajectory.md,
/// Tuned constants).
pub(crate) const MEDIAN_STEP_EM: f64 = 8.0;

/// [`crate::Method::Medians`]: each median (densified every [`MEDIAN_STEP_EM`]) is moved onto
/// the ridge of its own stroke outline's distance transform (the whole glyph's when the source
/// has no outline for it), its ends run out and its corners knobbed.
pub(crate) fn from_medians(g: &Glyph, analysis_px: u32) -> Result<Vec<StrokePath>, TrajectoryError> {
    let n = analysis_px as usize;
    let px_to_em = glyph::EM / analysis_px as f64;
    let medians = g.medians.as_ref().ok_or_else(|| TrajectoryError::NoMedians(g.source.kind().to_string()))?;
    let outlines = g.stroke_outlines.as_ref();
    let whole = raster::mask_of(&raster::render_glyph(g, analysis_px));
    let whole_dt = distance::distance_to_background(&whole, n, n);
    let mut out = Vec::with_capacity(medians.len());
    for (i, m) in medians.iter().enumerate() {
        let dt = match outlines.and_then(|o| o.get(i)) {
            Some(o) => {
                let mask = raster::mask_of(&raster::render_outlines(std::slice::from_ref(o), analysis_px));
                distance::distance_to_background(&mask, n, n)
            }
            None => whole_dt.clone(),
        };
        let (pts, half_widths) = centre_on_ridge(&densify(m, MEDIAN_STEP_EM), &dt, n, px_to_em);
        let (pts, half_widths) = extend_ends(pts, half_widths, &dt, n, px_to_em);
        out.push(knob_corners(pts, half_widths, &dt, n, px_to_em));
    }
    Ok(out)
}

/// [`crate::Method::Skeleton`]: the skeleton's strokes ([`Skeleton::strokes`] with the default
/// [`GraphOptions`]) scaled into the em frame, half-widths from the glyph's distance transform,
/// ends run out (thinning stops short of them too) and corners knobbed.
pub(crate) fn from_skeleton(g: &Glyph, analysis_px: u32) -> Result<Vec<StrokePath>, TrajectoryError> {
    let px_to_em = glyph::EM / analysis_px as f64;
    let sk = Skeleton::of(g, analysis_px).ok_or(TrajectoryError::Empty(g.ch))?;
    let (dt, n) = (&sk.dt, sk.n);
    Ok(sk
        .strokes(&GraphOptions::default())
        .into_iter()
        .map(|p| {
            let half_widths = p.iter().map(|q| distance::sample(dt, n, n, q.x, q.y) * px_to_em).collect();
            let pts = p.iter().map(|q| Point::new(q.x * px_to_em, q.y * px_to_em)).collect();
            let (pts, half_widths) = extend_ends(pts, half_widths, dt, n, px_to_em);
            knob_corners(pts, half_widths, dt, n, px_to_em)
        })
        .collect())
}

/// Inserts points so no segment is longer than `step` (em units).
pub(crate) fn densify(p: &[Point], step: f64) -> Vec<Point> {
    let mut out = vec![p[0]];
    for w in p.windows(2) {
        let k = (w[0].distance(w[1]) / step).ceil().max(1.0) as usize;
        for i in 1..=k {
            out.push(w[0].lerp(w[1], i as f64 / k as f64));
        }
    }
    out
}

/// The ridge search reaches this far (px) beyond the distance to the outline at the median's
/// point... Hand-set.
const RIDGE_EXTRA_PX: f64 = 3.0;
/// ... but never farther than this (px) either way.
const RIDGE_MAX_PX: f64 = 40.0;
/// The ridge search's step across the stroke (px).
const RIDGE_STEP_PX: f64 = 0.5;

/// Moves each point of a median across the stroke onto the ridge of the stroke's distance
/// transform (hanzi-writer medians are hand-drawn and often off-centre), and returns the ridge
/// height there as the half-width (em units). The shifts are smoothed along the stroke so the
/// line stays smooth.
pub(crate) fn centre_on_ridge(p: &[Point], dt: &[f32], n: usize, px_to_em: f64) -> (Vec<Point>, Vec<f64>) {
    let at = |q: Point| distance::sample(dt, n, n, q.x / px_to_em, q.y / px_to_em);
    let mut shifts = Vec::with_capacity(p.len());
    let mut widths = Vec::with_capacity(p.len());
    for i in 0..p.len() {
        let (a, b) = (p[i.saturating_sub(1)], p[(i + 1).min(p.len() - 1)]);
        let d = b - a;
        let len = d.hypot();
        if len < 1e-9 {
            shifts.push(0.0);
            widths.push(at(p[i]) * px_to_em);
            continue;
        }
        let normal = Vec2::new(-d.y / len, d.x / len);
        let reach = (at(p[i]) + RIDGE_EXTRA_PX).min(RIDGE_MAX_PX) * px_to_em;
        let (mut best, mut best_off) = (at(p[i]), 0.0);
        let steps = (reach / (RIDGE_STEP_PX * px_to_em)).ceil() as i64;
        for k in -steps..=steps {
            let off = k as f64 * RIDGE_STEP_PX * px_to_em;
            let v = at(p[i] + normal * off);
            if v > best + 1e-9 {
                best = v;
                best_off = off;
            }
        }
        shifts.push(best_off);
        widths.push(best * px_to_em);
    }
    // Smooth the shifts (window 5) and apply them along each point's normal.
    let mut out = Vec::with_capacity(p.len());
    for i in 0..p.len() {
        let (lo, hi) = (i.saturating_sub(2), (i + 2).min(p.len() - 1));
        let off = shifts[lo..=hi].iter().sum::<f64>() / (hi - lo + 1) as f64;
        let (a, b) = (p[i.saturating_sub(1)], p[(i + 1).min(p.len() - 1)]);
        let d = b - a;
        let len = d.hypot().max(1e-9);
        out.push(p[i] + Vec2::new(-d.y / len, d.x / len) * off);
    }
    (out, widths)
}

/// Where a stroke's centre line should end, as a fraction of the local half-width left: hand-drawn
/// medians stop well inside the stroke's end cap, so each end is continued along its direction
/// until the distance to the outline falls to this fraction of the half-width at the old end.
/// Chosen on the tuning set (docs/trajectory.md, Tuned constants).
pub(crate) const END_CAP_FRACTION: f64 = 0.65;

/// Continues both ends of a centre line outward (see [`END_CAP_FRACTION`]), one em unit at a time.
pub(crate) fn extend_ends(p: Vec<Point>, w: Vec<f64>, dt: &[f32], n: usize, px_to_em: f64) -> (Vec<Point>, Vec<f64>) {
    extend_ends_by(p, w, |end, u, w_end| run_out(end, u, w_end, dt, n, px_to_em))
}

/// Continues both ends of a centre line outward with `run_out(end, unit direction, end
/// half-width)`, which returns the new points and half-widths (em) in order away from the end.
/// Each end's direction is taken over its last (up to) three segments; an end with no length or
/// no width is left as it is.
pub(crate) fn extend_ends_by(
    mut p: Vec<Point>,
    mut w: Vec<f64>,
    run_out: impl Fn(Point, Vec2, f64) -> Vec<(Point, f64)>,
) -> (Vec<Point>, Vec<f64>) {
    if p.len() < 2 {
        return (p, w);
    }
    let march = |end: Point, before: Point, w_end: f64| -> Vec<(Point, f64)> {
        let d = end - before;
        let len = d.hypot();
        if len < 1e-9 || w_end <= 0.0 {
            return Vec::new();
        }
        run_out(end, d / len, w_end)
    };
    let k = (p.len() - 1).min(3);
    let tail = march(p[p.len() - 1], p[p.len() - 1 - k], w[w.len() - 1]);
    for (q, v) in tail {
        p.push(q);
        w.push(v);
    }
    let head = march(p[0], p[k], w[0]);
    for (q, v) in head {
        p.insert(0, q);
        w.insert(0, v);
    }
    (p, w)
}

/// The points one em unit apart from `from` along the unit direction `u`, each with its distance
/// to the outline (em), while that distance stays above [`END_CAP_FRACTION`] of `w` (at most
/// 3·`w` steps).
fn run_out(from: Point, u: Vec2, w: f64, dt: &[f32], n: usize, px_to_em: f64) -> Vec<(Point, f64)> {
    let mut out = Vec::new();
    let mut q = from;
    for _ in 0..(3.0 * w).ceil() as usize {
        q += u;
        let v = distance::sample(dt, n, n, q.x / px_to_em, q.y / px_to_em) * px_to_em;
        if v <= END_CAP_FRACTION * w {
            break;
        }
        out.push((q, v));
    }
    out
}

/// Kaiti corners (折) and hook bends (钩) carry a knob where the brush pressed before turning;
/// centre lines cut the corner inside it. At each sharp corner of a centre line (the turn test of
/// [`crate::CORNER_RAD`] over ±[`crate::CORNER_REACH_EM`]) the line is continued out along the
/// corner's outer bisector until the distance to the outline falls to [`END_CAP_FRACTION`] of the
/// half-width at the corner, and the next leg starts from there (docs/trajectory.md, "Centre
/// lines").
pub(crate) fn knob_corners(mut p: Vec<Point>, mut w: Vec<f64>, dt: &[f32], n: usize, px_to_em: f64) -> StrokePath {
    let turns = crate::path::corner_turns(&p);
    let mut corners = Vec::with_capacity(turns.len());
    // Points inserted by earlier knobs shift the later corners' indices.
    let mut shift = 0;
    for (c, (u, v)) in turns {
        let c = c + shift;
        let out = u - v;
        let len = out.hypot();
        let knob = if len > 1e-9 { run_out(p[c], out / len, w[c], dt, n, px_to_em) } else { Vec::new() };
        // The corner point stays; the line runs out to the knob's tip and on from there to the
        // next leg, and the stroke's pieces meet at the tip.
        let k = knob.len();
        p.splice(c + 1..c + 1, knob.iter().map(|x| x.0));
        w.splice(c + 1..c + 1, knob.iter().map(|x| x.1));
        corners.push(c + k);
        shift += k;
    }
    StrokePath { points: p, half_widths: w, corners }
}
