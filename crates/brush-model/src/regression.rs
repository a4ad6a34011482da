//! Ordinary least squares for the brush model (docs/contracts.md §4, paper Eq. 1–6).
//!
//! Two forms are fitted from [`Measurement`]s:
//!
//! * **general** (Eq. 6): each of `lt`, `lh`, `lr` regressed on `(1, h, α, β)`;
//! * **paper** (Eq. 1–5): `lt + lh` regressed on `(1, h, α, β)`, plus the ratios
//!   `k4 = lh/lt` and `k5 = lr/lt` by least squares through the origin.
//!
//! Both are solved by SVD of the design matrix (never the normal equations) and report what
//! `statsmodels` OLS reports: coefficients, standard errors, t values, R², adjusted R², residual
//! standard error, n and the design's condition number. A regressor that does not vary over the
//! data is *unidentifiable*: it is named in [`FitReport::unidentifiable`] and left out of the fit.

use std::collections::BTreeMap;
use std::fmt;

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::measurements::Measurement;

/// Errors from fitting.
#[derive(Debug, Error, PartialEq)]
pub enum FitError {
    /// Fewer rows than the fit needs.
    #[error("too few measurements for the {form} fit: got {n}, need at least {needed}")]
    TooFewRows {
        /// The form being fitted.
        form: Form,
        /// Rows given.
        n: usize,
        /// Rows needed (one more than the identifiable coefficients).
        needed: usize,
    },
    /// The varying regressors are linearly dependent.
    #[error(
        "regressors {columns:?} are collinear in the data (condition number {condition:.3e}); vary them independently"
    )]
    Collinear {
        /// The regressors kept in the design.
        columns: Vec<String>,
        /// Ratio of largest to smallest singular value.
        condition: f64,
    },
    /// A value was not finite.
    #[error("measurement row {row} has a non-finite value")]
    NonFinite {
        /// Zero-based row index.
        row: usize,
    },
    /// `lt` is zero in every row, so `k4` and `k5` cannot be estimated.
    #[error("the paper form needs non-zero lt_mm values to estimate k4 and k5")]
    ZeroTipLength,
}

/// Which regression form.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Form {
    /// Eq. 6: one linear model per output.
    #[default]
    General,
    /// Eq. 1–5: a model of `lt + lh` plus the ratios `k4`, `k5`.
    Paper,
}

impl fmt::Display for Form {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Form::General => "general",
            Form::Paper => "paper",
        })
    }
}

/// Reads a number that may be `null` (how JSON writes NaN, e.g. an undefined R²) as NaN.
fn f64_or_nan<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// As [`f64_or_nan`] for an optional term: absent is `None`, `null` is `Some(NaN)`.
fn some_f64_or_nan<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    Ok(Some(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN)))
}

/// One value per regressor. `None` for a regressor left out as unidentifiable.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct Terms {
    /// Constant term (mm).
    #[serde(deserialize_with = "f64_or_nan")]
    pub intercept: f64,
    /// Per mm of press depth.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "some_f64_or_nan")]
    pub h_mm: Option<f64>,
    /// Per radian of tilt.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "some_f64_or_nan")]
    pub alpha_rad: Option<f64>,
    /// Per radian of rotation.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "some_f64_or_nan")]
    pub beta_rad: Option<f64>,
}

impl Terms {
    /// Evaluates `intercept + h·c_h + α·c_α + β·c_β`, treating missing terms as zero.
    pub fn eval(&self, h_mm: f64, alpha_rad: f64, beta_rad: f64) -> f64 {
        self.intercept
            + self.h_mm.unwrap_or(0.0) * h_mm
            + self.alpha_rad.unwrap_or(0.0) * alpha_rad
            + self.beta_rad.unwrap_or(0.0) * beta_rad
    }

    /// Every present term multiplied by `k`.
    pub fn scaled(&self, k: f64) -> Terms {
        Terms {
            intercept: self.intercept * k,
            h_mm: self.h_mm.map(|v| v * k),
            alpha_rad: self.alpha_rad.map(|v| v * k),
            beta_rad: self.beta_rad.map(|v| v * k),
        }
    }

