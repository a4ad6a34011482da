//! Footprint measurements: one row per pressed stroke, read from CSV.
//!
//! The CSV has a header with at least the columns `h_mm, alpha_deg, beta_deg, lt_mm, lh_mm,
//! lr_mm`, in any order; other columns are ignored. Angles are in degrees in the file and are
//! converted to radians on reading, so fitted α and β coefficients are per radian.

use std::io::Read;
use std::path::{Path, PathBuf};

use thiserror::Error;

use crate::footprint::Footprint;
use crate::units::Press;

/// The columns a measurements CSV must have.
pub(crate) const REQUIRED_COLUMNS: [&str; 6] = ["h_mm", "alpha_deg", "beta_deg", "lt_mm", "lh_mm", "lr_mm"];

/// The most rows a measurements file may have.
pub(crate) const MAX_ROWS: usize = 1_000_000;

/// The largest measurements file read, bytes (a million rows take about 40 MB).
pub(crate) const MAX_BYTES: u64 = 64 << 20;

/// Each column's accepted values (inclusive), with the reason given when a value is outside:
/// depths and lengths up to what a brush of [`MAX_BRUSH_MM`](crate::MAX_BRUSH_MM) can
/// do, tilts short of lying flat, rotations within a turn either way.
const BOUNDS: [(f64, f64, &str); 6] = [
    (0.0, 1000.0, "expected a depth of 0..=1000 mm"),
    (-90.0, 90.0, "expected a tilt of -90..=90 degrees"),
    (-360.0, 360.0, "expected a rotation of -360..=360 degrees"),
    (0.0, 2000.0, "expected a positive length of at most 2000 mm"),
    (0.0, 2000.0, "expected a positive length of at most 2000 mm"),
    (0.0, 2000.0, "expected a positive length of at most 2000 mm"),
];

/// One measured press and the footprint it left.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measurement {
    /// The press (angles in radians).
    pub press: Press,
    /// The measured footprint, mm.
    pub footprint: Footprint,
}

/// Errors from reading measurements. Each names the source and, where there is one, the line
/// (1-based, the header being line 1) and the column.
#[derive(Debug, Error)]
pub enum MeasurementError {
    /// The file could not be opened or read.
    #[error("{}: cannot read", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A required column is missing from the header.
    #[error("{source_name}: header has no column `{column}` (need {})", REQUIRED_COLUMNS.join(","))]
    MissingColumn {
        /// File name or other source label.
        source_name: String,
        /// The missing column.
        column: &'static str,
    },
    /// A field is not a finite number (or a length is negative).
    #[error("{source_name}: line {line}, column `{column}`: {expected}, got {value:?}")]
    Field {
        /// File name or other source label.
        source_name: String,
        /// 1-based line number.
        line: u64,
        /// Column name.
        column: &'static str,
        /// The text found.
        value: String,
        /// What was expected.
        expected: &'static str,
    },
    /// A file larger than 64 MiB.
    #[error("{}: {bytes} bytes; a measurements file is at most {max} bytes", path.display())]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Its size.
        bytes: u64,
        /// The limit.
        max: u64,
    },
    /// More than a million rows.
    #[error("{source_name}: more than {max} rows")]
    TooManyRows {
        /// File name or other source label.
        source_name: String,
        /// The limit.
        max: usize,
    },
    /// The CSV itself is malformed (ragged rows, bad quoting, bad UTF-8).
    #[error("{source_name}: line {line}: malformed CSV")]
    Csv {
        /// File name or other source label.
        source_name: String,
        /// 1-based line number.
        line: u64,
        /// The CSV reader's error.
        #[source]
        source: csv::Error,
    },
}

/// Reads measurements from a CSV file.
///
/// # Errors
/// [`MeasurementError`] naming the file, line and column of the first problem.
pub fn load_measurements(path: &Path) -> Result<Vec<Measurement>, MeasurementError> {
    let io = |source| MeasurementError::Io { path: path.to_path_buf(), source };
    let file = crate::open_regular(path).map_err(io)?;
    let len = file.metadata().map_err(io)?.len();
    if len > MAX_BYTES {
        return Err(MeasurementError::TooLarge { path: path.to_path_buf(), bytes: len, max: MAX_BYTES });
    }
    // Bounded even if the file grows while it is read.
    read_measurements(file.take(MAX_BYTES), &path.display().to_string())
}

