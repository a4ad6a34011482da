//! `cargo xtask gates [--update]`: similarity regression gates.
//!
//! Every figure is computed afresh and compared with `fixtures/baselines/<group>.json`. A figure
//! that got worse by more than its tolerance fails the gate with a message naming the figure, its
//! baseline and its value; improvements pass (run `--update` to record them deliberately).

use std::collections::BTreeMap;
use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use bezier_raster::{Coverage, DatasetSpec, ModelKind, Rasterizer, StrokeModel};
use brush_model::BrushProfile;
use pipeline::{BoxRule, ReportMeans, WriteOptions, prepare, write_placed};
use rayon::prelude::*;
use stroke_metrics::{SsimWorkspace, Summary};
use trajectory::{Method, embedded_glyph};

use crate::figures::{Better, Figures, Regression, compare, fig};
use crate::fixtures::root;
use crate::refine_gate::refine_figures;

/// Characters the character gates write (all in the embedded subset).
pub const GATE_CHARS: &str = "永字八法十口人丁山水中国书大小日月";

/// Stroke-model figures: each of `models` against `reference` over `n` presses of pen1 at 128²
/// (CSIM and SSIM best, worst, mean), plus the reference's mean relative error of rendered ink
/// against the analytic B-BSM area.
pub fn model_figures(reference: &dyn StrokeModel, models: &[(&str, &dyn StrokeModel)], n: u64) -> Figures {
    let spec = DatasetSpec::new(BrushProfile::builtin("pen1").expect("built-in"), 128, 2024);
    let s2 = spec.canvas.px_per_mm * spec.canvas.px_per_mm;
    let rows: Vec<(f64, Vec<(f64, f64)>)> = (0..n)
        .into_par_iter()
        .map_init(
            || (Rasterizer::new(), Coverage::new(128, 128), Coverage::new(128, 128), SsimWorkspace::new()),
            |(r, truth, img, ws), i| {
                let s = spec.sample(i).expect("in range");
                spec.render(&s, reference, r, truth);
                let area_err = (truth.ink() - s.footprint.area_mm2() * s2).abs() / (s.footprint.area_mm2() * s2);
                let scores = models
                    .iter()
                    .map(|(_, m)| {
                        spec.render(&s, *m, r, img);
                        (
                            stroke_metrics::csim(truth.as_gray(), img.as_gray()).expect("same size"),
                            ws.ssim(truth.as_gray(), img.as_gray()).expect("same size"),
                        )
                    })
                    .collect();
                (area_err, scores)
            },
        )
        .collect();
    let mut f = Figures::new();
    f.insert(
        "models/bsm/ink_vs_area_rel_error".into(),
        fig(rows.iter().map(|r| r.0).sum::<f64>() / n as f64, 0.002, Better::Lower),
    );
    for (k, (name, _)) in models.iter().enumerate() {
        for (metric, idx) in [("csim", 0), ("ssim", 1)] {
            let s = Summary::of(rows.iter().map(|r| if idx == 0 { r.1[k].0 } else { r.1[k].1 }));
            // A baseline model scoring *higher* against the B-BSM is as suspicious as lower: both
            // mean a model changed. Record means two-sided via two entries.
            f.insert(format!("models/{name}/{metric}_mean"), fig(s.mean, 0.002, Better::Higher));
            f.insert(format!("models/{name}/{metric}_mean_upper"), fig(s.mean, 0.002, Better::Lower));
            f.insert(format!("models/{name}/{metric}_worst"), fig(s.worst, 0.005, Better::Higher));
            f.insert(format!("models/{name}/{metric}_best"), fig(s.best, 0.005, Better::Higher));
        }
    }
    f
}

