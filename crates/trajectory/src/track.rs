//! Centre lines with widths → a 5D brush track on the paper: per corner-free piece a reverse
//! entry, a turn-over glide and forward writing ([`build_track`]).
//!
//! Frames and units: centre lines come in the em frame (em units), the track goes out on paper
//! (mm, radians) through the [`CharBox`]. Invariants: the track holds only commanded motion
//! (β is what [`brush_model::ForwardModel`] derives from it, never set freely); consecutive
//! points while the brush presses are at most one spacing apart; every pressed depth is
//! predictable by the profile (refused otherwise).

use brush_model::{
    BrushProfile, Clamp, Extrapolation, ForwardModel, PointMm, Press, ProfileError, Stroke, Track, TrackPoint,
};

use crate::paper::CharBox;
use crate::path::StrokePath;
use crate::polyline::arc_lengths_by;

/// How footprints are sized.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Sizing {
    /// By the brush profile: h from the inverse model, clamped to the calibrated range.
    #[default]
    Brush,
    /// Freely from the glyph width (h unclamped, extrapolating): the upper bound of what a
    /// brush with any width range could do with this footprint shape.
    Unconstrained,
}

/// Options of track building.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackOptions {
    /// Where the character sits.
    pub char_box: CharBox,
    /// Distance between consecutive track points along a stroke, mm.
    pub spacing_mm: f64,
    /// Tilt α for every point, radians (policy: constant; 0 gives the shortest footprint for a
    /// width, so the least overshoot at stroke ends).
    pub alpha_rad: f64,
    /// Footprint sizing.
    pub sizing: Sizing,
}

/// Default spacing between track points, mm: fine enough that halving it hardly changes the
/// rendered character (a test checks it). Chosen on the tuning set (docs/trajectory.md, Tuned
/// constants).
pub const DEFAULT_SPACING_MM: f64 = 0.15;

/// What track building measured.
#[derive(Clone, Debug, PartialEq)]
pub struct BuiltTrack {
    /// The track.
    pub track: Track,
    /// Points whose wanted width needed an h below the range (clamped up).
    pub clamped_low: usize,
    /// Points whose wanted width needed an h above the range (clamped down).
    pub clamped_high: usize,
}

/// The segment of the ascending arc lengths `s` holding `t` and the fraction along it, clamped
/// to the ends (binary search).
fn locate(s: &[f64], t: f64) -> (usize, f64) {
    if t <= s[0] {
        return (0, 0.0);
    }
    let last = s.len() - 1;
    if t >= s[last] {
        return (last.saturating_sub(1), if last == 0 { 0.0 } else { 1.0 });
    }
    // First index with s[i] ≥ t (≥ 1 here).
    let i = s.partition_point(|&x| x < t);
    let f = if s[i] > s[i - 1] { (t - s[i - 1]) / (s[i] - s[i - 1]) } else { 0.0 };
    (i - 1, f)
}

/// Linear interpolation of `(s, v)` samples at `t`.
fn interp(s: &[f64], v: &[f64], t: f64) -> f64 {
    let (i, f) = locate(s, t);
    if i + 1 >= v.len() {
        return v[v.len() - 1];
    }
    v[i] + f * (v[i + 1] - v[i])
}

fn point_at(s: &[f64], p: &[PointMm], t: f64) -> PointMm {
    let (i, f) = locate(s, t);
    if i + 1 >= p.len() {
        return p[p.len() - 1];
    }
    PointMm::new(p[i].x_mm + f * (p[i + 1].x_mm - p[i].x_mm), p[i].y_mm + f * (p[i + 1].y_mm - p[i].y_mm))
}

/// The footprint length `lh + lt` as a linear function of h at fixed α: `(slope, offset)`.
fn length_model(profile: &BrushProfile, alpha: f64, beta: f64) -> (f64, f64) {
    let m = &profile.model;
    let at = |h: f64| m.lt_mm.eval(h, alpha, beta) + m.lh_mm.eval(h, alpha, beta);
    (at(1.0) - at(0.0), at(0.0))
}

/// The lightest glide, mm: a brush whose hairs follow any touch (`hairs.contact_h_mm = 0`)
/// glides with its tip only touching the paper, far lighter than any calibrated press, so it
/// leaves no footprint in the model (a real brush leaves at most a hairline there).
pub const GLIDE_H_MM: f64 = 0.01;

/// How much deeper than its hairs' contact depth (`BrushProfile::hairs.contact_h_mm`) the brush
/// glides: a light press, so the glide turns the hairs even when they need up to this factor
/// more press than the profile says. Hand-set (docs/trajectory.md, "Track building").
pub const GLIDE_CONTACT_FACTOR: f64 = 2.0;

