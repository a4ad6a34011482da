//! Worlds that disagree with maobi's model of the moving brush, to judge plans by ink the model
//! did not make (docs/trajectory.md, "Worlds that disagree with the model"; docs/closed-loop.md).
//! Test and measurement code only: no library crate depends on this one, so its constants never
//! reach what a user runs.
//!
//! A [`World`] inks a path of brush states with its own brush and its own drag rule, written
//! here apart from `brush_model::ForwardModel`:
//!
//! * the path is sampled as the forward model samples it (every 0.1 mm of travel, 0.25 mm of
//!   depth, 0.5° of tool-axis turn), so a world that agrees with the model in every constant
//!   leaves the model's ink;
//! * a sample pressed at least [`World::contact_h_mm`] extends the pressed path; an upright
//!   brush's footprint points at the first point of that path, walking back, at least
//!   [`World::trail_reach`] footprint lengths away (else at its farthest point once that is
//!   0.3 mm away, else the way it last pointed, else, right at touch-down, opposite the first
//!   0.3 mm of the pressed motion that follows); a tilted brush's (α ≥ 2°) along its lean;
//! * a sample touching the paper more lightly neither inks nor turns the hairs: their bend, the
//!   pressed path so far, is carried along with the brush; lifting (`h ≤ 0`) forgets it;
//! * a pressed sample leaves the profile's footprint for its press, its belly ×[`World::width`],
//!   its lengths ×[`World::length`], grown by [`World::spread_mm`] all round, its root
//!   [`World::lag_mm`] behind along the path; presses lighter than the calibrated range leave
//!   nothing, or with [`World::light_ink`] the profile's footprint extrapolated.

use std::f64::consts::FRAC_PI_2;

use bezier_raster::{Coverage, ModelKind, Stamp, render_stamps};
use brush_model::{BrushProfile, DEPTH_EDGE_TOLERANCE_MM, Extrapolation, Footprint, PointMm, Press, TrackPoint};
use thiserror::Error;

/// The closed loop's test world's belly half-width against the profile's.
pub const MISMATCH_WIDTH: f64 = 1.18;
/// The closed loop's test world's tip and root lengths against the profile's.
pub const MISMATCH_LENGTH: f64 = 1.12;
/// How far the closed loop's test world's footprint root lags behind the commanded point along
/// the path, mm.
pub const MISMATCH_LAG_MM: f64 = 0.4;
/// Where the closed loop's test world's upright tip lies on the path, footprint lengths back
/// (the forward model's nominal: 0.5).
pub const MISMATCH_TRAIL_REACH: f64 = 0.3;
/// How far the closed loop's test world's ink spreads past the footprint's outline, mm.
pub const MISMATCH_SPREAD_MM: f64 = 0.3;

/// Path sampling: travel, mm (the forward model's default).
const STEP_MM: f64 = 0.1;
/// Path sampling: depth, mm (the forward model's default).
const STEP_H_MM: f64 = 0.25;
/// Path sampling: tool-axis turn, degrees (the forward model's default).
const STEP_TURN_DEG: f64 = 0.5;
/// Tilt from which a footprint points along the lean, degrees.
const TILT_DEG: f64 = 2.0;
/// Pressed travel that sets the hairs at touch-down and before the reach, mm.
const MIN_MOTION_MM: f64 = 0.3;

/// A world: how its brush writes against the profile, and how its hairs follow the motion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct World {
    /// Belly half-width factor.
    pub width: f64,
    /// Tip and root length factor.
    pub length: f64,
    /// The footprint root's lag behind the commanded point along the pressed path, mm.
    pub lag_mm: f64,
    /// An upright brush's tip lies on the pressed path this fraction of a footprint length back.
    pub trail_reach: f64,
    /// Ink spread past the footprint's outline, mm.
    pub spread_mm: f64,
    /// The depth from which the hairs follow motion (and ink), mm: lighter motion neither inks
    /// nor turns them.
    pub contact_h_mm: f64,
    /// Presses lighter than the profile's calibrated range (and at least `contact_h_mm`) leave
    /// the profile's footprint extrapolated instead of nothing.
    pub light_ink: bool,
}

