//! Faults named in text, `KEY=VALUE` each: [`Faults::parse`] for the AUBO simulator,
//! [`UrFaults::parse`] for the UR stand-in.

use std::num::ParseIntError;

use thiserror::Error;

use super::Faults;
use super::ur::UrFaults;

/// The keys [`Faults::parse`] knows, each followed by a whole number.
pub const AUBO_FAULT_KEYS: [&str; 3] = ["drop-after", "delay-ms", "queue-full-every"];
/// The keys [`UrFaults::parse`] knows, each followed by a program time in seconds.
pub const UR_FAULT_KEYS: [&str; 3] = ["protective-stop-at-s", "program-stop-at-s", "pose-offset-at-s"];

/// A fault spec that does not parse. Its text says what is wrong with the spec (the value, or
/// the unknown key with the known ones); [`FaultSpecError::spec`] names the whole spec, for the
/// caller to put in front (the CLI writes `--fault SPEC: ` before it).
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum FaultSpecError {
    /// No `=` in the spec.
    #[error("expected KEY=VALUE")]
    NotKeyValue {
        /// The spec as given.
        spec: String,
    },
    /// The value of a key that counts (moves, ms) is not a whole number (`source` says why).
    #[error("{value} is not a whole number")]
    NotWholeNumber {
        /// The spec as given.
        spec: String,
        /// The key.
        key: String,
        /// The value as given.
        value: String,
        /// The parser's error.
        #[source]
        source: ParseIntError,
    },
    /// The value of a key that times (s) is not a finite, non-negative number of seconds.
    #[error("{value} is not a time in seconds")]
    NotSeconds {
        /// The spec as given.
        spec: String,
        /// The key.
        key: String,
        /// The value as given.
        value: String,
    },
    /// The key is not one the simulator knows.
    #[error("unknown fault `{key}` ({})", known.join(", "))]
    Unknown {
        /// The spec as given.
        spec: String,
        /// The key.
        key: String,
        /// The keys it knows ([`AUBO_FAULT_KEYS`] or [`UR_FAULT_KEYS`]).
        known: &'static [&'static str],
    },
}

impl FaultSpecError {
    /// The spec as given.
    pub fn spec(&self) -> &str {
        match self {
            FaultSpecError::NotKeyValue { spec }
            | FaultSpecError::NotWholeNumber { spec, .. }
            | FaultSpecError::NotSeconds { spec, .. }
            | FaultSpecError::Unknown { spec, .. } => spec,
        }
    }
}

/// The faults of `specs`, each split at its first `=`, its value read by `value` (from the spec,
/// the key and the value) and set by `set`, which says whether it knows the key (else
/// [`FaultSpecError::Unknown`] with `known`).
fn parse_specs<F: Default, V, S: AsRef<str>>(
    specs: impl IntoIterator<Item = S>,
    known: &'static [&'static str],
    value: impl Fn(&str, &str, &str) -> Result<V, FaultSpecError>,
    set: impl Fn(&mut F, &str, V) -> bool,
) -> Result<F, FaultSpecError> {
    let mut faults = F::default();
    for spec in specs {
        let spec = spec.as_ref();
        let (key, v) = spec.split_once('=').ok_or_else(|| FaultSpecError::NotKeyValue { spec: spec.into() })?;
        let v = value(spec, key, v)?;
        if !set(&mut faults, key, v) {
            return Err(FaultSpecError::Unknown { spec: spec.into(), key: key.into(), known });
        }
    }
    Ok(faults)
}

impl Faults {
    /// Faults from specs `KEY=N` ([`AUBO_FAULT_KEYS`]): `drop-after=N` (the N-th move request
    /// drops the connection, [`Faults::drop_after_moves`]), `delay-ms=D` (every answer `D` ms
    /// late) or `queue-full-every=K` (every K-th move answered "queue full"). A key given twice
    /// takes its last value; no spec, no fault.
    ///
    /// # Examples
    /// ```
    /// use robot_io::sim::Faults;
    /// let f = Faults::parse(["drop-after=50", "delay-ms=40"]).unwrap();
    /// assert_eq!((f.drop_after_moves, f.delay_ms, f.queue_full_every), (Some(50), Some(40), None));
    /// let e = Faults::parse(["delay-ms=soon"]).unwrap_err();
    /// assert_eq!((e.spec(), e.to_string().as_str()), ("delay-ms=soon", "soon is not a whole number"));
    /// ```
    ///
    /// # Errors
    /// [`FaultSpecError`] for the first spec without `=`, with an unknown key or with a value
    /// that is not a whole number.
    pub fn parse<S: AsRef<str>>(specs: impl IntoIterator<Item = S>) -> Result<Self, FaultSpecError> {
        let whole = |spec: &str, key: &str, value: &str| {
            value.parse::<u64>().map_err(|source| FaultSpecError::NotWholeNumber {
                spec: spec.into(),
                key: key.into(),
                value: value.into(),
                source,
            })
        };
        parse_specs(specs, &AUBO_FAULT_KEYS, whole, |f: &mut Faults, key, n| {
            let count = usize::try_from(n).unwrap_or(usize::MAX);
            match key {
                "drop-after" => f.drop_after_moves = Some(count),
                "delay-ms" => f.delay_ms = Some(n),
                "queue-full-every" => f.queue_full_every = Some(count),
                _ => return false,
            }
            true
        })
    }
}

