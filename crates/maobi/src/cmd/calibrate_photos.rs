//! The photo path of `maobi calibrate`: fit every labelled photo, keep the good fits, write
//! `measurements.csv`.

use std::path::Path;

use anyhow::{bail, Context, Result};
use brush_model::{Footprint, Measurement, Press};
use rayon::prelude::*;

use crate::cmd::fit_stroke::{fit_photo, scale_for};
use crate::common::{progress, write_atomic};

struct Label {
    file: String,
    press: Press,
    px_per_mm: Option<f64>,
}

fn read_labels(path: &Path) -> Result<Vec<Label>> {
    let name = path.display().to_string();
    let mut rdr = csv::ReaderBuilder::new().trim(csv::Trim::All).from_path(path).with_context(|| format!("{name}: cannot read"))?;
    let header = rdr.headers().with_context(|| format!("{name}: cannot read the header"))?.clone();
    let col = |c: &str| header.iter().position(|h| h == c);
    let need = |c: &'static str| col(c).with_context(|| format!("{name}: header has no column `{c}` (need file,h_mm,alpha_deg,beta_deg)"));
    let (fi, hi, ai, bi) = (need("file")?, need("h_mm")?, need("alpha_deg")?, need("beta_deg")?);
    let si = col("px_per_mm");
    let mut out = Vec::new();
    for rec in rdr.records() {
        let rec = rec.with_context(|| format!("{name}: malformed CSV"))?;
        let line = rec.position().map_or(0, |p| p.line());
        let num = |i: usize, c: &str| -> Result<f64> {
            let v = rec.get(i).unwrap_or("");
            v.parse::<f64>().ok().filter(|x| x.is_finite()).with_context(|| format!("{name}: line {line}, column `{c}`: expected a number, got {v:?}"))
        };
        let px = match si {
            Some(i) if !rec.get(i).unwrap_or("").is_empty() => Some(num(i, "px_per_mm")?),
            _ => None,
        };
        out.push(Label { file: rec.get(fi).unwrap_or("").to_string(), press: Press::from_degrees(num(hi, "h_mm")?, num(ai, "alpha_deg")?, num(bi, "beta_deg")?), px_per_mm: px });
    }
    if out.is_empty() {
        bail!("{name}: no rows");
    }
    Ok(out)
}

/// Fits every photo listed in the labels (in parallel, with a progress bar), lists and drops
/// the poor fits, writes `measurements.csv` beside `profile_out`, and returns the measurements.
pub fn measure(dir: &Path, labels: Option<&Path>, min_iou: f64, profile_out: &Path) -> Result<Vec<Measurement>> {
    let labels_path = labels.map(Path::to_path_buf).unwrap_or_else(|| dir.join("labels.csv"));
    let labels = read_labels(&labels_path)?;
    let pb = progress(labels.len() as u64, "fitting");
    let results: Vec<(usize, Result<stroke_fit::StrokeFit>)> = labels
        .par_iter()
        .enumerate()
        .map(|(i, l)| {
            let photo = dir.join(&l.file);
            let r = scale_for(&photo, l.px_per_mm).and_then(|scale| Ok(fit_photo(&photo, scale)?.0));
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
    let mut csv = String::from("file,h_mm,alpha_deg,beta_deg,lt_mm,lh_mm,lr_mm,iou\n");
    let mut rows = Vec::new();
    let mut poor = Vec::new();
    for (i, f) in &fits {
        let l = &labels[*i];
        csv.push_str(&format!(
            "{},{},{},{},{:.4},{:.4},{:.4},{:.4}\n",
            l.file,
            l.press.h_mm,
            l.press.alpha_rad.to_degrees(),
            l.press.beta_rad.to_degrees(),
            f.lt_mm,
            f.lh_mm,
            f.lr_mm,
            f.iou
        ));
        if f.iou < min_iou {
            poor.push(format!("{} (IoU {:.3})", l.file, f.iou));
        } else {
            rows.push(Measurement { press: l.press, footprint: Footprint { lt_mm: f.lt_mm, lh_mm: f.lh_mm, lr_mm: f.lr_mm } });
        }
    }
    write_atomic(&profile_out.with_file_name("measurements.csv"), csv.as_bytes())?;
    if !poor.is_empty() {
        eprintln!("left out {} photo(s) whose fit IoU is below {min_iou}: {}", poor.len(), poor.join(", "));
    }
    eprintln!("fitted {} photo(s), {} used", fits.len(), rows.len());
    Ok(rows)
}
