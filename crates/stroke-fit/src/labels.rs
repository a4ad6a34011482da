//! A folder of stroke photos' labels: `labels.csv` with one row per photo, the press that made
//! it and, optionally, its scale (`file,h_mm,alpha_deg,beta_deg[,px_per_mm]`, angles in
//! degrees, any column order, extra columns ignored).

use std::path::{Path, PathBuf};

use brush_model::Press;
use thiserror::Error;

/// The largest labels file read, bytes.
pub const MAX_LABELS_BYTES: u64 = 64 << 20;

/// The most rows a labels file may hold.
pub const MAX_LABELS_ROWS: usize = 100_000;

/// One row of a stroke-photo labels file.
#[derive(Clone, Debug, PartialEq)]
pub struct StrokeLabel {
    /// Image file, relative to the labels' folder.
    pub file: String,
    /// The press that made the stroke (angles converted to radians).
    pub press: Press,
    /// Scale of this photo, px per mm, when given (an empty cell is none).
    pub px_per_mm: Option<f64>,
}

/// Why a labels file was refused. Every message starts with the file's name, and names the line
/// and column where one is at fault.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum LabelsError {
    /// The file cannot be opened or read.
    #[error("{}: cannot read", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The file is larger than [`MAX_LABELS_BYTES`].
    #[error("{}: {bytes} bytes; a labels file is at most {MAX_LABELS_BYTES} bytes", path.display())]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Its size, bytes.
        bytes: u64,
    },
    /// The CSV reader failed (`what`: where).
    #[error("{}: {what}", path.display())]
    Csv {
        /// The file.
        path: PathBuf,
        /// `cannot read`, `cannot read the header` or `malformed CSV`.
        what: &'static str,
        /// Why.
        #[source]
        source: csv::Error,
    },
    /// A required column is missing.
    #[error("{}: header has no column `{column}` (need file,h_mm,alpha_deg,beta_deg)", path.display())]
    NoColumn {
        /// The file.
        path: PathBuf,
        /// The column.
        column: &'static str,
    },
    /// More than [`MAX_LABELS_ROWS`] rows.
    #[error("{}: more than {MAX_LABELS_ROWS} rows", path.display())]
    TooManyRows {
        /// The file.
        path: PathBuf,
    },
    /// A cell is not a finite number.
    #[error("{}: line {line}, column `{column}`: expected a number, got {value:?}", path.display())]
    NotANumber {
        /// The file.
        path: PathBuf,
        /// The line, from 1.
        line: u64,
        /// The column.
        column: &'static str,
        /// The cell as written.
        value: String,
    },
    /// No rows after the header.
    #[error("{}: no rows", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
}

/// Reads a labels file (`file,h_mm,alpha_deg,beta_deg[,px_per_mm]`, cells trimmed, extra
/// columns ignored): at most [`MAX_LABELS_BYTES`] and [`MAX_LABELS_ROWS`] rows, at least one.
///
/// # Errors
/// [`LabelsError`] naming the file and, where one is at fault, the line and column.
///
/// # Examples
/// ```
/// let dir = tempfile::tempdir()?;
/// let path = dir.path().join("labels.csv");
/// std::fs::write(&path, "file,h_mm,alpha_deg,beta_deg,px_per_mm\na.png,2.5,10,0,\nb.png,3,10,90,8\n")?;
/// let labels = stroke_fit::read_labels(&path)?;
/// assert_eq!(labels.len(), 2);
/// assert_eq!(labels[0].px_per_mm, None);
/// assert!((labels[1].press.beta_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn read_labels(path: &Path) -> Result<Vec<StrokeLabel>, LabelsError> {
    let p = || path.to_path_buf();
    let len = std::fs::metadata(path).map_err(|source| LabelsError::Read { path: p(), source })?.len();
    if len > MAX_LABELS_BYTES {
        return Err(LabelsError::TooLarge { path: p(), bytes: len });
    }
    let csv_err = |what| move |source| LabelsError::Csv { path: path.to_path_buf(), what, source };
    let mut rdr = csv::ReaderBuilder::new().trim(csv::Trim::All).from_path(path).map_err(csv_err("cannot read"))?;
    let header = rdr.headers().map_err(csv_err("cannot read the header"))?.clone();
    let col = |c: &str| header.iter().position(|h| h == c);
    let need = |column: &'static str| col(column).ok_or_else(|| LabelsError::NoColumn { path: p(), column });
    let (fi, hi, ai, bi) = (need("file")?, need("h_mm")?, need("alpha_deg")?, need("beta_deg")?);
    let si = col("px_per_mm");
    let mut out = Vec::new();
    for rec in rdr.records() {
        let rec = rec.map_err(csv_err("malformed CSV"))?;
        if out.len() == MAX_LABELS_ROWS {
            return Err(LabelsError::TooManyRows { path: p() });
        }
        let line = rec.position().map_or(0, |pos| pos.line());
        let num = |i: usize, column: &'static str| -> Result<f64, LabelsError> {
            let v = rec.get(i).unwrap_or("");
            v.parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| LabelsError::NotANumber {
                path: p(),
                line,
                column,
                value: v.to_string(),
            })
        };
        let px_per_mm = match si {
            Some(i) if !rec.get(i).unwrap_or("").is_empty() => Some(num(i, "px_per_mm")?),
            _ => None,
        };
        out.push(StrokeLabel {
            file: rec.get(fi).unwrap_or("").to_string(),
            press: Press::from_degrees(num(hi, "h_mm")?, num(ai, "alpha_deg")?, num(bi, "beta_deg")?),
            px_per_mm,
        });
    }
    if out.is_empty() {
        return Err(LabelsError::Empty { path: p() });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<Vec<StrokeLabel>, LabelsError> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("labels.csv");
        std::fs::write(&path, text).unwrap();
        read_labels(&path)
    }

    #[test]
    fn columns_in_any_order_with_extras_are_read() {
        let l = read("beta_deg, extra ,file,alpha_deg,h_mm\n0,x,a.png,30,2.5\n").unwrap();
        assert_eq!(l.len(), 1);
        assert_eq!(l[0].file, "a.png");
        assert_eq!(l[0].press, Press::from_degrees(2.5, 30.0, 0.0));
        assert_eq!(l[0].px_per_mm, None);
    }

    #[test]
    fn bad_files_name_the_line_and_column() {
        let e = read("file,h_mm,alpha_deg\n").unwrap_err().to_string();
        assert!(e.ends_with("labels.csv: header has no column `beta_deg` (need file,h_mm,alpha_deg,beta_deg)"), "{e}");
        let e = read("file,h_mm,alpha_deg,beta_deg\na.png,2,x,0\n").unwrap_err().to_string();
        assert!(e.ends_with("labels.csv: line 2, column `alpha_deg`: expected a number, got \"x\""), "{e}");
        let e = read("file,h_mm,alpha_deg,beta_deg,px_per_mm\na.png,2,1,0,inf\n").unwrap_err().to_string();
        assert!(e.contains("column `px_per_mm`"), "{e}");
        let e = read("file,h_mm,alpha_deg,beta_deg\n").unwrap_err();
        assert!(matches!(e, LabelsError::Empty { .. }), "{e:?}");
        let e = read_labels(Path::new("/no/such/labels.csv")).unwrap_err();
        assert!(matches!(e, LabelsError::Read { .. }), "{e:?}");
    }
}
