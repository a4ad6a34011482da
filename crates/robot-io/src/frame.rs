//! The paper frame in the robot's base frame, fitted from touched points (Kabsch).

use std::path::Path;

use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use crate::RobotError;

/// The largest `max_residual_mm` accepted, mm.
pub const MAX_RESIDUAL_MM: f64 = 5.0;
/// How far from the robot base a touched point may lie, m (an AUBO-i5 reaches 0.886 m).
pub const MAX_TOUCH_REACH_M: f64 = 2.0;
/// The smallest extent of the touched points on the paper, mm.
pub const MIN_TOUCH_SPAN_MM: f64 = 20.0;
/// The largest sheet side, mm (A0 is 1189 mm).
pub const MAX_SHEET_MM: f64 = 2000.0;

/// One touched point: where on the paper (mm, paper frame) and where the robot's TCP was (m,
/// base frame) when the brush tip just touched it (H = 0).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TouchPoint {
    /// Paper position `[u, v]`, mm (x right, y down).
    pub paper_mm: [f64; 2],
    /// Robot TCP position `[x, y, z]`, m.
    pub robot_m: [f64; 3],
}

/// `paper.json`: touched points, and optionally the sheet's size.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PaperFile {
    /// Three or more touched points, not collinear.
    pub touch_points: Vec<TouchPoint>,
    /// Sheet size `[width, height]`, mm; default: the touched points' bounding box.
    #[serde(default)]
    pub size_mm: Option<[f64; 2]>,
    /// Largest RMS fit residual accepted, mm (default 1.0, at most [`MAX_RESIDUAL_MM`]).
    #[serde(default)]
    pub max_residual_mm: Option<f64>,
}

/// A fitted paper frame: the rigid transform from paper coordinates (metres, z into the paper)
/// to the robot's base frame.
#[derive(Clone, Debug, PartialEq)]
pub struct PaperFrame {
    /// Paper (m) → base (m).
    pub iso: Isometry3<f64>,
    /// RMS distance between the touched robot points and the mapped paper points, mm.
    pub residual_mm: f64,
    /// Usable area of the sheet: `[x0, y0, x1, y1]` in paper mm.
    pub bounds_mm: [f64; 4],
}

impl PaperFrame {
    /// Loads `paper.json` and fits the frame.
    ///
    /// # Examples
    /// ```
    /// use robot_io::PaperFrame;
    /// // Three corners of a 300 mm sheet touched with the brush tip.
    /// let json = r#"{"touch_points": [
    ///     {"paper_mm": [0, 0], "robot_m": [0.3, 0.25, 0.05]},
    ///     {"paper_mm": [300, 0], "robot_m": [0.6, 0.25, 0.05]},
    ///     {"paper_mm": [0, 300], "robot_m": [0.3, -0.05, 0.05]}
    /// ], "size_mm": [300, 300]}"#;
    /// let path = std::env::temp_dir().join(format!("maobi-doc-paper-{}.json", std::process::id()));
    /// std::fs::write(&path, json).unwrap();
    /// let frame = PaperFrame::load(&path);
    /// std::fs::remove_file(&path).unwrap();
    /// let frame = frame.unwrap();
    /// assert!(frame.residual_mm < 1e-6);
    /// // The paper point (150, 150) mm, 2 mm deep, in the base frame and back.
    /// let [x_mm, y_mm, depth_mm] = frame.to_paper([0.45, 0.1, 0.048]);
    /// assert!((x_mm - 150.0).abs() < 1e-6 && (y_mm - 150.0).abs() < 1e-6 && (depth_mm - 2.0).abs() < 1e-6);
    /// ```
    ///
    /// # Errors
    /// [`RobotError::Read`] or [`RobotError::Json`] naming the file for an unreadable file or
    /// invalid JSON; [`RobotError::Config`] naming it for too few or collinear points, or a
    /// residual above the tolerance.
    pub fn load(path: &Path) -> Result<Self, RobotError> {
        let file: PaperFile = crate::load_json(path)?;
        Self::fit(&file).map_err(|e| match e {
            RobotError::Config { message, .. } => RobotError::Config { file: path.to_path_buf(), message },
            other => other,
        })
    }

