//! Files maobi wrote and reads back (a sheet's `track.json`, an observation's `summary.json`):
//! read with a size bound, parsed, and validated where they are parsed. Such folders travel (a
//! sheet written last week, on another machine, by someone else), so they are untrusted input:
//! every error names the file and the field, and nothing in them becomes a path.

use std::path::{Path, PathBuf};

use thiserror::Error;

/// Why a file maobi reads back was refused. Every message names the file, and the field where
/// one is at fault.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ReadBackError {
    /// The file could not be read.
    #[error("cannot read {}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The file is larger than any maobi writes.
    #[error("{} is larger than {} MiB: not {what}", path.display(), max_bytes >> 20)]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// What it should be.
        what: &'static str,
        /// The bound, bytes.
        max_bytes: u64,
    },
    /// Not JSON of the expected shape (truncated, a field of the wrong type, …).
    #[error("{} is not {what}", path.display())]
    Json {
        /// The file.
        path: PathBuf,
        /// What it should be.
        what: &'static str,
        /// Where serde stopped (line and column).
        #[source]
        source: serde_json::Error,
    },
    /// A field holds a value the file cannot hold.
    #[error("{}: field `{field}`: {expected}", path.display())]
    Field {
        /// The file.
        path: PathBuf,
        /// The field, as a path into the JSON (`chars[2].strokes`).
        field: String,
        /// What was found and what was expected.
        expected: String,
    },
    /// A file of another kind, or of a version this build does not read.
    #[error("{} is a `{kind}` layout of version {version}; expected a {expected} layout of version {expected_version}", path.display())]
    Kind {
        /// The file.
        path: PathBuf,
        /// The kind it says it is.
        kind: String,
        /// Its version.
        version: u32,
        /// The kind expected.
        expected: &'static str,
        /// The version this build reads.
        expected_version: u32,
    },
    /// A list that must hold something is empty.
    #[error("{} lists no {what}", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
        /// What it lists none of.
        what: &'static str,
    },
    /// The sheet's brush profile is invalid (the same validation as `--brush`).
    #[error("{}", path.display())]
    Profile {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: brush_model::ProfileError,
    },
}

impl ReadBackError {
    /// A [`ReadBackError::Field`].
    pub(crate) fn field(path: &Path, field: impl Into<String>, expected: impl Into<String>) -> Self {
        ReadBackError::Field { path: path.to_path_buf(), field: field.into(), expected: expected.into() }
    }
}

/// Reads `path` whole, refusing (from its metadata, before reading, and again while reading, for
/// a pipe) a file over `max_bytes`.
///
/// # Errors
/// [`ReadBackError::Read`], [`ReadBackError::TooLarge`].
pub fn read_bounded(path: &Path, max_bytes: u64, what: &'static str) -> Result<Vec<u8>, ReadBackError> {
    use std::io::Read;
    let read_err = |source| ReadBackError::Read { path: path.to_path_buf(), source };
    let file = std::fs::File::open(path).map_err(read_err)?;
    let listed = file.metadata().map(|m| m.len()).map_err(read_err)?;
    let too_large = || ReadBackError::TooLarge { path: path.to_path_buf(), what, max_bytes };
    if listed > max_bytes {
        return Err(too_large());
    }
    let mut bytes = Vec::with_capacity(listed as usize);
    file.take(max_bytes + 1).read_to_end(&mut bytes).map_err(read_err)?;
    if bytes.len() as u64 > max_bytes {
        return Err(too_large());
    }
    Ok(bytes)
}

/// A fingerprint of a file's bytes: `fnv1a64:` and the 64-bit FNV-1a hash in hex. It tells one
/// sheet's `track.json` from another (a different or edited sheet); it is not a cryptographic
/// hash and does not stop a forger who also controls the observation.
///
/// # Examples
/// ```
/// assert_eq!(pipeline::fingerprint(b""), "fnv1a64:cbf29ce484222325");
/// assert_ne!(pipeline::fingerprint(b"{\"a\":1}"), pipeline::fingerprint(b"{\"a\":2}"));
/// ```
pub fn fingerprint(bytes: &[u8]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    format!("fnv1a64:{h:016x}")
}

/// The name of character `i`'s folder (from 0) in a sheet's or an observation's output:
/// `NN-<char>`, the index from 1, the character replaced by `_` when it could be read as part of
/// a path or is not printable (a separator, `:`, a control or a space). Always one path
/// component.
///
/// # Examples
/// ```
/// assert_eq!(pipeline::char_folder(0, "永"), "01-永");
/// assert_eq!(pipeline::char_folder(11, "x/../../escaped"), "12-_");
/// ```
pub fn char_folder(i: usize, ch: &str) -> String {
    let mut it = ch.chars();
    let safe = match (it.next(), it.next()) {
        (Some(c), None) if !c.is_control() && !c.is_whitespace() && !matches!(c, '/' | '\\' | ':') => c.to_string(),
        _ => "_".to_string(),
    };
    format!("{:02}-{safe}", i + 1)
}

/// A finite number in `[lo, hi]`, or the field error saying so.
pub(crate) fn check_num(path: &Path, field: &str, v: f64, lo: f64, hi: f64, unit: &str) -> Result<(), ReadBackError> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(())
    } else {
        Err(ReadBackError::field(path, field, format!("{} {unit}: expected a number in {lo}..={hi} {unit}", short(v))))
    }
}

/// A number as a message shows it: in exponent form when plain digits would be long (`1e308`).
pub(crate) fn short(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-4..1e7).contains(&v.abs()) { format!("{v:e}") } else { format!("{v}") }
}
