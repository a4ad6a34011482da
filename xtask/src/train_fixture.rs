//! `cargo xtask train-fixture`: trains the committed pen1 generator with the recorded recipe.

use std::process::Command;

use anyhow::{Result, bail};

use crate::fixtures::root;

/// The recipe of `crates/neural-gen/data/pen1.safetensors`.
pub const RECIPE: &[&str] =
    &["--brush", "pen1", "--steps", "2500", "--batch", "64", "--lr", "2e-3", "--seed", "1", "--eval-n", "500"];

/// Builds `maobi` in release and trains.
pub fn run(args: &[String]) -> Result<()> {
    if let Some(a) = args.first() {
        bail!("train-fixture: unexpected argument `{a}`");
    }
    let root = root();
    let st =
        Command::new(env!("CARGO")).current_dir(&root).args(["build", "--release", "-q", "-p", "maobi"]).status()?;
    if !st.success() {
        bail!("building maobi failed");
    }
    let st = Command::new(root.join("target/release/maobi"))
        .current_dir(&root)
        .arg("train")
        .args(RECIPE)
        .args(["-o", "crates/neural-gen/data/pen1.safetensors", "--force"])
        .status()?;
    if !st.success() {
        bail!("training failed");
    }
    println!(
        "trained crates/neural-gen/data/pen1.safetensors (+ .json, loss.csv, loss.png); rebuild maobi to embed it, then `cargo xtask gates --update` if its figures moved"
    );
    Ok(())
}
