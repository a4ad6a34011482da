//! Which brush suits a sheet: the built-in whose width range covers the glyphs at the box size.

use brush_model::BrushProfile;
use serde::Serialize;

use crate::Prepared;

/// The brush [`choose_brush`] picked, and why.
#[derive(Clone, Debug, Serialize)]
pub struct BrushChoice {
    /// The chosen brush's name.
    pub name: String,
    /// The char box side the chosen brush's width range suits for these glyphs
    /// ([`trajectory::auto_char_mm`] of all their centre lines), mm.
    pub brush_char_mm: f64,
    /// The char box side asked for, mm.
    pub char_mm: f64,
    /// Every candidate with the char box side it suits, mm, in the order tried.
    pub candidates: Vec<(String, f64)>,
    /// The choice in one sentence.
    pub reason: String,
    /// The chosen profile.
    #[serde(skip)]
    pub profile: BrushProfile,
}

/// The candidates of `--brush auto`: every built-in profile ([`BrushProfile::BUILTINS`]: pen1,
/// pen2 and pen1's geometric scalings), largest first.
///
/// # Panics
/// Never: every name in `BUILTINS` is a built-in.
pub fn builtin_brushes() -> Vec<BrushProfile> {
    let mut v: Vec<BrushProfile> =
        BrushProfile::BUILTINS.iter().map(|n| BrushProfile::builtin(n).expect("a built-in name")).collect();
    v.sort_by(|a, b| b.brush.radius_mm.total_cmp(&a.brush.radius_mm));
    v
}

/// Picks from `candidates` the brush whose width range suits `prepared`'s glyphs written in
/// `char_mm` boxes at tilt `alpha_rad`: the one whose suited char box side
/// ([`trajectory::auto_char_mm`] over all the glyphs' centre lines, the size at which the
/// glyphs' typical stroke widths map onto the brush's width range) is nearest `char_mm` on a
/// log scale (a factor too large costs as much as the same factor too small).
///
/// # Examples
/// ```
/// use pipeline::{builtin_brushes, choose_brush, prepare};
///
/// let p = prepare(trajectory::embedded_glyph('永')?, None)?;
/// let pen1 = choose_brush(&[p.clone()], &builtin_brushes(), 127.0, 0.0);
/// assert_eq!(pen1.name, "pen1");
/// let small = choose_brush(&[p], &builtin_brushes(), 40.0, 0.0);
/// assert!(small.profile.brush.radius_mm < 6.0 * 0.5, "{}", small.reason);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Panics
/// When `candidates` is empty.
pub fn choose_brush(prepared: &[Prepared], candidates: &[BrushProfile], char_mm: f64, alpha_rad: f64) -> BrushChoice {
    assert!(!candidates.is_empty(), "choose_brush needs at least one candidate");
    let all: Vec<_> = prepared.iter().flat_map(|p| p.paths.iter().cloned()).collect();
    let suited: Vec<(String, f64)> =
        candidates.iter().map(|b| (b.name.clone(), trajectory::auto_char_mm(&all, b, alpha_rad))).collect();
    let miss = |mm: f64| (mm / char_mm).ln().abs();
    let best = (0..candidates.len()).min_by(|&a, &b| miss(suited[a].1).total_cmp(&miss(suited[b].1))).unwrap_or(0);
    let (name, brush_char_mm) = suited[best].clone();
    let first = &suited[0];
    let reason = format!(
        "{name} (radius {:.1} mm, {}): its width range suits about {brush_char_mm:.0} mm characters for these glyphs, the nearest to the {char_mm:.1} mm box ({} suits {:.0} mm)",
        candidates[best].brush.radius_mm,
        match (name.contains('+'), name.contains("-s")) {
            (true, _) => "its profile corrected from the photo",
            (false, true) => "pen1 scaled down, nominal",
            (false, false) => "nominal",
        },
        first.0,
        first.1
    );
    BrushChoice { name, brush_char_mm, char_mm, candidates: suited, reason, profile: candidates[best].clone() }
}
