//! Means over character reports: the one computation behind `maobi evaluate`'s summary,
//! `maobi write`'s summary.json and the character and refinement gates.

use serde::{Serialize, Serializer};

use crate::write::{CharReport, Similarity};

/// Means of [`Similarity`] figures over the reports that have them, and the worst CSIM.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct SimilarityMeans {
    /// How many reports had the figure.
    pub count: usize,
    /// Mean cosine similarity.
    pub csim: f64,
    /// Mean structural similarity.
    pub ssim: f64,
    /// Mean intersection over union.
    pub iou: f64,
    /// The lowest cosine similarity.
    pub csim_min: f64,
}

impl SimilarityMeans {
    /// The means of `figures` (summed in order), `None` when there are none.
    pub fn of(figures: impl IntoIterator<Item = Similarity>) -> Option<Self> {
        let v: Vec<Similarity> = figures.into_iter().collect();
        if v.is_empty() {
            return None;
        }
        let k = v.len() as f64;
        Some(SimilarityMeans {
            count: v.len(),
            csim: v.iter().map(|s| s.csim).sum::<f64>() / k,
            ssim: v.iter().map(|s| s.ssim).sum::<f64>() / k,
            iou: v.iter().map(|s| s.iou).sum::<f64>() / k,
            csim_min: v.iter().map(|s| s.csim).fold(f64::INFINITY, f64::min),
        })
    }
}

/// Means and counts over character reports ([`ReportMeans::of`]).
///
/// Serialises as `maobi evaluate --json`'s `summary` (docs/outputs.md): `count`, the plan's
/// `csim`, `ssim` and `iou`, `chamfer_pct`, `strokes_match_fraction`, `millis_mean`,
/// `executed` and `agreement` (with `csim_min`), `free_widths`, and `refine` when there is one.
#[derive(Clone, Debug, PartialEq)]
pub struct ReportMeans {
    /// Reports.
    pub count: usize,
    /// The plans against their glyphs (every report).
    pub plan: SimilarityMeans,
    /// Mean chamfer distance, % of the em box, over the reports that have one.
    pub chamfer_pct: Option<f64>,
    /// Of the reports that know how many strokes to expect, the fraction that found that many
    /// (and, from a registered template, found every stroke's ink).
    pub strokes_match_fraction: Option<f64>,
    /// Mean planning time, ms.
    pub plan_millis: f64,
    /// What the robot would write against the glyph, over the executed reports.
    pub executed: Option<SimilarityMeans>,
    /// The plan against the executed render, over the executed reports.
    pub agreement: Option<SimilarityMeans>,
    /// The plan with footprints sized freely from the glyph, over the reports that have it.
    pub free_widths: Option<SimilarityMeans>,
    /// The refinement's figures, over the refined reports.
    pub refine: Option<RefineMeans>,
}

/// Means over the refinement reports ([`crate::RefineReport`]).
///
/// Serialises as `maobi evaluate --json`'s `summary.refine`: the counts, the four figures
/// (`csim`, `ssim`, `iou` each) and the times.
#[derive(Clone, Debug, PartialEq)]
pub struct RefineMeans {
    /// Refined reports.
    pub count: usize,
    /// How many refined tracks the robot check refused.
    pub rejected: usize,
    /// The built tracks' programs against the glyph (where executed).
    pub executed_before: Option<SimilarityMeans>,
    /// The refined tracks' programs against the glyph (where executed).
    pub executed_after: Option<SimilarityMeans>,
    /// The built tracks' renders against the glyph.
    pub planned_before: SimilarityMeans,
    /// The refined tracks' renders against the glyph.
    pub planned_after: SimilarityMeans,
    /// Mean of each report's executed CSIM after minus before, over the reports executed both
    /// ways.
    pub executed_csim_gain: Option<f64>,
    /// Mean time of a refinement, ms.
    pub millis_mean: f64,
    /// Longest refinement, ms.
    pub millis_max: f64,
}

