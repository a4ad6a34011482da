//! The G-code maobi exports, as lines to stream: each statement of the checked text with its
//! comment and spaces taken off (GRBL ignores both, and they cost bytes of its receive buffer),
//! where it is in the file, which stroke it belongs to, where it moves to and how long it was
//! planned to take.

use robot_io::{GcodeStatement, RobotError, read_gcode};
use serde::Serialize;

/// GRBL 1.1's line buffer (`LINE_BUFFER_SIZE`, 80 bytes with its terminator): a longer line
/// is refused with `error:11`.
pub const GRBL_MAX_LINE: usize = 79;

/// What a line does in the writing program.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum LineKind {
    /// `G21`, `G90`: modes.
    Setup,
    /// A `G0`: the brush up, travelling.
    Travel,
    /// A `G1`: pressing, descending, or soaking in the ink pot.
    Feed,
    /// `M2`: the end.
    End,
}

/// One line to stream.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ProgramLine {
    /// Its line number in the exported text (1-based).
    pub source_line: usize,
    /// What is sent, without the line end (`G1X50.000000Y-60.000000Z-3.000000F327.5`).
    pub text: String,
    /// The zero-based stroke it belongs to (`None`: the start or the end).
    pub stroke: Option<usize>,
    /// What it does.
    pub kind: LineKind,
    /// The work position after it, mm, where known (before the first `G0 X Y`, X and Y are
    /// wherever the machine stands).
    pub to: [Option<f64>; 3],
    /// The feed rate it moves at, mm/min (`G0`: the program's travel speed, which GRBL
    /// replaces by its maximum rates).
    pub feed_mm_min: f64,
    /// Its length, mm, where both ends are known (0 for a line that does not move).
    pub length_mm: f64,
    /// Its planned duration, s: its length over its feed (no acceleration).
    pub planned_s: f64,
}

/// A writing program as lines to stream to GRBL.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GcodeProgram {
    /// The lines, in order.
    pub lines: Vec<ProgramLine>,
    /// Strokes in the program.
    pub strokes: usize,
    /// The pen-up height the program travels at, work mm (its first `G0 Z`).
    pub lift_mm: f64,
    /// The deepest Z the program reaches, work mm (the deepest press, or the ink pot).
    pub min_z_mm: f64,
}

