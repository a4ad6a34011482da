//! What GRBL 1.1's numbered `error:N` and `ALARM:N` answers mean, in maobi's words (the codes
//! and their sense as GRBL 1.1 documents them in its `doc/csv/*_codes_en_US.csv`).

/// GRBL 1.1's meaning of `error:N`, or `None` for a code it does not define.
///
/// # Examples
/// ```
/// assert_eq!(robot_grbl::error_meaning(22), Some("feed rate not set (G1 without F)"));
/// assert_eq!(robot_grbl::error_meaning(99), None);
/// ```
pub fn error_meaning(code: u16) -> Option<&'static str> {
    Some(match code {
        1 => "a G-code word without its letter",
        2 => "a number missing or malformed",
        3 => "unknown `$` command",
        4 => "a negative value where a positive one is needed",
        5 => "homing is not enabled ($22)",
        6 => "step pulse shorter than 3 µs",
        7 => "settings could not be read from EEPROM (defaults restored)",
        8 => "a `$` command that needs the machine idle",
        9 => "G-code refused while in alarm or jogging",
        10 => "soft limits need homing enabled ($22)",
        11 => "line longer than the firmware's line buffer",
        12 => "a setting that would step faster than 30 kHz",
        13 => "the safety door is open",
        14 => "a startup or build-info line too long for EEPROM",
        15 => "a jog beyond the machine's travel",
        16 => "an invalid jog command",
        17 => "laser mode needs PWM output",
        20 => "an unsupported G-code command",
        21 => "two commands of one modal group in a line",
        22 => "feed rate not set (G1 without F)",
        23 => "a command that needs an integer value",
        24 => "two commands that both take the axis words",
        25 => "a word repeated in one line",
        26 => "a motion without axis words",
        27 => "an invalid line number",
        28 => "a command missing a value word it needs",
        29 => "G59.x work coordinate systems are not supported",
        30 => "G53 with a motion other than G0 or G1",
        31 => "axis words that no command in the line uses",
        32 => "an arc without an axis word in its plane",
        33 => "an invalid motion target",
        34 => "an invalid arc radius",
        35 => "an arc without an offset in its plane",
        36 => "value words that nothing in the line uses",
        37 => "G43.1 on an axis other than the tool length axis",
        38 => "a tool number beyond what is supported",
        _ => return None,
    })
}

/// GRBL 1.1's meaning of `ALARM:N`, or `None` for a code it does not define.
///
/// # Examples
/// ```
/// assert!(robot_grbl::alarm_meaning(2).unwrap().starts_with("soft limit"));
/// ```
pub fn alarm_meaning(code: u16) -> Option<&'static str> {
    Some(match code {
        1 => "hard limit switch triggered (the position is likely lost)",
        2 => "soft limit: a target beyond the machine's travel (the position is kept)",
        3 => "reset while moving (the position is likely lost)",
        4 => "probe not in its expected state before probing",
        5 => "probe did not touch within the programmed travel",
        6 => "homing reset",
        7 => "safety door opened while homing",
        8 => "homing pull-off did not clear the limit switch",
        9 => "homing did not find the limit switch",
        _ => return None,
    })
}

/// Whether GRBL keeps the machine position through `ALARM:N` (so a move in machine coordinates
/// still lands where it should): a soft limit or a failed probe stops without losing steps; a
/// hard limit, a reset in motion or a homing failure may have.
pub(crate) fn alarm_keeps_position(code: u16) -> bool {
    matches!(code, 2 | 4 | 5)
}

/// `error:N` or `ALARM:N` with its meaning, as messages show it.
pub(crate) fn describe(kind: &str, code: u16) -> String {
    let meaning = if kind == "ALARM" { alarm_meaning(code) } else { error_meaning(code) };
    match meaning {
        Some(m) => format!("{kind}:{code} ({m})"),
        None => format!("{kind}:{code} (a code GRBL 1.1 does not define)"),
    }
}
