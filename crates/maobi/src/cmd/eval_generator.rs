//! `maobi eval-generator`: the generator against the analytic B-BSM, with the baselines, in the
//! layout of the paper's Table 3.

use std::collections::BTreeMap;
use std::path::PathBuf;

use anyhow::Result;
use bezier_raster::ModelKind;
use brush_model::Extrapolation;
use pipeline::{ModelTarget, score_models};
use serde_json::json;
use stroke_metrics::Summary;

use crate::common::{check_range, print_json, print_model_table};

/// Arguments of `maobi eval-generator`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Generator weights (`.safetensors`, its `.json` config beside); default: the committed
    /// pen1 generator.
    #[arg(long, value_name = "FILE")]
    generator: Option<PathBuf>,
    /// Held-out presses.
    #[arg(long, default_value_t = 500)]
    n: usize,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    check_range("--n", args.n, 1, 100_000, "presses")?;
    let g = crate::generator::load_generator(args.generator.as_deref())?;
    let t0 = std::time::Instant::now();
    let (gc, gs) = neural_gen::evaluate(&g, args.n)?;
    let secs = t0.elapsed().as_secs_f64();
    let s = g.config.size;
    let spec = neural_gen::held_out_spec(&g.config);
    let targets = ModelTarget::presses(&spec, args.n as u64);
    let baselines = score_models(&spec.profile, &targets, s, &ModelKind::BASELINES, Extrapolation::Refuse, &|| {})?;
    let mut table: BTreeMap<String, (Summary, Summary)> = BTreeMap::new();
    table.insert("b-bsmg".into(), (gc, gs));
    for (name, m) in baselines {
        table.insert(name.into(), (m.csim, m.ssim));
    }
    if args.json {
        let models: BTreeMap<_, _> =
            table.iter().map(|(k, (c, s))| (k.clone(), json!({"csim": c, "ssim": s}))).collect();
        let weights = args.generator.as_ref().map_or("committed".to_string(), |p| p.display().to_string());
        print_json(
            &json!({"n": args.n, "reference": "analytic b-bsm", "generator": weights, "generator_seconds": secs, "models": models}),
        )?;
    } else {
        crate::outln!(
            "{} held-out presses of {}, each model against the analytic B-BSM (%); b-bsmg is {}:",
            args.n,
            g.config.profile.name,
            args.generator
                .as_ref()
                .map_or("the committed generator (fixtures/generator/pen1.safetensors)".to_string(), |p| p
                    .display()
                    .to_string())
        )?;
        print_model_table(["b-bsmg", "circle", "ellipse", "line", "qbc"].map(|name| {
            let (c, s) = table[name];
            (name, c, s)
        }))?;
    }
    Ok(())
}
