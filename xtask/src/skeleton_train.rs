//! `cargo xtask skeleton-train`: trains the skeleton's two learned decisions, junction pairing
//! and corner splitting (`crates/trajectory/data/skeleton-models.json`,
//! [`trajectory::SkeletonModels`]), on hanzi-writer characters that are neither embedded nor in
//! `fixtures/hanzi/heldout-2000.txt`, with labels from each glyph's own medians
//! ([`trajectory::Skeleton::pair_samples`], [`trajectory::Skeleton::corner_samples`]).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use rayon::prelude::*;
use trajectory::{
    CORNER_FEATURE_NAMES, DEFAULT_ANALYSIS_PX, DecisionModel, FEATURE_NAMES, GraphOptions, Skeleton, SkeletonModels,
    embedded_chars, glyph_from_hanzi_dir,
};

use crate::io::{char_bar, write_atomic};
use numerics::SplitMix64 as SplitMix;

const HELP: &str = "\
cargo xtask skeleton-train --hanzi-data DIR [--out FILE] [--hidden H] [--epochs E] [--every K]
                           [--heldout FILE]

Trains the skeleton's junction pairing model, then its corner model (on chains as the new
pairing model makes them), and writes both (default crates/trajectory/data/skeleton-models.json,
compiled into the trajectory crate: rebuild to use them).

Training set: every character with a file <char>.json in DIR (hanzi-writer-data), minus the
embedded subset, minus every character of --heldout (default fixtures/hanzi/heldout-2000.txt,
both its tuning and its report half), in code-point order, every K-th (--every, default 1).
Samples: every candidate pair of branch ends at every skeleton junction, then every corner of
every chain, labelled from the glyph's medians; one character in five is kept aside to report
validation accuracy. The model: standardised features, one hidden
layer of H tanh units (--hidden, default 12; 0: logistic regression), trained with Adam on
minibatches for E epochs (--epochs, default 30), seed fixed: the same inputs give the same file.

  cargo xtask skeleton-train --hanzi-data /path/to/hanzi-writer-data
";

/// Runs the task with its arguments (after `skeleton-train`).
pub fn run(args: &[String]) -> Result<()> {
    let mut hanzi: Option<PathBuf> = None;
    let mut out = PathBuf::from("crates/trajectory/data/skeleton-models.json");
    let mut heldout = PathBuf::from("fixtures/hanzi/heldout-2000.txt");
    let (mut hidden, mut epochs, mut every) = (12usize, 30usize, 1usize);
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().with_context(|| format!("{a} needs a value"));
        match a.as_str() {
            "--help" | "-h" => {
                print!("{HELP}");
                return Ok(());
            }
            "--hanzi-data" => hanzi = Some(PathBuf::from(val()?)),
            "--out" => out = PathBuf::from(val()?),
            "--heldout" => heldout = PathBuf::from(val()?),
            "--hidden" => hidden = val()?.parse().context("--hidden")?,
            "--epochs" => epochs = val()?.parse().context("--epochs")?,
            "--every" => every = val()?.parse::<usize>().context("--every")?.max(1),
            other => bail!("unknown argument `{other}`\n\n{HELP}"),
        }
    }
    let dir = hanzi.context("--hanzi-data DIR is required (hanzi-writer-data, files <char>.json)")?;
    let chars = training_chars(&dir, &heldout, every)?;
    eprintln!("training set: {} characters", chars.len());
    // Chains for the corner samples as the new pairing model makes them at probability 0.5 (the
    // skeleton's own threshold is tuned afterwards, GraphOptions::pair_threshold).
    let opts = GraphOptions { pair_threshold: 0.5, ..GraphOptions::default() };
    let pair_samples = collect(&dir, &chars, "pairs", |sk, medians| {
        sk.pair_samples(&opts, medians).into_iter().filter_map(|p| Some((p.features.to_vec(), p.label?))).collect()
    })?;
    let (pairs, pairs_note) = train("pairs", &FEATURE_NAMES, "rule_pair", pair_samples, hidden, epochs)?;
    let corner_samples = collect(&dir, &chars, "corners", |sk, medians| {
        sk.corner_samples(&opts, Some(&pairs), medians)
            .into_iter()
            .filter_map(|p| Some((p.features.to_vec(), p.label?)))
            .collect()
    })?;
    let (corners, corners_note) =
        train("corners", &CORNER_FEATURE_NAMES, "rule_split", corner_samples, hidden, epochs)?;
    let models = SkeletonModels {
        about: format!(
            "Skeleton junction pairing and corner models (trajectory::SkeletonModels), written by `cargo xtask \
             skeleton-train --hanzi-data DIR --hidden {hidden} --epochs {epochs} --every {every}` from \
             hanzi-writer-data 2.0.1. Training set: its characters minus the embedded subset minus every \
             character of {} ({} characters, code-point order). Pairs: {pairs_note}. Corners: {corners_note}.",
            heldout.display(),
            chars.len(),
        ),
        pairs,
        corners,
    };
    let json = serde_json::to_string_pretty(&models)?;
    SkeletonModels::from_json(&json).context("the trained models do not read back")?;
    write_atomic(&out, json.as_bytes())?;
    eprintln!("wrote {} (rebuild the trajectory crate to use it)", out.display());
    Ok(())
}

