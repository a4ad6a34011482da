//! `maobi dataset`: N random footprints as PNGs plus `labels.csv`.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use bezier_raster::{Coverage, DatasetSpec, ModelKind, Rasterizer};
use rayon::prelude::*;

use crate::common::{BrushArg, load_brush, parse_model, progress, write_atomic};

/// Arguments of `maobi dataset`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Number of images.
    #[arg(long)]
    n: u64,
    /// Canvas side, px.
    #[arg(long, default_value_t = 128)]
    size: u32,
    #[command(flatten)]
    brush: BrushArg,
    /// Random seed: the same seed gives the same dataset, whatever the thread count.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Stroke model to draw with.
    #[arg(long, default_value = "bsm", value_parser = parse_model)]
    model: ModelKind,
    /// Output folder (created if missing).
    #[arg(short, long)]
    output: PathBuf,
}

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    if args.n == 0 {
        bail!("--n 0: expected at least one image");
    }
    if !(8..=4096).contains(&args.size) {
        bail!("--size {}: expected a canvas side between 8 and 4096 px", args.size);
    }
    let profile = load_brush(&args.brush.brush)?;
    let spec = DatasetSpec::new(profile, args.size, args.seed);
    std::fs::create_dir_all(&args.output).with_context(|| format!("cannot create folder {}", args.output.display()))?;
    let digits = (args.n - 1).to_string().len().max(6);
    let pb = progress(args.n, "dataset");
    let started = std::time::Instant::now();
    let rows: Vec<String> = (0..args.n)
        .into_par_iter()
        .map_init(
            || (Rasterizer::new(), Coverage::new(args.size, args.size)),
            |(raster, img), i| -> Result<String> {
                let s = spec.sample(i)?;
                spec.render(&s, args.model.model(), raster, img);
                let file = format!("fp_{i:0digits$}.png");
                write_atomic(&args.output.join(&file), &img.encode_png()?)?;
                pb.inc(1);
                let (p, f) = (s.press, s.footprint);
                Ok(format!(
                    "{file},{},{},{},{},{},{},{},{},{}\n",
                    p.h_mm,
                    p.alpha_rad.to_degrees(),
                    p.beta_rad.to_degrees(),
                    f.lt_mm,
                    f.lh_mm,
                    f.lr_mm,
                    spec.canvas.px_per_mm,
                    s.anchor_px[0],
                    s.anchor_px[1]
                ))
            },
        )
        .collect::<Result<_>>()?;
    pb.finish_and_clear();
    let mut csv = String::from("file,h_mm,alpha_deg,beta_deg,lt_mm,lh_mm,lr_mm,px_per_mm,anchor_u,anchor_v\n");
    for r in rows {
        csv.push_str(&r);
    }
    write_atomic(&args.output.join("labels.csv"), csv.as_bytes())?;
    let secs = started.elapsed().as_secs_f64();
    let mut msg = String::new();
    let _ = write!(
        msg,
        "wrote {} images ({}×{}, model {}) and labels.csv to {} in {:.2} s ({:.0} images/s)",
        args.n,
        args.size,
        args.size,
        args.model.name(),
        args.output.display(),
        secs,
        args.n as f64 / secs
    );
    eprintln!("{msg}");
    Ok(())
}
