//! A calibration sheet read back from one photo of it: its `layout.json` loaded and checked
//! (untrusted: every number bounded before anything is sized from it), then every press's
//! footprint measured on the registered photo and judged: found as one footprint, fitted well,
//! pointing the press's way and rooted at its press point (docs/closed-loop.md, "Calibration
//! sheet").

use std::path::Path;

use brush_model::{Footprint, Measurement, Press, measurement_fields, wrap_angle_rad};
use observe::{InkMap, KnownMark, ObserveError, Registration, measure_footprint};
use rayon::prelude::*;

use crate::readback::{ReadBackError, read_bounded};
use crate::{CALIBRATION_LAYOUT_VERSION, CalibrationLayout, MAX_SHEET_MM, known_marks};

/// How far a measured footprint may point from its press's direction, rad (20°). Hand-set.
pub const MAX_PRESS_TURN_RAD: f64 = 20.0 * std::f64::consts::PI / 180.0;

/// How far a measured footprint's root may lie from its press point, mm. Hand-set.
pub const MAX_PRESS_ROOT_MM: f64 = 5.0;

/// Below this share of a sheet's presses measured and used, the photo is taken to be of
/// another sheet ([`SheetReading::enough`]). Hand-set.
pub const MIN_MEASURED_SHARE: f64 = 0.75;

/// The largest press cell a calibration layout read back may hold, mm a side (each is measured
/// at up to 10 px per mm: 2,500 px).
pub const MAX_CELL_MM: f64 = 250.0;

/// The most presses a calibration layout read back may list.
pub const MAX_PRESSES: usize = 10_000;

/// The largest `layout.json` read back, bytes (a layout of [`MAX_PRESSES`] presses is about
/// 3 MiB).
pub const MAX_LAYOUT_BYTES: u64 = 16 << 20;

const WHAT: &str = "a calibration sheet's layout.json (written by `maobi calibrate-sheet`)";

impl CalibrationLayout {
    /// Reads a calibration sheet's `layout.json` (at most [`MAX_LAYOUT_BYTES`]), checks its
    /// kind and version, that it lists presses, and [`CalibrationLayout::validate`]s it.
    ///
    /// # Errors
    /// [`ReadBackError`] naming `path` and, where one is at fault, the field.
    ///
    /// # Examples
    /// ```
    /// let e = pipeline::CalibrationLayout::load("no/such/layout.json".as_ref()).unwrap_err();
    /// assert!(e.to_string().starts_with("cannot read no/such/layout.json"), "{e}");
    /// ```
    pub fn load(path: &Path) -> Result<CalibrationLayout, ReadBackError> {
        let bytes = read_bounded(path, MAX_LAYOUT_BYTES, WHAT)?;
        let layout: CalibrationLayout = serde_json::from_slice(&bytes).map_err(|source| ReadBackError::Json {
            path: path.to_path_buf(),
            what: WHAT,
            source,
        })?;
        if layout.kind != "calibration-sheet" || layout.version != CALIBRATION_LAYOUT_VERSION {
            return Err(ReadBackError::Kind {
                path: path.to_path_buf(),
                kind: layout.kind,
                version: layout.version,
                expected: "calibration-sheet",
                expected_version: CALIBRATION_LAYOUT_VERSION,
            });
        }
        if layout.presses.is_empty() {
            return Err(ReadBackError::Empty { path: path.to_path_buf(), what: "presses" });
        }
        layout.validate(path)?;
        Ok(layout)
    }

    /// Checks what a layout read back may hold before anything is sized from it: the sheet
    /// (sides of 10 mm up to [`MAX_SHEET_MM`]), the number of presses (at most
    /// [`MAX_PRESSES`]) and marks (at most 6), every mark on the sheet, every press's cell
    /// (finite, on the sheet, at most [`MAX_CELL_MM`] a side) and its press values finite.
    /// `path` names the file in errors.
    ///
    /// # Errors
    /// [`ReadBackError::Field`] for the first field at fault.
    pub fn validate(&self, path: &Path) -> Result<(), ReadBackError> {
        let bad = |field: String, what: String| Err(ReadBackError::field(path, field, what));
        let (w, h) = (self.sheet.width_mm, self.sheet.height_mm);
        if !([w, h].iter().all(|v| v.is_finite() && (10.0..=MAX_SHEET_MM).contains(v))) {
            return bad("sheet".into(), format!("{w}×{h} mm: expected sides of 10..={MAX_SHEET_MM} mm"));
        }
        if self.presses.len() > MAX_PRESSES {
            return bad("presses".into(), format!("{} presses: expected at most {MAX_PRESSES}", self.presses.len()));
        }
        if self.marks.len() > 6 {
            return bad("marks".into(), format!("{} marks: a sheet has at most 6", self.marks.len()));
        }
        for (i, m) in self.marks.iter().enumerate() {
            let [x, y] = m.centre_mm;
            let sizes = [m.half_length_mm, m.half_width_mm];
            let on = x.is_finite() && y.is_finite() && (0.0..=w).contains(&x) && (0.0..=h).contains(&y);
            if !(on && sizes.iter().all(|v| v.is_finite() && *v > 0.0 && *v <= MAX_CELL_MM)) {
                return bad(format!("marks[{i}]"), "expected a mark on the sheet, its half sizes 0..=250 mm".into());
            }
        }
        for (i, p) in self.presses.iter().enumerate() {
            let [x0, y0, x1, y1] = p.cell_mm;
            let on = [x0, y0, x1, y1].iter().all(|v| v.is_finite()) && x0 >= 0.0 && y0 >= 0.0 && x1 <= w && y1 <= h;
            if !(on && x1 > x0 && y1 > y0 && x1 - x0 <= MAX_CELL_MM && y1 - y0 <= MAX_CELL_MM) {
                return bad(
                    format!("presses[{i}].cell_mm"),
                    format!(
                        "[{x0}, {y0}, {x1}, {y1}] mm: expected a cell on the {w}×{h} mm sheet, at most {MAX_CELL_MM} mm a side"
                    ),
                );
            }
            let values = [p.h_mm, p.alpha_rad, p.beta_rad, p.root_mm[0], p.root_mm[1]];
            if !values.iter().all(|v| v.is_finite()) {
                return bad(format!("presses[{i}]"), "expected finite h_mm, alpha_rad, beta_rad and root_mm".into());
            }
        }
        Ok(())
    }

