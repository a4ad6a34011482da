//! Blended `moveLine`s as the simulator executes them: a chain of linear moves whose corners are
//! rounded by parabolic blends (a quadratic Bézier from the blend radius before the corner to
//! the blend radius after it, the corner its control point), run on one time law: from rest
//! at the chain's start to rest at its end, each piece at most its move's speed, each blend at
//! most the speed whose centripetal acceleration stays within the move's acceleration, and the
//! speed changing at most at that acceleration (trapezoidal ramps, no jerk limit).

use nalgebra::{Isometry3, UnitQuaternion, Vector3};

use crate::exec::{MAX_SAMPLES_PER_MOVE, TRACE_STEP_M, TRACE_STEP_RAD, TRACE_STEP_S, TraceEntry, TraceKind};
use crate::pose::Pose;

/// One linear move of a chain: its target, speed (after the speed fraction), acceleration
/// and the blend radius at its target (0 for the chain's last move).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlendMove {
    /// Target TCP pose.
    pub pose: Pose,
    /// Speed, m/s.
    pub v_m_s: f64,
    /// Acceleration, m/s².
    pub a_m_s2: f64,
    /// Blend radius at the target, m.
    pub blend_m: f64,
}

/// Why a blend is refused: the radius is more than half of one of the two moves it joins
/// (so two blends could overlap, or one would run past a move's start).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlendRefused {
    /// The blend radius, m.
    pub blend_m: f64,
    /// The shorter of the two moves it joins, m.
    pub shorter_m: f64,
}

/// Whether the blend radius `blend_m` at the end of a move of length `before_m` into one of
/// length `after_m` (m) is one a controller accepts: at most half of each (so neighbouring
/// blends never overlap). A radius of 0 is always accepted. The check allows 1 nm
/// ([`BLEND_SLACK_M`]): a printed program (a script) gives its lengths to the digits its numbers
/// keep, and a radius of exactly half a move may read back a few tenths of a nanometre over.
///
/// # Errors
/// [`BlendRefused`] naming the radius and the shorter move.
pub fn check_blend(blend_m: f64, before_m: f64, after_m: f64) -> Result<(), BlendRefused> {
    let shorter_m = before_m.min(after_m);
    if blend_m > 0.0 && blend_m > 0.5 * shorter_m + BLEND_SLACK_M {
        return Err(BlendRefused { blend_m, shorter_m });
    }
    Ok(())
}

/// The slack of [`check_blend`], m.
pub const BLEND_SLACK_M: f64 = 1e-9;

/// Dense points along a chain's path, m apart at most (or the move's length / 1000).
const DENSE_M: f64 = TRACE_STEP_M / 4.0;
/// Most dense points per move (a long travel is sampled more coarsely).
const MAX_DENSE_PER_MOVE: usize = 1000;

/// One point of the blended path: its arc length, pose and the speed limit there.
struct Dense {
    s: f64,
    p: Vector3<f64>,
    r: UnitQuaternion<f64>,
    v_max: f64,
    a: f64,
}

/// Executes a chain of linear moves from `from` as the simulator does: the corner at each
/// move's target rounded by a parabolic blend of its radius (the last move ends at rest on its
/// target), on one trapezoidal time law (see the module docs). The orientation turns by slerp
/// along each move in proportion to its position, and from one move's to the next across a
/// blend. Every move of the chain must be longer than zero and every blend valid
/// ([`check_blend`]); a chain of one move is [`super::ramped_line_motion`]. Returns the samples
/// after `from` to the last target, evenly in time (at most [`TRACE_STEP_S`] apart and, at the
/// top speed, [`TRACE_STEP_M`] and [`TRACE_STEP_RAD`]; at most [`MAX_SAMPLES_PER_MOVE`]), with
/// their times after `t0_s`.
///
/// # Examples
/// ```
/// use robot_io::Pose;
/// use robot_io::sim::{BlendMove, blended_line_motion};
/// let at = |x: f64, y: f64| Pose([x, y, 0.3, std::f64::consts::PI, 0.0, 0.0]);
/// let mv = |p: Pose, blend_m: f64| BlendMove { pose: p, v_m_s: 0.02, a_m_s2: 0.3, blend_m };
/// // Two 10 mm moves at a right angle, the corner blended by 2 mm.
/// let trace = blended_line_motion(&at(0.4, 0.0), &[mv(at(0.41, 0.0), 0.002), mv(at(0.41, 0.01), 0.0)], 0.0);
/// // The path cuts the corner: no sample comes closer than 0.5 mm to it.
/// let corner = |e: &robot_io::TraceEntry| (e.pose.0[0] - 0.41).hypot(e.pose.0[1]);
/// assert!(trace.iter().map(corner).fold(f64::INFINITY, f64::min) > 0.0005);
/// assert_eq!(trace.last().unwrap().pose, at(0.41, 0.01));
/// ```
pub fn blended_line_motion(from: &Pose, chain: &[BlendMove], t0_s: f64) -> Vec<TraceEntry> {
    match chain {
        [] => Vec::new(),
        [m] => super::ramped_line_motion(from, &m.pose, m.v_m_s, m.a_m_s2, t0_s),
        _ => blended(from, chain, t0_s),
    }
}

