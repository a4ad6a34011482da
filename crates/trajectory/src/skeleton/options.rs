//! The skeleton graph's tuning ([`GraphOptions`]) and its defaults.
//!
//! Every length here is relative to the local stroke half-width `w` (the distance transform at
//! a junction or chain point, px), except [`GraphOptions::loose_end_em`] (em units); angles are
//! radians (degrees only in [`GraphOptions::set`]'s keys, for sweeps).
//!
//! The defaults were chosen on a tuning set with `cargo xtask skeleton-counts`; the sets, the
//! sweeps and the scores on characters not tuned on are in docs/trajectory.md ("Skeleton stroke
//! counts on characters not used for tuning", "Learned junction pairing and corner splitting",
//! "Tuned constants"), and `cargo xtask tidy` checks that the values there and here agree. The
//! learned decisions (`learned_pairing`, `learned_corners`, on by default) come on top of these
//! rules.

/// Tuning of the skeleton graph, relative to the local stroke half-width `w` (the distance
/// transform at a junction).
#[derive(Clone, Copy, Debug)]
pub struct GraphOptions {
    /// A branch from a junction to a free end shorter than `spur_factor · w` is a spur and is
    /// removed (thinning leaves them at blunt stroke ends and corners).
    pub spur_factor: f64,
    /// The same for a branch off a corner (the junction's two other branches turn rather than
    /// continue each other, and the branch points away from both by more than
    /// `corner_spur_away_rad`): thinning leaves the pressed outer corner of 折, 钩 and 提 as
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
    /// to it (default: `LOOSE_END_EM` in docs/trajectory.md, "Tuned constants").
    pub loose_end_em: f64,
    /// A corner spur points away from both legs of its corner by more than this (radians,
    /// `corner_spur_away_rad`).
    pub corner_spur_away_rad: f64,
    /// How far each way the turn at a chain point is measured, in local half-widths
    /// (default: `CORNER_REACH` in docs/trajectory.md, "Tuned constants").
    pub corner_reach: f64,
    /// A chain's end leg no longer than this many half-widths can be a hook (default: `HOOK_WIDTHS` in docs/trajectory.md, "Tuned constants").
    pub hook_widths: f64,
    /// ... when shorter than this fraction of the leg it turns from (default: `HOOK_RATIO` in docs/trajectory.md, "Tuned constants").
    pub hook_ratio: f64,
    /// Pieces no longer than this many half-widths that lie inside other strokes are dropped
    /// (default: `COVERED_MAX_WIDTHS` in docs/trajectory.md, "Tuned constants").
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
    /// Pair branch ends at junctions of three or more branches with the learned model
    /// ([`crate::SkeletonModels::embedded`], the hand rules' verdict one of its features)
    /// instead of the hand rules alone (`straight_min_rad`, `pair_width_ratio`).
    pub learned_pairing: bool,
    /// Decide at each corner of a chain whether it splits with the learned model
    /// ([`crate::skeleton::SkeletonModels::embedded`], the hand rules' verdicts among its
    /// features) instead of the hand rules alone.
    pub learned_corners: bool,
    /// With `learned_pairing`, a pair continues through its junction when the model's
    /// probability reaches this.
    pub pair_threshold: f64,
    /// With `learned_corners`, a corner splits when the model's probability reaches this.
    pub corner_threshold: f64,
}

impl Default for GraphOptions {
    fn default() -> Self {
        Self {
            spur_factor: SPUR_FACTOR,
            corner_spur_factor: CORNER_SPUR_FACTOR,
            merge_factor: MERGE_FACTOR,
            straight_min_rad: STRAIGHT_MIN_DEG.to_radians(),
            corner_rad: CORNER_DEG.to_radians(),
            split_box_corners: true,
            loose_end_em: LOOSE_END_EM,
            corner_spur_away_rad: CORNER_SPUR_AWAY_RAD,
            corner_reach: CORNER_REACH,
            hook_widths: HOOK_WIDTHS,
            hook_ratio: HOOK_RATIO,
            covered_max_widths: COVERED_MAX_WIDTHS,
            pair_width_ratio: PAIR_WIDTH_RATIO,
            open_box_min_ratio: OPEN_BOX_MIN_RATIO,
            ti_min_rise: TI_MIN_RISE,
            learned_pairing: true,
            learned_corners: true,
            pair_threshold: PAIR_THRESHOLD,
            corner_threshold: CORNER_THRESHOLD,
        }
    }
}

