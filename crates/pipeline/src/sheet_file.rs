//! A sheet's `track.json` read back (by `maobi observe`, `write --observed`): every field
//! validated against what it indexes or holds, naming the file and the field.

use std::path::Path;

use crate::readback::{ReadBackError, check_num, read_bounded, short};
use crate::{MAX_SHEET_MM, MarkRole, SheetTrack};

/// The most characters a sheet's `track.json` read back may hold (their boxes must also fit on
/// the sheet without overlapping).
pub const MAX_SHEET_CHARS: usize = 10_000;

/// The smallest character box a sheet read back may hold, mm (as `write --char-mm`).
pub const SHEET_MIN_CHAR_MM: f64 = 1.0;

/// The largest character box a sheet read back may hold, mm (as `write --char-mm`).
pub const SHEET_MAX_CHAR_MM: f64 = 1000.0;

/// The largest sheet `track.json` read back, bytes (as `robot_io::MAX_FILE_BYTES`).
pub const MAX_SHEET_TRACK_BYTES: u64 = robot_io::MAX_FILE_BYTES;

/// How far a track point may lie outside the sheet, mm (none of maobi's do).
const POINT_SLACK_MM: f64 = 1.0;

impl SheetTrack {
    /// Reads and validates a sheet's `track.json` ([`SheetTrack::validate`]); returns it with
    /// the file's bytes (for [`crate::fingerprint`]).
    ///
    /// # Errors
    /// [`ReadBackError`] naming `path` and, where one is at fault, the field.
    pub fn load(path: &Path) -> Result<(SheetTrack, Vec<u8>), ReadBackError> {
        const WHAT: &str = "a sheet's track.json (as a sheet write saves it)";
        let bytes = read_bounded(path, MAX_SHEET_TRACK_BYTES, WHAT)?;
        let track: SheetTrack = serde_json::from_slice(&bytes).map_err(|source| ReadBackError::Json {
            path: path.to_path_buf(),
            what: WHAT,
            source,
        })?;
        track.validate(path)?;
        Ok((track, bytes))
    }

    /// Checks what a sheet read back may hold: its kind; the sheet's size; the character side
    /// and every box (finite, of that side, on the sheet, no more than fit on it, at most
    /// [`MAX_SHEET_CHARS`]); each character one printable character; the stroke ranges (in
    /// order, one after another from the marks' strokes to the last stroke); `stroke_chars`
    /// (one per stroke, each the character whose range holds it); the marks (at most one per
    /// role, on the sheet, two strokes each); every track point finite and on the sheet; the
    /// brush (as `--brush` is validated). `path` names the file in errors.
    ///
    /// # Errors
    /// [`ReadBackError::Field`] or [`ReadBackError::Profile`] for the first field at fault.
    pub fn validate(&self, path: &Path) -> Result<(), ReadBackError> {
        let bad = |field: &str, expected: String| Err(ReadBackError::field(path, field, expected));
        if self.kind != "sheet" {
            return bad("kind", format!("{:?}: expected \"sheet\"", self.kind));
        }
        for (i, side) in ["sheet_mm[0]", "sheet_mm[1]"].iter().enumerate() {
            check_num(path, side, self.sheet_mm[i], 10.0, MAX_SHEET_MM, "mm")?;
        }
        let [w, h] = self.sheet_mm;
        check_num(path, "char_mm", self.char_mm, SHEET_MIN_CHAR_MM, SHEET_MAX_CHAR_MM, "mm")?;
        check_num(path, "margin_mm", self.margin_mm, 0.0, w.min(h) / 2.0, "mm")?;
        self.validate_chars(path)?;
        self.validate_stroke_chars(path)?;
        self.validate_marks(path)?;
        self.validate_points(path)?;
        self.brush.validate("brush").map_err(|source| ReadBackError::Profile { path: path.to_path_buf(), source })
    }

    /// [`SheetTrack::validate`]'s characters: how many the sheet holds, each one printable
    /// character in a box of the sheet's side on the sheet, their stroke ranges one after another.
    fn validate_chars(&self, path: &Path) -> Result<(), ReadBackError> {
        let bad = |field: &str, expected: String| Err(ReadBackError::field(path, field, expected));
        let [w, h] = self.sheet_mm;
        let n = self.chars.len();
        if n == 0 {
            return bad("chars", "empty: expected the sheet's characters".into());
        }
        // Boxes do not overlap, so no more than the paper's area holds.
        let fit = ((w * h) / (self.char_mm * self.char_mm)).floor().min(MAX_SHEET_CHARS as f64) as usize;
        if n > fit.max(1) {
            return bad(
                "chars",
                format!(
                    "{n} characters: a {w}×{h} mm sheet holds at most {fit} boxes of {} mm (and a sheet read back at most {MAX_SHEET_CHARS})",
                    self.char_mm
                ),
            );
        }
        let tol = 1e-6 * (1.0 + self.char_mm);
        let mut next = self.mark_strokes;
        for (i, c) in self.chars.iter().enumerate() {
            let mut it = c.char.chars();
            match (it.next(), it.next()) {
                (Some(ch), None) if !ch.is_control() && !ch.is_whitespace() && !matches!(ch, '/' | '\\') => {}
                _ => {
                    return bad(&format!("chars[{i}].char"), format!("{:?}: expected one printable character", c.char));
                }
            }
            let [x0, y0, size] = c.char_box_mm;
            let field = format!("chars[{i}].char_box_mm");
            if !(size.is_finite() && (size - self.char_mm).abs() <= tol) {
                return bad(
                    &field,
                    format!("side {} mm: expected the sheet's char_mm {} mm", short(size), self.char_mm),
                );
            }
            if !(x0.is_finite()
                && y0.is_finite()
                && x0 >= -tol
                && y0 >= -tol
                && x0 + size <= w + tol
                && y0 + size <= h + tol)
            {
                return bad(
                    &field,
                    format!(
                        "[{}, {}, {}] mm: expected a box on the {w}×{h} mm sheet",
                        short(x0),
                        short(y0),
                        short(size)
                    ),
                );
            }
            let [a, b] = c.strokes;
            if a != next || b < a || b > self.strokes.len() {
                return bad(
                    &format!("chars[{i}].strokes"),
                    format!(
                        "[{a}, {b}]: expected [{next}, end) with end at most the {} strokes (each character's strokes follow the last one's)",
                        self.strokes.len()
                    ),
                );
            }
            next = b;
        }
        if next != self.strokes.len() {
            return bad(
                "chars",
                format!("the characters' strokes end at {next}, the sheet has {} strokes", self.strokes.len()),
            );
        }
        Ok(())
    }

