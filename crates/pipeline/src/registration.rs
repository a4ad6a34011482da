//! A sheet's registration marks as the photo registration takes them.

use observe::KnownMark;

use crate::{Mark, MarkRole};

/// `marks` in the order [`observe::register`] takes them: the four corners first (top left,
/// top right, bottom right, bottom left), then the others; `None` when a corner is missing.
///
/// # Examples
/// ```
/// use pipeline::{Flow, known_marks, registration_marks};
///
/// let pen1 = brush_model::BrushProfile::builtin("pen1")?;
/// let layout = pipeline::layout_on_sheet(&pipeline::parse_sheet("A5")?, 2, Flow::Columns, None, 15.0, None)?;
/// let marks = registration_marks(&layout, &pen1)?;
/// let known = known_marks(&marks).expect("four corners");
/// assert_eq!(known[0].role, "top-left");
/// assert_eq!(known.len(), marks.len());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn known_marks(marks: &[Mark]) -> Option<Vec<KnownMark>> {
    let order = [MarkRole::TopLeft, MarkRole::TopRight, MarkRole::BottomRight, MarkRole::BottomLeft];
    let mut ordered: Vec<&Mark> = order.iter().filter_map(|r| marks.iter().find(|m| m.role == *r)).collect();
    if ordered.len() != 4 {
        return None;
    }
    ordered.extend(marks.iter().filter(|m| !order.contains(&m.role)));
    Some(
        ordered
            .iter()
            .map(|m| KnownMark {
                role: m.role.name().into(),
                centre_mm: m.centre_mm,
                half_length_mm: m.half_length_mm,
                half_width_mm: m.half_width_mm,
            })
            .collect(),
    )
}
