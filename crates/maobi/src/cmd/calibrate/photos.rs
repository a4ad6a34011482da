//! The photo path of `maobi calibrate`: fit every labelled photo, keep the good fits, and
//! `measurements.csv`.

use std::path::Path;

use anyhow::Result;
use brush_model::Measurement;
use rayon::prelude::*;

use crate::common::{fit_photo, progress};

/// Fits every photo listed in the labels (in parallel, with a progress bar), lists and drops
/// the poor fits, and returns the measurements and `measurements.csv` (every fit).
pub fn measure(dir: &Path, labels: Option<&Path>, min_iou: f64) -> Result<(Vec<Measurement>, String)> {
    let labels_path = labels.map(Path::to_path_buf).unwrap_or_else(|| dir.join("labels.csv"));
    let labels = stroke_fit::read_labels(&labels_path)?;
    let pb = progress(labels.len() as u64, "fitting");
    let results: Vec<(usize, Result<stroke_fit::StrokeFit>)> = labels
        .par_iter()
        .enumerate()
        .map(|(i, l)| {
            let photo = dir.join(&l.file);
            let what = format!("{}: column `px_per_mm`", labels_path.display());
            let r = fit_photo(&photo, l.px_per_mm, &what).map(|f| f.0);
            pb.inc(1);
            (i, r)
        })
        .collect();
    pb.finish_and_clear();
    let mut fits = Vec::new();
    let mut failed = Vec::new();
    for (i, r) in results {
        match r {
            Ok(f) => fits.push((i, f)),
            Err(e) => failed.push(format!("{e:#}")),
        }
    }
    if !failed.is_empty() {
        eprintln!("left out {} photo(s) that could not be fitted: {}", failed.len(), failed.join("; "));
    }
    let m = stroke_fit::photo_measurements(fits.iter().map(|(i, f)| (&labels[*i], f)), min_iou);
    if !m.poor.is_empty() {
        let poor: Vec<String> = m.poor.iter().map(|(file, iou)| format!("{file} (IoU {iou:.3})")).collect();
        eprintln!("left out {} photo(s) whose fit IoU is below {min_iou}: {}", poor.len(), poor.join(", "));
    }
    eprintln!("fitted {} photo(s), {} used", fits.len(), m.rows.len());
    Ok((m.rows, m.csv))
}