/// What [`World::parse`] refuses.
#[derive(Debug, Error, PartialEq)]
#[error("world `{spec}`: `{item}`: {why}")]
pub struct WorldError {
    /// The whole spec.
    pub spec: String,
    /// The item that is wrong.
    pub item: String,
    /// What was expected.
    pub why: String,
}

impl World {
    /// The forward model's rule with hairs that follow any touch (the model before the contact
    /// depth): the profile's brush, tip 0.5 footprint lengths back, no lag, no spread.
    pub const MODEL: World = World {
        width: 1.0,
        length: 1.0,
        lag_mm: 0.0,
        trail_reach: brush_model::TRAIL_REACH,
        spread_mm: 0.0,
        contact_h_mm: 0.0,
        light_ink: false,
    };

    /// The closed loop's test world: wider and longer than its profile, its root lagging, its
    /// tip trailing less, its ink spreading; hairs that follow any touch.
    pub const MISMATCH: World = World {
        width: MISMATCH_WIDTH,
        length: MISMATCH_LENGTH,
        lag_mm: MISMATCH_LAG_MM,
        trail_reach: MISMATCH_TRAIL_REACH,
        spread_mm: MISMATCH_SPREAD_MM,
        contact_h_mm: 0.0,
        light_ink: false,
    };

    /// The world that agrees with the model for `profile`: its brush, its hairs.
    pub fn of_profile(profile: &BrushProfile) -> World {
        World { trail_reach: profile.hairs.trail_reach, contact_h_mm: profile.hairs.contact_h_mm, ..World::MODEL }
    }

    /// A world from its name: `model` or `mismatch`, then modifiers, all joined by `,`:
    /// `pressure:MM` (contact depth), `trail:R`, `width:F`, `length:F`, `lag:MM`, `spread:MM`,
    /// `light`. Without a base the modifiers apply to `model`; `pressure:0.05` alone is the
    /// model's rule with hairs that need 0.05 mm.
    ///
    /// # Errors
    /// [`WorldError`] naming the item that is not one of these, or a value out of range.
    pub fn parse(spec: &str) -> Result<World, WorldError> {
        let bad =
            |item: &str, why: &str| WorldError { spec: spec.to_string(), item: item.to_string(), why: why.into() };
        let mut w = World::MODEL;
        for (i, item) in spec.split(',').map(str::trim).enumerate() {
            let (key, value) = match item.split_once(':') {
                Some((k, v)) => (k, Some(v)),
                None => (item, None),
            };
            let num = |lo: f64, hi: f64, what: &str| -> Result<f64, WorldError> {
                let v = value.ok_or_else(|| bad(item, &format!("expected `{key}:{what}`")))?;
                match v.trim().parse::<f64>() {
                    Ok(x) if x.is_finite() && (lo..=hi).contains(&x) => Ok(x),
                    _ => Err(bad(item, &format!("expected {what} in [{lo}, {hi}]"))),
                }
            };
            match key {
                "model" | "mismatch" if i == 0 && value.is_none() => {
                    w = if key == "model" { World::MODEL } else { World::MISMATCH };
                }
                "pressure" => w.contact_h_mm = num(0.0, 20.0, "a depth in mm")?,
                "trail" => w.trail_reach = num(0.01, 1.0, "a share of the footprint length")?,
                "width" => w.width = num(0.1, 10.0, "a factor")?,
                "length" => w.length = num(0.1, 10.0, "a factor")?,
                "lag" => w.lag_mm = num(0.0, 20.0, "a length in mm")?,
                "spread" => w.spread_mm = num(-2.0, 5.0, "a length in mm")?,
                "light" if value.is_none() => w.light_ink = true,
                _ => {
                    return Err(bad(
                        item,
                        "expected `model` or `mismatch` first, then pressure:MM, trail:R, width:F, length:F, lag:MM, spread:MM or light",
                    ));
                }
            }
        }
        Ok(w)
    }