impl UrFaults {
    /// Faults from specs `KEY=S` ([`UR_FAULT_KEYS`], `S` a program time in seconds, finite and
    /// not negative): `protective-stop-at-s=S`, `program-stop-at-s=S` or `pose-offset-at-s=S`
    /// (the fields of the same names). A key given twice takes its last value; no spec, no
    /// fault. The hostile controller's faults are not named by any key.
    ///
    /// # Examples
    /// ```
    /// use robot_io::sim::UrFaults;
    /// let f = UrFaults::parse(["protective-stop-at-s=9"]).unwrap();
    /// assert_eq!(f.protective_stop_at_s, Some(9.0));
    /// assert!(UrFaults::parse(["drop-after=4"]).unwrap_err().to_string().starts_with("unknown fault `drop-after`"));
    /// ```
    ///
    /// # Errors
    /// [`FaultSpecError`] for the first spec without `=`, with an unknown key or with a value
    /// that is not a time in seconds.
    pub fn parse<S: AsRef<str>>(specs: impl IntoIterator<Item = S>) -> Result<Self, FaultSpecError> {
        let seconds =
            |spec: &str, key: &str, value: &str| {
                value.parse::<f64>().ok().filter(|t| t.is_finite() && *t >= 0.0).ok_or_else(|| {
                    FaultSpecError::NotSeconds { spec: spec.into(), key: key.into(), value: value.into() }
                })
            };
        parse_specs(specs, &UR_FAULT_KEYS, seconds, |f: &mut UrFaults, key, t| {
            match key {
                "protective-stop-at-s" => f.protective_stop_at_s = Some(t),
                "program-stop-at-s" => f.program_stop_at_s = Some(t),
                "pose-offset-at-s" => f.pose_offset_at_s = Some(t),
                _ => return false,
            }
            true
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aubo_specs_set_their_fields_and_the_last_of_a_key_wins() {
        let f = Faults::parse(["drop-after=4", "queue-full-every=3", "delay-ms=10", "delay-ms=40"]).unwrap();
        assert_eq!(f, Faults { drop_after_moves: Some(4), delay_ms: Some(40), queue_full_every: Some(3) });
        assert_eq!(Faults::parse(Vec::<String>::new()).unwrap(), Faults::default());
        // A value may itself hold `=`: only the first one splits (and then it is no number).
        assert!(matches!(
            Faults::parse(["delay-ms=1=2"]),
            Err(FaultSpecError::NotWholeNumber { ref value, .. }) if value == "1=2"
        ));
    }

    #[test]
    fn aubo_refusals_name_the_spec_the_key_and_what_was_expected() {
        let e = Faults::parse(["drop-after=4", "delay-ms"]).unwrap_err();
        assert_eq!((e.spec(), e.to_string()), ("delay-ms", "expected KEY=VALUE".to_string()));
        let e = Faults::parse(["drop-after=-1"]).unwrap_err();
        assert_eq!(e.to_string(), "-1 is not a whole number");
        assert!(std::error::Error::source(&e).is_some(), "the parser's reason is kept");
        let FaultSpecError::NotWholeNumber { key, .. } = &e else { panic!("{e:?}") };
        assert_eq!(key, "drop-after");
        let e = Faults::parse(["explode=1"]).unwrap_err();
        assert_eq!(e.spec(), "explode=1");
        assert_eq!(e.to_string(), "unknown fault `explode` (drop-after, delay-ms, queue-full-every)");
        // The value is checked before the key: an unknown key with a bad value says the value.
        assert_eq!(Faults::parse(["explode=x"]).unwrap_err().to_string(), "x is not a whole number");
    }

    #[test]
    fn ur_specs_take_finite_non_negative_seconds() {
        let f = UrFaults::parse(["protective-stop-at-s=9", "program-stop-at-s=14.5", "pose-offset-at-s=0"]).unwrap();
        assert_eq!(
            (f.protective_stop_at_s, f.program_stop_at_s, f.pose_offset_at_s),
            (Some(9.0), Some(14.5), Some(0.0))
        );
        assert_eq!(
            (f.nan_pose_at_s, f.rtde_garbage_at_s, f.rtde_silent_at_s, f.rtde_close_at_s),
            (None, None, None, None)
        );
        for bad in ["-1", "inf", "NaN", "soon", ""] {
            let e = UrFaults::parse([format!("program-stop-at-s={bad}")]).unwrap_err();
            assert_eq!(e.to_string(), format!("{bad} is not a time in seconds"));
        }
        let e = UrFaults::parse(["drop-after=4"]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "unknown fault `drop-after` (protective-stop-at-s, program-stop-at-s, pose-offset-at-s)"
        );
        assert!(matches!(e, FaultSpecError::Unknown { known, .. } if known == UR_FAULT_KEYS));
        // The hostile controller's faults have no key.
        assert!(UrFaults::parse(["nan-pose-at-s=1"]).is_err());
    }
}
