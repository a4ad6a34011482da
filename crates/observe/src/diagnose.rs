//! Observed strokes against planned ones: width, ends, lateral offset.

use bezier_raster::Coverage;
use serde::{Deserialize, Serialize};

use crate::Frame;

/// Ink ends this far from a stroke's path end are not searched beyond, mm.
const REACH_MM: f64 = 12.0;

/// Spacing of the width probes along a stroke, mm.
const PROBE_MM: f64 = 1.0;

/// An end whose observed ink differs from the plan's by more than this runs into another
/// stroke's ink (or stops at a gap in it): not measured, mm.
const END_OUTLIER_MM: f64 = 6.0;

/// Share of a stroke's length at each end left out of the width probes (the ends are measured
/// on their own).
const END_SHARE: f64 = 0.2;

/// One stroke observed against its plan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StrokeDiagnosis {
    /// Its index in the character.
    pub stroke: usize,
    /// Width probes where both images have ink.
    pub probes: usize,
    /// Median observed width ÷ median planned width (None without probes).
    pub width_ratio: Option<f64>,
    /// Observed ink beyond the planned ink at the stroke's start (negative: short of it), mm.
    pub start_beyond_mm: Option<f64>,
    /// Observed ink beyond the planned ink at the stroke's end (negative: short of it), mm.
    pub end_beyond_mm: Option<f64>,
    /// Median shift of the observed ink's middle from the planned ink's, across the stroke,
    /// positive to the right of the writing direction (as seen on the paper), mm.
    pub lateral_mm: Option<f64>,
}

/// A character's strokes observed against their plan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Diagnosis {
    /// Per stroke.
    pub strokes: Vec<StrokeDiagnosis>,
    /// All probes' observed width ÷ planned width (ratio of the sums).
    pub width_ratio: Option<f64>,
    /// Median over the strokes' ends (starts and ends) of the observed ink beyond the planned
    /// ink (negative: short of it), mm.
    pub end_beyond_mm: Option<f64>,
    /// Median over strokes of the lateral shift, mm.
    pub lateral_mm: Option<f64>,
}

impl Diagnosis {
    /// One line: how much wider or narrower, longer or shorter, and shifted the ink is than
    /// planned, with `brush` naming the profile.
    pub fn verdict(&self, brush: &str) -> String {
        let mut parts = Vec::new();
        match self.width_ratio {
            Some(r) if (r - 1.0).abs() >= 0.03 => parts.push(format!(
                "the brush writes {:.0} % {} than {brush} says",
                100.0 * (r - 1.0).abs(),
                if r > 1.0 { "wider" } else { "narrower" }
            )),
            Some(_) => parts.push(format!("the brush writes as wide as {brush} says (within 3 %)")),
            None => {}
        }
        match self.end_beyond_mm {
            Some(l) if l.abs() >= 0.3 => parts.push(format!(
                "strokes run {:.1} mm {} at each end",
                l.abs(),
                if l > 0.0 { "long" } else { "short" }
            )),
            Some(_) => parts.push("strokes end where planned (within 0.3 mm)".into()),
            None => {}
        }
        if let Some(l) = self.lateral_mm {
            if l.abs() >= 0.2 {
                parts.push(format!(
                    "ink sits {:.1} mm {} of the path",
                    l.abs(),
                    if l > 0.0 { "right" } else { "left" }
                ));
            }
        }
        if parts.is_empty() { "no stroke could be measured".into() } else { parts.join("; ") }
    }
}

fn sample(img: &Coverage, frame: &Frame, p: [f64; 2]) -> f32 {
    let q = frame.to_px(p);
    let (fx, fy) = (q[0] - 0.5, q[1] - 0.5);
    if !(fx >= 0.0 && fy >= 0.0) {
        return 0.0;
    }
    let (x0, y0) = (fx.floor() as u32, fy.floor() as u32);
    if x0 + 1 >= img.width() || y0 + 1 >= img.height() {
        return 0.0;
    }
    let (tx, ty) = ((fx - x0 as f64) as f32, (fy - y0 as f64) as f32);
    let g = |x, y| img.get(x, y);
    let a = g(x0, y0) * (1.0 - tx) + g(x0 + 1, y0) * tx;
    let b = g(x0, y0 + 1) * (1.0 - tx) + g(x0 + 1, y0 + 1) * tx;
    a * (1.0 - ty) + b * ty
}

