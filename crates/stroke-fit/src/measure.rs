//! Fitted stroke photos as calibration measurements: the rows a fit keeps and the
//! `measurements.csv` that records every fit.

use brush_model::{MEASUREMENT_COLUMNS, Measurement, measurement_fields};

use crate::{StrokeFit, StrokeLabel};

/// The calibration measurements of fitted stroke photos ([`photo_measurements`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PhotoMeasurements {
    /// A measurement (the label's press, the fitted footprint) per fit whose IoU reaches the
    /// minimum, in the order given: what `brush_model::fit` takes.
    pub rows: Vec<Measurement>,
    /// `measurements.csv`: the header `file,` [`MEASUREMENT_COLUMNS`] `,iou` and a row per fit,
    /// the ones left out too (the fitted lengths and the IoU to 4 decimals).
    pub csv: String,
    /// The fits left out because their IoU is under the minimum: the photo's file and its IoU.
    pub poor: Vec<(String, f64)>,
}

/// The measurements of fitted photos, each with its label: fits whose IoU (outline against
/// ink) is under `min_iou` are recorded in the CSV but left out of the rows.
///
/// # Examples
/// ```
/// use stroke_fit::{StrokeFit, StrokeLabel, photo_measurements};
/// let label = StrokeLabel { file: "a.png".into(), press: stroke_fit::brush_model::Press::new(3.0, 0.0, 0.0), px_per_mm: None };
/// let fit = StrokeFit { lt_mm: 6.0, lh_mm: 2.0, lr_mm: 1.5, anchor_mm: [0.0, 0.0], beta_rad: 0.0, iou: 0.95 };
/// let m = photo_measurements([(&label, &fit)], 0.9);
/// assert_eq!(m.rows.len(), 1);
/// assert!(m.csv.starts_with("file,h_mm,") && m.csv.ends_with(",0.9500\n"));
/// assert_eq!(photo_measurements([(&label, &fit)], 0.99).poor, [("a.png".to_string(), 0.95)]);
/// ```
pub fn photo_measurements<'a>(
    fits: impl IntoIterator<Item = (&'a StrokeLabel, &'a StrokeFit)>,
    min_iou: f64,
) -> PhotoMeasurements {
    let mut csv = format!("file,{MEASUREMENT_COLUMNS},iou\n");
    let (mut rows, mut poor) = (Vec::new(), Vec::new());
    for (l, f) in fits {
        let m = Measurement { press: l.press, footprint: f.footprint() };
        csv.push_str(&format!("{},{},{:.4}\n", l.file, measurement_fields(&m, Some(4)), f.iou));
        if f.iou < min_iou {
            poor.push((l.file.clone(), f.iou));
        } else {
            rows.push(m);
        }
    }
    PhotoMeasurements { rows, csv, poor }
}

#[cfg(test)]
mod tests {
    use super::*;
    use brush_model::Press;

    fn fit(lt_mm: f64, iou: f64) -> StrokeFit {
        StrokeFit { lt_mm, lh_mm: 2.0, lr_mm: 1.25, anchor_mm: [1.0, 2.0], beta_rad: 0.5, iou }
    }

    #[test]
    fn poor_fits_are_recorded_but_not_measured() {
        let label =
            |file: &str, h_mm| StrokeLabel { file: file.into(), press: Press::new(h_mm, 0.0, 0.0), px_per_mm: None };
        let (a, b, c) = (label("a.png", 2.0), label("b.png", 3.0), label("c.png", 4.0));
        let (fa, fb, fc) = (fit(5.0, 0.93), fit(6.0, 0.5), fit(7.0, 0.9));
        let m = photo_measurements([(&a, &fa), (&b, &fb), (&c, &fc)], 0.9);
        // The minimum itself is kept; the rows keep the given order and the fitted lengths.
        assert_eq!(
            m.rows.iter().map(|r| (r.press.h_mm, r.footprint.lt_mm)).collect::<Vec<_>>(),
            [(2.0, 5.0), (4.0, 7.0)]
        );
        assert_eq!(m.poor, [("b.png".to_string(), 0.5)]);
        let lines: Vec<&str> = m.csv.lines().collect();
        assert_eq!(lines[0], format!("file,{MEASUREMENT_COLUMNS},iou"));
        assert_eq!(lines.len(), 4);
        assert_eq!(lines[2], "b.png,3,0,0,6.0000,2.0000,1.2500,0.5000");
    }
}