impl GraphOptions {
    /// Sets one option by name, for sweeps (`cargo xtask skeleton-counts --opts`): the field
    /// names above, with angles in degrees and named `*_deg` instead of `*_rad`
    /// (`straight_min_deg`, `corner_deg`, `corner_spur_away_deg`); `split_box_corners`,
    /// `learned_pairing` and `learned_corners` take 0 or 1.
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
            "learned_pairing" => self.learned_pairing = value != 0.0,
            "learned_corners" => self.learned_corners = value != 0.0,
            "pair_threshold" => self.pair_threshold = value,
            "corner_threshold" => self.corner_threshold = value,
            _ => return Err(format!("unknown skeleton option `{key}`")),
        }
        Ok(())
    }
}

/// Spur length limit, in junction half-widths ([`GraphOptions::spur_factor`]). Chosen on the tuning
/// set (docs/trajectory.md, Tuned constants).
const SPUR_FACTOR: f64 = 2.0;

/// Corner-spur length limit, in junction half-widths ([`GraphOptions::corner_spur_factor`]). Chosen
/// on the tuning set (docs/trajectory.md, Tuned constants).
const CORNER_SPUR_FACTOR: f64 = 3.0;

/// Junctions closer than this many half-widths merge ([`GraphOptions::merge_factor`]). Chosen on
/// the tuning set (docs/trajectory.md, Tuned constants).
const MERGE_FACTOR: f64 = 2.0;

/// Two branches continue each other above this angle, degrees ([`GraphOptions::straight_min_rad`]).
/// Chosen on the tuning set (docs/trajectory.md, Tuned constants).
const STRAIGHT_MIN_DEG: f64 = 125.0;

/// A chain has a corner where it turns by more than this, degrees ([`GraphOptions::corner_rad`]).
/// Chosen on the tuning set (docs/trajectory.md, Tuned constants).
const CORNER_DEG: f64 = 50.0;

/// An end point this near a junction (em units) is joined to it ([`GraphOptions::loose_end_em`]).
/// Chosen on the tuning set (docs/trajectory.md, Tuned constants).
const LOOSE_END_EM: f64 = 9.0;

/// A corner spur points away from both legs by more than this, radians (120°;
/// [`GraphOptions::corner_spur_away_rad`]). Chosen on the tuning set (docs/trajectory.md, Tuned
/// constants).
const CORNER_SPUR_AWAY_RAD: f64 = 2.0 * std::f64::consts::FRAC_PI_3;

/// How far each way a chain point's turn is measured, in local half-widths (a skeleton corner is
/// rounded over about one width; [`GraphOptions::corner_reach`]). Chosen on the tuning set
/// (docs/trajectory.md, Tuned constants).
const CORNER_REACH: f64 = 2.5;

/// A chain's end leg no longer than this many half-widths can be a hook (钩)
/// ([`GraphOptions::hook_widths`]). Chosen on the tuning set (docs/trajectory.md, Tuned constants).
const HOOK_WIDTHS: f64 = 5.0;

/// ... when shorter than this fraction of the leg it turns from ([`GraphOptions::hook_ratio`]).
/// Chosen on the tuning set (docs/trajectory.md, Tuned constants).
const HOOK_RATIO: f64 = 0.5;

/// Short pieces inside other strokes are dropped up to this many half-widths
/// ([`GraphOptions::covered_max_widths`]). Chosen on the tuning set (docs/trajectory.md, Tuned
/// constants).
const COVERED_MAX_WIDTHS: f64 = 3.0;

/// Branches pair only if the thinner is at least this fraction of the thicker's width
/// ([`GraphOptions::pair_width_ratio`]). Chosen on the tuning set (docs/trajectory.md, Tuned
/// constants).
const PAIR_WIDTH_RATIO: f64 = 0.5;

/// Open-chain 竖折 split when the vertical leg is at least this many times the horizontal
/// ([`GraphOptions::open_box_min_ratio`]). Chosen on the tuning set (docs/trajectory.md, Tuned
/// constants).
const OPEN_BOX_MIN_RATIO: f64 = 0.5;

/// 提 rises by more than this per unit run ([`GraphOptions::ti_min_rise`]). Chosen on the tuning set
/// (docs/trajectory.md, Tuned constants).
const TI_MIN_RISE: f64 = 0.4;

/// A pair of branch ends continues through its junction at this probability of the learned model
/// ([`GraphOptions::pair_threshold`]). Chosen on the tuning set (docs/trajectory.md, Tuned
/// constants).
const PAIR_THRESHOLD: f64 = 0.2;

/// A corner splits at this probability of the learned model ([`GraphOptions::corner_threshold`]).
/// Chosen on the tuning set (docs/trajectory.md, Tuned constants).
const CORNER_THRESHOLD: f64 = 0.5;