    fn from_kept(kept: &[Regressor], values: &[f64]) -> Terms {
        let mut t = Terms::default();
        for (r, v) in kept.iter().zip(values) {
            match r {
                Regressor::Intercept => t.intercept = *v,
                Regressor::H => t.h_mm = Some(*v),
                Regressor::Alpha => t.alpha_rad = Some(*v),
                Regressor::Beta => t.beta_rad = Some(*v),
            }
        }
        t
    }
}

/// The fit of one output.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputFit {
    /// Estimated coefficients.
    pub coef: Terms,
    /// Their standard errors.
    pub std_err: Terms,
    /// Their t values (coefficient / standard error); NaN (JSON `null`) when the output is
    /// constant in the data.
    pub t: Terms,
    /// Coefficient of determination; NaN (JSON `null`) when the output is constant in the data
    /// (no variance to explain: statsmodels says nan too). See [`OutputFit::is_constant`].
    #[serde(deserialize_with = "f64_or_nan")]
    pub r2: f64,
    /// R² adjusted for the number of regressors; NaN when R² is.
    #[serde(deserialize_with = "f64_or_nan")]
    pub adj_r2: f64,
    /// Residual standard error `sqrt(SSR / (n − p))`, mm.
    pub resid_se: f64,
}

impl OutputFit {
    /// Whether the output was constant in the data (R² undefined).
    pub fn is_constant(&self) -> bool {
        self.r2.is_nan()
    }
}

/// A full fit report, in the shape `maobi calibrate --json` prints.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitReport {
    /// The form fitted.
    pub form: Form,
    /// Number of measurements.
    pub n: usize,
    /// Condition number of the design matrix (largest over smallest singular value), as
    /// statsmodels reports it.
    pub condition_number: f64,
    /// Regressors that did not vary and were left out.
    #[serde(default)]
    pub unidentifiable: Vec<String>,
    /// Per output: `lt_mm`, `lh_mm`, `lr_mm` (general) or `sum_mm` (paper).
    pub outputs: BTreeMap<String, OutputFit>,
    /// Paper form: `k4 = lh / lt` through the origin.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k4: Option<f64>,
    /// Standard error of `k4`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k4_std_err: Option<f64>,
    /// Paper form: `k5 = lr / lt` through the origin.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k5: Option<f64>,
    /// Standard error of `k5`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k5_std_err: Option<f64>,
}

/// Linear coefficients of the three footprint lengths in `(1, h, α, β)`: what a profile stores
/// and predicts with, whichever form produced it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinearModel {
    /// Tip length.
    pub lt_mm: Terms,
    /// Root length.
    pub lh_mm: Terms,
    /// Belly half-width.
    pub lr_mm: Terms,
}

