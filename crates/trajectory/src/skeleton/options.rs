//! The skeleton graph's tuning ([`GraphOptions`]) and its defaults.
//!
//! Every length here is relative to the local stroke half-width `w` (the distance transform at
//! a junction or chain point, px), except [`GraphOptions::loose_end_em`] (em units); angles are
//! radians (degrees only in [`GraphOptions::set`]'s keys, for sweeps). The defaults were tuned on
//! the skeleton report's tuning half and checked on its held-out half (docs/trajectory.md,
//! "Skeleton rules").

/// Tuning of the skeleton graph, relative to the local stroke half-width `w` (the distance
/// transform at a junction).
#[derive(Clone, Copy, Debug)]
pub struct GraphOptions {
    /// A branch from a junction to a free end shorter than `spur_factor · w` is a spur and is
    /// removed (thinning leaves them at blunt stroke ends and corners).
    pub spur_factor: f64,
    /// The same for a branch off a corner (the junction's two other branches turn rather than
    /// continue each other, and the branch points away from both by more than
    /// [`CORNER_SPUR_AWAY_RAD`]): thinning leaves the pressed outer corner of 折, 钩 and 提 as
    /// such a branch, longer than ordinary spurs.
    pub corner_spur_factor: f64,
    /// Junctions closer than `merge_factor · w` are one crossing.
    pub merge_factor: f64,
    /// At a junction, two branches continue each other if the angle between them exceeds this
    /// (radians; π = perfectly straight).
    pub straight_min_rad: f64,
    /// A chain that turns by more than this (radians, measured over about a stroke width each
    /// way) has a corner there; see [`GraphOptions::split_box_corners`] for which corners
    /// end a stroke.
    pub corner_rad: f64,
    /// On a closed chain (a box), split where a vertical leg turns right (竖折): the lower left
    /// corner of 口 or 日, whose bottom is a stroke of its own. Open chains keep 竖折 (山, 出).
    pub split_box_corners: bool,
    /// An end point within this distance (em units) of a junction it is not joined to is joined
    /// to it ([`LOOSE_END_EM`]).
    pub loose_end_em: f64,
    /// A corner spur points away from both legs of its corner by more than this (radians,
    /// [`CORNER_SPUR_AWAY_RAD`]).
    pub corner_spur_away_rad: f64,
    /// How far each way the turn at a chain point is measured, in local half-widths
    /// ([`CORNER_REACH`]).
    pub corner_reach: f64,
    /// A chain's end leg no longer than this many half-widths can be a hook ([`HOOK_WIDTHS`]).
    pub hook_widths: f64,
    /// ... when shorter than this fraction of the leg it turns from ([`HOOK_RATIO`]).
    pub hook_ratio: f64,
    /// Pieces no longer than this many half-widths that lie inside other strokes are dropped
    /// ([`COVERED_MAX_WIDTHS`]).
    pub covered_max_widths: f64,
    /// At a junction of three or more branches, two branches continue each other only if the
    /// thinner one's half-width (measured one to three junction half-widths out) is at least this
    /// fraction of the thicker one's: a tapering tip (the end of a 提 or 撇) that touches the
    /// start of another stroke is not its continuation. 0 turns the test off.
    pub pair_width_ratio: f64,
    /// Split a vertical leg turning right (竖折) on open chains too, when the vertical leg is at
    /// least this many times as long as the horizontal one (0: never). The bottom of a box
    /// (口, 日, 甘, 自) is a stroke of its own; 竖折 (山, 出, 区) tends to have a short vertical leg
    /// and a long horizontal one.
    pub open_box_min_ratio: f64,
    /// A leg rising to the right out of a downward one is 提 (竖提, one stroke) when it rises by
    /// more than this much per unit run; a box's bottom (口, 日) rises a little too and is a
    /// stroke of its own.
    pub ti_min_rise: f64,
}

impl Default for GraphOptions {
    fn default() -> Self {
        Self {
            spur_factor: 2.0,
            corner_spur_factor: 3.0,
            merge_factor: 2.0,
            straight_min_rad: 125f64.to_radians(),
            corner_rad: 50f64.to_radians(),
            split_box_corners: true,
            loose_end_em: LOOSE_END_EM,
            corner_spur_away_rad: CORNER_SPUR_AWAY_RAD,
            corner_reach: CORNER_REACH,
            hook_widths: HOOK_WIDTHS,
            hook_ratio: HOOK_RATIO,
            covered_max_widths: COVERED_MAX_WIDTHS,
            pair_width_ratio: 0.5,
            open_box_min_ratio: 0.5,
            ti_min_rise: 0.4,
        }
    }
}

impl GraphOptions {
    /// Sets one option by name, for sweeps (`cargo xtask skeleton-counts --opts`): the field
    /// names above, with angles in degrees and named `*_deg` instead of `*_rad`
    /// (`straight_min_deg`, `corner_deg`, `corner_spur_away_deg`); `split_box_corners` takes 0
    /// or 1.
    ///
    /// # Errors
    /// A message naming the key when it is unknown or the value is not finite.
    pub fn set(&mut self, key: &str, value: f64) -> Result<(), String> {
        if !value.is_finite() {
            return Err(format!("option {key}: {value} is not a finite number"));
        }
        match key {
            "spur_factor" => self.spur_factor = value,
            "corner_spur_factor" => self.corner_spur_factor = value,
            "merge_factor" => self.merge_factor = value,
            "straight_min_deg" => self.straight_min_rad = value.to_radians(),
            "corner_deg" => self.corner_rad = value.to_radians(),
            "split_box_corners" => self.split_box_corners = value != 0.0,
            "loose_end_em" => self.loose_end_em = value,
            "corner_spur_away_deg" => self.corner_spur_away_rad = value.to_radians(),
            "corner_reach" => self.corner_reach = value,
            "hook_widths" => self.hook_widths = value,
            "hook_ratio" => self.hook_ratio = value,
            "covered_max_widths" => self.covered_max_widths = value,
            "pair_width_ratio" => self.pair_width_ratio = value,
            "open_box_min_ratio" => self.open_box_min_ratio = value,
            "ti_min_rise" => self.ti_min_rise = value,
            _ => return Err(format!("unknown skeleton option `{key}`")),
        }
        Ok(())
    }
}

/// A piece no longer than this many half-widths, all of whose points lie within one local
/// half-width of another stroke's centre line, is dropped by `drop_covered`.
const COVERED_MAX_WIDTHS: f64 = 3.0;

/// How near a junction (em units) an end point is taken to belong to it.
const LOOSE_END_EM: f64 = 9.0;

/// A corner spur points away from both legs of its corner by more than this (radians).
const CORNER_SPUR_AWAY_RAD: f64 = 2.0 * std::f64::consts::FRAC_PI_3;

/// A chain's end leg no longer than this many local half-widths can be a hook (钩) of the
/// stroke it turns from rather than a stroke of its own...
const HOOK_WIDTHS: f64 = 5.0;
/// ... when it is shorter than this fraction of that stroke's leg, or rises away from the corner.
const HOOK_RATIO: f64 = 0.5;
/// How far each way the turn at a chain point is measured, in local half-widths (a skeleton
/// corner is rounded over about one width).
const CORNER_REACH: f64 = 2.5;