    /// Fits the frame (Kabsch: SVD of the cross-covariance, no scale, reflection guarded).
    ///
    /// # Errors
    /// [`RobotError::Config`] for fewer than 3 points, collinear points, non-finite values, or a
    /// residual above `max_residual_mm`.
    pub fn fit(file: &PaperFile) -> Result<Self, RobotError> {
        let bad = |m: String| RobotError::Config { file: "paper.json".into(), message: m };
        let tp = &file.touch_points;
        if tp.len() < 3 {
            return Err(bad(format!("touch_points: need at least 3, got {}", tp.len())));
        }
        if tp.iter().any(|t| t.paper_mm.iter().chain(t.robot_m.iter()).any(|v| !v.is_finite())) {
            return Err(bad("touch_points: every coordinate must be a finite number".into()));
        }
        // Units: paper positions in mm, robot positions in m. A sheet touched within a few
        // millimetres, or a robot point metres from the base, is a unit mistake.
        if let Some((i, t)) = tp.iter().enumerate().find(|(_, t)| Vector3::from(t.robot_m).norm() > MAX_TOUCH_REACH_M) {
            return Err(bad(format!(
                "touch_points[{i}].robot_m = {:?} lies {:.3} m from the robot base, beyond {MAX_TOUCH_REACH_M} m: robot_m is in metres",
                t.robot_m,
                Vector3::from(t.robot_m).norm()
            )));
        }
        let span = |k: usize| {
            let v = tp.iter().map(|t| t.paper_mm[k]);
            v.clone().fold(f64::NEG_INFINITY, f64::max) - v.fold(f64::INFINITY, f64::min)
        };
        let span_mm = span(0).max(span(1));
        if span_mm < MIN_TOUCH_SPAN_MM {
            return Err(bad(format!(
                "touch_points span only {span_mm} mm of paper (at least {MIN_TOUCH_SPAN_MM} mm expected): paper_mm is in millimetres"
            )));
        }
        if let Some(size) = file.size_mm.filter(|s| !s.iter().all(|v| v.is_finite() && *v <= MAX_SHEET_MM)) {
            return Err(bad(format!("size_mm = {size:?} must be finite and at most {MAX_SHEET_MM} mm per side")));
        }
        let p: Vec<Vector3<f64>> =
            tp.iter().map(|t| Vector3::new(t.paper_mm[0] / 1000.0, t.paper_mm[1] / 1000.0, 0.0)).collect();
        let q: Vec<Vector3<f64>> = tp.iter().map(|t| Vector3::from(t.robot_m)).collect();
        let n = tp.len() as f64;
        let pc = p.iter().sum::<Vector3<f64>>() / n;
        let qc = q.iter().sum::<Vector3<f64>>() / n;
        // Collinearity: the paper points' spread must be two-dimensional.
        let mut cov_p = Matrix3::zeros();
        for v in &p {
            let d = v - pc;
            cov_p += d * d.transpose();
        }
        let sv = cov_p.symmetric_eigenvalues();
        let mut s: Vec<f64> = sv.iter().copied().collect();
        s.sort_by(|a, b| b.total_cmp(a));
        if s[0] <= 0.0 || s[1] < 1e-4 * s[0] {
            return Err(bad("touch_points are collinear (or coincide); touch three points that span the sheet".into()));
        }
        let mut h = Matrix3::zeros();
        for (a, b) in p.iter().zip(&q) {
            h += (a - pc) * (b - qc).transpose();
        }
        let svd = h.svd(true, true);
        let (u, v_t) = (svd.u.expect("u"), svd.v_t.expect("v_t"));
        let mut d = Matrix3::identity();
        if (v_t.transpose() * u.transpose()).determinant() < 0.0 {
            d[(2, 2)] = -1.0;
        }
        let r = v_t.transpose() * d * u.transpose();
        let rot = Rotation3::from_matrix_unchecked(r);
        let t = qc - r * pc;
        let iso = Isometry3::from_parts(Translation3::from(t), UnitQuaternion::from_rotation_matrix(&rot));
        let residual_mm =
            (p.iter().zip(&q).map(|(a, b)| (iso * Point3::from(*a) - Point3::from(*b)).norm_squared()).sum::<f64>()
                / n)
                .sqrt()
                * 1000.0;
        let tol = file.max_residual_mm.unwrap_or(1.0);
        if !(tol.is_finite() && tol > 0.0 && tol <= MAX_RESIDUAL_MM) {
            return Err(bad(format!(
                "max_residual_mm = {tol} must be in (0, {MAX_RESIDUAL_MM}] mm: a larger residual means the touch points do not describe one sheet"
            )));
        }
        if residual_mm > tol {
            return Err(bad(format!(
                "fit residual {residual_mm:.3} mm exceeds the tolerance {tol} mm: re-touch the points"
            )));
        }
        let bounds_mm = match file.size_mm {
            Some([w, hh]) if w > 0.0 && hh > 0.0 => [0.0, 0.0, w, hh],
            Some(_) => return Err(bad("size_mm: width and height must be positive".into())),
            None => {
                let xs = tp.iter().map(|t| t.paper_mm[0]);
                let ys = tp.iter().map(|t| t.paper_mm[1]);
                [
                    xs.clone().fold(f64::INFINITY, f64::min),
                    ys.clone().fold(f64::INFINITY, f64::min),
                    xs.fold(f64::NEG_INFINITY, f64::max),
                    ys.fold(f64::NEG_INFINITY, f64::max),
                ]
            }
        };
        Ok(PaperFrame { iso, residual_mm, bounds_mm })
    }

    /// A level sheet whose paper x is the base +x, paper y the base −y (so the paper normal,
    /// into the paper, is base −z), with its origin at `origin_m`. For tests and simulators.
    pub fn level(origin_m: [f64; 3], size_mm: [f64; 2]) -> Self {
        let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(Matrix3::new(
            1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0,
        )));
        PaperFrame {
            iso: Isometry3::from_parts(Translation3::new(origin_m[0], origin_m[1], origin_m[2]), rot),
            residual_mm: 0.0,
            bounds_mm: [0.0, 0.0, size_mm[0], size_mm[1]],
        }
    }

    /// Whether a paper point (mm) lies on the usable sheet.
    pub fn contains(&self, x_mm: f64, y_mm: f64) -> bool {
        let b = self.bounds_mm;
        x_mm >= b[0] - 1e-9 && x_mm <= b[2] + 1e-9 && y_mm >= b[1] - 1e-9 && y_mm <= b[3] + 1e-9
    }

    /// The inverse map: a base-frame point (m) to paper `(x_mm, y_mm, depth_mm)`, depth measured
    /// into the paper.
    pub fn to_paper(&self, p: [f64; 3]) -> [f64; 3] {
        let v = self.iso.inverse() * Point3::from(p);
        [v.x * 1000.0, v.y * 1000.0, v.z * 1000.0]
    }
}
