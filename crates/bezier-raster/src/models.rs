//! Stroke models: the B-BSM outline and the baselines the paper compares it with.
//!
//! Every model turns the same [`Footprint`] `(lt, lh, lr)`, anchor and β into a closed outline
//! in paper millimetres. In the footprint's own frame (root end at the origin, axis along +x to
//! the tip; the outline is then rotated by β about the anchor and moved there):
//!
//! | model | shape |
//! |---|---|
//! | [`Bsm`] | the two mirrored cubic Béziers of docs/contracts.md §3 |
//! | [`Circle`] | a disc of radius `lr` centred on the belly `(lh, 0)` |
//! | [`Ellipse`] | semi-axes `(lt + lh)/2` along the axis and `lr` across, centred midway `((lh + lt)/2, 0)`, so it spans root to tip |
//! | [`Line`] | the segment root → tip drawn `2·lr` wide with butt ends: the rectangle `[0, lh + lt] × [−lr, lr]` |
//! | [`Qbc`] | LearningToPaint's quadratic-Bézier stroke: the union of [`QBC_DISCS`] discs centred along the quadratic `C0 = (lr, 0)` (so the first disc touches the root end), `C1 = (lh, 0)` (the belly), `C2 = (lh + lt, 0)` (the tip), radius varying linearly from `r0 = lr` to `r2 = lr/8` |
//!
//! See `docs/stroke-models.md` for the reasoning.

use std::str::FromStr;

use brush_model::{Footprint, PointMm};
use kurbo::{Affine, BezPath, Circle as KCircle, Ellipse as KEllipse, PathEl, Point, Rect, Shape, Vec2};

/// Number of discs in the [`Qbc`] stroke (LearningToPaint draws 100).
pub const QBC_DISCS: usize = 100;

/// A stroke model: a footprint, anchor (mm) and direction β (rad) to a closed outline in paper
/// millimetres (nonzero fill rule).
pub trait StrokeModel: Sync {
    /// Short name used on the command line (`bsm`, `circle`, ...).
    fn name(&self) -> &'static str;
    /// The outline in the footprint's own frame (root end at the origin, tip along +x), mm.
    fn local_outline(&self, fp: &Footprint) -> BezPath;
    /// The outline placed on the paper: rotated by `beta_rad` about the root end, which is put
    /// at `anchor`, mm.
    fn outline(&self, fp: &Footprint, anchor: PointMm, beta_rad: f64) -> BezPath {
        let mut p = self.local_outline(fp);
        p.apply_affine(Affine::translate(Vec2::new(anchor.x_mm, anchor.y_mm)) * Affine::rotate(beta_rad));
        p
    }
}

/// The analytic B-BSM footprint (two mirrored cubic Béziers).
#[derive(Clone, Copy, Debug, Default)]
pub struct Bsm;
/// Baseline: a disc of radius `lr` at the belly.
#[derive(Clone, Copy, Debug, Default)]
pub struct Circle;
/// Baseline: an ellipse from root to tip, `lr` wide.
#[derive(Clone, Copy, Debug, Default)]
pub struct Ellipse;
/// Baseline: a straight segment root → tip of width `2·lr`, butt ends.
#[derive(Clone, Copy, Debug, Default)]
pub struct Line;
/// Baseline: LearningToPaint's quadratic Bézier curve stroke with linearly varying radius.
#[derive(Clone, Copy, Debug, Default)]
pub struct Qbc;

fn pt(p: PointMm) -> Point {
    Point::new(p.x_mm, p.y_mm)
}

impl StrokeModel for Bsm {
    fn name(&self) -> &'static str {
        "bsm"
    }
    fn local_outline(&self, fp: &Footprint) -> BezPath {
        let (u, l) = (fp.upper().points, fp.lower().points);
        let mut p = BezPath::new();
        p.move_to(pt(u[0]));
        p.curve_to(pt(u[1]), pt(u[2]), pt(u[3]));
        p.curve_to(pt(l[1]), pt(l[2]), pt(l[3]));
        p.close_path();
        p
    }
}

impl StrokeModel for Circle {
    fn name(&self) -> &'static str {
        "circle"
    }
    fn local_outline(&self, fp: &Footprint) -> BezPath {
        KCircle::new((fp.lh_mm, 0.0), fp.lr_mm).to_path(1e-4)
    }
}

impl StrokeModel for Ellipse {
    fn name(&self) -> &'static str {
        "ellipse"
    }
    fn local_outline(&self, fp: &Footprint) -> BezPath {
        let a = 0.5 * fp.length_mm();
        KEllipse::new((a, 0.0), (a, fp.lr_mm), 0.0).to_path(1e-4)
    }
}

impl StrokeModel for Line {
    fn name(&self) -> &'static str {
        "line"
    }
    fn local_outline(&self, fp: &Footprint) -> BezPath {
        Rect::new(0.0, -fp.lr_mm, fp.length_mm(), fp.lr_mm).to_path(1e-4)
    }
}

impl Qbc {
    /// The parameters `(C0, C1, C2, r0, r2)` this footprint gives (mm, own frame).
    pub fn parameters(fp: &Footprint) -> ([Point; 3], f64, f64) {
        let c = [Point::new(fp.lr_mm, 0.0), Point::new(fp.lh_mm, 0.0), Point::new(fp.length_mm(), 0.0)];
        (c, fp.lr_mm, fp.lr_mm / 8.0)
    }
}

impl StrokeModel for Qbc {
    fn name(&self) -> &'static str {
        "qbc"
    }
    fn local_outline(&self, fp: &Footprint) -> BezPath {
        let ([c0, c1, c2], r0, r2) = Qbc::parameters(fp);
        let mut p = BezPath::new();
        for i in 0..QBC_DISCS {
            let t = i as f64 / (QBC_DISCS - 1) as f64;
            let u = 1.0 - t;
            let centre = (c0.to_vec2() * (u * u) + c1.to_vec2() * (2.0 * u * t) + c2.to_vec2() * (t * t)).to_point();
            let r = u * r0 + t * r2;
            // Each disc as its own counter-clockwise subpath: the nonzero fill is their union.
            p.extend(KCircle::new(centre, r).path_elements(1e-4).filter(|e| !matches!(e, PathEl::ClosePath)));
            p.close_path();
        }
        p
    }
}

/// The models by name, for the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ModelKind {
    /// [`Bsm`].
    Bsm,
    /// [`Circle`].
    Circle,
    /// [`Ellipse`].
    Ellipse,
    /// [`Line`].
    Line,
    /// [`Qbc`].
    Qbc,
}

impl ModelKind {
    /// Every model, B-BSM first.
    pub const ALL: [ModelKind; 5] =
        [ModelKind::Bsm, ModelKind::Circle, ModelKind::Ellipse, ModelKind::Line, ModelKind::Qbc];
    /// The baselines (every model but B-BSM).
    pub const BASELINES: [ModelKind; 4] = [ModelKind::Circle, ModelKind::Ellipse, ModelKind::Line, ModelKind::Qbc];

    /// The model itself.
    pub fn model(self) -> &'static dyn StrokeModel {
        match self {
            ModelKind::Bsm => &Bsm,
            ModelKind::Circle => &Circle,
            ModelKind::Ellipse => &Ellipse,
            ModelKind::Line => &Line,
            ModelKind::Qbc => &Qbc,
        }
    }
    /// Its command-line name.
    pub fn name(self) -> &'static str {
        self.model().name()
    }
}

impl FromStr for ModelKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        ModelKind::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| format!("unknown stroke model `{s}` (expected bsm, circle, ellipse, line or qbc)"))
    }
}
