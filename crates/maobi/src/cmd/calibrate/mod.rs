//! `maobi calibrate`: measurements → regression → brush profile.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use brush_model::{BrushProfile, Form, PressRanges, load_measurements};

use crate::common::{FileSet, check_output_file, check_range, install_files, load_brush, print_json};

mod photos;
mod sheet_photo;

/// Arguments of `maobi calibrate`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Measurements CSV with columns h_mm,alpha_deg,beta_deg,lt_mm,lh_mm,lr_mm (any order).
    #[arg(required_unless_present_any = ["images", "sheet_photo"], conflicts_with_all = ["images", "sheet_photo"])]
    measurements: Option<PathBuf>,
    /// Calibrate from stroke photos in this folder instead (see --labels).
    #[arg(long, conflicts_with = "sheet_photo")]
    images: Option<PathBuf>,
    /// Calibrate from one photo of a calibration sheet (`maobi calibrate-sheet`) pressed by the
    /// robot; needs --layout and -o (measurements.csv and regression.png go beside the profile).
    #[arg(long, value_name = "PHOTO", requires = "layout")]
    sheet_photo: Option<PathBuf>,
    /// The calibration sheet's folder (or its layout.json) the photo shows.
    #[arg(long, value_name = "CAL", requires = "sheet_photo")]
    layout: Option<PathBuf>,
    /// Labels of the photos: `file,h_mm,alpha_deg,beta_deg` (optional `px_per_mm`); default
    /// `<images>/labels.csv`.
    #[arg(long, requires = "images")]
    labels: Option<PathBuf>,
    /// Photos (or sheet presses) whose fit IoU is below this are listed and left out.
    #[arg(long, default_value_t = 0.9)]
    min_iou: f64,
    /// Regression form: `general` (Eq. 6, one model per length) or `paper` (Eq. 1–5).
    #[arg(long, value_enum, default_value_t = FormArg::General)]
    form: FormArg,
    /// Write the calibrated profile (JSON) here.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Brush whose length and radius the profile records: pen1, pen2 or a profile JSON
    /// (default: with --sheet-photo the brush the sheet was made for, otherwise pen1).
    #[arg(long)]
    brush: Option<String>,
    /// Name of the new profile (default: the output file's stem, e.g. `pen1-cal` for
    /// `-o pen1-cal.json`).
    #[arg(long)]
    name: Option<String>,
    /// Print the fit report as JSON instead of a table.
    #[arg(long)]
    json: bool,
    /// Replace the output files if they exist (without it, an existing file is refused).
    #[arg(long)]
    force: bool,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum FormArg {
    General,
    Paper,
}

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    check_range("--min-iou", args.min_iou, 0.0, 1.0, "")?;
    if let Some(out) = &args.output {
        check_output_file("-o", out, args.force)?;
        if args.images.is_some() || args.sheet_photo.is_some() {
            for beside in ["measurements.csv", "regression.png"] {
                check_output_file("-o (beside it)", &out.with_file_name(beside), args.force)?;
            }
        }
    }
    let (rows, source, photo_csv, sheet_brush) = measurements(&args)?;
    let form = match args.form {
        FormArg::General => Form::General,
        FormArg::Paper => Form::Paper,
    };
    let report = brush_model::fit(&rows, form).with_context(|| format!("{}: cannot fit", source.display()))?;
    for (name, o) in &report.outputs {
        if o.is_constant() {
            eprintln!(
                "warning: {}: {name} is constant in the data ({:.4} mm): R² is undefined and the profile predicts that constant",
                source.display(),
                o.coef.intercept
            );
        }
    }
    let brush = match (&args.brush, sheet_brush) {
        (Some(b), _) => load_brush(b)?.brush,
        (None, Some(b)) => b,
        (None, None) => load_brush("pen1")?.brush,
    };
    let ranges = PressRanges::spanning(&rows);
    // Named after the file it is written to (`-o out/pen1-cal.json` → `pen1-cal`), so the name
    // and the file agree; without -o after the input.
    let name = args.name.clone().unwrap_or_else(|| {
        args.output
            .as_deref()
            .unwrap_or(&source)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "calibrated".into())
    });
    if let Some(out) = &args.output {
        let profile = BrushProfile::calibrated(&name, brush, ranges, report.clone());
        profile
            .validate(&format!("the profile fitted from {}", source.display()))
            .with_context(|| format!("not writing {}: the fitted model is not a usable profile", out.display()))?;
        // Every file's bytes first, then all replaced together: a failure writes nothing.
        let (csv, plot) = (out.with_file_name("measurements.csv"), out.with_file_name("regression.png"));
        let mut files = FileSet::new();
        let photos = photo_csv.is_some();
        if let Some(text) = photo_csv {
            files.add(&csv, text.into_bytes());
            files.add(&plot, figures::regression_png(&rows, &profile)?);
        }
        files.add(out, profile.to_json().into_bytes());
        install_files(files, "calibrate-install")?;
        if photos {
            eprintln!("wrote {} and {}", csv.display(), plot.display());
        }
    }
    if args.json {
        print_json(&report)?;
        if let Some(out) = &args.output {
            eprintln!("profile `{name}` written to {}", out.display());
        }
    } else {
        crate::out!("{report}")?;
        if let Some(out) = &args.output {
            crate::outln!("\nprofile `{name}` written to {}", out.display())?;
        }
    }
    Ok(())
}

/// The measurements the flags give, where they came from, for photos their measurements.csv
/// (written once the fit is accepted: a refused fit writes nothing) and for a sheet photo the
/// brush the sheet was made for.
type Measured = (Vec<brush_model::Measurement>, PathBuf, Option<String>, Option<brush_model::Brush>);

/// The measurements the flags name ([`Measured`]).
fn measurements(args: &Args) -> Result<Measured> {
    Ok(match (&args.measurements, &args.images) {
        (Some(m), _) => (load_measurements(m)?, m.clone(), None, None),
        (None, None) if args.sheet_photo.is_some() => {
            let (photo, cal) = (args.sheet_photo.as_ref().expect("matched"), args.layout.as_ref().expect("clap"));
            args.output
                .as_ref()
                .context("--sheet-photo needs -o PROFILE.json (measurements.csv and regression.png go beside it)")?;
            let (rows, csv, brush) = sheet_photo::measure(photo, cal, args.min_iou)?;
            (rows, photo.clone(), Some(csv), Some(brush))
        }
        (None, Some(dir)) => {
            args.output
                .as_ref()
                .context("--images needs -o PROFILE.json (measurements.csv and regression.png go beside it)")?;
            let (rows, csv) = photos::measure(dir, args.labels.as_deref(), args.min_iou)?;
            (rows, dir.clone(), Some(csv), None)
        }
        (None, None) => bail!("give a measurements CSV, --images DIR or --sheet-photo PHOTO --layout CAL"),
    })
}