/// The depth the brush glides at while it turns over at a piece's head and into a short head,
/// mm: [`GLIDE_CONTACT_FACTOR`] times the hairs' contact depth (so the glide is pressed and
/// drags the hairs round, not only touching), at least [`GLIDE_H_MM`], at most the lightest
/// calibrated press (a brush whose hairs need more than that cannot turn them without ink).
/// Lighter than the calibrated range it leaves no footprint in the model.
///
/// # Examples
/// ```
/// use trajectory::brush_model::BrushProfile;
/// let mut pen1 = BrushProfile::builtin("pen1").unwrap();
/// assert_eq!(trajectory::glide_h_mm(&pen1), 2.0 * pen1.hairs.contact_h_mm);
/// pen1.hairs.contact_h_mm = 0.0;
/// assert_eq!(trajectory::glide_h_mm(&pen1), trajectory::GLIDE_H_MM);
/// ```
pub fn glide_h_mm(profile: &BrushProfile) -> f64 {
    (GLIDE_CONTACT_FACTOR * profile.hairs.contact_h_mm).max(GLIDE_H_MM).min(profile.ranges.h_mm.min)
}

/// Builds the brush track of a character from its stroke centre lines.
///
/// The track holds only what a robot can be told to do: where the brush is, how deep it
/// presses and how it leans. Which way each footprint points follows from that motion through
/// the forward model ([`brush_model::ForwardModel`], docs/brush-model.md), never set freely.
///
/// Per stroke: the centre line is split at its [`StrokePath::corners`] and each piece is
/// resampled every `spacing_mm`. A piece is written as a *reverse entry* (逆锋) and then forward:
///
/// 1. **Entry.** The brush touches down at the first station where a trailing footprint fits
///    behind it (its length at most the straight distance back to the piece's start) and presses
///    *backwards* to the start. Moving back, the hairs trail ahead, so the tip points forward as
///    kaiti's blunt stroke heads want: the root on the station, the belly `lh` ahead sized to
///    the glyph's half-width there, pressed lighter (or not at all) where the tip would reach
///    past the piece's end. When that leaves only the head pressed (a piece shorter than the
///    lightest footprint), the brush glides back to it pressed lightly ([`glide_h_mm`]) and
///    presses there, so the head trails forward along the piece too.
/// 2. **Turn.** At the start the brush eases up to a light press ([`glide_h_mm`]: deeper than
///    its hairs need to follow the motion, lighter than any footprint, so no ink), glides
///    forward along the stroke to the first station where its lightest press fits behind it,
///    and presses again: turning the hairs over under a writing press would sweep the tail out
///    behind the stroke's head, and a glide lighter than the hairs' contact depth would leave
///    them pointing forward.
/// 3. **Writing.** Forward to the piece's end, the hairs trailing; each belly (`lh` behind the
///    anchor) is sized to the glyph's half-width there through the inverse model, and no press
///    is so long that its tail passes the piece's start (pressed lighter until it fits).
///
/// Between the pieces of a stroke the brush eases up in place and glides to the next entry, so
/// the stroke stays one robot stroke (no jump with the brush down). With `alpha_rad` at or above
/// the model's tilt threshold the brush leans the way the upright model would point each
/// footprint (the wrist turns while the brush glides at h = 0).
///
/// # Examples
/// ```
/// use trajectory::brush_model::BrushProfile;
/// use trajectory::{CharBox, DEFAULT_SPACING_MM, Method, Sizing, TrackOptions, build_track, centre_lines, embedded_glyph};
/// let paths = centre_lines(&embedded_glyph('一').unwrap(), Method::Medians, 256).unwrap();
/// let pen1 = BrushProfile::builtin("pen1").unwrap();
/// let opts = TrackOptions {
///     char_box: CharBox { x0_mm: 10.0, y0_mm: 20.0, size_mm: 80.0 },
///     spacing_mm: DEFAULT_SPACING_MM,
///     alpha_rad: 0.0,
///     sizing: Sizing::Brush,
/// };
/// let built = build_track(&paths, &pen1, &opts).unwrap();
/// assert_eq!(built.track.strokes.len(), 1);
/// // The stroke lies in its box and presses within the brush's calibrated depths.
/// let h = &pen1.ranges.h_mm;
/// assert!(built.track.strokes[0].points.iter().all(|p| (10.0..=90.0).contains(&p.x_mm) && p.h_mm <= h.max));
/// ```
///
/// # Errors
/// [`ProfileError`] if the profile cannot be inverted or predicts degenerate footprints.
pub fn build_track(
    paths: &[StrokePath],
    profile: &BrushProfile,
    opts: &TrackOptions,
) -> Result<BuiltTrack, ProfileError> {
    let placer = Placer::new(profile, opts);
    let k = opts.char_box.mm_per_em();
    let mut counts = Clamped::default();
    let mut strokes = Vec::with_capacity(paths.len());
    // Directions as an upright brush would leave them (the tilt threshold out of reach), its
    // hairs as the profile describes them.
    let dragged = ForwardModel { tilt_threshold_rad: f64::INFINITY, ..ForwardModel::default() };
    for path in paths {
        if path.points.is_empty() {
            continue;
        }
        let pts: Vec<PointMm> = path.points.iter().map(|&p| opts.char_box.to_paper(p)).collect();
        let widths: Vec<f64> = path.half_widths.iter().map(|w| w * k).collect();
        let mut points: Vec<TrackPoint> = Vec::new();
        let mut start = 0;
        for end in path.corners.iter().copied().filter(|&c| c > 0 && c + 1 < pts.len()).chain([pts.len() - 1]) {
            if end > start {
                let piece = placer.piece(&pts[start..=end], &widths[start..=end], &mut counts)?;
                if let (Some(last), Some(first)) = (points.last().copied(), piece.first().copied()) {
                    // Ease up in place, glide to the next entry.
                    points.push(TrackPoint { h_mm: 0.0, ..last });
                    points.push(TrackPoint { h_mm: 0.0, ..first });
                }
                points.extend(piece);
                start = end;
            }
        }
        let mut points = dragged.with_directions(profile, &points, placer.extrapolation());
        // A brush easing up in place keeps its lean; it turns while gliding to the next press.
        for i in 1..points.len() {
            let (a, b) = (points[i - 1], points[i]);
            if !b.is_pressed() && a.is_pressed() && a.x_mm == b.x_mm && a.y_mm == b.y_mm {
                points[i].beta_rad = a.beta_rad;
            }
        }
        strokes.push(Stroke { points });
    }
    // Every pressed footprint must be predictable (refused only if the profile is degenerate).
    for p in strokes.iter().flat_map(|s| s.points.iter()).filter(|p| p.h_mm >= placer.lowest) {
        profile.predict_oriented(&Press::new(p.h_mm, p.alpha_rad, p.beta_rad), placer.extrapolation())?;
    }
    Ok(BuiltTrack { track: Track { strokes }, clamped_low: counts.low, clamped_high: counts.high })
}