impl ReportMeans {
    /// The means over `reports`, each summed in report order.
    ///
    /// # Panics
    /// When `reports` is empty.
    ///
    /// # Examples
    /// ```no_run
    /// # fn main() -> Result<(), pipeline::Error> {
    /// use pipeline::{BoxRule, ReportMeans, WriteOptions, prepare, write_placed};
    /// use trajectory::embedded_glyph;
    /// let pen1 = brush_model::BrushProfile::builtin("pen1")?;
    /// let mut reports = Vec::new();
    /// for c in ['十', '口'] {
    ///     let p = prepare(embedded_glyph(c)?, None)?;
    ///     reports.push(write_placed(&p, &pen1, &WriteOptions::default(), BoxRule::Auto)?.report);
    /// }
    /// let means = ReportMeans::of(&reports);
    /// println!("plan CSIM {:.3} over {} characters", means.plan.csim, means.count);
    /// # Ok(())
    /// # }
    /// ```
    pub fn of<'a>(reports: impl IntoIterator<Item = &'a CharReport>) -> Self {
        let r: Vec<&CharReport> = reports.into_iter().collect();
        assert!(!r.is_empty(), "means over no reports");
        let n = r.len() as f64;
        let plan =
            SimilarityMeans::of(r.iter().map(|c| Similarity { csim: c.plan.csim, ssim: c.plan.ssim, iou: c.plan.iou }))
                .expect("at least one report");
        let chamfers: Vec<f64> = r.iter().filter_map(|c| c.plan.chamfer_pct).collect();
        let with_count: Vec<&&CharReport> = r.iter().filter(|c| c.plan.strokes_expected.is_some()).collect();
        // A registered template always has the template's count: it is right when every stroke
        // found its own ink.
        let strokes_ok = with_count
            .iter()
            .filter(|c| {
                c.plan.strokes_expected == Some(c.plan.strokes_found)
                    && c.template.as_ref().is_none_or(|t| t.strokes_ok)
            })
            .count();
        ReportMeans {
            count: r.len(),
            plan,
            chamfer_pct: (!chamfers.is_empty()).then(|| chamfers.iter().sum::<f64>() / chamfers.len() as f64),
            strokes_match_fraction: (!with_count.is_empty()).then(|| strokes_ok as f64 / with_count.len() as f64),
            plan_millis: r.iter().map(|c| c.timing_ms.plan).sum::<f64>() / n,
            executed: SimilarityMeans::of(r.iter().filter_map(|c| c.executed)),
            agreement: SimilarityMeans::of(r.iter().filter_map(|c| c.agreement)),
            free_widths: SimilarityMeans::of(r.iter().filter_map(|c| c.plan.free_widths)),
            refine: RefineMeans::of(r.iter().filter_map(|c| c.refine.as_ref())),
        }
    }
}

/// The centre-line methods `reports` used: one name, or the names in order joined by `+` when
/// they differ (`"medians"`, `"medians+template"`).
pub fn methods_used(reports: &[CharReport]) -> String {
    let mut names: Vec<&str> = reports.iter().map(|r| r.method).collect();
    names.sort_unstable();
    names.dedup();
    names.join("+")
}

impl RefineMeans {
    /// The means over `reports`, `None` when there are none.
    pub fn of<'a>(reports: impl IntoIterator<Item = &'a crate::RefineReport>) -> Option<Self> {
        let rf: Vec<&crate::RefineReport> = reports.into_iter().collect();
        let planned_before = SimilarityMeans::of(rf.iter().map(|x| x.planned_before))?;
        let planned_after = SimilarityMeans::of(rf.iter().map(|x| x.planned_after))?;
        let gains: Vec<f64> =
            rf.iter().filter_map(|x| Some(x.executed_after?.csim - x.executed_before?.csim)).collect();
        let ms: Vec<f64> = rf.iter().map(|x| x.millis).collect();
        Some(RefineMeans {
            count: rf.len(),
            rejected: rf.iter().filter(|x| x.rejected.is_some()).count(),
            executed_before: SimilarityMeans::of(rf.iter().filter_map(|x| x.executed_before)),
            executed_after: SimilarityMeans::of(rf.iter().filter_map(|x| x.executed_after)),
            planned_before,
            planned_after,
            executed_csim_gain: (!gains.is_empty()).then(|| gains.iter().sum::<f64>() / gains.len() as f64),
            millis_mean: ms.iter().sum::<f64>() / ms.len() as f64,
            millis_max: ms.iter().copied().fold(0.0, f64::max),
        })
    }
}

