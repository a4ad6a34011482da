//! Metrics of a track against reference centre lines, in percent of the em box.

use brush_model::Track;
use kurbo::Point;

use crate::glyph::EM;
use crate::paper::CharBox;

/// Spacing (em units) at which [`chamfer_pct`] resamples the reference centre lines: fine
/// against a stroke width (about 30–80 em), coarse enough to stay cheap. Not tuned.
const CHAMFER_STEP_EM: f64 = 4.0;

/// Symmetric chamfer distance between a track and reference centre lines, in percent of the em
/// box: the mean over track points of the distance to the nearest reference point and the mean
/// over reference points (resampled every 4 em units) of the distance to the nearest track
/// point, averaged.
pub fn chamfer_pct(track: &Track, char_box: &CharBox, medians: &[Vec<Point>]) -> f64 {
    let a: Vec<Point> = track.points().map(|p| char_box.to_em(p.anchor())).collect();
    let mut b = Vec::new();
    for m in medians {
        b.push(m[0]);
        for w in m.windows(2) {
            let d = w[0].distance(w[1]);
            let steps = (d / CHAMFER_STEP_EM).ceil().max(1.0) as usize;
            for i in 1..=steps {
                b.push(w[0].lerp(w[1], i as f64 / steps as f64));
            }
        }
    }
    if a.is_empty() || b.is_empty() {
        return 100.0;
    }
    let mean_nn = |from: &[Point], to: &[Point]| {
        from.iter().map(|p| to.iter().map(|q| p.distance(*q)).fold(f64::INFINITY, f64::min)).sum::<f64>()
            / from.len() as f64
    };
    0.5 * (mean_nn(&a, &b) + mean_nn(&b, &a)) / EM * 100.0
}