/// A labelled sample: character index, features, label.
type Sample = (usize, Vec<f64>, bool);

/// Fits one model on `samples` (one character in five kept aside) and says how it did.
fn train(
    what: &str,
    names: &[&str],
    rule_feature: &str,
    samples: Vec<Sample>,
    hidden: usize,
    epochs: usize,
) -> Result<(DecisionModel, String)> {
    let (train, val): (Vec<_>, Vec<_>) = samples.into_iter().partition(|(k, _, _)| k % 5 != 0);
    let to_xy = |s: Vec<Sample>| -> (Vec<Vec<f64>>, Vec<bool>) { s.into_iter().map(|(_, x, y)| (x, y)).unzip() };
    let ((xt, yt), (xv, yv)) = (to_xy(train), to_xy(val));
    if xt.is_empty() {
        bail!("{what}: no training samples");
    }
    let positives = yt.iter().filter(|&&y| y).count();
    eprintln!("{what}: {} training samples ({positives} positive), {} validation", xt.len(), xv.len());
    let model = fit(names, &xt, &yt, hidden, epochs);
    let acc = |xs: &[Vec<f64>], ys: &[bool]| {
        xs.iter().zip(ys).filter(|(x, y)| (model.probability(x) >= model.threshold) == **y).count() as f64
            / xs.len().max(1) as f64
    };
    let rule = names.iter().position(|&f| f == rule_feature).context("rule feature")?;
    let rule_acc = xv.iter().zip(&yv).filter(|(x, y)| (x[rule] > 0.5) == **y).count() as f64 / xv.len().max(1) as f64;
    let (ta, va) = (acc(&xt, &yt), acc(&xv, &yv));
    let note = format!(
        "{} training and {} validation samples (one character in five kept aside), accuracy training {ta:.4}, \
         validation {va:.4}, hand rules on validation {rule_acc:.4}",
        xt.len(),
        xv.len()
    );
    eprintln!("{what}: {note}");
    Ok((model, note))
}

/// The training characters (see [`HELP`]).
fn training_chars(dir: &Path, heldout: &Path, every: usize) -> Result<Vec<char>> {
    let mut excluded: std::collections::HashSet<char> = embedded_chars().into_iter().collect();
    let text = std::fs::read_to_string(heldout).with_context(|| format!("--heldout {}", heldout.display()))?;
    excluded.extend(text.lines().filter(|l| !l.starts_with('#')).filter_map(|l| l.trim().chars().next()));
    let mut chars: Vec<char> = std::fs::read_dir(dir)
        .with_context(|| format!("--hanzi-data {}", dir.display()))?
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            let name = e.file_name().into_string().ok()?;
            let stem = name.strip_suffix(".json")?;
            let mut cs = stem.chars();
            let c = cs.next()?;
            (cs.next().is_none() && !excluded.contains(&c)).then_some(c)
        })
        .collect();
    chars.sort_unstable();
    let chars: Vec<char> = chars.into_iter().step_by(every).collect();
    if chars.is_empty() {
        bail!("--hanzi-data {}: no training characters (files <char>.json)", dir.display());
    }
    Ok(chars)
}