impl GcodeProgram {
    /// Reads G-code as `robot_io::gcode_chars` writes it (its grammar only: anything
    /// else is refused naming the line), with `travel_mm_min` the speed its `G0` moves were
    /// planned at (`robot.json` `travel_speed_m_s` × 60 000).
    ///
    /// # Examples
    /// ```
    /// let text = "; maobi writing program: 一\nG21 ; millimetres\nG90 ; absolute\nG0 Z5.000000\n; stroke 1\n\
    ///             G0 X10.000000 Y-20.000000 F3000.000000\nG1 X10.000000 Y-20.000000 Z-2.000000 F600.000000\n\
    ///             G1 X30.000000 Y-20.000000 Z-2.000000 F1200.000000\nG0 Z5.000000\nM2\n";
    /// let p = robot_grbl::GcodeProgram::from_export(text, 3000.0).unwrap();
    /// assert_eq!(p.lines.len(), 8);
    /// assert_eq!(p.lines[4].text, "G1X10.000000Y-20.000000Z-2.000000F600.000000");
    /// assert_eq!((p.strokes, p.lift_mm, p.min_z_mm), (1, 5.0, -2.0));
    /// // The 20 mm stroke at 1200 mm/min was planned to take 1 s.
    /// assert!((p.lines[5].planned_s - 1.0).abs() < 1e-12);
    /// ```
    ///
    /// # Errors
    /// [`RobotError::Unsafe`] for text outside the exporter's grammar, a line longer than GRBL
    /// takes ([`GRBL_MAX_LINE`]), or a program that does not raise the brush first.
    pub fn from_export(text: &str, travel_mm_min: f64) -> Result<GcodeProgram, RobotError> {
        let statements = read_gcode(text)?;
        let source: Vec<&str> = text.split('\n').collect();
        let refuse = |line: usize, reason: String| RobotError::Unsafe {
            stroke: None,
            point: None,
            reason: format!("G-code line {line}: {reason}"),
        };
        if !(travel_mm_min.is_finite() && travel_mm_min > 0.0) {
            return Err(refuse(1, format!("the travel speed {travel_mm_min} mm/min is not positive")));
        }
        // Stroke markers, from the comment lines the exporter writes.
        let mut stroke_at = vec![None; source.len() + 2];
        let mut current = None;
        let mut strokes = 0;
        for (i, l) in source.iter().enumerate() {
            if let Some(n) = l
                .strip_prefix("; stroke ")
                .or_else(|| l.strip_prefix("; ink dip before stroke "))
                .and_then(|n| n.trim().parse::<usize>().ok())
                .filter(|n| *n >= 1)
            {
                current = Some(n - 1);
                strokes = strokes.max(n);
            }
            stroke_at[i + 1] = current;
        }
        let mut lines = Vec::with_capacity(statements.len());
        let mut pos: [Option<f64>; 3] = [None; 3];
        let mut lift = None;
        let mut min_z = f64::INFINITY;
        for (n, st) in statements {
            let raw = source.get(n - 1).copied().unwrap_or_default();
            let code = raw.split(';').next().unwrap_or_default();
            let sent: String = code.chars().filter(|c| !c.is_whitespace()).collect();
            if sent.len() > GRBL_MAX_LINE || !sent.bytes().all(|b| b.is_ascii_graphic()) {
                return Err(refuse(
                    n,
                    format!("`{sent}` is {} bytes; GRBL 1.1 takes at most {GRBL_MAX_LINE} printable ASCII", sent.len()),
                ));
            }
            let (kind, feed, target) = match st {
                GcodeStatement::Millimetres | GcodeStatement::Absolute => (LineKind::Setup, 0.0, pos),
                GcodeStatement::End => (LineKind::End, 0.0, pos),
                GcodeStatement::Move { rapid, x_mm, y_mm, z_mm, f_mm_min } => {
                    let to = [x_mm.or(pos[0]), y_mm.or(pos[1]), z_mm.or(pos[2])];
                    let feed = if rapid { travel_mm_min } else { f_mm_min.unwrap_or(0.0) };
                    (if rapid { LineKind::Travel } else { LineKind::Feed }, feed, to)
                }
            };
            if kind == LineKind::Travel && lift.is_none() {
                lift = target[2];
            }
            if kind == LineKind::Feed && lift.is_none() {
                return Err(refuse(
                    n,
                    "the program presses before it has raised the brush to its travel height".into(),
                ));
            }
            if let Some(z) = target[2] {
                min_z = min_z.min(z);
            }
            let length: f64 = if target.iter().zip(&pos).all(|(a, b)| a.is_some() && b.is_some()) {
                target.iter().zip(&pos).map(|(a, b)| (a.unwrap_or(0.0) - b.unwrap_or(0.0)).powi(2)).sum::<f64>().sqrt()
            } else if pos[2].is_some() && target[2].is_some() && target[..2] == pos[..2] {
                (target[2].unwrap_or(0.0) - pos[2].unwrap_or(0.0)).abs()
            } else {
                0.0
            };
            let planned_s = if feed > 0.0 { 60.0 * length / feed } else { 0.0 };
            lines.push(ProgramLine {
                source_line: n,
                text: sent,
                stroke: stroke_at.get(n).copied().flatten(),
                kind,
                to: target,
                feed_mm_min: feed,
                length_mm: length,
                planned_s,
            });
            pos = target;
        }
        let lift_mm = lift.ok_or_else(|| refuse(1, "the program never raises the brush (`G0 Z`)".into()))?;
        Ok(GcodeProgram { lines, strokes, lift_mm, min_z_mm: min_z })
    }

    /// The planned time of the whole program, s (lengths over feeds, no acceleration).
    pub fn planned_s(&self) -> f64 {
        self.lines.iter().map(|l| l.planned_s).sum()
    }

    /// The program's reach in work coordinates, mm: `[min, max]` per axis over every known
    /// target (`None` for an axis it never names).
    pub fn bounds(&self) -> [Option<[f64; 2]>; 3] {
        let mut b: [Option<[f64; 2]>; 3] = [None; 3];
        for l in &self.lines {
            for (k, v) in l.to.iter().enumerate() {
                if let Some(v) = v {
                    let e = b[k].get_or_insert([*v, *v]);
                    e[0] = e[0].min(*v);
                    e[1] = e[1].max(*v);
                }
            }
        }
        b
    }
}