    /// The world in words, e.g. `hairs from 0.05 mm` or `belly ×1.18, lengths ×1.12, …`.
    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        if self.width != 1.0 {
            parts.push(format!("belly ×{}", self.width));
        }
        if self.length != 1.0 {
            parts.push(format!("lengths ×{}", self.length));
        }
        if self.lag_mm != 0.0 {
            parts.push(format!("root lag {} mm", self.lag_mm));
        }
        if self.trail_reach != brush_model::TRAIL_REACH {
            parts.push(format!("tip {} footprint lengths back", self.trail_reach));
        }
        if self.spread_mm != 0.0 {
            parts.push(format!("spread {} mm", self.spread_mm));
        }
        parts.push(if self.contact_h_mm > 0.0 {
            format!("hairs turn from {} mm of press", self.contact_h_mm)
        } else {
            "hairs turn at any touch".into()
        });
        if self.light_ink {
            parts.push("light presses ink".into());
        }
        parts.join(", ")
    }

    /// The footprints this world's brush leaves along `states` (one stroke, or a whole executed
    /// path with lifts in it), for a brush described by `profile` (its footprints; its hairs
    /// are the world's, not the profile's).
    pub fn stamps(&self, states: &[TrackPoint], profile: &BrushProfile) -> Vec<Stamp> {
        let samples = sample(states);
        let mut out = Vec::new();
        // The pressed path since touch-down, less `shift` (how far the bent hairs were carried
        // while the brush touched without a press), and its length so far at each point.
        let mut hist: Vec<[f64; 2]> = Vec::new();
        let mut cum: Vec<f64> = Vec::new();
        let mut shift = [0.0, 0.0];
        let mut prev: Option<[f64; 2]> = None;
        let mut last: Option<f64> = None;
        for (i, p) in samples.iter().enumerate() {
            let here = [p.x_mm, p.y_mm];
            if !(p.h_mm > 0.0) {
                hist.clear();
                cum.clear();
                shift = [0.0, 0.0];
                prev = None;
                last = None;
                continue;
            }
            if p.h_mm < self.contact_h_mm {
                if let Some(q) = prev {
                    shift = [shift[0] + here[0] - q[0], shift[1] + here[1] - q[1]];
                }
                prev = Some(here);
                continue;
            }
            prev = Some(here);
            let rel = [here[0] - shift[0], here[1] - shift[1]];
            let c = match (hist.last(), cum.last()) {
                (Some(q), Some(c)) => c + (rel[0] - q[0]).hypot(rel[1] - q[1]),
                _ => 0.0,
            };
            hist.push(rel);
            cum.push(c);
            let Some(p) = self.pressed(profile, p) else { continue };
            // Where the root sits: lagging along the pressed path (the point itself without lag),
            // and the last point of the path behind it.
            let (anchor, k) = if self.lag_mm > 0.0 {
                let target = c - self.lag_mm;
                let k = cum.partition_point(|&v| v < target).min(hist.len() - 1);
                let a = if target <= 0.0 || k == 0 {
                    hist[0]
                } else {
                    let (a, b, ca, cb) = (hist[k - 1], hist[k], cum[k - 1], cum[k]);
                    let f = if cb > ca { (target - ca) / (cb - ca) } else { 0.0 };
                    [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])]
                };
                ([a[0] + shift[0], a[1] + shift[1]], k)
            } else {
                (here, hist.len() - 1)
            };
            let dir = if p.alpha_rad >= TILT_DEG.to_radians() {
                p.beta_rad
            } else {
                let reach = self.trail_reach * self.length * self.reach_length(profile, &p);
                self.dragged(&hist[..=k], shift, anchor, reach)
                    .or(last)
                    .or_else(|| self.ahead(&samples[i..], here))
                    .unwrap_or(FRAC_PI_2)
            };
            last = Some(dir);
            let Some(fp) = self.footprint(profile, &TrackPoint { beta_rad: dir, ..p }) else { continue };
            let s = self.spread_mm;
            let footprint = Footprint {
                lt_mm: self.length * fp.lt_mm + s,
                lh_mm: self.length * fp.lh_mm + s,
                lr_mm: self.width * fp.lr_mm + s,
            };
            let anchor = PointMm::new(anchor[0] - s * dir.cos(), anchor[1] - s * dir.sin());
            out.push(Stamp { footprint, anchor, beta_rad: dir });
        }
        out
    }

    /// [`World::stamps`] of every stroke (each one contact from its first point to its last).
    pub fn track_stamps(&self, strokes: &[brush_model::Stroke], profile: &BrushProfile) -> Vec<Stamp> {
        strokes.iter().flat_map(|s| self.stamps(&s.points, profile)).collect()
    }

    /// The sample as this world presses it: its depth snapped onto the calibrated range's end
    /// when within [`DEPTH_EDGE_TOLERANCE_MM`] of it (a robot's read-back), or `None` when it
    /// leaves no footprint (lighter than the range without [`World::light_ink`], deeper than
    /// it, or a tilt out of range).
    fn pressed(&self, profile: &BrushProfile, p: &TrackPoint) -> Option<TrackPoint> {
        let r = profile.ranges.h_mm;
        let h = if r.contains(p.h_mm) {
            p.h_mm
        } else if p.h_mm < r.min && p.h_mm >= r.min - DEPTH_EDGE_TOLERANCE_MM {
            r.min
        } else if p.h_mm > r.max && p.h_mm <= r.max + DEPTH_EDGE_TOLERANCE_MM {
            r.max
        } else if self.light_ink && p.h_mm < r.min {
            p.h_mm
        } else {
            return None;
        };
        let q = TrackPoint { h_mm: h, ..*p };
        self.footprint(profile, &q).map(|_| q)
    }

    /// The profile's footprint for a pressed sample (its β the footprint's direction);
    /// extrapolated below the calibrated range.
    fn footprint(&self, profile: &BrushProfile, p: &TrackPoint) -> Option<Footprint> {
        let ex = if p.h_mm < profile.ranges.h_mm.min { Extrapolation::Allow } else { Extrapolation::Refuse };
        profile.predict_oriented(&p.press(), ex).ok()
    }

    /// The profile's footprint length for the drag rule's reach (β = 0, as the footprint's
    /// size does not depend on where it points), mm.
    fn reach_length(&self, profile: &BrushProfile, p: &TrackPoint) -> f64 {
        let ex = if p.h_mm < profile.ranges.h_mm.min { Extrapolation::Allow } else { Extrapolation::Refuse };
        profile.predict_oriented(&Press::new(p.h_mm, p.alpha_rad, 0.0), ex).map_or(0.0, |f| f.length_mm())
    }

    /// An upright brush's direction from the pressed path `hist` (less `shift`): towards the
    /// first point walking back at least `reach` from `from`, else the farthest once it is
    /// [`MIN_MOTION_MM`] away.
    fn dragged(&self, hist: &[[f64; 2]], shift: [f64; 2], from: [f64; 2], reach: f64) -> Option<f64> {
        let mut far = (0.0f64, None);
        for q in hist.iter().rev() {
            let q = [q[0] + shift[0], q[1] + shift[1]];
            let d = (q[0] - from[0]).hypot(q[1] - from[1]);
            if d >= reach {
                return Some((q[1] - from[1]).atan2(q[0] - from[0]));
            }
            if d > far.0 {
                far = (d, Some(q));
            }
        }
        match far {
            (d, Some(q)) if d >= MIN_MOTION_MM => Some((q[1] - from[1]).atan2(q[0] - from[0])),
            _ => None,
        }
    }

    /// At touch-down: opposite the first [`MIN_MOTION_MM`] of the pressed motion that follows.
    fn ahead(&self, rest: &[TrackPoint], here: [f64; 2]) -> Option<f64> {
        for q in rest.iter().skip(1) {
            if !(q.h_mm > 0.0 && q.h_mm >= self.contact_h_mm) {
                return None;
            }
            if (q.x_mm - here[0]).hypot(q.y_mm - here[1]) >= MIN_MOTION_MM {
                return Some((here[1] - q.y_mm).atan2(here[0] - q.x_mm));
            }
        }
        None
    }
}

