//! What text and numbers may reach an exported program: comment text made inert for its target
//! language, and numbers printed so that they read back as the checked values.

/// The language an exported program is written in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExportTarget {
    /// AUBO ARCS Lua: `--` comments end at a line end (`\n` or `\r`); `--[[ ... ]]` (and
    /// `--[==[ ... ]==]`) are long comments spanning lines.
    Lua,
    /// Universal Robots URScript: `#` comments end at a line end; strings are quoted.
    UrScript,
    /// G-code: `;` comments end at a line end; `( ... )` are comments on some controllers;
    /// `%` delimits a program and `*` starts a checksum on others.
    Gcode,
}

impl ExportTarget {
    /// The format's name, as errors print it.
    pub fn name(self) -> &'static str {
        match self {
            ExportTarget::Lua => "ARCS Lua",
            ExportTarget::UrScript => "URScript",
            ExportTarget::Gcode => "G-code",
        }
    }

    /// The characters, besides those [`comment_text`] replaces in every target, that are
    /// special in or around this target's comments.
    fn special(self) -> &'static [char] {
        match self {
            ExportTarget::Lua => &['[', ']'],
            ExportTarget::UrScript => &['#'],
            ExportTarget::Gcode => &[';', '(', ')', '%', '*'],
        }
    }
}

/// Longest text, in characters (before escaping), that [`comment_text`] keeps; longer text is
/// cut there and marked with `…`.
pub const MAX_COMMENT_CHARS: usize = 64;

/// Whether `c` ends a line or changes how the line around it is shown, in some reader: every
/// control character (C0, DEL, C1, so `\r`, `\n`, `\t`, NEL U+0085, VT, FF), the Unicode line
/// and paragraph separators U+2028 and U+2029, and the invisible format characters that
/// reorder or hide text (bidirectional marks and overrides, zero-width characters, the BOM).
pub(crate) fn unsafe_anywhere(c: char) -> bool {
    c.is_control()
        || matches!(
            c,
            '\u{2028}'
                | '\u{2029}'
                | '\u{061c}'
                | '\u{200b}'..='\u{200f}'
                | '\u{202a}'..='\u{202e}'
                | '\u{2060}'..='\u{206f}'
                | '\u{feff}'
                | '\u{fff9}'..='\u{fffb}'
        )
}

/// Whether [`comment_text`] replaces `c` for `target` (every target: the characters of
/// `unsafe_anywhere`, quotes, backquotes and the backslash that starts the escapes).
fn escaped(c: char, target: ExportTarget) -> bool {
    unsafe_anywhere(c) || matches!(c, '\\' | '"' | '\'' | '`') || target.special().contains(&c)
}

/// Whether `text` may follow a comment marker in an exported `target` program: nothing that
/// [`comment_text`] replaces, except the backslash of its escapes.
pub(crate) fn is_inert_comment(text: &str, target: ExportTarget) -> bool {
    text.chars().all(|c| c == '\\' || !escaped(c, target))
}

/// `text` made safe to follow a comment marker on one line of a `target` program: printable
/// characters (CJK included) are kept; every control character, line or paragraph separator,
/// invisible format character, quote, backslash and every character special in the target's
/// comment syntax (Lua `[` `]`, URScript `#`, G-code `;` `(` `)` `%` `*`) becomes `\u{HEX}`
/// (its code point in lowercase hexadecimal, so the escaping can be undone); text beyond
/// [`MAX_COMMENT_CHARS`] characters is cut and marked with `…`. The result is one line that
/// none of the target's readers can end early.
pub fn comment_text(text: &str, target: ExportTarget) -> String {
    let mut out = String::new();
    for (i, c) in text.chars().enumerate() {
        if i == MAX_COMMENT_CHARS {
            out.push('…');
            break;
        }
        if escaped(c, target) {
            out.push_str(&format!("\\u{{{:x}}}", c as u32));
        } else {
            out.push(c);
        }
    }
    out
}

/// Fewest decimals a number is printed with.
const MIN_DECIMALS: usize = 6;
/// Most decimals a number is printed with; a number that still does not read back within
/// [`close`] is printed so and the export's parse-back refuses it.
pub(crate) const MAX_DECIMALS: usize = 20;
/// Relative tolerance between a printed number, read back, and the value it stands for.
pub(crate) const REL_TOL: f64 = 1e-9;
/// Absolute tolerance for lengths in metres and angles in radians (1 pm, 1 prad): far below
/// what an arm resolves, so that components that are rounding noise (a rotation vector's
/// 1e-17) need not be printed to their last digit. Speeds, accelerations, feed rates, blend
/// radii and the speed fraction have none: they are compared relatively, so a speed of 1e-300
/// printed as `0.000000` is caught.
pub(crate) const LENGTH_FLOOR: f64 = 1e-12;

