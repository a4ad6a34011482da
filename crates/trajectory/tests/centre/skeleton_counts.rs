//! The skeleton method's stroke counts on embedded characters: the learned junction and corner
//! decisions (compiled in) against the hand rules alone. A small, fixed sample of the embedded
//! subset; the full figures come from `cargo xtask skeleton-counts` (docs/trajectory.md).

use trajectory::{DEFAULT_ANALYSIS_PX, GraphOptions, Skeleton, embedded_chars, embedded_glyph};

/// Every 25th embedded character (40 of them).
fn sample() -> Vec<char> {
    embedded_chars().into_iter().step_by(25).take(40).collect()
}

/// How many of `chars` the skeleton finds the medians' stroke count for, with `opts`.
fn right(chars: &[char], opts: &GraphOptions) -> usize {
    chars
        .iter()
        .filter(|&&c| {
            let g = embedded_glyph(c).expect("embedded");
            let expected = g.medians.as_ref().expect("medians").len();
            let sk = Skeleton::of(&g, DEFAULT_ANALYSIS_PX).expect("ink");
            sk.strokes(opts).len() == expected
        })
        .count()
}

#[test]
fn learned_decisions_count_strokes_at_least_as_well_as_the_rules() {
    let chars = sample();
    assert_eq!(chars.len(), 40);
    let learned = right(&chars, &GraphOptions::default());
    let rules =
        right(&chars, &GraphOptions { learned_pairing: false, learned_corners: false, ..GraphOptions::default() });
    assert!(learned >= rules, "learned {learned}/40, rules {rules}/40");
    assert!(learned >= 32, "learned {learned}/40 (at least 80 %)");
}
