//! `maobi compare`: similarity of two images.

use std::path::PathBuf;

use anyhow::{Result, bail};

use crate::common::{load_image, print_json};

/// Arguments of `maobi compare`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// First image (PNG/JPEG, dark ink on light paper).
    a: PathBuf,
    /// Second image, same size.
    b: PathBuf,
    /// Print `{"csim","ssim","iou","mse","psnr"}` as JSON (`psnr` is null for identical images).
    #[arg(long)]
    json: bool,
}

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    let a = load_image(&args.a)?;
    let b = load_image(&args.b)?;
    if (a.width(), a.height()) != (b.width(), b.height()) {
        bail!(
            "images differ in size: {} is {}×{}, {} is {}×{}",
            args.a.display(),
            a.width(),
            a.height(),
            args.b.display(),
            b.width(),
            b.height()
        );
    }
    let s = stroke_metrics::compare(a.as_gray(), b.as_gray())?;
    if args.json {
        print_json(&s)?;
    } else {
        let psnr = s.psnr.map_or("inf (identical)".to_string(), |p| format!("{p:.3} dB"));
        crate::outln!("CSIM {:.6}\nSSIM {:.6}\nIoU  {:.6}\nMSE  {:.6e}\nPSNR {psnr}", s.csim, s.ssim, s.iou, s.mse)?;
    }
    Ok(())
}