/// Character figures: the write pipeline on [`GATE_CHARS`] for each method and model at 256²,
/// mean CSIM, SSIM, IoU and chamfer; for the B-BSM also the executed figures (the program run as
/// the simulator moves, against the glyph) and the plan's agreement with them (mean and worst).
pub fn character_figures() -> Result<Figures> {
    let pen1 = BrushProfile::builtin("pen1")?;
    let chars: Vec<char> = GATE_CHARS.chars().collect();
    let mut f = Figures::new();
    for method in [Method::Medians, Method::Skeleton] {
        let prepared =
            chars.par_iter().map(|&c| Ok(prepare(embedded_glyph(c)?, Some(method))?)).collect::<Result<Vec<_>>>()?;
        for model in ModelKind::ALL {
            // The executed figures (the program run as the simulator moves) for the B-BSM only.
            let execute = model == ModelKind::Bsm;
            let opts = WriteOptions { model, size: 256, free_widths: false, execute, ..WriteOptions::default() };
            let reports = prepared
                .par_iter()
                .map(|p| Ok(write_placed(p, &pen1, &opts, BoxRule::Auto)?.report))
                .collect::<Result<Vec<_>>>()?;
            let m = ReportMeans::of(&reports);
            let key = |name: &str| format!("chars/{}/{}/{name}", method.name(), model.name());
            f.insert(key("csim"), fig(m.plan.csim, 0.003, Better::Higher));
            f.insert(key("ssim"), fig(m.plan.ssim, 0.003, Better::Higher));
            f.insert(key("iou"), fig(m.plan.iou, 0.005, Better::Higher));
            if model == ModelKind::Bsm {
                let (Some(ex), Some(ag), Some(chamfer), Some(strokes)) =
                    (m.executed, m.agreement, m.chamfer_pct, m.strokes_match_fraction)
                else {
                    bail!(
                        "{} {}: a character was not executed or has no chamfer or stroke count",
                        method.name(),
                        model.name()
                    );
                };
                if ex.count != m.count || ag.count != m.count {
                    bail!("{} {}: {} of {} characters executed", method.name(), model.name(), ex.count, m.count);
                }
                f.insert(key("chamfer_pct"), fig(chamfer, 0.05, Better::Lower));
                f.insert(key("executed_csim"), fig(ex.csim, 0.003, Better::Higher));
                f.insert(key("executed_iou"), fig(ex.iou, 0.005, Better::Higher));
                f.insert(key("agreement_csim"), fig(ag.csim, 0.002, Better::Higher));
                f.insert(key("agreement_csim_worst"), fig(ag.csim_min, 0.005, Better::Higher));
                f.insert(key("strokes_right_fraction"), fig(strokes, 0.0, Better::Higher));
            }
        }
    }
    Ok(f)
}

/// World figures: the gate characters planned with pen1 at 256², executed as sent and inked by
/// each of [`crate::worlds::GATE_WORLDS`] (worlds that disagree with the model: hairs that need
/// a press, another trail, the mismatched brush): mean executed CSIM and IoU, mean and worst
/// agreement with the plan; and `worlds/pressure_shortfall`, how far the worse of the two
/// pressure worlds falls below the model's own executed CSIM (the plan must not depend on what
/// the hairs do below a press).
pub fn world_figures() -> Result<Figures> {
    let rows = crate::worlds::gate_rows(GATE_CHARS, &crate::worlds::GATE_WORLDS, 256)?;
    let mut f = Figures::new();
    for (world, csim, iou, agreement, worst) in &rows[1..] {
        let key = |m: &str| format!("worlds/{world}/{m}");
        f.insert(key("executed_csim"), fig(*csim, 0.003, Better::Higher));
        f.insert(key("executed_iou"), fig(*iou, 0.005, Better::Higher));
        f.insert(key("agreement_csim"), fig(*agreement, 0.003, Better::Higher));
        f.insert(key("agreement_csim_worst"), fig(*worst, 0.005, Better::Higher));
    }
    let pressure = rows.iter().filter(|r| r.0.starts_with("pressure:")).map(|r| r.1).fold(f64::INFINITY, f64::min);
    let shortfall = rows[0].1 - pressure;
    f.insert("worlds/pressure_shortfall".into(), fig(shortfall, 0.002, Better::Lower));
    Ok(f)
}

/// The committed pen1 generator (`crates/neural-gen/data/pen1.*`, the one the `maobi` binary
/// compiles in).
fn committed_generator() -> Result<neural_gen::Generator> {
    Ok(neural_gen::Generator::pen1()?)
}

/// Generator figures: the committed pen1 generator against the analytic B-BSM on 200 held-out
/// presses (CSIM and SSIM mean and worst).
pub fn generator_figures() -> Result<Figures> {
    let g = committed_generator()?;
    let (c, s) = neural_gen::evaluate(&g, 200)?;
    Ok(Figures::from([
        ("generator/csim_mean".to_string(), fig(c.mean, 0.003, Better::Higher)),
        ("generator/csim_worst".to_string(), fig(c.worst, 0.01, Better::Higher)),
        ("generator/ssim_mean".to_string(), fig(s.mean, 0.003, Better::Higher)),
        ("generator/ssim_worst".to_string(), fig(s.worst, 0.01, Better::Higher)),
    ]))
}

fn baseline_path(group: &str) -> PathBuf {
    root().join(format!("fixtures/baselines/{group}.json"))
}