/// The path through `states` sampled every [`STEP_MM`] of travel, [`STEP_H_MM`] of depth and
/// [`STEP_TURN_DEG`] of tool-axis turn (position and depth linear, tilt and lean linear too),
/// each state itself included.
fn sample(states: &[TrackPoint]) -> Vec<TrackPoint> {
    let axis = |p: &TrackPoint| {
        let (s, c) = p.alpha_rad.sin_cos();
        [s * p.beta_rad.cos(), s * p.beta_rad.sin(), c]
    };
    let mut out = Vec::with_capacity(states.len() * 2);
    for (i, s) in states.iter().enumerate() {
        if i > 0 {
            let a = states[i - 1];
            let d = (s.x_mm - a.x_mm).hypot(s.y_mm - a.y_mm);
            let (u, v) = (axis(&a), axis(s));
            let dot = (u[0] * v[0] + u[1] * v[1] + u[2] * v[2]).clamp(-1.0, 1.0);
            let cr = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
            let turn = (cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]).sqrt().atan2(dot);
            let n = (d / STEP_MM)
                .max(turn / STEP_TURN_DEG.to_radians())
                .max((s.h_mm - a.h_mm).abs() / STEP_H_MM)
                .ceil()
                .clamp(1.0, 1e6) as usize;
            for k in 1..n {
                let f = k as f64 / n as f64;
                out.push(TrackPoint {
                    x_mm: a.x_mm + f * (s.x_mm - a.x_mm),
                    y_mm: a.y_mm + f * (s.y_mm - a.y_mm),
                    h_mm: a.h_mm + f * (s.h_mm - a.h_mm),
                    alpha_rad: a.alpha_rad + f * (s.alpha_rad - a.alpha_rad),
                    beta_rad: a.beta_rad + f * brush_model::wrap_angle_rad(s.beta_rad - a.beta_rad),
                });
            }
        }
        out.push(*s);
    }
    out
}