fn blended(from: &Pose, chain: &[BlendMove], t0_s: f64) -> Vec<TraceEntry> {
    let isos: Vec<Isometry3<f64>> =
        std::iter::once(from).chain(chain.iter().map(|m| &m.pose)).map(Pose::to_iso).collect();
    let pos = |i: usize| isos[i].translation.vector;
    let rot = |i: usize| isos[i].rotation;
    let n = chain.len();
    let len: Vec<f64> = (1..=n).map(|i| (pos(i) - pos(i - 1)).norm()).collect();
    let dir: Vec<Vector3<f64>> = (1..=n).map(|i| (pos(i) - pos(i - 1)) / len[i - 1].max(1e-300)).collect();
    // Move i (0-based) runs from pos(i) to pos(i + 1); the orientation along it at fraction f.
    let along = |i: usize, f: f64| -> UnitQuaternion<f64> {
        rot(i).try_slerp(&rot(i + 1), f.clamp(0.0, 1.0), 1e-12).unwrap_or(if f < 0.5 { rot(i) } else { rot(i + 1) })
    };
    // A move's speed, slowed where it turns the tool by more than 0.1 m per radian.
    let speed = |i: usize| {
        let turn = rot(i).angle_to(&rot(i + 1));
        chain[i].v_m_s * len[i] / len[i].max(0.1 * turn)
    };
    let blend = |i: usize| if i + 1 < n { chain[i].blend_m.min(0.5 * len[i]).min(0.5 * len[i + 1]) } else { 0.0 };
    let mut dense: Vec<Dense> = Vec::new();
    let mut s = 0.0;
    let mut push = |dense: &mut Vec<Dense>, p: Vector3<f64>, r: UnitQuaternion<f64>, v_max: f64, a: f64| {
        if let Some(last) = dense.last() {
            s += (p - last.p).norm();
        }
        dense.push(Dense { s, p, r, v_max, a });
    };
    for i in 0..n {
        let m = &chain[i];
        let before = if i > 0 { blend(i - 1) } else { 0.0 };
        let after = blend(i);
        // The straight piece of move i, from the end of the blend before to the start of the next.
        let frac = |x: f64| if len[i] > 0.0 { x / len[i] } else { 0.0 };
        let (f0, f1) = (frac(before), 1.0 - frac(after));
        let piece = (f1 - f0) * len[i];
        let k = ((piece / DENSE_M).ceil() as usize).clamp(1, MAX_DENSE_PER_MOVE);
        let first = usize::from(i > 0);
        for j in first..=k {
            let f = f0 + (f1 - f0) * j as f64 / k as f64;
            push(&mut dense, pos(i) + dir[i] * (f * len[i]), along(i, f), speed(i), m.a_m_s2);
        }
        if after > 0.0 {
            // The parabolic blend around pos(i + 1): B(u) = (1-u)²A + 2u(1-u)P + u²C.
            let (a_pt, p_pt, c_pt) = (pos(i + 1) - dir[i] * after, pos(i + 1), pos(i + 1) + dir[i + 1] * after);
            let (r0, r1) = (along(i, f1), along(i + 1, after / len[i + 1].max(1e-300)));
            let acc = m.a_m_s2.min(chain[i + 1].a_m_s2);
            let v_top = speed(i).min(speed(i + 1));
            let k = (((2.0 * after) / DENSE_M).ceil() as usize).clamp(2, MAX_DENSE_PER_MOVE).next_multiple_of(2);
            for j in 1..k {
                let u = j as f64 / k as f64;
                let p = a_pt * (1.0 - u).powi(2) + p_pt * (2.0 * u * (1.0 - u)) + c_pt * (u * u);
                let d1 = (p_pt - a_pt) * (2.0 * (1.0 - u)) + (c_pt - p_pt) * (2.0 * u);
                let d2 = (c_pt - p_pt * 2.0 + a_pt) * 2.0;
                let speed_d1 = d1.norm();
                // The radius of curvature |B'|³ / |B' × B''| bounds the speed by √(a·ρ); where
                // B' vanishes (a blend that turns back) the brush stops.
                let cross = d1.cross(&d2).norm();
                let v_curve = if speed_d1 < 1e-12 {
                    0.0
                } else if cross < 1e-300 {
                    v_top
                } else {
                    (acc * speed_d1.powi(3) / cross).sqrt()
                };
                let r = r0.try_slerp(&r1, u, 1e-12).unwrap_or(if u < 0.5 { r0 } else { r1 });
                push(&mut dense, p, r, v_top.min(v_curve), acc);
            }
        }
    }
    // From rest to rest, each step's speed change within its acceleration (forward, backward).
    let m = dense.len();
    let mut v: Vec<f64> = dense.iter().map(|d| d.v_max).collect();
    v[0] = 0.0;
    v[m - 1] = 0.0;
    for k in 1..m {
        let ds = dense[k].s - dense[k - 1].s;
        v[k] = v[k].min((v[k - 1].powi(2) + 2.0 * dense[k].a.min(dense[k - 1].a) * ds).sqrt());
    }
    for k in (0..m - 1).rev() {
        let ds = dense[k + 1].s - dense[k].s;
        v[k] = v[k].min((v[k + 1].powi(2) + 2.0 * dense[k].a.min(dense[k + 1].a) * ds).sqrt());
    }
    let mut t = vec![0.0; m];
    let (mut v_peak, mut w_peak) = (0.0f64, 0.0f64);
    for k in 1..m {
        let ds = dense[k].s - dense[k - 1].s;
        let sum = v[k] + v[k - 1];
        let dt = if sum > 1e-12 { 2.0 * ds / sum } else { 0.0 };
        t[k] = t[k - 1] + dt;
        v_peak = v_peak.max(v[k]);
        if dt > 0.0 {
            w_peak = w_peak.max(dense[k].r.angle_to(&dense[k - 1].r) / dt);
        }
    }
    let total = t[m - 1];
    let dt = TRACE_STEP_S.min(TRACE_STEP_M / v_peak.max(1e-300)).min(TRACE_STEP_RAD / w_peak.max(1e-300));
    let count =
        if (total / dt).is_nan() { 1 } else { (total / dt).ceil().clamp(1.0, MAX_SAMPLES_PER_MOVE as f64) as usize };
    let last = chain[n - 1].pose;
    let mut out = Vec::with_capacity(count);
    let mut k = 1;
    for j in 1..=count {
        let tj = total * j as f64 / count as f64;
        if j == count {
            out.push(TraceEntry { t_s: t0_s + total, kind: TraceKind::Line, pose: last });
            break;
        }
        while k < m - 1 && t[k] < tj {
            k += 1;
        }
        let span = t[k] - t[k - 1];
        let f = if span > 0.0 { ((tj - t[k - 1]) / span).clamp(0.0, 1.0) } else { 1.0 };
        let (a, b) = (&dense[k - 1], &dense[k]);
        let p = a.p.lerp(&b.p, f);
        let r = a.r.try_slerp(&b.r, f, 1e-12).unwrap_or(b.r);
        let pose = Pose::from_iso(&Isometry3::from_parts(nalgebra::Translation3::from(p), r));
        out.push(TraceEntry { t_s: t0_s + tj, kind: TraceKind::Line, pose });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(x: f64, y: f64) -> Pose {
        Pose([x, y, 0.3, std::f64::consts::PI, 0.0, 0.0])
    }

    fn mv(p: Pose, blend_m: f64) -> BlendMove {
        BlendMove { pose: p, v_m_s: 0.02, a_m_s2: 0.3, blend_m }
    }

    #[test]
    fn a_blend_rounds_the_corner_inside_its_radius_and_keeps_moving() {
        let r = 0.002;
        let trace = blended_line_motion(&at(0.4, 0.0), &[mv(at(0.41, 0.0), r), mv(at(0.41, 0.01), 0.0)], 0.0);
        let corner = |e: &TraceEntry| (e.pose.0[0] - 0.41).hypot(e.pose.0[1]);
        let closest = trace.iter().min_by(|a, b| corner(a).total_cmp(&corner(b))).unwrap();
        // The parabola's apex lies r/2 · √2 / 2 · 2 = r·√2/4 ≈ 0.707 mm from the corner for 90°.
        let d = corner(closest);
        assert!((d - r * 2f64.sqrt() / 4.0).abs() < 2e-5, "closest {d}");
        // It does not stop there: the speed at the apex is well above zero.
        let i = trace.iter().position(|e| std::ptr::eq(e, closest)).unwrap();
        let (p, q) = (&trace[i - 1], &trace[i + 1]);
        let v = (q.pose.0[0] - p.pose.0[0]).hypot(q.pose.0[1] - p.pose.0[1]) / (q.t_s - p.t_s);
        // √(a·ρ) at the apex: ρ = r·cos²(45°)/tan(45°) = 1 mm, 0.0173 m/s.
        assert!(v > 0.015, "speed at the apex {v}");
        // Every sample stays within the blend's band of the commanded polyline.
        for e in &trace {
            let (x, y) = (e.pose.0[0], e.pose.0[1]);
            let off = if x < 0.41 - r {
                y.abs()
            } else if y > r {
                (x - 0.41).abs()
            } else {
                0.0
            };
            assert!(off < 1e-9, "{x} {y}");
        }
        // Faster than stopping at the corner.
        let stop = super::super::ramped_line_motion(&at(0.4, 0.0), &at(0.41, 0.0), 0.02, 0.3, 0.0);
        let stop2 = super::super::ramped_line_motion(&at(0.41, 0.0), &at(0.41, 0.01), 0.02, 0.3, 0.0);
        let stopping = stop.last().unwrap().t_s + stop2.last().unwrap().t_s;
        assert!(trace.last().unwrap().t_s < stopping - 0.05, "{} vs {stopping}", trace.last().unwrap().t_s);
    }

    #[test]
    fn the_time_law_keeps_the_speed_and_starts_and_ends_at_rest() {
        let trace = blended_line_motion(
            &at(0.4, 0.0),
            &[mv(at(0.42, 0.0), 0.001), mv(at(0.44, 0.001), 0.001), mv(at(0.46, 0.0), 0.0)],
            1.0,
        );
        assert!(trace.windows(2).all(|w| w[1].t_s > w[0].t_s) && trace[0].t_s > 1.0);
        let speeds: Vec<f64> = trace
            .windows(2)
            .map(|w| {
                let d: f64 = (0..3).map(|i| (w[1].pose.0[i] - w[0].pose.0[i]).powi(2)).sum::<f64>().sqrt();
                d / (w[1].t_s - w[0].t_s)
            })
            .collect();
        assert!(speeds.iter().all(|v| *v <= 0.02 * (1.0 + 1e-6)), "{:?}", speeds.iter().fold(0.0f64, |a, b| a.max(*b)));
        // Reaches the top speed on the way, and starts and ends slowly (rest at 0.3 m/s²).
        assert!(speeds.iter().any(|v| *v > 0.0199));
        assert!(speeds[0] < 0.005 && *speeds.last().unwrap() < 0.005);
        // The time at least the length at the top speed.
        assert!(trace.last().unwrap().t_s - 1.0 > 0.06 / 0.02);
    }

    #[test]
    fn a_blend_more_than_half_a_move_is_refused() {
        assert!(check_blend(0.0005, 0.001, 0.002).is_ok());
        assert_eq!(check_blend(0.0006, 0.001, 0.002), Err(BlendRefused { blend_m: 0.0006, shorter_m: 0.001 }));
        assert!(check_blend(0.0006, 0.005, 0.001).is_err());
        assert!(check_blend(0.0, 0.0, 0.0).is_ok());
    }
}