/// Runs the gates (or rewrites the baselines with `--update`).
pub fn run(args: &[String]) -> Result<()> {
    let update = args.iter().any(|a| a == "--update");
    if let Some(bad) = args.iter().find(|a| *a != "--update") {
        bail!("gates: unknown argument `{bad}` (expected --update)");
    }
    let t0 = std::time::Instant::now();
    let baselines: Vec<(&str, &dyn StrokeModel)> = ModelKind::BASELINES.iter().map(|m| (m.name(), m.model())).collect();
    let groups: Vec<(&str, Figures)> = vec![
        ("models", model_figures(ModelKind::Bsm.model(), &baselines, 300)),
        ("characters", character_figures()?),
        ("generator", generator_figures()?),
        ("refine", refine_figures()?),
        ("worlds", world_figures()?),
    ];
    println!("{:<48} {:>12} {:>12} {:>10}", "figure", "baseline", "now", "Δ");
    let mut failures = Vec::new();
    for (group, now) in &groups {
        let path = baseline_path(group);
        let base: Option<Figures> = std::fs::read_to_string(&path)
            .ok()
            .map(|t| serde_json::from_str(&t))
            .transpose()
            .with_context(|| format!("{}: not a baseline file", path.display()))?;
        for (name, n) in now {
            let b = base.as_ref().and_then(|b| b.get(name));
            let (bs, d) = match b {
                Some(b) => (format!("{:.6}", b.value), format!("{:+.6}", n.value - b.value)),
                None => ("—".into(), "new".into()),
            };
            let regressed = b.is_some_and(|b| {
                !compare(&BTreeMap::from([(name.clone(), *b)]), &BTreeMap::from([(name.clone(), *n)])).is_empty()
            });
            println!("{name:<48} {bs:>12} {:>12.6} {d:>10}  {}", n.value, if regressed { "FAIL" } else { "ok" });
        }
        match (&base, update) {
            (_, true) => {
                std::fs::create_dir_all(path.parent().expect("folder"))?;
                std::fs::write(&path, serde_json::to_string_pretty(now)? + "\n")?;
                println!("updated {}", path.display());
            }
            (Some(b), false) => failures.extend(compare(b, now)),
            (None, false) => failures.push(Regression {
                name: format!("{group} (no baseline file {})", path.display()),
                baseline: f64::NAN,
                value: f64::NAN,
                tolerance: 0.0,
            }),
        }
    }
    println!("gates ran in {:.1} s", t0.elapsed().as_secs_f64());
    if !failures.is_empty() {
        for f in &failures {
            eprintln!("gate: {f}");
        }
        bail!(
            "{} figure(s) regressed; if the change is intended, run `cargo xtask gates --update` and explain it in the commit",
            failures.len()
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use brush_model::Footprint;
    use kurbo::BezPath;

    /// The B-BSM with its belly narrowed by 15 %: a plausible bug.
    struct Narrow;
    impl StrokeModel for Narrow {
        fn name(&self) -> &'static str {
            "narrow"
        }
        fn local_outline(&self, fp: &Footprint) -> BezPath {
            let f = Footprint { lr_mm: fp.lr_mm * 0.85, ..*fp };
            bezier_raster::Bsm.local_outline(&f)
        }
    }

    #[test]
    fn a_degraded_stroke_model_fails_the_gate_with_a_readable_message() {
        let circle: &dyn StrokeModel = ModelKind::Circle.model();
        let base = model_figures(ModelKind::Bsm.model(), &[("circle", circle)], 24);
        // The same computation passes.
        assert!(compare(&base, &model_figures(ModelKind::Bsm.model(), &[("circle", circle)], 24)).is_empty());
        // A broken B-BSM fails on its ink-vs-area figure and on the model comparisons.
        let broken = model_figures(&Narrow, &[("circle", circle)], 24);
        let r = compare(&base, &broken);
        let msgs: Vec<String> = r.iter().map(|x| x.to_string()).collect();
        assert!(msgs.iter().any(|m| m.starts_with("models/bsm/ink_vs_area_rel_error regressed: baseline")), "{msgs:?}");
        // A baseline model that changes fails too.
        let changed = model_figures(ModelKind::Bsm.model(), &[("circle", &Narrow)], 24);
        let msgs: Vec<String> = compare(&base, &changed).iter().map(|x| x.to_string()).collect();
        assert!(msgs.iter().any(|m| m.starts_with("models/circle/")), "{msgs:?}");
    }
}