    /// [`SheetTrack::validate`]'s `stroke_chars`: one per stroke, each the character whose range
    /// holds it (the marks' strokes count as the first character's).
    fn validate_stroke_chars(&self, path: &Path) -> Result<(), ReadBackError> {
        let bad = |field: &str, expected: String| Err(ReadBackError::field(path, field, expected));
        let n = self.chars.len();
        if self.stroke_chars.len() != self.strokes.len() {
            return bad(
                "stroke_chars",
                format!("{} entries: expected one per stroke ({})", self.stroke_chars.len(), self.strokes.len()),
            );
        }
        // The marks' strokes count as the first character's.
        let owners = std::iter::repeat_n(0, self.mark_strokes).chain(
            self.chars.iter().enumerate().flat_map(|(i, ch)| std::iter::repeat_n(i, ch.strokes[1] - ch.strokes[0])),
        );
        for (s, (&c, owner)) in self.stroke_chars.iter().zip(owners).enumerate() {
            if c != owner {
                return bad(
                    &format!("stroke_chars[{s}]"),
                    format!("{c}: expected {owner}, the character whose strokes hold stroke {s} (of {n} characters)"),
                );
            }
        }
        Ok(())
    }

    /// [`SheetTrack::validate`]'s marks: at most one per role, two strokes each, on the sheet.
    fn validate_marks(&self, path: &Path) -> Result<(), ReadBackError> {
        let bad = |field: &str, expected: String| Err(ReadBackError::field(path, field, expected));
        let [w, h] = self.sheet_mm;
        if self.marks.len() > 6 {
            return bad("marks", format!("{} marks: a sheet has at most 6 (one per role)", self.marks.len()));
        }
        if self.mark_strokes != 2 * self.marks.len() {
            return bad(
                "mark_strokes",
                format!("{}: expected two per mark ({})", self.mark_strokes, 2 * self.marks.len()),
            );
        }
        let mut seen: Vec<MarkRole> = Vec::new();
        for (i, m) in self.marks.iter().enumerate() {
            if seen.contains(&m.role) {
                return bad(&format!("marks[{i}].role"), format!("{}: a second mark of this role", m.role.name()));
            }
            seen.push(m.role);
            check_num(path, &format!("marks[{i}].centre_mm[0]"), m.centre_mm[0], 0.0, w, "mm")?;
            check_num(path, &format!("marks[{i}].centre_mm[1]"), m.centre_mm[1], 0.0, h, "mm")?;
            check_num(path, &format!("marks[{i}].half_length_mm"), m.half_length_mm, 0.01, w / 4.0, "mm")?;
            check_num(path, &format!("marks[{i}].half_width_mm"), m.half_width_mm, 0.01, h / 4.0, "mm")?;
        }
        Ok(())
    }

    /// [`SheetTrack::validate`]'s track points: finite, and on the sheet.
    fn validate_points(&self, path: &Path) -> Result<(), ReadBackError> {
        let bad = |field: &str, expected: String| Err(ReadBackError::field(path, field, expected));
        let [w, h] = self.sheet_mm;
        for (s, st) in self.strokes.iter().enumerate() {
            for (k, p) in st.points.iter().enumerate() {
                let on = |v: f64, side: f64| v.is_finite() && v >= -POINT_SLACK_MM && v <= side + POINT_SLACK_MM;
                let angles = [p.h_mm, p.alpha_rad, p.beta_rad].iter().all(|v| v.is_finite());
                if !(on(p.x_mm, w) && on(p.y_mm, h) && angles) {
                    return bad(
                        &format!("strokes[{s}][{k}]"),
                        format!(
                            "({}, {}) mm, h {} mm, α {}, β {}: expected finite numbers, the point on the {w}×{h} mm sheet",
                            short(p.x_mm),
                            short(p.y_mm),
                            short(p.h_mm),
                            short(p.alpha_rad),
                            short(p.beta_rad)
                        ),
                    );
                }
            }
        }
        Ok(())
    }
}
