//! Figures the gates record and how a figure regresses: the baseline format of
//! `fixtures/baselines/<group>.json` and the directional comparison with a tolerance.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// Which way is better for a figure.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Better {
    /// Larger values are better (similarities).
    Higher,
    /// Smaller values are better (distances, errors).
    Lower,
}

/// One recorded figure.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Figure {
    /// The value.
    pub value: f64,
    /// How much worse it may get before the gate fails.
    pub tolerance: f64,
    /// Which way is better.
    pub better: Better,
}

/// A group of figures, as stored in `fixtures/baselines/<group>.json`.
pub type Figures = BTreeMap<String, Figure>;

/// A figure that got worse than its baseline allows.
#[derive(Debug, PartialEq)]
pub struct Regression {
    /// Figure name.
    pub name: String,
    /// Baseline value.
    pub baseline: f64,
    /// Value now.
    pub value: f64,
    /// Allowed change.
    pub tolerance: f64,
}

impl std::fmt::Display for Regression {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} regressed: baseline {:.6}, now {:.6} (tolerance {})",
            self.name, self.baseline, self.value, self.tolerance
        )
    }
}

/// Compares figures with their baselines: every figure that got worse by more than its
/// tolerance, and every baseline figure that is missing now.
pub fn compare(baseline: &Figures, now: &Figures) -> Vec<Regression> {
    let mut out = Vec::new();
    for (name, b) in baseline {
        let Some(n) = now.get(name) else {
            out.push(Regression {
                name: format!("{name} (missing)"),
                baseline: b.value,
                value: f64::NAN,
                tolerance: b.tolerance,
            });
            continue;
        };
        let worse = match b.better {
            Better::Higher => b.value - n.value,
            Better::Lower => n.value - b.value,
        };
        if !(worse <= b.tolerance) {
            out.push(Regression { name: name.clone(), baseline: b.value, value: n.value, tolerance: b.tolerance });
        }
    }
    out
}

/// A figure of `value`, allowed to get worse by `tolerance` in the direction `better`.
pub fn fig(value: f64, tolerance: f64, better: Better) -> Figure {
    Figure { value, tolerance, better }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn comparison_is_directional_with_tolerance() {
        let base =
            Figures::from([("a".into(), fig(0.9, 0.01, Better::Higher)), ("d".into(), fig(1.0, 0.1, Better::Lower))]);
        let ok =
            Figures::from([("a".into(), fig(0.895, 0.01, Better::Higher)), ("d".into(), fig(0.5, 0.1, Better::Lower))]);
        assert!(compare(&base, &ok).is_empty());
        let bad =
            Figures::from([("a".into(), fig(0.85, 0.01, Better::Higher)), ("d".into(), fig(1.2, 0.1, Better::Lower))]);
        let r = compare(&base, &bad);
        assert_eq!(r.len(), 2);
        assert_eq!(r[0].to_string(), "a regressed: baseline 0.900000, now 0.850000 (tolerance 0.01)");
        let nan = Figures::from([("a".into(), fig(f64::NAN, 0.01, Better::Higher))]);
        assert_eq!(compare(&base, &nan).len(), 2, "NaN and a missing figure both fail");
    }
}
