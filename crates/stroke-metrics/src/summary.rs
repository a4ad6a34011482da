//! Best / worst / mean over a set of scores.

use serde::{Deserialize, Serialize};

/// Summary of a set of scores where higher is better (CSIM, SSIM, IoU).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Number of scores.
    pub count: usize,
    /// Highest score (`NaN`-free; 0 for an empty set).
    pub best: f64,
    /// Lowest score.
    pub worst: f64,
    /// Arithmetic mean.
    pub mean: f64,
}

impl Summary {
    /// Summarises the scores; an empty set gives count 0 and zeros.
    pub fn of(scores: impl IntoIterator<Item = f64>) -> Self {
        let (mut count, mut best, mut worst, mut sum) = (0usize, f64::NEG_INFINITY, f64::INFINITY, 0.0);
        for s in scores {
            count += 1;
            best = best.max(s);
            worst = worst.min(s);
            sum += s;
        }
        if count == 0 {
            return Summary { count: 0, best: 0.0, worst: 0.0, mean: 0.0 };
        }
        Summary { count, best, worst, mean: sum / count as f64 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn summarises() {
        let s = Summary::of([0.5, 0.9, 0.7]);
        assert_eq!((s.count, s.best, s.worst), (3, 0.9, 0.5));
        assert!((s.mean - 0.7).abs() < 1e-12);
        assert_eq!(Summary::of([]).count, 0);
    }
}