/// Reads measurements from any reader; `source_name` labels errors.
///
/// # Errors
/// [`MeasurementError`] naming the source, line and column of the first problem.
pub fn read_measurements(reader: impl Read, source_name: &str) -> Result<Vec<Measurement>, MeasurementError> {
    let mut rdr = csv::ReaderBuilder::new().trim(csv::Trim::All).from_reader(reader);
    let csv_err = |e: csv::Error| MeasurementError::Csv {
        source_name: source_name.to_string(),
        line: e.position().map(|p| p.line()).unwrap_or(1),
        source: e,
    };
    let header = rdr.headers().map_err(csv_err)?.clone();
    let mut idx = [0usize; 6];
    for (k, col) in REQUIRED_COLUMNS.iter().enumerate() {
        idx[k] = header
            .iter()
            .position(|h| h == *col)
            .ok_or(MeasurementError::MissingColumn { source_name: source_name.to_string(), column: col })?;
    }
    let mut out = Vec::new();
    for rec in rdr.records() {
        let rec = rec.map_err(csv_err)?;
        if out.len() == MAX_ROWS {
            return Err(MeasurementError::TooManyRows { source_name: source_name.to_string(), max: MAX_ROWS });
        }
        let line = rec.position().map(|p| p.line()).unwrap_or(0);
        let mut v = [0.0f64; 6];
        for (k, col) in REQUIRED_COLUMNS.iter().enumerate() {
            let text = rec.get(idx[k]).unwrap_or("");
            let field_err = |expected| MeasurementError::Field {
                source_name: source_name.to_string(),
                line,
                column: col,
                value: text.to_string(),
                expected,
            };
            let x: f64 = text.parse().map_err(|_| field_err("expected a number"))?;
            if !x.is_finite() {
                return Err(field_err("expected a finite number"));
            }
            if k >= 3 && x <= 0.0 {
                return Err(field_err("expected a positive length in mm"));
            }
            if k == 0 && x < 0.0 {
                return Err(field_err("expected a non-negative depth in mm"));
            }
            let (lo, hi, expected) = BOUNDS[k];
            if !(lo..=hi).contains(&x) {
                return Err(field_err(expected));
            }
            v[k] = x;
        }
        out.push(Measurement {
            press: Press::from_degrees(v[0], v[1], v[2]),
            footprint: Footprint { lt_mm: v[3], lh_mm: v[4], lr_mm: v[5] },
        });
    }
    Ok(out)
}

/// The measurement columns of a CSV header, in the order [`measurement_fields`] writes them:
/// what [`read_measurements`] needs. Writers with other columns put theirs around these.
pub const MEASUREMENT_COLUMNS: &str = "h_mm,alpha_deg,beta_deg,lt_mm,lh_mm,lr_mm";

/// One measurement as the fields of a CSV row under [`MEASUREMENT_COLUMNS`] (angles in
/// degrees, no line end): every value with all its digits, or the lengths rounded to
/// `length_decimals` places (a length fitted from a photo is not known to more).
///
/// # Examples
/// ```
/// use brush_model::{Footprint, Measurement, Press, measurement_fields};
/// let m = Measurement {
///     press: Press::from_degrees(12.0, 10.0, 0.0),
///     footprint: Footprint { lt_mm: 9.25, lh_mm: 3.0, lr_mm: 2.0 / 3.0 },
/// };
/// assert_eq!(measurement_fields(&m, Some(4)), "12,10,0,9.2500,3.0000,0.6667");
/// ```
pub fn measurement_fields(m: &Measurement, length_decimals: Option<usize>) -> String {
    let (p, f) = (&m.press, &m.footprint);
    let press = format!("{},{},{}", p.h_mm, p.alpha_rad.to_degrees(), p.beta_rad.to_degrees());
    match length_decimals {
        None => format!("{press},{},{},{}", f.lt_mm, f.lh_mm, f.lr_mm),
        Some(d) => format!("{press},{:.d$},{:.d$},{:.d$}", f.lt_mm, f.lh_mm, f.lr_mm),
    }
}

