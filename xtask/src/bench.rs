//! `cargo xtask bench`: runs the criterion benchmarks (release) and the dataset throughput, and
//! prints one summary table, also written to `target/bench-summary.md`; then the maobi/PyTorch
//! pairs of the generator (inference, training step, the LearningToPaint-size training step),
//! each pair run back to back (interleaved, `--rounds N` times, same thread count), with every
//! figure as a fraction of the machine's peak FP32 rate (measured by `peak_fp32` in
//! benches/generator.rs) and the load average at the time. `--pairs` runs the pairs only.

use std::path::Path;
use std::process::Command;
use std::time::Instant;

use anyhow::{Context, Result, bail};

use crate::fixtures::root;

/// Every criterion benchmark target: (package, bench).
const BENCHES: &[(&str, &str)] = &[
    ("stroke-metrics", "metrics"),
    ("bezier-raster", "raster"),
    ("trajectory", "track"),
    ("maobi", "write"),
    ("neural-gen", "generator"),
    ("neural-gen", "ltp"),
    ("neural-gen", "gen_vjp"),
    ("track-refine", "refine"),
];

/// (criterion id, label).
const ROWS: &[(&str, &str)] = &[
    ("footprint_128/bsm", "B-BSM footprint render, 128², reused buffer"),
    ("footprint_128/qbc", "QBC footprint render, 128²"),
    ("batch_128/bsm_256", "256 footprints in parallel (rayon), 128²"),
    ("composite_400_stamps_512", "400 stamps composed into 512²"),
    ("ssim/128x128", "SSIM 128²"),
    ("ssim/512x512", "SSIM 512²"),
    ("centre_lines_medians_yong", "centre lines of 永, medians (512² analysis)"),
    ("centre_lines_skeleton_yong", "centre lines of 永, skeleton"),
    ("build_track_yong", "track building for 永"),
    ("write_yong_medians_512", "`write` 永 end to end, medians, 512²"),
    ("write_yong_skeleton_512", "`write` 永 end to end, skeleton, 512²"),
    ("generator_inference/batch_1", "generator inference, batch 1 (per call)"),
    ("generator_inference/batch_64", "generator inference, batch 64 (per call of 64)"),
    (
        "generator_inference/batch_64_candle_graph",
        "generator inference, batch 64, through candle's graph (the old path)",
    ),
    ("generator_inference/analytic_64", "analytic B-BSM, 64 footprints (one thread)"),
    ("generator_training/step_batch_64", "generator training step, batch 64 (incl. validation setup)"),
    ("generator_training/network_step_batch_64", "generator training step, batch 64, network alone, direct kernels"),
    (
        "generator_training/network_step_batch_64_candle_graph",
        "generator training step, batch 64, network alone, candle's graph (the old path)",
    ),
    ("peak_fp32/fma_all_threads", "peak FP32: independent FMAs on every thread (fixed work)"),
    ("ltp_training/step_batch_64_maobi", "LearningToPaint-size net, Adam step, batch 64, maobi kernels"),
    ("ltp_training/step_batch_64_candle", "LearningToPaint-size net, Adam step, batch 64, stock candle"),
    ("ltp_training/step_batch_64_direct", "LearningToPaint-size net, Adam step, batch 64, direct kernels"),
    ("ltp_inference/batch_64_direct", "LearningToPaint-size net, inference batch 64, direct kernels"),
    (
        "generator_training/train_job_10_steps_batch_64",
        "the whole `train` job, 10 steps of batch 64 (targets rendered, one validation)",
    ),
    ("ltp_inference/batch_1_maobi", "LearningToPaint-size net, inference batch 1, maobi kernels"),
    ("ltp_inference/batch_64_maobi", "LearningToPaint-size net, inference batch 64, maobi kernels"),
    ("ltp_inference/batch_1_candle", "LearningToPaint-size net, inference batch 1, stock candle"),
    ("ltp_inference/batch_64_candle", "LearningToPaint-size net, inference batch 64, stock candle"),
    ("generator_vjp/batch_64_direct", "generator forward + VJP to the presses, batch 64, maobi kernels (InputVjp)"),
    ("generator_vjp/batch_64_forward_direct", "generator forward alone, batch 64, maobi kernels"),
    ("generator_vjp/batch_64_jacobian_direct", "generator Jacobian to the presses (forward mode), batch 64"),
    ("generator_vjp/batch_64_candle_autograd", "generator forward + VJP to the presses, batch 64, candle autograd"),
    ("refine/永 default", "refining 永 at the defaults (analytic gradients, 20 steps)"),
    ("refine/字 default", "refining 字 at the defaults (analytic gradients, 20 steps)"),
];

fn estimate_ns(dir: &Path, id: &str) -> Option<f64> {
    let p = dir.join(id).join("new/estimates.json");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(p).ok()?).ok()?;
    v["mean"]["point_estimate"].as_f64()
}