impl FitReport {
    /// The linear model this fit implies. For the paper form, with `S = lt + lh`:
    /// `lt = S/(1 + k4)`, `lh = k4·S/(1 + k4)`, `lr = k5·S/(1 + k4)` (Eq. 3–5).
    pub fn linear_model(&self) -> LinearModel {
        match self.form {
            Form::General => LinearModel {
                lt_mm: self.outputs["lt_mm"].coef,
                lh_mm: self.outputs["lh_mm"].coef,
                lr_mm: self.outputs["lr_mm"].coef,
            },
            Form::Paper => {
                let s = self.outputs["sum_mm"].coef;
                let k4 = self.k4.unwrap_or(0.0);
                let k5 = self.k5.unwrap_or(0.0);
                LinearModel {
                    lt_mm: s.scaled(1.0 / (1.0 + k4)),
                    lh_mm: s.scaled(k4 / (1.0 + k4)),
                    lr_mm: s.scaled(k5 / (1.0 + k4)),
                }
            }
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Regressor {
    Intercept,
    H,
    Alpha,
    Beta,
}

impl Regressor {
    fn name(self) -> &'static str {
        match self {
            Regressor::Intercept => "intercept",
            Regressor::H => "h_mm",
            Regressor::Alpha => "alpha_rad",
            Regressor::Beta => "beta_rad",
        }
    }
}

/// The design matrix with constant regressors removed, and its SVD-based pseudo-inverse pieces.
struct Design {
    kept: Vec<Regressor>,
    dropped: Vec<String>,
    x: DMatrix<f64>,
    svd: nalgebra::SVD<f64, nalgebra::Dyn, nalgebra::Dyn>,
    condition: f64,
}

impl Design {
    fn new(rows: &[Measurement], form: Form) -> Result<Self, FitError> {
        for (i, m) in rows.iter().enumerate() {
            let v = [
                m.press.h_mm,
                m.press.alpha_rad,
                m.press.beta_rad,
                m.footprint.lt_mm,
                m.footprint.lh_mm,
                m.footprint.lr_mm,
            ];
            if v.iter().any(|x| !x.is_finite()) {
                return Err(FitError::NonFinite { row: i });
            }
        }
        let column = |r: Regressor| -> Vec<f64> {
            rows.iter()
                .map(|m| match r {
                    Regressor::Intercept => 1.0,
                    Regressor::H => m.press.h_mm,
                    Regressor::Alpha => m.press.alpha_rad,
                    Regressor::Beta => m.press.beta_rad,
                })
                .collect()
        };
        let mut kept = vec![Regressor::Intercept];
        let mut dropped = Vec::new();
        for r in [Regressor::H, Regressor::Alpha, Regressor::Beta] {
            let c = column(r);
            let lo = c.iter().cloned().fold(f64::INFINITY, f64::min);
            let hi = c.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            if rows.is_empty() || hi - lo <= 1e-12 * hi.abs().max(lo.abs()).max(1.0) {
                dropped.push(r.name().to_string());
            } else {
                kept.push(r);
            }
        }
        let n = rows.len();
        let p = kept.len();
        if n < p + 1 {
            return Err(FitError::TooFewRows { form, n, needed: p + 1 });
        }
        let cols: Vec<Vec<f64>> = kept.iter().map(|r| column(*r)).collect();
        let x = DMatrix::from_fn(n, p, |i, j| cols[j][i]);
        let svd = x.clone().svd(true, true);
        let smax = svd.singular_values.max();
        let smin = svd.singular_values.min();
        let condition = smax / smin;
        // NaN-aware: a NaN singular value is not well conditioned either.
        let well_conditioned = smin > 1e-10 * smax;
        if !well_conditioned {
            return Err(FitError::Collinear {
                columns: kept.iter().map(|r| r.name().to_string()).collect(),
                condition,
            });
        }
        Ok(Design { kept, dropped, x, svd, condition })
    }

    fn fit(&self, y: &DVector<f64>) -> OutputFit {
        let (n, p) = self.x.shape();
        let u = self.svd.u.as_ref().expect("u computed");
        let v_t = self.svd.v_t.as_ref().expect("v_t computed");
        let s = &self.svd.singular_values;
        // beta = V · diag(1/s) · Uᵀ · y
        let uty = u.transpose() * y;
        let scaled = DVector::from_fn(p, |i, _| uty[i] / s[i]);
        let beta = v_t.transpose() * scaled;
        let resid = y - &self.x * &beta;
        let ssr = resid.norm_squared();
        let mean = y.mean();
        let sst: f64 = y.iter().map(|v| (v - mean).powi(2)).sum();
        let df_resid = (n - p) as f64;
        let sigma2 = ssr / df_resid;
        // Var(beta_j) = sigma² · Σ_k (V_jk / s_k)²
        let se: Vec<f64> = (0..p)
            .map(|j| {
                let v: f64 = (0..p).map(|k| (v_t[(k, j)] / s[k]).powi(2)).sum();
                (sigma2 * v).sqrt()
            })
            .collect();
        let t: Vec<f64> = beta
            .iter()
            .zip(&se)
            .map(|(b, e)| {
                if *e > 0.0 {
                    b / e
                } else if *b == 0.0 {
                    0.0
                } else {
                    b.signum() * f64::MAX
                }
            })
            .collect();
        // An output constant in the data (up to rounding) has no variance to explain: R² and the
        // t values are undefined, not the −4.4 or 1e15 that rounding noise over rounding noise
        // gives.
        let scale = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let constant = sst <= n as f64 * (64.0 * f64::EPSILON * scale).powi(2);
        let t: Vec<f64> = if constant { vec![f64::NAN; t.len()] } else { t };
        let r2 = if constant { f64::NAN } else { 1.0 - ssr / sst };
        let adj_r2 = 1.0 - (1.0 - r2) * ((n - 1) as f64) / df_resid;
        OutputFit {
            coef: Terms::from_kept(&self.kept, beta.as_slice()),
            std_err: Terms::from_kept(&self.kept, &se),
            t: Terms::from_kept(&self.kept, &t),
            r2,
            adj_r2,
            resid_se: sigma2.sqrt(),
        }
    }
}

/// Fits the general form (Eq. 6): `lt`, `lh`, `lr` each on `(1, h, α, β)`.
///
/// # Examples
/// ```
/// use brush_model::{FitError, Footprint, Measurement, Press, fit_general};
/// // Footprints that follow a known law in (h, α, β).
/// let mut rows = Vec::new();
/// for h_mm in [2.0, 4.0, 6.0, 8.0] {
///     for alpha_rad in [0.0, 0.05, 0.1] {
///         for beta_rad in [-0.1, 0.0, 0.1] {
///             let press = Press { h_mm, alpha_rad, beta_rad };
///             let footprint =
///                 Footprint { lt_mm: 4.0 + 0.5 * h_mm + 2.0 * alpha_rad, lh_mm: 1.0 + 0.2 * h_mm, lr_mm: 0.5 + 0.1 * h_mm };
///             rows.push(Measurement { press, footprint });
///         }
///     }
/// }
/// let report = fit_general(&rows).unwrap();
/// let lt = &report.outputs["lt_mm"].coef;
/// assert!((lt.intercept - 4.0).abs() < 1e-9 && (lt.h_mm.unwrap() - 0.5).abs() < 1e-9);
/// assert!((lt.alpha_rad.unwrap() - 2.0).abs() < 1e-9 && lt.beta_rad.unwrap().abs() < 1e-9);
/// // One press cannot fit even a constant and its error.
/// assert!(matches!(fit_general(&rows[..1]), Err(FitError::TooFewRows { .. })));
/// ```
///
/// # Errors
/// [`FitError`] when there are too few rows, a non-finite value, or collinear regressors.
pub fn fit_general(rows: &[Measurement]) -> Result<FitReport, FitError> {
    /// An output's name and how to read it from a row.
    type Output = (&'static str, fn(&Measurement) -> f64);
    let design = Design::new(rows, Form::General)?;
    let mut outputs = BTreeMap::new();
    let pick: [Output; 3] =
        [("lt_mm", |m| m.footprint.lt_mm), ("lh_mm", |m| m.footprint.lh_mm), ("lr_mm", |m| m.footprint.lr_mm)];
    for (name, f) in pick {
        let y = DVector::from_iterator(rows.len(), rows.iter().map(f));
        outputs.insert(name.to_string(), design.fit(&y));
    }
    Ok(FitReport {
        form: Form::General,
        n: rows.len(),
        condition_number: design.condition,
        unidentifiable: design.dropped.clone(),
        outputs,
        k4: None,
        k4_std_err: None,
        k5: None,
        k5_std_err: None,
    })
}

/// Fits the paper form (Eq. 1–5): `lt + lh` on `(1, h, α, β)`, and `k4 = lh/lt`, `k5 = lr/lt`
/// by least squares through the origin.
///
/// # Errors
/// As [`fit_general`], plus [`FitError::ZeroTipLength`] when every `lt` is zero.
pub fn fit_paper(rows: &[Measurement]) -> Result<FitReport, FitError> {
    let design = Design::new(rows, Form::Paper)?;
    let y = DVector::from_iterator(rows.len(), rows.iter().map(|m| m.footprint.lt_mm + m.footprint.lh_mm));
    let mut outputs = BTreeMap::new();
    outputs.insert("sum_mm".to_string(), design.fit(&y));
    let (k4, k4_se) = ratio_through_origin(rows, |m| m.footprint.lh_mm)?;
    let (k5, k5_se) = ratio_through_origin(rows, |m| m.footprint.lr_mm)?;
    Ok(FitReport {
        form: Form::Paper,
        n: rows.len(),
        condition_number: design.condition,
        unidentifiable: design.dropped.clone(),
        outputs,
        k4: Some(k4),
        k4_std_err: Some(k4_se),
        k5: Some(k5),
        k5_std_err: Some(k5_se),
    })
}

/// Fits either form.
///
/// # Errors
/// See [`fit_general`] and [`fit_paper`].
pub fn fit(rows: &[Measurement], form: Form) -> Result<FitReport, FitError> {
    match form {
        Form::General => fit_general(rows),
        Form::Paper => fit_paper(rows),
    }
}

/// `k = Σ lt·y / Σ lt²` and its standard error `sqrt(s² / Σ lt²)` with `s² = SSR/(n − 1)`.
fn ratio_through_origin(rows: &[Measurement], y: impl Fn(&Measurement) -> f64) -> Result<(f64, f64), FitError> {
    let sxx: f64 = rows.iter().map(|m| m.footprint.lt_mm.powi(2)).sum();
    if sxx <= 0.0 {
        return Err(FitError::ZeroTipLength);
    }
    let sxy: f64 = rows.iter().map(|m| m.footprint.lt_mm * y(m)).sum();
    let k = sxy / sxx;
    let ssr: f64 = rows.iter().map(|m| (y(m) - k * m.footprint.lt_mm).powi(2)).sum();
    let s2 = ssr / (rows.len() as f64 - 1.0);
    Ok((k, (s2 / sxx).sqrt()))
}

/// A residual standard error at or below this (mm, a picometre) is an exact fit for
/// [`FitReport`]'s `Display`: standard errors and t values are printed as undefined.
const EXACT_FIT_SE_MM: f64 = 1e-9;

impl fmt::Display for FitReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "{} form, n = {}, condition number = {:.4e}", self.form, self.n, self.condition_number)?;
        if !self.unidentifiable.is_empty() {
            writeln!(f, "unidentifiable (constant in the data, left out): {}", self.unidentifiable.join(", "))?;
        }
        // lt, lh, lr (the footprint's order), then anything else.
        const ORDER: [&str; 4] = ["lt_mm", "lh_mm", "lr_mm", "sum_mm"];
        let rank = |n: &str| ORDER.iter().position(|o| *o == n).unwrap_or(ORDER.len());
        let mut outputs: Vec<(&String, &OutputFit)> = self.outputs.iter().collect();
        outputs.sort_by_key(|(n, _)| rank(n));
        for (name, o) in outputs {
            writeln!(f)?;
            // Residuals that are zero to rounding (data generated from the model): standard
            // errors are rounding noise and t values meaningless, so they are printed as such.
            let exact = o.resid_se <= EXACT_FIT_SE_MM;
            if o.is_constant() {
                writeln!(f, "{name}: R² undefined ({name} is constant in the data)  resid. SE = {:.5} mm", o.resid_se)?;
            } else if exact {
                writeln!(f, "{name}: R² = {:.5}  resid. SE = 0 mm (an exact fit: std err and t are undefined)", o.r2)?;
            } else {
                writeln!(f, "{name}: R² = {:.5}  adj. R² = {:.5}  resid. SE = {:.5} mm", o.r2, o.adj_r2, o.resid_se)?;
            }
            writeln!(f, "  {:<10} {:>14} {:>12} {:>10}", "term", "coef", "std err", "t")?;
            let rows = [
                ("intercept", Some(o.coef.intercept), Some(o.std_err.intercept), Some(o.t.intercept)),
                ("h_mm", o.coef.h_mm, o.std_err.h_mm, o.t.h_mm),
                ("alpha_rad", o.coef.alpha_rad, o.std_err.alpha_rad, o.t.alpha_rad),
                ("beta_rad", o.coef.beta_rad, o.std_err.beta_rad, o.t.beta_rad),
            ];
            for (term, c, se, t) in rows {
                if let (Some(c), Some(se), Some(t)) = (c, se, t) {
                    if exact {
                        writeln!(f, "  {term:<10} {c:>14.6} {:>12} {:>10}", "undefined", "undefined")?;
                    } else if t.is_nan() {
                        writeln!(f, "  {term:<10} {c:>14.6} {se:>12.6} {:>10}", "undefined")?;
                    } else {
                        writeln!(f, "  {term:<10} {c:>14.6} {se:>12.6} {t:>10.3}")?;
                    }
                }
            }
        }
        if let (Some(k4), Some(k4se), Some(k5), Some(k5se)) = (self.k4, self.k4_std_err, self.k5, self.k5_std_err) {
            writeln!(f)?;
            writeln!(f, "k4 = lh/lt = {k4:.6} (std err {k4se:.6})")?;
            writeln!(f, "k5 = lr/lt = {k5:.6} (std err {k5se:.6})")?;
        }
        Ok(())
    }
}