/// How many pressed points had their h clamped up (`low`) or down (`high`) to the brush's range.
#[derive(Default)]
struct Clamped {
    low: usize,
    high: usize,
}

impl Clamped {
    fn tally(&mut self, clamp: Clamp) {
        match clamp {
            Clamp::Min => self.low += 1,
            Clamp::Max => self.high += 1,
            Clamp::None => {}
        }
    }
}

/// A piece's end replaces the last regular station when closer to it than this share of a
/// spacing (no two commanded points at one place). Hand-set.
const END_STATION_MERGE: f64 = 0.05;

/// The stations of a piece `total` mm long: every `step` mm from 0, and the end (which replaces
/// a last regular station closer than [`END_STATION_MERGE`] of a step).
fn stations(total: f64, step: f64) -> Vec<f64> {
    let n = (total / step).floor() as usize;
    let mut stations: Vec<f64> = (0..=n).map(|i| i as f64 * step).collect();
    if total - n as f64 * step > END_STATION_MERGE * step || n == 0 {
        if total > 1e-9 {
            stations.push(total);
        }
    } else {
        stations[n] = total;
    }
    stations
}

/// Places footprints along one corner-free piece of a stroke.
struct Placer<'a> {
    profile: &'a BrushProfile,
    opts: &'a TrackOptions,
    beta_shape: f64,
    l_slope: f64,
    l_off: f64,
    lowest: f64,
    glide_h: f64,
}

impl<'a> Placer<'a> {
    fn new(profile: &'a BrushProfile, opts: &'a TrackOptions) -> Self {
        let beta_shape = profile.ranges.beta_rad.min;
        let (l_slope, l_off) = length_model(profile, opts.alpha_rad, beta_shape);
        let lowest = match opts.sizing {
            Sizing::Brush => profile.ranges.h_mm.min,
            Sizing::Unconstrained => 1e-3,
        };
        Self { profile, opts, beta_shape, l_slope, l_off, lowest, glide_h: glide_h_mm(profile) }
    }

    fn extrapolation(&self) -> Extrapolation {
        match self.opts.sizing {
            Sizing::Brush => Extrapolation::Refuse,
            Sizing::Unconstrained => Extrapolation::Allow,
        }
    }

    fn length(&self, h: f64) -> f64 {
        self.l_off + self.l_slope * h
    }

    /// The h whose footprint is at most `len` long (∞ if length does not grow with h).
    fn h_for_length(&self, len: f64) -> f64 {
        if self.l_slope > 0.0 { (len - self.l_off) / self.l_slope } else { f64::INFINITY }
    }