/// Labelled samples of every character (`samples` of its skeleton and medians, em frame).
fn collect(
    dir: &Path,
    chars: &[char],
    what: &str,
    samples: impl Fn(&Skeleton, &[Vec<kurbo::Point>]) -> Vec<(Vec<f64>, bool)> + Sync,
) -> Result<Vec<Sample>> {
    let pb = char_bar(chars.len(), what);
    let per_char: Vec<Vec<Sample>> = chars
        .par_iter()
        .enumerate()
        .map(|(k, &c)| -> Result<_> {
            let g = glyph_from_hanzi_dir(dir, c).with_context(|| format!("{c}"))?;
            let medians = g.medians.clone().unwrap_or_default();
            let out = match Skeleton::of(&g, DEFAULT_ANALYSIS_PX) {
                Some(s) => samples(&s, &medians).into_iter().map(|(x, y)| (k, x, y)).collect(),
                None => Vec::new(),
            };
            pb.inc(1);
            Ok(out)
        })
        .collect::<Result<_>>()?;
    pb.finish_and_clear();
    Ok(per_char.into_iter().flatten().collect())
}

/// Adam on minibatches of the logistic loss (with a little L2 on the weights).
fn fit(names: &[&str], xs: &[Vec<f64>], ys: &[bool], hidden: usize, epochs: usize) -> DecisionModel {
    let f_len = names.len();
    const BATCH: usize = 256;
    const LR: f64 = 0.005;
    const L2: f64 = 1e-4;
    let n = xs.len() as f64;
    let mean: Vec<f64> = (0..f_len).map(|k| xs.iter().map(|x| x[k]).sum::<f64>() / n).collect();
    let scale: Vec<f64> =
        (0..f_len).map(|k| (xs.iter().map(|x| (x[k] - mean[k]).powi(2)).sum::<f64>() / n).sqrt().max(1e-6)).collect();
    let z: Vec<Vec<f64>> = xs.iter().map(|x| (0..f_len).map(|k| (x[k] - mean[k]) / scale[k]).collect()).collect();
    let mut rng = SplitMix(0x5EED_0015);
    // Parameters flattened: hidden rows (H·f_len), hidden biases (H), out (H or f_len), out bias.
    let h = hidden;
    let n_out = if h == 0 { f_len } else { h };
    let mut p: Vec<f64> = Vec::new();
    for _ in 0..h * f_len {
        p.push(rng.normal() / (f_len as f64).sqrt());
    }
    p.extend(std::iter::repeat_n(0.0, h));
    for _ in 0..n_out {
        p.push(if h == 0 { 0.0 } else { rng.normal() / (h as f64).sqrt() });
    }
    p.push(0.0);
    let (mut m1, mut m2) = (vec![0.0; p.len()], vec![0.0; p.len()]);
    let mut order: Vec<usize> = (0..z.len()).collect();
    let mut step = 0i32;
    for epoch in 0..epochs {
        // Fisher–Yates with the fixed generator.
        for i in (1..order.len()).rev() {
            order.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
        }
        let mut loss = 0.0;
        for batch in order.chunks(BATCH) {
            let mut grad = vec![0.0; p.len()];
            for &i in batch {
                let (x, y) = (&z[i], f64::from(u8::from(ys[i])));
                let a: Vec<f64> = (0..h)
                    .map(|u| {
                        (p[u * f_len..(u + 1) * f_len].iter().zip(x).map(|(w, v)| w * v).sum::<f64>()
                            + p[h * f_len + u])
                            .tanh()
                    })
                    .collect();
                let feats: &[f64] = if h == 0 { x } else { &a };
                let o0 = h * f_len + h;
                let logit = p[o0..o0 + n_out].iter().zip(feats).map(|(w, v)| w * v).sum::<f64>() + p[o0 + n_out];
                let q = 1.0 / (1.0 + (-logit).exp());
                loss -= if y > 0.5 { q.max(1e-12).ln() } else { (1.0 - q).max(1e-12).ln() };
                let d = q - y;
                for k in 0..n_out {
                    grad[o0 + k] += d * feats[k];
                }
                grad[o0 + n_out] += d;
                for u in 0..h {
                    let du = d * p[o0 + u] * (1.0 - a[u] * a[u]);
                    for k in 0..f_len {
                        grad[u * f_len + k] += du * x[k];
                    }
                    grad[h * f_len + u] += du;
                }
            }
            step += 1;
            let b = batch.len() as f64;
            for k in 0..p.len() {
                let g = grad[k] / b + L2 * p[k];
                m1[k] = 0.9 * m1[k] + 0.1 * g;
                m2[k] = 0.999 * m2[k] + 0.001 * g * g;
                let (c1, c2) = (1.0 - 0.9f64.powi(step), 1.0 - 0.999f64.powi(step));
                p[k] -= LR * (m1[k] / c1) / ((m2[k] / c2).sqrt() + 1e-8);
            }
        }
        if epoch % 5 == 4 || epoch + 1 == epochs {
            eprintln!("epoch {}: mean loss {:.4}", epoch + 1, loss / n);
        }
    }
    let o0 = h * f_len + h;
    DecisionModel {
        about: String::new(),
        features: names.iter().map(|s| s.to_string()).collect(),
        mean,
        scale,
        hidden: (0..h).map(|u| p[u * f_len..(u + 1) * f_len].to_vec()).collect(),
        hidden_bias: p[h * f_len..h * f_len + h].to_vec(),
        out: p[o0..o0 + n_out].to_vec(),
        out_bias: p[o0 + n_out],
        threshold: 0.5,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    /// Bad input is refused with a message naming the argument, and nothing is written.
    #[test]
    fn bad_input_names_the_argument_and_writes_nothing() {
        let tmp = std::env::temp_dir().join(format!("maobi-skeleton-train-{}", std::process::id()));
        std::fs::create_dir_all(&tmp).unwrap();
        let out = tmp.join("models.json");
        let heldout = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/hanzi/heldout-2000.txt");
        let (o, h) = (out.to_str().unwrap(), heldout.to_str().unwrap());
        let err = |v: &[&str]| format!("{:#}", run(&args(v)).unwrap_err());

        assert!(err(&["--out", o]).contains("--hanzi-data DIR is required"));
        assert!(err(&["--hanzi-data"]).contains("--hanzi-data needs a value"));
        assert!(err(&["--bogus"]).contains("unknown argument `--bogus`"));
        assert!(err(&["--hidden", "many"]).contains("--hidden"));
        let missing = tmp.join("no-such-dir");
        let e = err(&["--hanzi-data", missing.to_str().unwrap(), "--heldout", h, "--out", o]);
        assert!(e.contains("--hanzi-data") && e.contains("no-such-dir"), "{e}");
        // A folder without <char>.json files: no training characters.
        let e = err(&["--hanzi-data", tmp.to_str().unwrap(), "--heldout", h, "--out", o]);
        assert!(e.contains("no training characters"), "{e}");
        let e = err(&["--hanzi-data", tmp.to_str().unwrap(), "--heldout", "/no/such/heldout.txt", "--out", o]);
        assert!(e.contains("--heldout /no/such/heldout.txt"), "{e}");
        assert!(!out.exists());
        let temporary =
            |e: std::io::Result<std::fs::DirEntry>| e.unwrap().file_name().to_string_lossy().starts_with(".tmp");
        assert!(!std::fs::read_dir(out.parent().unwrap()).unwrap().any(temporary));
        std::fs::remove_dir_all(&tmp).unwrap();
    }
}