    /// The layout's marks in [`observe::register`]'s order, when it has the four corners and at
    /// least one more (what a photo's registration needs); `None` otherwise.
    pub fn registration_marks(&self) -> Option<Vec<KnownMark>> {
        known_marks(&self.marks).filter(|_| self.marks.len() >= 5)
    }
}

/// Why a press of a calibration sheet is left out of the fit.
#[derive(Debug)]
#[non_exhaustive]
pub enum LeftOut {
    /// No single footprint was measured in its cell.
    NotFound(ObserveError),
    /// The outline fits the ink poorly.
    PoorFit {
        /// The fit's IoU.
        iou: f64,
        /// The least IoU asked for.
        min_iou: f64,
    },
    /// It points more than [`MAX_PRESS_TURN_RAD`] from the press's direction.
    Turned {
        /// How far, rad (absolute).
        turn_rad: f64,
    },
    /// Its root lies more than [`MAX_PRESS_ROOT_MM`] from the press point.
    Away {
        /// How far, mm.
        off_mm: f64,
    },
}

impl std::fmt::Display for LeftOut {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LeftOut::NotFound(e) => write!(f, "{e}"),
            LeftOut::PoorFit { iou, min_iou } => write!(f, "fit IoU {iou:.3} below {min_iou}"),
            LeftOut::Turned { turn_rad } => {
                write!(f, "points {:.0}° away from the press's direction", turn_rad.to_degrees())
            }
            LeftOut::Away { off_mm } => write!(f, "its root end lies {off_mm:.1} mm from the press point"),
        }
    }
}

/// One press of a calibration sheet read on its photo.
#[derive(Debug)]
pub struct PressReading {
    /// Its number on the sheet (from 1).
    pub number: usize,
    /// The press and the footprint measured, with the fit's IoU; `None` when none was found.
    pub measured: Option<(Measurement, f64)>,
    /// Why it is left out of the fit; `None` when it is used.
    pub left_out: Option<LeftOut>,
}

impl PressReading {
    /// Its label on the sheet and in messages: `P` and its number in two digits (`P07`).
    pub fn label(&self) -> String {
        format!("P{:02}", self.number)
    }
}

/// Every press of a calibration sheet read on its photo, in the layout's order.
#[derive(Debug)]
pub struct SheetReading {
    /// The presses.
    pub presses: Vec<PressReading>,
}

impl SheetReading {
    /// The measurements used (those not left out).
    pub fn used(&self) -> Vec<Measurement> {
        self.presses.iter().filter(|p| p.left_out.is_none()).filter_map(|p| p.measured.map(|m| m.0)).collect()
    }

    /// Whether at least [`MIN_MEASURED_SHARE`] of the presses are used; fewer says the photo
    /// is of another sheet.
    pub fn enough(&self) -> bool {
        self.used().len() as f64 >= MIN_MEASURED_SHARE * self.presses.len() as f64
    }

    /// `measurements.csv`: `press`, brush-model's measurement columns (angles in degrees,
    /// lengths to 0.1 µm), the fit's IoU and whether the press was used; a press not found has
    /// no row.
    pub fn csv(&self) -> String {
        let mut csv = format!("press,{},iou,used\n", brush_model::MEASUREMENT_COLUMNS);
        for p in &self.presses {
            if let Some((m, iou)) = &p.measured {
                let fields = measurement_fields(m, Some(4));
                csv.push_str(&format!("{},{fields},{iou:.4},{}\n", p.label(), p.left_out.is_none()));
            }
        }
        csv
    }
}