/// Distance from `p` along unit `d` to where the ink ends (coverage below ½): positive when
/// `p` is on ink, negative (the distance back to the ink) when it is not; `None` when no ink
/// edge lies within reach.
fn extent(img: &Coverage, frame: &Frame, p: [f64; 2], d: [f64; 2]) -> Option<f64> {
    let step = 0.25 / frame.px_per_mm;
    let at = |t: f64| sample(img, frame, [p[0] + t * d[0], p[1] + t * d[1]]) >= 0.5;
    let n = (REACH_MM / step) as usize;
    if at(0.0) {
        (1..=n).map(|k| k as f64 * step).find(|&t| !at(t)).map(|t| t - step / 2.0)
    } else {
        (1..=n).map(|k| -(k as f64) * step).find(|&t| at(t)).map(|t| t + step / 2.0)
    }
}

fn median(v: &mut [f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[v.len() / 2])
}

/// Compares the observed ink with the planned ink of one character, both in `frame`, along the
/// strokes' paths (`paths[k]`: stroke k's inking points in paper mm, in writing order): widths
/// across the middle of each stroke (probes every 1 mm, the first and last fifth left out), how
/// far the ink reaches past each end (the end: outwards along the last 2 mm; the start: where a
/// reverse entry turns, outwards along it, else the first point), and the shift of the ink's
/// middle across the stroke.
pub fn diagnose(observed: &Coverage, planned: &Coverage, frame: &Frame, paths: &[Vec<[f64; 2]>]) -> Diagnosis {
    let mut strokes = Vec::new();
    let (mut sum_obs, mut sum_plan) = (0.0, 0.0);
    for (k, path) in paths.iter().enumerate() {
        let mut d = StrokeDiagnosis {
            stroke: k,
            probes: 0,
            width_ratio: None,
            start_beyond_mm: None,
            end_beyond_mm: None,
            lateral_mm: None,
        };
        if path.len() < 2 {
            strokes.push(d);
            continue;
        }
        let mut cum = vec![0.0];
        for w in path.windows(2) {
            cum.push(cum.last().unwrap() + (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]));
        }
        let len = *cum.last().unwrap();
        let (mut wo, mut wp, mut lat) = (Vec::new(), Vec::new(), Vec::new());
        if len > 0.0 {
            let n = ((len * (1.0 - 2.0 * END_SHARE)) / PROBE_MM).floor().max(1.0) as usize;
            for i in 0..n {
                let s = len * END_SHARE + (i as f64 + 0.5) * len * (1.0 - 2.0 * END_SHARE) / n as f64;
                let seg = cum.partition_point(|&c| c < s).clamp(1, path.len() - 1);
                let (a, b) = (path[seg - 1], path[seg]);
                let l = (b[0] - a[0]).hypot(b[1] - a[1]);
                if l < 1e-9 {
                    continue;
                }
                let t = [(b[0] - a[0]) / l, (b[1] - a[1]) / l];
                let f = ((s - cum[seg - 1]) / l).clamp(0.0, 1.0);
                let p = [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])];
                // Right of the writing direction on the paper (y down).
                let nrm = [-t[1], t[0]];
                let neg = [t[1], -t[0]];
                let probe = |img: &Coverage| -> Option<(f64, f64)> {
                    if sample(img, frame, p) < 0.5 {
                        return None;
                    }
                    let (r, l) = (extent(img, frame, p, nrm)?, extent(img, frame, p, neg)?);
                    Some((r + l, (r - l) / 2.0))
                };
                if let (Some(o), Some(q)) = (probe(observed), probe(planned)) {
                    wo.push(o.0);
                    wp.push(q.0);
                    lat.push(o.1 - q.1);
                }
            }
        }
        d.probes = wo.len();
        sum_obs += wo.iter().sum::<f64>();
        sum_plan += wp.iter().sum::<f64>();
        if let (Some(o), Some(q)) = (median(&mut wo.clone()), median(&mut wp.clone())) {
            d.width_ratio = (q > 0.0).then_some(o / q);
        }
        d.lateral_mm = median(&mut lat);
        let dir = |a: [f64; 2], b: [f64; 2]| {
            let l = (b[0] - a[0]).hypot(b[1] - a[1]);
            (l > 1e-9).then(|| [(b[0] - a[0]) / l, (b[1] - a[1]) / l])
        };
        // Ink of a neighbouring stroke is not this stroke's end.
        let beyond = |p: [f64; 2], d: [f64; 2]| {
            let v = extent(observed, frame, p, d)? - extent(planned, frame, p, d)?;
            (v.abs() <= END_OUTLIER_MM).then_some(v)
        };
        // The end: the last point, outwards along the last 2 mm of the path.
        let last = path[path.len() - 1];
        let back = path.iter().rev().find(|q| (q[0] - last[0]).hypot(q[1] - last[1]) >= 2.0);
        if let Some(t) = back.and_then(|q| dir(*q, last)) {
            d.end_beyond_mm = beyond(last, t);
        }
        // The start: where a reverse entry turns (the first reversal in the path's first third),
        // outwards along the entry; without one, the first point, against the first 2 mm.
        let turn = (1..path.len() - 1).take_while(|&i| cum[i] < len / 3.0).find(|&i| {
            let (a, b) = (dir(path[i - 1], path[i]), dir(path[i], path[i + 1]));
            matches!((a, b), (Some(a), Some(b)) if a[0] * b[0] + a[1] * b[1] < -0.5)
        });
        let start = match turn {
            Some(i) => dir(path[0], path[i]).map(|t| (path[i], t)),
            None => path
                .iter()
                .find(|q| (q[0] - path[0][0]).hypot(q[1] - path[0][1]) >= 2.0)
                .and_then(|q| dir(*q, path[0]))
                .map(|t| (path[0], t)),
        };
        if let Some((p, t)) = start {
            d.start_beyond_mm = beyond(p, t);
        }
        strokes.push(d);
    }
    let width_ratio = (sum_plan > 0.0).then_some(sum_obs / sum_plan);
    let mut ends: Vec<f64> = strokes.iter().flat_map(|s| [s.start_beyond_mm, s.end_beyond_mm]).flatten().collect();
    let end_beyond_mm = median(&mut ends);
    let mut lats: Vec<f64> = strokes.iter().filter_map(|s| s.lateral_mm).collect();
    let lateral_mm = median(&mut lats);
    Diagnosis { strokes, width_ratio, end_beyond_mm, lateral_mm }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A horizontal bar from x0 to x1 (mm), `half_mm` either side of y = 20 mm.
    fn bar(frame: &Frame, x0: f64, x1: f64, half_mm: f64) -> Coverage {
        let mut c = Coverage::new(frame.width, frame.height);
        for j in 0..frame.height {
            for i in 0..frame.width {
                let p = frame.centre_mm(i, j);
                if p[0] >= x0 && p[0] <= x1 && (p[1] - 20.0).abs() <= half_mm {
                    c.data_mut()[(j * frame.width + i) as usize] = 1.0;
                }
            }
        }
        c
    }

    #[test]
    fn a_wider_longer_stroke_is_diagnosed_as_such() {
        let frame = Frame { x0_mm: 0.0, y0_mm: 0.0, px_per_mm: 10.0, width: 400, height: 400 };
        let planned = bar(&frame, 10.0, 30.0, 2.0);
        let observed = bar(&frame, 9.0, 31.0, 2.5);
        let path: Vec<[f64; 2]> = (0..=20).map(|k| [10.0 + k as f64, 20.0]).collect();
        let d = diagnose(&observed, &planned, &frame, &[path]);
        let w = d.width_ratio.unwrap();
        assert!((w - 1.25).abs() < 0.03, "width ratio {w}");
        let e = d.end_beyond_mm.unwrap();
        assert!((e - 1.0).abs() < 0.1, "ends {e}");
        assert!(d.lateral_mm.unwrap().abs() < 0.05);
        let v = d.verdict("pen1");
        assert!(v.contains("wider than pen1") && v.contains("long"), "{v}");
        // The same ink: nothing to say but that it matches.
        let same = diagnose(&planned, &planned, &frame, &[(0..=20).map(|k| [10.0 + k as f64, 20.0]).collect()]);
        assert!(same.verdict("pen1").contains("as wide as"), "{}", same.verdict("pen1"));
    }
}
