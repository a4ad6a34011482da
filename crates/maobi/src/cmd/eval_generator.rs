//! `maobi eval-generator`: the generator against the analytic B-BSM, with the baselines, in the
//! layout of the paper's Table 3.

use std::collections::BTreeMap;
use std::path::PathBuf;

use anyhow::Result;
use bezier_raster::{Coverage, DatasetSpec, ModelKind, Rasterizer, StrokeCanvas};
use rayon::prelude::*;
use serde_json::json;
use stroke_metrics::{SsimWorkspace, Summary, csim};

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
    let spec = DatasetSpec {
        profile: g.config.profile.clone(),
        canvas: StrokeCanvas::with_scale(s, g.config.px_per_mm),
        seed: neural_gen::HELD_OUT_SEED,
    };
    let rows: Vec<Vec<(f64, f64)>> = (0..args.n as u64)
        .into_par_iter()
        .map_init(
            || (Rasterizer::new(), Coverage::new(s, s), Coverage::new(s, s), SsimWorkspace::new()),
            |(r, truth, img, ws), i| {
                let smp = spec.sample(i).expect("in range");
                spec.render(&smp, ModelKind::Bsm.model(), r, truth);
                ModelKind::BASELINES
                    .iter()
                    .map(|m| {
                        spec.render(&smp, m.model(), r, img);
                        (
                            csim(truth.as_gray(), img.as_gray()).expect("same size"),
                            ws.ssim(truth.as_gray(), img.as_gray()).expect("same size"),
                        )
                    })
                    .collect()
            },
        )
        .collect();
    let mut table: BTreeMap<String, (Summary, Summary)> = BTreeMap::new();
    table.insert("b-bsmg".into(), (gc, gs));
    for (k, m) in ModelKind::BASELINES.iter().enumerate() {
        table.insert(
            m.name().into(),
            (Summary::of(rows.iter().map(|r| r[k].0)), Summary::of(rows.iter().map(|r| r[k].1))),
        );
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