    fn lh(&self, h: f64) -> f64 {
        self.profile.model.lh_mm.eval(h, self.opts.alpha_rad, self.beta_shape).max(0.0)
    }

    /// h for a wanted belly half-width, and whether the brush had to clamp it.
    fn size_for(&self, w: f64) -> Result<(f64, Clamp), ProfileError> {
        let inv = self.profile.h_for_half_width(w.max(1e-3), self.opts.alpha_rad, self.beta_shape)?;
        Ok(match self.opts.sizing {
            Sizing::Brush => (inv.h_mm, inv.clamped),
            Sizing::Unconstrained => (inv.exact_h_mm.max(self.lowest), Clamp::None),
        })
    }

    /// h sizing the belly at `belly_at(lh)` (iterated, since lh depends on h).
    fn size_belly(&self, belly_at: impl Fn(f64) -> f64) -> Result<(f64, Clamp), ProfileError> {
        let mut out = (self.profile.ranges.h_mm.lerp(0.5), Clamp::None);
        for _ in 0..3 {
            out = self.size_for(belly_at(self.lh(out.0)))?;
        }
        Ok(out)
    }

    /// The commanded states of one corner-free piece (see [`build_track`]): entry backwards,
    /// turn, writing forwards. β is left at 0 for the forward model to fill in.
    fn piece(&self, pts: &[PointMm], widths: &[f64], counts: &mut Clamped) -> Result<Vec<TrackPoint>, ProfileError> {
        let alpha = self.opts.alpha_rad;
        let s = arc_lengths_by(pts, PointMm::distance);
        let total = s[s.len() - 1];
        let stations = stations(total, self.opts.spacing_mm);
        let (first, end) = (pts[0], pts[pts.len() - 1]);
        let at = |t: f64, h: f64| {
            let p = point_at(&s, pts, t);
            TrackPoint { x_mm: p.x_mm, y_mm: p.y_mm, h_mm: h, alpha_rad: alpha, beta_rad: 0.0 }
        };
        // Trailing sizes (belly lh behind), and the first station where such a footprint fits
        // behind the brush.
        let mut trailing = Vec::with_capacity(stations.len());
        for &t in &stations {
            trailing.push(self.size_belly(|lh| interp(&s, widths, (t - lh).max(0.0)))?);
        }
        let entry_end = (1..stations.len())
            .find(|&j| self.length(trailing[j].0) <= first.distance(point_at(&s, pts, stations[j])))
            .unwrap_or(stations.len() - 1);
        // Writing resumes at the first station where even the lightest press fits behind (pressed
        // lighter there, up to the trailing size).
        let resume = (1..stations.len())
            .find(|&j| self.length(self.lowest) <= first.distance(point_at(&s, pts, stations[j])))
            .unwrap_or(stations.len() - 1)
            .min(entry_end);
        let mut out: Vec<TrackPoint> = Vec::with_capacity(stations.len() + entry_end + 3);
        // 1. Entry: backwards from the touch-down station to the start, tips ahead.
        for j in (0..=entry_end).rev() {
            let t = stations[j];
            let p = point_at(&s, pts, t);
            let (h_in, clamp) = self.size_belly(|lh| interp(&s, widths, (t + lh).min(total)))?;
            let fit = self.h_for_length(p.distance(end));
            let h = if fit >= self.lowest {
                counts.tally(clamp);
                h_in.min(fit)
            } else if j == 0 {
                // The head must be inked even when the piece is shorter than any footprint. When
                // no other entry station is pressed, the brush glides back to the head pressed
                // lightly (no ink) instead of coming down on it from the air: so the
                // head's footprint trails forward along the piece by the drag rule, as the
                // entry's do, rather than pointing whichever way the model or a real brush
                // happens to leave an upright brush pressed straight down and lifted again.
                if !out.is_empty() && out.iter().all(|p| p.h_mm <= 0.0) {
                    for p in &mut out {
                        p.h_mm = self.glide_h;
                    }
                    // Down in place at the head.
                    out.push(at(t, self.glide_h));
                }
                self.lowest
            } else {
                0.0
            };
            out.push(at(t, h));
        }
        if resume + 1 < stations.len() {
            // 2. Turn: ease up at the start to a light press, glide along the stroke to where
            //    writing resumes (the hairs turn over, dragged along the path).
            for &t in &stations[..=resume] {
                out.push(at(t, self.glide_h));
            }
            // 3. Writing, the hairs trailing.
            for j in resume..stations.len() {
                let t = stations[j];
                let (h_tr, clamp) = trailing[j];
                let fit = self.h_for_length(first.distance(point_at(&s, pts, t)));
                counts.tally(clamp);
                out.push(at(t, h_tr.min(fit).max(self.lowest)));
            }
        }
        Ok(out)
    }
}
