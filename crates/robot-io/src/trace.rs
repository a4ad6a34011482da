//! A simulator's trace read back: the executed TCP path the simulator writes (`robot sim
//! --trace`, [`crate::sim::SimOptions::trace_path`]), one [`TraceEntry`] a JSON line, flushed
//! after every move, so that a file the simulator stopped writing mid-line (killed, or its disk
//! full) still reads up to its last whole sample.

use std::path::{Path, PathBuf};

use crate::RobotError;
use crate::exec::TraceEntry;

/// A simulator trace as [`read_trace`] reads it.
#[derive(Clone, Debug, PartialEq)]
pub struct Trace {
    /// The samples, in the file's order.
    pub samples: Vec<TraceEntry>,
    /// The last line, cut short and skipped: its number (from 1) and its length, bytes. The
    /// trace ends at the sample before.
    pub cut_line: Option<(usize, usize)>,
}

/// Reads a simulator trace: JSON lines (one [`TraceEntry`] a line, blank lines skipped), or one
/// JSON array of them. A last line cut short (not JSON, and either unfinished JSON or the file
/// not ending in a line end) is skipped and reported in [`Trace::cut_line`]; a bad line before
/// it, or a last line that is whole JSON but not a sample, is an error. A file cut inside a
/// UTF-8 character is read up to it.
///
/// # Examples
/// ```
/// use robot_io::{TraceEntry, TraceKind, Pose, read_trace};
/// let sample = TraceEntry { t_s: 0.5, kind: TraceKind::Line, pose: Pose([0.4, 0.0, 0.1, 3.14, 0.0, 0.0]) };
/// let line = serde_json::to_string(&sample).unwrap();
/// let path = std::env::temp_dir().join(format!("maobi-read-trace-doc-{}.jsonl", std::process::id()));
/// // The simulator stopped while writing the second sample.
/// std::fs::write(&path, format!("{line}\n{}", &line[..10])).unwrap();
/// let trace = read_trace(&path).unwrap();
/// assert_eq!(trace.samples, vec![sample]);
/// assert_eq!(trace.cut_line, Some((2, 10)));
/// # std::fs::remove_file(&path).unwrap();
/// ```
///
/// # Errors
/// [`RobotError::Read`] when the file cannot be read; [`RobotError::Trace`] naming the file (and
/// the line) when it is not a trace, or holds no sample.
pub fn read_trace(path: &Path) -> Result<Trace, RobotError> {
    let bytes = std::fs::read(path).map_err(|source| RobotError::Read { path: path.to_path_buf(), source })?;
    parse(&bytes, path)
}