fn human(ns: f64) -> String {
    if ns < 1e3 {
        format!("{ns:.0} ns")
    } else if ns < 1e6 {
        format!("{:.1} µs", ns / 1e3)
    } else if ns < 1e9 {
        format!("{:.2} ms", ns / 1e6)
    } else {
        format!("{:.2} s", ns / 1e9)
    }
}

/// Runs the benchmarks and writes the table.
pub fn run(args: &[String]) -> Result<()> {
    let quick = args.iter().any(|a| a == "--quick");
    let root = root();
    let rounds = match args.iter().position(|a| a == "--rounds") {
        Some(i) => args
            .get(i + 1)
            .and_then(|v| v.parse::<usize>().ok())
            .filter(|&n| (1..=20).contains(&n))
            .context("--rounds takes a count from 1 to 20")?,
        None => 3,
    };
    if args.iter().any(|a| a == "--pairs") {
        let table = pairs(&root, quick, rounds)?;
        print!("{table}");
        return Ok(());
    }
    for (package, bench) in BENCHES {
        let mut cmd = Command::new(env!("CARGO"));
        cmd.current_dir(&root).args(["bench", "-p", package, "--bench", bench, "--"]);
        if quick {
            cmd.args(["--warm-up-time", "1", "--measurement-time", "2"]);
        }
        let st = cmd.status().with_context(|| format!("running the {package} benchmarks"))?;
        if !st.success() {
            bail!("cargo bench -p {package} --bench {bench} failed");
        }
    }
    let crit = root.join("target/criterion");
    let mut table = String::from("| benchmark | time (mean) |\n|---|---|\n");
    for (id, label) in ROWS {
        let cell = estimate_ns(&crit, id).map_or("not run".to_string(), human);
        table.push_str(&format!("| {label} | {cell} |\n"));
    }
    // Dataset throughput: the CLI end to end (process start, rendering, PNG writing).
    let st =
        Command::new(env!("CARGO")).current_dir(&root).args(["build", "--release", "-q", "-p", "maobi"]).status()?;
    if !st.success() {
        bail!("building maobi failed");
    }
    let out = root.join("target/bench-dataset");
    let _ = std::fs::remove_dir_all(&out);
    let t0 = Instant::now();
    let st = Command::new(root.join("target/release/maobi"))
        .args(["dataset", "--n", "10000", "--size", "128", "-o"])
        .arg(&out)
        .status()?;
    let secs = t0.elapsed().as_secs_f64();
    if !st.success() {
        bail!("maobi dataset failed");
    }
    table.push_str(&format!(
        "| `maobi dataset --n 10000 --size 128` ({} threads) | {:.2} s, {:.0} images/s |\n",
        std::thread::available_parallelism().map_or(1, |n| n.get()),
        secs,
        10000.0 / secs
    ));
    let _ = std::fs::remove_dir_all(&out);
    table.push_str(&torch_rows(&root));
    table.push('\n');
    table.push_str(&pairs(&root, quick, rounds)?);
    let path = root.join("target/bench-summary.md");
    std::fs::write(&path, format!("# maobi benchmarks\n\n{table}"))?;
    print!("{table}");
    println!("written to {}", path.display());
    Ok(())
}

/// The Python that runs the PyTorch references: `$MAOBI_PYTHON`, else `python3`.
fn python() -> String {
    std::env::var("MAOBI_PYTHON").unwrap_or_else(|_| "python3".to_string())
}

/// The PyTorch references (2 threads): the LearningToPaint-size network
/// (`benches/ltp_torch.py`) and the generator's forward + VJP (`benches/gen_vjp_torch.py`),
/// when the Python (`$MAOBI_PYTHON` or python3) has torch; rows saying "not run" otherwise.
fn torch_rows(root: &Path) -> String {
    let mut rows = ltp_torch_row(root);
    let script = root.join("crates/neural-gen/benches/gen_vjp_torch.py");
    let out = Command::new(python()).arg(&script).args(["--threads", "2", "--json"]).output();
    let parsed = out
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| serde_json::from_slice::<serde_json::Value>(&o.stdout).ok());
    match parsed {
        Some(v) => rows.push_str(&format!(
            "| generator forward + VJP to the presses, batch 64, PyTorch {} CPU (2 threads) | {} |\n\
             | generator forward alone, batch 64, PyTorch (2 threads) | {} |\n",
            v["torch"].as_str().unwrap_or("?"),
            human(v["forward_vjp_s"].as_f64().unwrap_or(f64::NAN) * 1e9),
            human(v["forward_s"].as_f64().unwrap_or(f64::NAN) * 1e9),
        )),
        None => rows.push_str("| generator forward + VJP, batch 64, PyTorch | not run (no Python with torch) |\n"),
    }
    rows
}