/// A figure's three means, as the summaries print them.
#[derive(Serialize)]
struct Means3 {
    csim: f64,
    ssim: f64,
    iou: f64,
}

/// A figure's three means and its worst CSIM.
#[derive(Serialize)]
struct Means4 {
    csim: f64,
    ssim: f64,
    iou: f64,
    csim_min: f64,
}

impl From<SimilarityMeans> for Means3 {
    fn from(s: SimilarityMeans) -> Self {
        Means3 { csim: s.csim, ssim: s.ssim, iou: s.iou }
    }
}

impl From<SimilarityMeans> for Means4 {
    fn from(s: SimilarityMeans) -> Self {
        Means4 { csim: s.csim, ssim: s.ssim, iou: s.iou, csim_min: s.csim_min }
    }
}

impl Serialize for ReportMeans {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        #[derive(Serialize)]
        struct Summary<'a> {
            count: usize,
            csim: f64,
            ssim: f64,
            iou: f64,
            chamfer_pct: Option<f64>,
            strokes_match_fraction: Option<f64>,
            millis_mean: f64,
            executed: Option<Means4>,
            agreement: Option<Means4>,
            free_widths: Option<Means3>,
            #[serde(skip_serializing_if = "Option::is_none")]
            refine: Option<&'a RefineMeans>,
        }
        Summary {
            count: self.count,
            csim: self.plan.csim,
            ssim: self.plan.ssim,
            iou: self.plan.iou,
            chamfer_pct: self.chamfer_pct,
            strokes_match_fraction: self.strokes_match_fraction,
            millis_mean: self.plan_millis,
            executed: self.executed.map(Means4::from),
            agreement: self.agreement.map(Means4::from),
            free_widths: self.free_widths.map(Means3::from),
            refine: self.refine.as_ref(),
        }
        .serialize(s)
    }
}

impl Serialize for RefineMeans {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        #[derive(Serialize)]
        struct Summary {
            count: usize,
            rejected: usize,
            executed_before: Option<Means3>,
            executed_after: Option<Means3>,
            planned_before: Means3,
            planned_after: Means3,
            millis_mean: f64,
            millis_max: f64,
        }
        Summary {
            count: self.count,
            rejected: self.rejected,
            executed_before: self.executed_before.map(Means3::from),
            executed_after: self.executed_after.map(Means3::from),
            planned_before: self.planned_before.into(),
            planned_after: self.planned_after.into(),
            millis_mean: self.millis_mean,
            millis_max: self.millis_max,
        }
        .serialize(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn means(csim: f64) -> SimilarityMeans {
        SimilarityMeans { count: 2, csim, ssim: 0.5, iou: 0.25, csim_min: csim - 0.1 }
    }

    #[test]
    fn the_means_serialise_as_evaluates_summary() {
        let mut m = ReportMeans {
            count: 2,
            plan: means(0.9),
            chamfer_pct: None,
            strokes_match_fraction: Some(1.0),
            plan_millis: 12.0,
            executed: Some(means(0.8)),
            agreement: None,
            free_widths: Some(means(0.7)),
            refine: None,
        };
        let v = serde_json::to_value(&m).unwrap();
        let keys: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
        let want = [
            "agreement",
            "chamfer_pct",
            "count",
            "csim",
            "executed",
            "free_widths",
            "iou",
            "millis_mean",
            "ssim",
            "strokes_match_fraction",
        ];
        assert_eq!(keys, want);
        assert_eq!(v["csim"], 0.9);
        assert_eq!(v["millis_mean"], 12.0);
        assert_eq!(v["executed"]["csim_min"].as_f64(), Some(0.8 - 0.1));
        assert!(v["free_widths"].get("csim_min").is_none() && v["agreement"].is_null());
        m.refine = Some(RefineMeans {
            count: 2,
            rejected: 1,
            executed_before: None,
            executed_after: Some(means(0.85)),
            planned_before: means(0.9),
            planned_after: means(0.95),
            executed_csim_gain: None,
            millis_mean: 30.0,
            millis_max: 40.0,
        });
        let rf = &serde_json::to_value(&m).unwrap()["refine"];
        assert_eq!(rf["rejected"], 1);
        assert_eq!(rf["planned_after"]["csim"], 0.95);
        assert!(rf["executed_before"].is_null() && rf.get("executed_csim_gain").is_none());
    }
}