fn parse(bytes: &[u8], path: &Path) -> Result<Trace, RobotError> {
    let refused = |line: Option<usize>, message: String, source: Option<serde_json::Error>| RobotError::Trace {
        path: PathBuf::from(path),
        line,
        message,
        source,
    };
    // A cut can split a UTF-8 character: the text is read up to what decodes.
    let text = match std::str::from_utf8(bytes) {
        Ok(t) => t,
        Err(e) => std::str::from_utf8(&bytes[..e.valid_up_to()]).unwrap_or_default(),
    };
    if text.trim_start().starts_with('[') {
        return serde_json::from_str(text)
            .map(|samples| Trace { samples, cut_line: None })
            .map_err(|e| refused(None, "not a simulator trace".into(), Some(e)));
    }
    let mut samples = Vec::new();
    let mut cut_line = None;
    let lines: Vec<&str> = text.split('\n').collect();
    let last = lines.iter().rposition(|l| !l.trim().is_empty());
    for (i, line) in lines.iter().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        match serde_json::from_str(line) {
            Ok(t) => samples.push(t),
            // The last line, unfinished: the file was cut there.
            // (A last line that is complete JSON but not a sample is an error like any other.)
            Err(e)
                if Some(i) == last
                    && (e.is_eof()
                        || (!text.ends_with('\n') && serde_json::from_str::<serde_json::Value>(line).is_err())) =>
            {
                cut_line = Some((i + 1, line.len()));
            }
            Err(e) => {
                let message = "not a simulator trace sample (expected {\"t_s\", \"kind\", \"pose\"})".to_string();
                return Err(refused(Some(i + 1), message, Some(e)));
            }
        }
    }
    if samples.is_empty() {
        return Err(refused(None, "the trace is empty (did the simulator execute any move?)".into(), None));
    }
    Ok(Trace { samples, cut_line })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exec::TraceKind;
    use crate::pose::Pose;

    fn sample(t_s: f64) -> TraceEntry {
        TraceEntry { t_s, kind: TraceKind::Joint, pose: Pose([0.4, 0.1, 0.2, 3.0, 0.1, -0.2]) }
    }

    fn read(text: &str) -> Result<Trace, String> {
        parse(text.as_bytes(), Path::new("t.jsonl")).map_err(|e| {
            let cause = std::error::Error::source(&e).map_or(String::new(), |s| format!(": {s}"));
            format!("{e}{cause}")
        })
    }

    #[test]
    fn lines_and_arrays_read_and_a_cut_last_line_is_skipped() {
        let lines: Vec<String> = [0.0, 0.25, 0.5].map(|t| serde_json::to_string(&sample(t)).unwrap()).into();
        let whole = lines.join("\n") + "\n";
        let want: Vec<TraceEntry> = [0.0, 0.25, 0.5].map(sample).into();
        assert_eq!(read(&whole).unwrap(), Trace { samples: want.clone(), cut_line: None });
        // Blank lines (and none at the end) change nothing.
        assert_eq!(read(&lines.join("\n\n")).unwrap().samples, want);
        let array = serde_json::to_string(&want).unwrap();
        assert_eq!(read(&format!("  {array}")).unwrap().samples, want);
        // Cut inside the last line, anywhere: the samples before it, the cut named.
        let from = whole.trim_end().rfind('\n').unwrap() + 1;
        for keep in [1, 7, lines[2].len() - 1] {
            let t = read(&whole[..from + keep]).unwrap();
            assert_eq!(t.samples, want[..2], "keep {keep}");
            assert_eq!(t.cut_line, Some((3, keep)), "keep {keep}");
        }
        // Cut inside a UTF-8 character: read up to it.
        let mut bytes = whole.clone().into_bytes();
        bytes.extend_from_slice(&"{\"t_s\": \"永".as_bytes()[..10]);
        let t = parse(&bytes, Path::new("t.jsonl")).unwrap();
        assert_eq!((t.samples.len(), t.cut_line), (3, Some((4, 9))));
    }

    #[test]
    fn what_is_not_a_trace_is_refused_naming_the_line() {
        let good = serde_json::to_string(&sample(0.0)).unwrap();
        // A bad line before the last.
        let e = read(&format!("{good}\n{{\"t_s\": 1,\n{good}\n")).unwrap_err();
        assert!(
            e.starts_with("t.jsonl:2: not a simulator trace sample (expected {\"t_s\", \"kind\", \"pose\"}): "),
            "{e}"
        );
        // A whole last line that is JSON but not a sample, ended or not.
        for end in ["\n", ""] {
            let e = read(&format!("{good}\n{{\"t\": 1}}{end}")).unwrap_err();
            assert!(e.starts_with("t.jsonl:2: not a simulator trace sample"), "{e}");
        }
        // A cut last line that is the only one: nothing left.
        assert_eq!(read("{\"t_s\"").unwrap_err(), "t.jsonl: the trace is empty (did the simulator execute any move?)");
        assert!(read("\n\n").unwrap_err().starts_with("t.jsonl: the trace is empty"));
        assert!(read("[{\"t_s\": 1}]").unwrap_err().starts_with("t.jsonl: not a simulator trace: "));
        let e = read_trace(Path::new("/nonexistent/maobi/trace.jsonl")).unwrap_err();
        assert!(matches!(e, RobotError::Read { .. }) && e.to_string() == "/nonexistent/maobi/trace.jsonl: cannot read");
    }
}