fn ltp_torch_row(root: &Path) -> String {
    let script = root.join("crates/neural-gen/benches/ltp_torch.py");
    let out = Command::new(python()).arg(&script).args(["--threads", "2", "--steps", "10", "--json"]).output();
    let parsed = out
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| serde_json::from_slice::<serde_json::Value>(&o.stdout).ok());
    let Some(v) = parsed else {
        return "| LearningToPaint-size net in PyTorch | not run (python3 with torch not found) |\n".to_string();
    };
    let num = |k: &str| v[k].as_f64().unwrap_or(f64::NAN);
    format!(
        "| LearningToPaint-size net, Adam step, batch 64, PyTorch {} CPU (2 threads) | {} |\n\
         | LearningToPaint-size net, inference, PyTorch | {:.0} img/s at batch 1, {:.0} img/s at batch 64 |\n",
        v["torch"].as_str().unwrap_or("?"),
        human(num("step_s") * 1e9),
        num("inference_b1_img_per_s"),
        num("inference_b64_img_per_s"),
    )
}

/// Runs one criterion benchmark (`bench` of neural-gen, ids matching `filter`) and returns the
/// mean of `id`, ns.
fn criterion_ns(root: &Path, bench: &str, filter: &str, id: &str, quick: bool) -> Result<f64> {
    let mut cmd = Command::new(env!("CARGO"));
    cmd.current_dir(root).args(["bench", "-q", "-p", "neural-gen", "--bench", bench, "--", filter]);
    if quick {
        cmd.args(["--warm-up-time", "1", "--measurement-time", "2"]);
    }
    let st = cmd.status().with_context(|| format!("running the neural-gen {bench} benchmark"))?;
    if !st.success() {
        bail!("cargo bench -p neural-gen --bench {bench} -- {filter} failed");
    }
    estimate_ns(&root.join("target/criterion"), id).with_context(|| format!("no criterion estimate for {id}"))
}

/// Runs a PyTorch reference script with `--json` and the given arguments; `None` when the Python
/// (`$MAOBI_PYTHON` or python3) has no torch or the script fails.
fn torch_json(root: &Path, script: &str, args: &[String]) -> Option<serde_json::Value> {
    let out = Command::new(python())
        .arg(root.join("crates/neural-gen/benches").join(script))
        .args(args)
        .arg("--json")
        .output()
        .ok()
        .filter(|o| o.status.success())?;
    serde_json::from_slice(&out.stdout).ok()
}

/// The 1-minute load average (`/proc/loadavg`), or "?" where there is none.
fn load() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().map(str::to_string))
        .unwrap_or_else(|| "?".to_string())
}

/// One maobi/PyTorch pair: a criterion benchmark and the key of a PyTorch script's JSON (s).
struct Pair {
    label: &'static str,
    bench: &'static str,
    filter: &'static str,
    id: &'static str,
    /// Units of work in one criterion iteration (the figure is per unit: per training step).
    per_iter: f64,
    script: &'static str,
    args: &'static [&'static str],
    key: &'static str,
    /// FLOPs of one unit of work (2 per multiply–add).
    flops: f64,
}

