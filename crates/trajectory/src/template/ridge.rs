//! Stage 3 of [`super::register`] on the target's distance ridge: the snap across a stroke onto
//! the ridge, the margin of a stroke's own ink, and the run-outs of its ends to the caps.

use kurbo::{Point, Vec2};

use crate::distance;

/// A stroke's own ink is the target's ink within this distance of the template's stroke outline
/// carried over by both fits, em units.
const OWN_INK_MARGIN_EM: f64 = 10.0;

/// The own-ink margin of one stroke, px: [`OWN_INK_MARGIN_EM`] plus how much thicker the target's
/// stroke is than the template's outline carried onto it (`outline`, a mask): the difference of
/// the medians of their half-widths (distance transforms `dt` and the outline's) along the
/// snapped centre line `line`. A brush font's strokes can be twice as thick as the template's;
/// a fixed margin cut them down to the template's width.
pub(super) fn own_margin_px(line: &[Point], dt: &[f32], outline: &[bool], n: usize, px_to_em: f64) -> f64 {
    let odt = distance::distance_to_background(outline, n, n);
    let median = |f: &[f32]| {
        let mut v: Vec<f64> = line.iter().map(|p| distance::sample(f, n, n, p.x / px_to_em, p.y / px_to_em)).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    OWN_INK_MARGIN_EM / px_to_em + (median(dt) - median(&odt)).max(0.0)
}

/// Continues both ends of a stroke's centre line outward along its end direction, one em unit at
/// a time, while the distance to the outline (`dt`, px, on the `n²` raster) stays above
/// [`END_STOP_FRACTION`] of the end's half-width and has not grown again by more than
/// [`RUN_OUT_REGROW_EM`] after narrowing (past a neck the line would run into other ink). Each new
/// point's half-width is the ink's half-chord across the line there, between the distance to the
/// outline and the end's half-width: a blunt or swollen terminal keeps its width out to the cap,
/// a taper narrows. (The medians method's [`crate::medians::extend_ends`] stops at 0.65 of the
/// width with the distance as the width, tuned on hanzi-writer's shapes.)
pub(super) fn extend_ends_own(
    p: Vec<Point>,
    w: Vec<f64>,
    dt: &[f32],
    n: usize,
    px_to_em: f64,
) -> (Vec<Point>, Vec<f64>) {
    crate::medians::extend_ends_by(p, w, |end, u, w_end| run_out_own(end, u, w_end, dt, n, px_to_em))
}

/// The run-out of [`extend_ends_own`] from `from` along the unit direction `u`: points and
/// half-widths, em units.
fn run_out_own(from: Point, u: Vec2, w_end: f64, dt: &[f32], n: usize, px_to_em: f64) -> Vec<(Point, f64)> {
    let at = |q: Point| distance::sample(dt, n, n, q.x / px_to_em, q.y / px_to_em) * px_to_em;
    let nrm = Vec2::new(-u.y, u.x);
    let mut out = Vec::new();
    let (mut q, mut lo) = (from, f64::INFINITY);
    for _ in 0..(3.0 * w_end).ceil() as usize {
        q += u;
        let v = at(q);
        if v <= END_STOP_FRACTION * w_end || v > lo + RUN_OUT_REGROW_EM {
            break;
        }
        lo = lo.min(v);
        // Half the chord of ink across the line through q (half-pixel steps, out to 2·w_end).
        let reach = |side: f64| {
            let step = 0.5 * px_to_em;
            let mut t = 0.0;
            while t < 2.0 * w_end && at(q + nrm * (side * (t + step))) > 0.0 {
                t += step;
            }
            t
        };
        let chord = 0.5 * (reach(1.0) + reach(-1.0));
        // Past the medians method's stop only while the ink keeps nearly its full width (a blunt
        // cap); a rounded or tapered end stops about where that method stops.
        if v <= crate::medians::END_CAP_FRACTION * w_end && chord < BLUNT_CHORD_FRACTION * w_end {
            break;
        }
        out.push((q, chord.clamp(v, w_end.max(v))));
    }
    out
}

/// A stroke end's run-out ([`extend_ends_own`]) stops where the distance to the outline falls to
/// this share of the end's half-width. Chosen on the tuning set (docs/trajectory.md, Tuned
/// constants).
const END_STOP_FRACTION: f64 = 0.1;

/// Past the medians method's stop ([`crate::medians::END_CAP_FRACTION`] of the end's width) a
/// run-out goes on only while the ink's half-chord across it is at least this share of the end's
/// half-width (a blunt cap). Chosen on the tuning set (docs/trajectory.md, Tuned constants).
const BLUNT_CHORD_FRACTION: f64 = 0.85;

/// A stroke end's run-out stops where its width grows again by this much (em units) after
/// narrowing: it has passed a neck into other ink (a run-out into a neighbour would make a press
/// jump the robot check refuses). Hand-set (docs/trajectory.md, Tuned constants).
const RUN_OUT_REGROW_EM: f64 = 4.0;

/// Moves each point across the stroke to the nearest ridge of the distance transform `dt`
/// (`n × n`): off the ink it first steps to the nearest ink along the normal, then climbs while
/// the distance grows. The shifts are smoothed along the stroke (window 5). Returns the moved
/// points and the ridge heights (half-widths), em units.
#[allow(clippy::needless_range_loop)] // indices address p, its normals and the shifts together
pub(super) fn snap_to_ridge(p: &[Point], dt: &[f32], n: usize, px_to_em: f64) -> (Vec<Point>, Vec<f64>) {
    let at = |q: Point| distance::sample(dt, n, n, q.x / px_to_em, q.y / px_to_em);
    let step = 0.5 * px_to_em;
    let normal_at = |i: usize| {
        let (a, b) = (p[i.saturating_sub(1)], p[(i + 1).min(p.len() - 1)]);
        let d = b - a;
        let len = d.hypot();
        if len < 1e-9 { None } else { Some(Vec2::new(-d.y / len, d.x / len)) }
    };
    let mut shifts = Vec::with_capacity(p.len());
    for i in 0..p.len() {
        let Some(nrm) = normal_at(i) else {
            shifts.push(0.0);
            continue;
        };
        let mut off = 0.0;
        if at(p[i]) < 0.5 {
            // Nearest ink along the normal, within 12 px.
            let found = (1..=24).find_map(|k| {
                let o = k as f64 * step;
                if at(p[i] + nrm * o) >= 0.5 {
                    Some(o)
                } else if at(p[i] - nrm * o) >= 0.5 {
                    Some(-o)
                } else {
                    None
                }
            });
            match found {
                Some(o) => off = o,
                None => {
                    shifts.push(0.0);
                    continue;
                }
            }
        }
        // Climb on the uphill side until clearly past the ridge (a raster's distance transform
        // has small dips along a line), then take the middle of the points near the top.
        let dir = if at(p[i] + nrm * (off + 2.0 * step)) >= at(p[i] + nrm * (off - 2.0 * step)) { 1.0 } else { -1.0 };
        let mut prof = vec![(off, at(p[i] + nrm * off))];
        let mut best = prof[0].1;
        let mut o = off;
        for _ in 0..160 {
            o += dir * step;
            let v = at(p[i] + nrm * o);
            if v < best - 1.0 || v <= 0.0 {
                break;
            }
            best = best.max(v);
            prof.push((o, v));
        }
        let top: Vec<f64> = prof.iter().filter(|(_, v)| *v >= best - 0.3).map(|(o, _)| *o).collect();
        shifts.push(top.iter().sum::<f64>() / top.len() as f64);
    }
    let mut out = Vec::with_capacity(p.len());
    let mut widths = Vec::with_capacity(p.len());
    for i in 0..p.len() {
        let (lo, hi) = (i.saturating_sub(2), (i + 2).min(p.len() - 1));
        let off = shifts[lo..=hi].iter().sum::<f64>() / (hi - lo + 1) as f64;
        let q = match normal_at(i) {
            Some(nrm) => p[i] + nrm * off,
            None => p[i],
        };
        out.push(q);
        widths.push(at(q) * px_to_em);
    }
    (out, widths)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::glyph::EM;

    /// An `n × n` mask (em box) inked where `ink(x_em, y_em)` holds, its distance transform and
    /// px → em factor.
    fn bar_dt(n: usize, ink: impl Fn(f64, f64) -> bool) -> (Vec<bool>, Vec<f32>, f64) {
        let s = EM / n as f64;
        let mask: Vec<bool> = (0..n * n).map(|i| ink(((i % n) as f64 + 0.5) * s, ((i / n) as f64 + 0.5) * s)).collect();
        let dt = distance::distance_to_background(&mask, n, n);
        (mask, dt, s)
    }

    #[test]
    fn an_end_runs_out_to_a_blunt_cap_at_full_width() {
        // A bar 60 em thick from x = 100 to 600: from x = 550 the line runs on to near the cap,
        // and the run-out keeps the bar's half-width (the distance to the outline would taper).
        let (_, dt, s) = bar_dt(256, |x, y| (100.0..600.0).contains(&x) && (200.0..260.0).contains(&y));
        let p: Vec<Point> = (0..=10).map(|i| Point::new(150.0 + 40.0 * i as f64, 230.0)).collect();
        let w = vec![30.0; p.len()];
        let (q, v) = extend_ends_own(p, w, &dt, 256, s);
        let (last, w_last) = (q[q.len() - 1], v[v.len() - 1]);
        assert!(last.x > 585.0 && last.x < 600.0, "{last:?}");
        assert!(w_last > 24.0, "{w_last}");
        // And the head (x = 150) runs back towards x = 100 the same way.
        assert!(q[0].x < 115.0 && q[0].x > 100.0, "{:?}", q[0]);
        assert_eq!(q.len(), v.len());
    }

    #[test]
    fn an_end_stops_at_a_neck_before_other_ink() {
        // The bar narrows to a 16 em neck at x = 500..520, then a wide blob: the run-out stops
        // in the neck instead of running on into the blob.
        let (_, dt, s) = bar_dt(256, |x, y| {
            ((100.0..500.0).contains(&x) && (200.0..260.0).contains(&y))
                || ((500.0..520.0).contains(&x) && (222.0..238.0).contains(&y))
                || ((520.0..700.0).contains(&x) && (160.0..300.0).contains(&y))
        });
        let from = Point::new(470.0, 230.0);
        let out = run_out_own(from, Vec2::new(1.0, 0.0), 30.0, &dt, 256, s);
        let end = out.last().map_or(from, |o| o.0);
        assert!(end.x < 530.0, "ran on to {end:?}");
    }

    #[test]
    fn the_own_ink_margin_grows_with_a_thicker_target() {
        // Template outline 20 em thick, target stroke 60 em thick on the same line: the margin
        // grows by about the 20 em difference of the half-widths.
        let n = 256;
        let (outline, _, s) = bar_dt(n, |x, y| (100.0..600.0).contains(&x) && (220.0..240.0).contains(&y));
        let (_, dt, _) = bar_dt(n, |x, y| (100.0..600.0).contains(&x) && (200.0..260.0).contains(&y));
        let line: Vec<Point> = (0..20).map(|i| Point::new(200.0 + 15.0 * i as f64, 230.0)).collect();
        let grown = own_margin_px(&line, &dt, &outline, n, s) * s - OWN_INK_MARGIN_EM;
        assert!((grown - 20.0).abs() < 5.0, "{grown}");
        // The same thickness: the fixed margin.
        let same = own_margin_px(&line, &distance::distance_to_background(&outline, n, n), &outline, n, s) * s;
        assert!((same - OWN_INK_MARGIN_EM).abs() < 1e-9, "{same}");
    }
}