/// The world's ink over a square box of the paper: `size_px²` px over `[x0, y0]` + `side_mm`
/// (the B-BSM outline, as every maobi render).
pub fn ink(stamps: &[Stamp], x0_mm: f64, y0_mm: f64, side_mm: f64, size_px: u32) -> Coverage {
    render_stamps(
        stamps,
        ModelKind::Bsm.model(),
        PointMm::new(x0_mm, y0_mm),
        size_px as f64 / side_mm,
        size_px,
        size_px,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn worlds_parse_by_name_and_bad_names_are_named() {
        assert_eq!(World::parse("model"), Ok(World::MODEL));
        assert_eq!(World::parse("mismatch"), Ok(World::MISMATCH));
        let p = World::parse("pressure:0.05").unwrap();
        assert_eq!(p, World { contact_h_mm: 0.05, ..World::MODEL });
        let m = World::parse("mismatch, pressure:1, light").unwrap();
        assert_eq!(m, World { contact_h_mm: 1.0, light_ink: true, ..World::MISMATCH });
        assert_eq!(World::parse("trail:0.3").unwrap().trail_reach, 0.3);
        for (spec, item) in [
            ("pressure", "pressure"),
            ("pressure:-1", "pressure:-1"),
            ("trail:2", "trail:2"),
            ("mud", "mud"),
            ("pressure:1,mismatch", "mismatch"),
        ] {
            let e = World::parse(spec).unwrap_err();
            assert_eq!(e.item, item, "{e}");
            assert!(e.to_string().starts_with(&format!("world `{spec}`")), "{e}");
        }
        assert!(World::MISMATCH.describe().contains("belly ×1.18"));
        assert_eq!(World::parse("pressure:1").unwrap().describe(), "hairs turn from 1 mm of press");
    }
}