/// Whether `read` (a number read back from a program) stands for `want`: within [`REL_TOL`]
/// of it, or within `floor` (absolute).
pub(crate) fn close(read: f64, want: f64, floor: f64) -> bool {
    (read - want).abs() <= (REL_TOL * want.abs()).max(floor)
}

/// `v` in plain decimal notation (no exponent, which G-code would read as a word `E`), with
/// the fewest decimals from 6 up to [`MAX_DECIMALS`] that read back [`close`] to `v`; `-0`
/// prints as `0`. A non-finite value prints as Rust does (`NaN`, `inf`), which no parser of
/// this module accepts.
pub(crate) fn num(v: f64, floor: f64) -> String {
    let mut s = String::new();
    for d in MIN_DECIMALS..=MAX_DECIMALS {
        s = format!("{v:.d$}");
        if s.parse::<f64>().is_ok_and(|r| close(r, v, floor)) {
            break;
        }
    }
    if s.starts_with('-') && s[1..].bytes().all(|b| b == b'0' || b == b'.') {
        s.remove(0);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_read_back_or_show_the_loss() {
        for (v, floor, want) in [
            (0.048, LENGTH_FLOOR, "0.048000"),
            (1.0, 0.0, "1.000000"),
            (-0.0, 0.0, "0.000000"),
            (-1e-13, LENGTH_FLOOR, "0.000000"),
            (1e-9, 0.0, "0.000000001"),
            (0.381234567891, LENGTH_FLOOR, "0.381234568"),
            (1200.0000000000002, 0.0, "1200.000000"),
            // Beyond 20 decimals: printed, and the parse-back refuses it.
            (1e-300, 0.0, "0.00000000000000000000"),
        ] {
            assert_eq!(num(v, floor), want, "{v:e}");
        }
        assert!(!close(0.0, 1e-300, 0.0) && close(0.0, 1e-13, LENGTH_FLOOR));
        assert_eq!(num(f64::NAN, 0.0), "NaN");
    }

    #[test]
    fn comments_keep_printable_text_and_escape_the_rest() {
        for (text, target, want) in [
            ("十", ExportTarget::Gcode, "十"),
            ("十\nG1 Z-40 F3000", ExportTarget::Gcode, "十\\u{a}G1 Z-40 F3000"),
            ("a\r\n\r\nb", ExportTarget::Lua, "a\\u{d}\\u{a}\\u{d}\\u{a}b"),
            ("a\u{2028}b\u{85}c\u{0}d\te", ExportTarget::UrScript, "a\\u{2028}b\\u{85}c\\u{0}d\\u{9}e"),
            ("x; (y) 5% *", ExportTarget::Gcode, "x\\u{3b} \\u{28}y\\u{29} 5\\u{25} \\u{2a}"),
            ("x; (y)", ExportTarget::Lua, "x; (y)"),
            ("--[[ ]]", ExportTarget::Lua, "--\\u{5b}\\u{5b} \\u{5d}\\u{5d}"),
            ("#x", ExportTarget::UrScript, "\\u{23}x"),
            ("#x", ExportTarget::Gcode, "#x"),
            ("\"q' `b` \\", ExportTarget::Lua, "\\u{22}q\\u{27} \\u{60}b\\u{60} \\u{5c}"),
            ("\u{202e}rtl\u{feff}", ExportTarget::Gcode, "\\u{202e}rtl\\u{feff}"),
        ] {
            let got = comment_text(text, target);
            assert_eq!(got, want, "{text:?} for {target:?}");
            assert!(is_inert_comment(&got, target), "{got:?}");
        }
        let long = "永".repeat(1000);
        let cut = comment_text(&long, ExportTarget::Lua);
        assert_eq!(cut.chars().count(), MAX_COMMENT_CHARS + 1);
        assert!(cut.ends_with('…'));
        // Worst case: every character escaped, each at most 10 bytes.
        assert!(comment_text(&"\u{9f}".repeat(500), ExportTarget::Gcode).len() <= MAX_COMMENT_CHARS * 10 + 3);
        assert!(!is_inert_comment("a\nb", ExportTarget::Gcode) && !is_inert_comment("(x)", ExportTarget::Gcode));
    }
}
