//! The variable layout: which values of the track are free, and where each sits in the
//! variable vector (every position group's `x, y`, then every pressed point's `h`, then every
//! tilt variable's `α`).

use brush_model::{BrushProfile, Extrapolation, ForwardModel, Track, TrackPoint};

use crate::{RefineError, RefineOptions};

/// A point of the flattened track.
#[derive(Clone, Copy, Debug)]
pub(super) struct Slot {
    /// Position group.
    pub(super) group: usize,
    /// Depth variable (pressed points).
    pub(super) h_var: Option<usize>,
}

/// What is free in a track (see [`super::Problem`]).
pub(super) struct Layout {
    /// The input points, stroke by stroke.
    pub(super) strokes: Vec<Vec<TrackPoint>>,
    /// Per stroke, per point.
    pub(super) slots: Vec<Vec<Slot>>,
    /// Initial group positions.
    pub(super) q0: Vec<[f64; 2]>,
    /// Per stroke, the range of its groups.
    pub(super) stroke_groups: Vec<std::ops::Range<usize>>,
    /// Group → α variable.
    pub(super) group_alpha: Vec<Option<usize>>,
    /// Pressed points as (stroke, index), in variable order of their depths.
    pub(super) pressed: Vec<(usize, usize)>,
    /// Initial depths of the pressed points.
    pub(super) h0: Vec<f64>,
    /// Initial tilt of each α variable.
    pub(super) a0: Vec<f64>,
    /// Allowed tilt range of the α variables.
    pub(super) alpha_range: (f64, f64),
}

impl Layout {
    /// The layout of `track`'s variables.
    ///
    /// # Errors
    /// [`RefineError::Profile`] when the profile cannot size a pressed point.
    pub(super) fn new(track: &Track, profile: &BrushProfile) -> Result<Self, RefineError> {
        let model = ForwardModel::default();
        let hmin = profile.ranges.h_mm.min;
        let mut strokes = Vec::new();
        let mut slots = Vec::new();
        let mut q0 = Vec::new();
        let mut stroke_groups = Vec::new();
        let mut group_alpha: Vec<Option<usize>> = Vec::new();
        let mut pressed = Vec::new();
        let mut h0 = Vec::new();
        let mut a0 = Vec::new();
        for (si, s) in track.strokes.iter().enumerate() {
            let g_start = q0.len();
            let mut st = Vec::with_capacity(s.points.len());
            for (pi, p) in s.points.iter().enumerate() {
                let same = pi > 0 && {
                    let a = s.points[pi - 1];
                    a.x_mm == p.x_mm && a.y_mm == p.y_mm
                };
                if !same {
                    q0.push([p.x_mm, p.y_mm]);
                    group_alpha.push(None);
                }
                let group = q0.len() - 1;
                let h_var = if p.h_mm >= hmin {
                    profile.predict_oriented(&p.press(), Extrapolation::Allow)?;
                    pressed.push((si, pi));
                    h0.push(p.h_mm);
                    if model.is_tilted(p) && group_alpha[group].is_none() {
                        group_alpha[group] = Some(a0.len());
                        a0.push(p.alpha_rad);
                    }
                    Some(h0.len() - 1)
                } else {
                    None
                };
                st.push(Slot { group, h_var });
            }
            stroke_groups.push(g_start..q0.len());
            strokes.push(s.points.clone());
            slots.push(st);
        }
        let ar = profile.ranges.alpha_rad;
        let alpha_range = (ar.min.max(model.tilt_threshold_rad), ar.max);
        Ok(Self { strokes, slots, q0, stroke_groups, group_alpha, pressed, h0, a0, alpha_range })
    }

    /// Number of variables: 2 per position group, 1 per pressed point, 1 per tilt group.
    pub(super) fn len(&self) -> usize {
        2 * self.q0.len() + self.h0.len() + self.a0.len()
    }

    /// Index of the first depth variable.
    pub(super) fn h_off(&self) -> usize {
        2 * self.q0.len()
    }

    /// Index of the first tilt variable.
    pub(super) fn a_off(&self) -> usize {
        2 * self.q0.len() + self.h0.len()
    }

    /// The input track as a variable vector.
    pub(super) fn initial(&self) -> Vec<f64> {
        let mut v: Vec<f64> = self.q0.iter().flat_map(|q| q.iter().copied()).collect();
        v.extend_from_slice(&self.h0);
        v.extend_from_slice(&self.a0);
        v
    }

    /// Per variable, the optimiser step (mm for positions and depths, rad for tilts).
    pub(super) fn steps(&self, opts: &RefineOptions) -> Vec<f64> {
        let mut s = vec![opts.step_mm; 2 * self.q0.len()];
        s.extend(std::iter::repeat_n(opts.step_h_mm, self.h0.len()));
        s.extend(std::iter::repeat_n(opts.step_alpha_rad, self.a0.len()));
        s
    }

    /// Per variable, its kind: 0 position, 1 depth, 2 tilt.
    pub(super) fn kinds(&self) -> Vec<u8> {
        let mut k = vec![0u8; 2 * self.q0.len()];
        k.extend(std::iter::repeat_n(1u8, self.h0.len()));
        k.extend(std::iter::repeat_n(2u8, self.a0.len()));
        k
    }

    /// Runs of consecutive pressed points of a stroke, as ranges of depth variables.
    pub(super) fn pressed_runs(&self) -> Vec<std::ops::Range<usize>> {
        let mut runs = Vec::new();
        let mut start = 0;
        for k in 1..=self.pressed.len() {
            let cont = k < self.pressed.len() && {
                let (a, b) = (self.pressed[k - 1], self.pressed[k]);
                a.0 == b.0 && a.1 + 1 == b.1
            };
            if !cont {
                runs.push(start..k);
                start = k;
            }
        }
        runs
    }

    /// The commanded states at an iterate, β as in the input (not yet re-derived).
    pub(super) fn states(&self, theta: &[f64]) -> Vec<Vec<TrackPoint>> {
        let (ho, ao) = (self.h_off(), self.a_off());
        self.strokes
            .iter()
            .zip(&self.slots)
            .map(|(pts, slots)| {
                pts.iter()
                    .zip(slots)
                    .map(|(p, s)| {
                        let mut q = *p;
                        q.x_mm = theta[2 * s.group];
                        q.y_mm = theta[2 * s.group + 1];
                        if let Some(h) = s.h_var {
                            q.h_mm = theta[ho + h];
                        }
                        if let Some(a) = self.group_alpha[s.group] {
                            q.alpha_rad = theta[ao + a];
                        }
                        q
                    })
                    .collect()
            })
            .collect()
    }
}