/// Reads every press of `layout` on a photo's ink registered by `reg` (in parallel; `each` is
/// called once per press measured, for progress): the footprint measured in its cell, and left
/// out when not found, when its fit IoU is below `min_iou`, when it points more than
/// [`MAX_PRESS_TURN_RAD`] from its press's direction or its root lies more than
/// [`MAX_PRESS_ROOT_MM`] from the press point.
pub fn read_calibration_sheet(
    layout: &CalibrationLayout,
    ink: &InkMap,
    reg: &Registration,
    min_iou: f64,
    each: &(dyn Fn() + Sync),
) -> SheetReading {
    let results: Vec<_> = layout
        .presses
        .par_iter()
        .map(|p| {
            let r = measure_footprint(ink, reg, p.cell_mm);
            each();
            r
        })
        .collect();
    let presses = layout
        .presses
        .iter()
        .zip(results)
        .map(|(p, r)| {
            let m = match r {
                Ok(m) => m,
                Err(e) => {
                    return PressReading { number: p.number, measured: None, left_out: Some(LeftOut::NotFound(e)) };
                }
            };
            let turn_rad = wrap_angle_rad(m.beta_rad - p.beta_rad).abs();
            let off_mm = (m.root_mm[0] - p.root_mm[0]).hypot(m.root_mm[1] - p.root_mm[1]);
            let left_out = if m.iou < min_iou {
                Some(LeftOut::PoorFit { iou: m.iou, min_iou })
            } else if turn_rad > MAX_PRESS_TURN_RAD {
                Some(LeftOut::Turned { turn_rad })
            } else if off_mm > MAX_PRESS_ROOT_MM {
                Some(LeftOut::Away { off_mm })
            } else {
                None
            };
            let press: Press = p.press();
            let footprint = Footprint { lt_mm: m.lt_mm, lh_mm: m.lh_mm, lr_mm: m.lr_mm };
            PressReading { number: p.number, measured: Some((Measurement { press, footprint }, m.iou)), left_out }
        })
        .collect();
    SheetReading { presses }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn layout() -> CalibrationLayout {
        let pen1 = brush_model::BrushProfile::builtin("pen1").unwrap();
        crate::calibration_sheet(&crate::parse_sheet("A4").unwrap(), 15.0, &pen1).unwrap().layout
    }

    #[test]
    fn a_sheets_own_layout_passes_and_a_huge_cell_is_named() {
        let mut l = layout();
        l.validate(Path::new("layout.json")).unwrap();
        assert_eq!(l.registration_marks().map(|m| m.len()), Some(l.marks.len()));
        l.presses[0].cell_mm = [10.0, 10.0, 2510.0, 2510.0];
        let e = l.validate(Path::new("layout.json")).unwrap_err().to_string();
        assert!(e.starts_with("layout.json: field `presses[0].cell_mm`: [10, 10, 2510, 2510] mm"), "{e}");
        l.presses[0].cell_mm = [10.0, 10.0, 20.0, 20.0];
        l.presses[1].h_mm = f64::NAN;
        let e = l.validate(Path::new("layout.json")).unwrap_err().to_string();
        assert!(e.contains("field `presses[1]`"), "{e}");
        l.marks.truncate(4);
        assert!(l.registration_marks().is_none(), "four corners alone do not register a photo");
    }

    #[test]
    fn readings_are_used_judged_and_written_in_order() {
        let m = |h: f64| Measurement {
            press: Press::from_degrees(h, 10.0, 0.0),
            footprint: Footprint { lt_mm: 9.0, lh_mm: 3.0, lr_mm: 2.0 },
        };
        let reading = SheetReading {
            presses: vec![
                PressReading { number: 1, measured: Some((m(1.0), 0.95)), left_out: None },
                PressReading { number: 2, measured: None, left_out: Some(LeftOut::NotFound(ObserveError::NoPaper)) },
                PressReading {
                    number: 3,
                    measured: Some((m(3.0), 0.5)),
                    left_out: Some(LeftOut::PoorFit { iou: 0.5, min_iou: 0.9 }),
                },
                PressReading { number: 4, measured: Some((m(4.0), 0.97)), left_out: None },
            ],
        };
        assert_eq!(reading.used().len(), 2);
        assert!(!reading.enough(), "two of four is under three quarters");
        let csv = reading.csv();
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines[0], "press,h_mm,alpha_deg,beta_deg,lt_mm,lh_mm,lr_mm,iou,used");
        assert_eq!(lines.len(), 4, "the press not found has no row: {csv}");
        assert!(lines[2].starts_with("P03,3,") && lines[2].ends_with(",0.5000,false"), "{csv}");
        assert_eq!(reading.presses[2].left_out.as_ref().unwrap().to_string(), "fit IoU 0.500 below 0.9");
        assert_eq!(LeftOut::Turned { turn_rad: 0.5 }.to_string(), "points 29° away from the press's direction");
    }
}
