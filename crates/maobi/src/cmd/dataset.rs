//! `maobi dataset`: N random footprints as PNGs plus `labels.csv` (streamed: see [`run`]).

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::PathBuf;

use anyhow::{Context, Result};
use bezier_raster::{Coverage, DatasetSpec, ModelKind, Rasterizer};
use rayon::prelude::*;

use crate::common::{
    BrushArg, OutputLock, Stage, check_output_folder, check_range, interrupted, load_brush, output_is_vacant,
    parse_model, progress, recover_leftovers, test_hook, write_atomic,
};

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
    #[arg(long, default_value = "bsm", value_parser = parse_model())]
    model: ModelKind,
    /// Output folder (created if missing). An existing non-empty folder is refused unless
    /// --force is given.
    #[arg(short, long, visible_alias = "out", value_name = "DIR")]
    output: PathBuf,
    /// Replace an existing output folder that maobi wrote (the new dataset is written beside it
    /// and swapped in once complete; an error or Ctrl-C leaves the old one in place). A folder
    /// holding files maobi did not write (not in its `.maobi-written` list) is refused, naming
    /// them: nothing else is ever deleted.
    #[arg(long)]
    force: bool,
}

/// The most images one run may write.
pub const MAX_IMAGES: u64 = 100_000_000;

/// Images rendered in parallel between two appends to `labels.csv`.
const CHUNK: u64 = 1024;

/// Runs the command.
///
/// Everything is written into a staging folder beside `--output` (`.NAME.maobi-partial-PID`)
/// that replaces it only once complete, so a run never mixes with an older dataset and an error
/// (a full disk) leaves the old folder as it was and no staging folder. `labels.csv` is
/// streamed: it is created first (header only) and, after each chunk of images has been written
/// (each one atomically), that chunk's rows are appended in index order and flushed. Ctrl-C (or
/// SIGTERM) stops at the end of the current image and removes that chunk's images past the last
/// row, leaving a consistent prefix (every row names a complete image and every image has its
/// row); that prefix is installed as `--output` when there was no older dataset there, and
/// discarded when there was one (the old dataset stays); either way the run exits 130 saying
/// `interrupted`. Memory stays at one chunk's rows whatever `--n`.
pub fn run(args: Args) -> Result<()> {
    check_range("--n", args.n, 1, MAX_IMAGES, "images")?;
    check_range("--size", args.size, 8, 4096, "px")?;
    let profile = load_brush(&args.brush.brush)?;
    let spec = DatasetSpec::new(profile, args.size, args.seed);
    let lock = OutputLock::acquire("--output", &args.output)?;
    recover_leftovers(&args.output)?;
    check_output_folder("--output", &args.output, args.force)?;
    let stage = Stage::new(&args.output)?;
    let dir = stage.path().to_path_buf();
    let labels_path = dir.join("labels.csv");
    let mut labels = std::io::BufWriter::new(
        std::fs::File::create(&labels_path).with_context(|| format!("cannot write {}", labels_path.display()))?,
    );
    let write_err = || format!("cannot write {}", labels_path.display());
    labels.write_all(DatasetSpec::labels_header().as_bytes()).and_then(|()| labels.flush()).with_context(write_err)?;
    crate::common::stop_on_interrupt();
    let digits = (args.n - 1).to_string().len().max(6);
    let file_name = |i: u64| format!("fp_{i:0digits$}.png");
    let pb = progress(args.n, "dataset");
    let started = std::time::Instant::now();
    let mut start = 0;
    while start < args.n {
        let end = (start + CHUNK).min(args.n);
        // None: skipped because of Ctrl-C.
        let rows = render_chunk(&args, &spec, &dir, start..end, &file_name, &pb)?;
        // Rows in index order up to the first image not written; later images of this chunk
        // (finished by other threads after Ctrl-C) are removed so the folder matches the labels.
        let done = rows.iter().take_while(|r| r.is_some()).count();
        for r in rows.iter().take(done).flatten() {
            labels.write_all(r.as_bytes()).with_context(write_err)?;
        }
        labels.flush().with_context(write_err)?;
        if done < rows.len() {
            for (k, r) in rows.iter().enumerate().skip(done) {
                if r.is_some() {
                    let _ = std::fs::remove_file(dir.join(file_name(start + k as u64)));
                }
            }
            pb.finish_and_clear();
            drop(labels);
            let written = start + done as u64;
            if output_is_vacant(&args.output) {
                stage.install("--output", &args.output, false)?;
                eprintln!(
                    "error: interrupted: {written} of {} images written to {}, labels.csv lists exactly those",
                    args.n,
                    args.output.display()
                );
            } else {
                drop(stage);
                eprintln!(
                    "error: interrupted after {written} of {} images; {} keeps the older dataset, the new one was removed",
                    args.n,
                    args.output.display()
                );
            }
            drop(lock);
            std::process::exit(130);
        }
        start = end;
    }
    pb.finish_and_clear();
    drop(labels);
    stage.install("--output", &args.output, args.force)?;
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

/// Renders and writes images `range` in parallel; each one's labels.csv row, or `None` when
/// skipped because of Ctrl-C.
fn render_chunk(
    args: &Args,
    spec: &DatasetSpec,
    dir: &std::path::Path,
    range: std::ops::Range<u64>,
    file_name: &(dyn Fn(u64) -> String + Sync),
    pb: &crate::common::Progress,
) -> Result<Vec<Option<String>>> {
    range
        .into_par_iter()
        .map_init(
            || (Rasterizer::new(), Coverage::new(args.size, args.size)),
            |(raster, img), i| -> Result<Option<String>> {
                if interrupted() {
                    return Ok(None);
                }
                let s = spec.sample(i)?;
                spec.render(&s, args.model.model(), raster, img);
                let file = file_name(i);
                if i == 700 {
                    test_hook("dataset-image-700")?;
                }
                write_atomic(&dir.join(&file), &img.encode_png()?)?;
                pb.inc(1);
                Ok(Some(spec.label_row(&file, &s)))
            },
        )
        .collect()
}
