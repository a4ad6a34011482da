//! A written character's pictures, as `maobi write` puts them in its folder.

use bezier_raster::Coverage;
use pipeline::CharResult;

use crate::{Result, labelled_row_png, loss_png, overlay_legend_png};

/// A written character's pictures (docs/outputs.md), each a file name and its PNG bytes, in
/// the order they are written: `render.png` (the plan), `reference.png` (the glyph),
/// `overlay.png` (the plan over the glyph, with its legend), then when the program was
/// executed `executed.png` and `side-by-side.png` (glyph | plan | executed, labelled), and
/// when the track was refined `refine.png` (its loss curve). Encoded at once on rayon's pool.
///
/// # Errors
/// [`crate::FigureError`] when an encoding or a plot fails.
///
/// # Examples
/// ```no_run
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use pipeline::{BoxRule, GlyphInput, WriteOptions, write_placed};
/// let pen1 = brush_model::BrushProfile::builtin("pen1")?;
/// let p = GlyphInput::Hanzi(None).prepare('永', None)?;
/// let r = write_placed(&p, &pen1, &WriteOptions::default(), BoxRule::Auto)?;
/// for (name, png) in figures::char_pictures(&r)? {
///     std::fs::write(name, png)?;
/// }
/// # Ok(())
/// # }
/// ```
pub fn char_pictures(r: &CharResult) -> Result<Vec<(&'static str, Vec<u8>)>> {
    let executed = |ex: &Coverage| -> Result<_> {
        let rows = [("reference (glyph)", &r.reference), ("plan", &r.render), ("executed", ex)];
        let (png, row) = rayon::join(|| ex.encode_png(), || labelled_row_png(&rows));
        Ok((png?, row?))
    };
    let ((render, reference), (overlay, executed)) = rayon::join(
        || rayon::join(|| r.render.encode_png(), || r.reference.encode_png()),
        || rayon::join(|| overlay_legend_png(&r.reference, &r.render), || r.executed.as_ref().map(executed)),
    );
    let mut out = vec![("render.png", render?), ("reference.png", reference?), ("overlay.png", overlay?)];
    if let Some((png, row)) = executed.transpose()? {
        out.push(("executed.png", png));
        out.push(("side-by-side.png", row));
    }
    if let Some(rf) = &r.report.refine {
        let total = rf.curve.iter().enumerate().map(|(i, l)| (i as f64, l.total)).collect();
        let image = rf.curve.iter().enumerate().map(|(i, l)| (i as f64, l.image)).collect();
        out.push(("refine.png", loss_png(&[("total", total), ("image", image)])?));
    }
    Ok(out)
}
