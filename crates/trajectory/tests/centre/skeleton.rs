//! The skeleton that `cargo xtask skeleton-counts` measures is the one `centre_lines` uses.

use trajectory::{
    DEFAULT_ANALYSIS_PX, Glyph, GlyphSource, GraphOptions, Method, Shape, Skeleton, centre_lines, embedded_glyph,
};

#[test]
fn skeleton_counts_are_the_centre_lines_counts() {
    for ch in "永字八法十口人丁山水".chars() {
        let g = embedded_glyph(ch).unwrap();
        let paths = centre_lines(&g, Method::Skeleton, 256).unwrap();
        let s = Skeleton::of(&g, 256).unwrap();
        assert_eq!(s.strokes(&GraphOptions::default()).len(), paths.len(), "{ch}");
    }
    assert_eq!(DEFAULT_ANALYSIS_PX, 512, "the measurement's default raster is the pipeline's");
}

#[test]
fn a_blank_glyph_has_no_skeleton() {
    let g = Glyph {
        ch: '一',
        source: GlyphSource::Embedded,
        shape: Shape::Outlines(vec![]),
        stroke_outlines: None,
        medians: None,
    };
    assert!(Skeleton::of(&g, 64).is_none());
}