/// Writes measurements as CSV with the standard header (angles in degrees).
pub fn write_measurements(rows: &[Measurement]) -> String {
    let mut s = format!("{MEASUREMENT_COLUMNS}\n");
    for m in rows {
        s.push_str(&measurement_fields(m, None));
        s.push('\n');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_columns_in_any_order_and_ignores_extras() {
        let csv = "note,lr_mm,lt_mm,lh_mm,beta_deg,alpha_deg,h_mm\nx,2,9,3.5,5,10,12\n";
        let rows = read_measurements(csv.as_bytes(), "t.csv").unwrap();
        assert_eq!(rows.len(), 1);
        let m = rows[0];
        assert_eq!(m.press.h_mm, 12.0);
        assert!((m.press.alpha_rad - 10f64.to_radians()).abs() < 1e-15);
        assert!((m.press.beta_rad - 5f64.to_radians()).abs() < 1e-15);
        assert_eq!((m.footprint.lt_mm, m.footprint.lh_mm, m.footprint.lr_mm), (9.0, 3.5, 2.0));
    }

    #[test]
    fn names_line_and_column_of_a_bad_field() {
        let csv = "h_mm,alpha_deg,beta_deg,lt_mm,lh_mm,lr_mm\n11,0,0,9,3,2\n12,abc,0,9,3,2\n";
        let e = read_measurements(csv.as_bytes(), "m.csv").unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains("m.csv") && msg.contains("line 3") && msg.contains("alpha_deg"), "{msg}");
    }

    #[test]
    fn names_a_missing_column() {
        let csv = "h_mm,alpha_deg,beta_deg,lt_mm,lh_mm\n11,0,0,9,3\n";
        let e = read_measurements(csv.as_bytes(), "m.csv").unwrap_err();
        assert!(e.to_string().contains("`lr_mm`"), "{e}");
    }

    #[test]
    fn rejects_negative_lengths_and_ragged_rows() {
        let csv = "h_mm,alpha_deg,beta_deg,lt_mm,lh_mm,lr_mm\n11,0,0,9,-3,2\n";
        let e = read_measurements(csv.as_bytes(), "m.csv").unwrap_err();
        assert!(e.to_string().contains("lh_mm") && e.to_string().contains("line 2"), "{e}");
        let csv = "h_mm,alpha_deg,beta_deg,lt_mm,lh_mm,lr_mm\n11,0,0,9,3\n";
        let e = read_measurements(csv.as_bytes(), "m.csv").unwrap_err();
        assert!(e.to_string().contains("line 2"), "{e}");
        // The CSV reader's own description is kept as the cause.
        let cause = std::error::Error::source(&e).expect("the csv error is the source");
        assert!(cause.to_string().contains("fields"), "{cause}");
    }

    #[test]
    fn a_missing_file_keeps_its_io_error() {
        let e = load_measurements(Path::new("/nonexistent/m.csv")).unwrap_err();
        assert!(matches!(&e, MeasurementError::Io { path, .. } if path == Path::new("/nonexistent/m.csv")), "{e}");
        let cause = std::error::Error::source(&e).and_then(|c| c.downcast_ref::<std::io::Error>());
        assert_eq!(cause.map(std::io::Error::kind), Some(std::io::ErrorKind::NotFound));
    }

    #[test]
    fn round_trips_through_writer() {
        let csv = "h_mm,alpha_deg,beta_deg,lt_mm,lh_mm,lr_mm\n11,5,2.5,9,3,2\n";
        let rows = read_measurements(csv.as_bytes(), "a").unwrap();
        let again = read_measurements(write_measurements(&rows).as_bytes(), "b").unwrap();
        for (a, b) in rows.iter().zip(&again) {
            assert!((a.press.alpha_rad - b.press.alpha_rad).abs() < 1e-12);
            assert_eq!(a.footprint, b.footprint);
        }
    }
}