/// One measured pair.
struct Measured {
    maobi_s: f64,
    torch_s: Option<f64>,
    peak: f64,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The machine's peak FP32 rate (FLOP/s): the `peak_fp32` criterion benchmark.
fn peak_flops(root: &Path, quick: bool) -> Result<f64> {
    let peak_id = "peak_fp32/fma_all_threads";
    let peak_ns = criterion_ns(root, "generator", "peak_fp32", peak_id, quick)?;
    // The benchmark's throughput is its FLOP count (lanes × accumulators × iterations × threads × 2).
    let peak_work = std::fs::read_to_string(root.join("target/criterion").join(peak_id).join("new/benchmark.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .and_then(|v| v["throughput"]["Elements"].as_f64())
        .context("no FLOP count in the peak_fp32 benchmark's record")?;
    Ok(peak_work / (peak_ns * 1e-9))
}

/// The generator pairs, interleaved: per round, the peak FP32 rate, then each pair's maobi
/// benchmark and its PyTorch script, at the same thread count; a table row per pair and round
/// with the times, the maobi/PyTorch ratio, each as a fraction of the round's peak, and the
/// load; then per pair the best and the median over the rounds.
fn pairs(root: &Path, quick: bool, rounds: usize) -> Result<String> {
    let threads = std::env::var("RAYON_NUM_THREADS")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
        .filter(|&n| n > 0)
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let pen1 = 2.0 * neural_gen::Arch::default_128().macs_per_image() as f64 * 64.0;
    let ltp = 2.0 * neural_gen::bench::Ltp::MACS_PER_IMAGE as f64 * 64.0;
    // A training step: the forward products, then those for the input and the weight gradients.
    let list = [
        Pair {
            label: "pen1 inference, batch 64",
            bench: "generator",
            filter: "generator_inference/batch_64$",
            id: "generator_inference/batch_64",
            per_iter: 1.0,
            script: "gen_vjp_torch.py",
            args: &["--reps", "10"],
            key: "forward_s",
            flops: pen1,
        },
        Pair {
            label: "pen1 training step (network), batch 64",
            bench: "generator",
            filter: "generator_training/network_step_batch_64$",
            id: "generator_training/network_step_batch_64",
            per_iter: 1.0,
            script: "gen_vjp_torch.py",
            args: &["--reps", "10"],
            key: "train_step_s",
            flops: 3.0 * pen1,
        },
        Pair {
            label: "`maobi train` job per step (targets rendered; PyTorch + OpenCV peer), batch 64",
            bench: "generator",
            filter: "generator_training/train_job_10_steps_batch_64",
            id: "generator_training/train_job_10_steps_batch_64",
            per_iter: 10.0,
            script: "train_torch.py",
            args: &["--steps", "10"],
            key: "step_s",
            flops: 3.0 * pen1,
        },
        Pair {
            label: "LearningToPaint-size training step, batch 64",
            bench: "ltp",
            filter: "ltp_training/step_batch_64_direct",
            id: "ltp_training/step_batch_64_direct",
            per_iter: 1.0,
            script: "ltp_torch.py",
            args: &["--steps", "10"],
            key: "step_s",
            flops: 3.0 * ltp,
        },
    ];
    let targs = |p: &Pair| -> Vec<String> {
        let mut v: Vec<String> = vec!["--threads".into(), threads.to_string()];
        v.extend(p.args.iter().map(|s| s.to_string()));
        v
    };
    let mut table = format!(
        "Pairs at {threads} threads, interleaved (maobi's criterion benchmark, then the PyTorch script), {rounds} rounds\n\n\
         | round | pair | maobi | PyTorch | maobi / PyTorch time | maobi of peak | PyTorch of peak | peak FP32 | load |\n\
         |---|---|---|---|---|---|---|---|---|\n"
    );
    let mut all: Vec<Vec<Measured>> = (0..list.len()).map(|_| Vec::new()).collect();
    for round in 1..=rounds {
        let peak = peak_flops(root, quick)?;
        for (p, seen) in list.iter().zip(&mut all) {
            let before = load();
            let ns = criterion_ns(root, p.bench, p.filter, p.id, quick)?;
            let torch_s = torch_json(root, p.script, &targs(p)).and_then(|v| v[p.key].as_f64());
            let m = ns * 1e-9 / p.per_iter;
            let frac = |s: f64| format!("{:.1} %", 100.0 * p.flops / s / peak);
            let (t_cell, ratio, tf) = match torch_s {
                Some(t) => (human(t * 1e9), format!("{:.2}", m / t), frac(t)),
                None => ("not run (no Python with torch)".to_string(), "–".to_string(), "–".to_string()),
            };
            table.push_str(&format!(
                "| {round} | {} | {} | {t_cell} | {ratio} | {} | {tf} | {:.0} GFLOP/s | {before}–{} |\n",
                p.label,
                human(m * 1e9),
                frac(m),
                peak / 1e9,
                load()
            ));
            seen.push(Measured { maobi_s: m, torch_s, peak });
        }
    }
    table.push_str(
        "\n| pair | maobi best / median | PyTorch best / median | ratio of bests | median of ratios | maobi best of peak |\n\
         |---|---|---|---|---|---|\n",
    );
    for (p, seen) in list.iter().zip(&all) {
        let ms: Vec<f64> = seen.iter().map(|s| s.maobi_s).collect();
        let ts: Vec<f64> = seen.iter().filter_map(|s| s.torch_s).collect();
        let ratios: Vec<f64> = seen.iter().filter_map(|s| s.torch_s.map(|t| s.maobi_s / t)).collect();
        let best_m = ms.iter().copied().fold(f64::INFINITY, f64::min);
        let best_peak = seen.iter().map(|s| s.peak).fold(0.0, f64::max);
        let (t_cell, r_best, r_med) = if ts.is_empty() {
            ("not run".to_string(), "–".to_string(), "–".to_string())
        } else {
            let best_t = ts.iter().copied().fold(f64::INFINITY, f64::min);
            (
                format!("{} / {}", human(best_t * 1e9), human(median(ts.clone()) * 1e9)),
                format!("{:.2}", best_m / best_t),
                format!("{:.2}", median(ratios)),
            )
        };
        table.push_str(&format!(
            "| {} | {} / {} | {t_cell} | {r_best} | {r_med} | {:.1} % |\n",
            p.label,
            human(best_m * 1e9),
            human(median(ms) * 1e9),
            100.0 * p.flops / best_m / best_peak
        ));
    }
    Ok(table)
}
