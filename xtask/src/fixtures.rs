//! `cargo xtask fixtures [--check]`: every generated file under `fixtures/`, made
//! deterministically from code in this module.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use brush_model::{BrushProfile, Extrapolation, Press};

use crate::rng::SplitMix;

/// One generated file.
struct Fixture {
    /// Path relative to the repository root.
    path: &'static str,
    /// What it holds, for the listing.
    about: &'static str,
    /// Produces its bytes.
    generate: fn() -> Result<Vec<u8>>,
}

fn all() -> Vec<Fixture> {
    vec![Fixture {
        path: "fixtures/measurements/pen1-sample.csv",
        about: "synthetic pen1 measurements on the paper's grid (nominal model + 0.15 mm noise)",
        generate: sample_measurements,
    }]
}

/// The repository root (xtask's parent folder).
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("xtask has a parent").to_path_buf()
}

pub fn run(args: &[String]) -> Result<()> {
    let check = args.iter().any(|a| a == "--check");
    if let Some(bad) = args.iter().find(|a| *a != "--check") {
        anyhow::bail!("fixtures: unknown argument `{bad}` (expected --check)");
    }
    let root = root();
    let mut differ = Vec::new();
    for f in all() {
        let bytes = (f.generate)().with_context(|| format!("generating {}", f.path))?;
        let path = root.join(f.path);
        if check {
            match std::fs::read(&path) {
                Ok(old) if old == bytes => println!("ok       {}", f.path),
                Ok(_) => {
                    println!("DIFFERS  {}", f.path);
                    differ.push(f.path);
                }
                Err(_) => {
                    println!("MISSING  {}", f.path);
                    differ.push(f.path);
                }
            }
        } else {
            std::fs::create_dir_all(path.parent().expect("fixture has a folder"))?;
            std::fs::write(&path, &bytes).with_context(|| format!("writing {}", path.display()))?;
            println!("wrote    {}  ({})", f.path, f.about);
        }
    }
    if !differ.is_empty() {
        anyhow::bail!(
            "{} fixture(s) differ from what the generators produce now: {}; run `cargo xtask fixtures` and review the diff",
            differ.len(),
            differ.join(", ")
        );
    }
    Ok(())
}

fn sample_measurements() -> Result<Vec<u8>> {
    let pen1 = BrushProfile::builtin("pen1")?;
    let mut rng = SplitMix(0x6d61_6f62_6931);
    let mut s = String::from("h_mm,alpha_deg,beta_deg,lt_mm,lh_mm,lr_mm\n");
    for h in [11.0, 13.0, 15.0, 17.0, 20.0] {
        for a in [0.0, 5.0, 10.0] {
            for b in [0.0, 5.0] {
                for _ in 0..3 {
                    let f = pen1.predict(&Press::from_degrees(h, a, b), Extrapolation::Refuse)?;
                    let mut noisy = |v: f64| v + 0.15 * rng.normal();
                    let (lt, lh, lr) = (noisy(f.lt_mm), noisy(f.lh_mm), noisy(f.lr_mm));
                    s.push_str(&format!("{h},{a},{b},{lt:.3},{lh:.3},{lr:.3}\n"));
                }
            }
        }
    }
    Ok(s.into_bytes())
}
