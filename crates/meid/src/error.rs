//! The crate's error type. Every message names what was wrong and what would be valid.

use std::path::PathBuf;

/// Result alias used across the crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Errors returned by the library.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A model or data file could not be parsed or failed validation.
    /// `location` is `file:line:column` where known.
    #[error("{location}: {message}")]
    Input { location: String, message: String },
    /// A value given through the API (not from a file) is out of range.
    #[error("invalid {field}: {message}")]
    InvalidValue { field: String, message: String },
    /// A numerical method failed (singular matrix, no convergence, ...).
    #[error("numerical failure in {context}: {message}")]
    Numerical { context: String, message: String },
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

impl Error {
    /// Shorthand for [`Error::InvalidValue`].
    pub fn invalid(field: impl Into<String>, message: impl Into<String>) -> Self {
        Error::InvalidValue {
            field: field.into(),
            message: message.into(),
        }
    }
    /// Shorthand for [`Error::Numerical`].
    pub fn numerical(context: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Numerical {
            context: context.into(),
            message: message.into(),
        }
    }
    /// Shorthand for [`Error::Io`].
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}

/// A number as error messages print it: the shortest text that reads back to the same `f64`,
/// in plain decimals for `1e-4 ≤ |v| < 1e9` (`0`, `60`, `0.000678`, `20000`) and in exponent
/// form outside (`1e100`, `6.5e-7`), so that no value prints as a 101-digit integer or a
/// string of zeros; `NaN`, `inf`, `-inf` as such.
pub fn num(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if !v.is_finite() || (1e-4..1e9).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

#[cfg(test)]
mod num_tests {
    use super::num;

    #[test]
    fn numbers_in_messages_are_compact_and_round_trip() {
        for (v, want) in [
            (0.0, "0"),
            (-0.0, "0"),
            (60.0, "60"),
            (6.78e-4, "0.000678"),
            (2e4, "20000"),
            (1e100, "1e100"),
            (-2.5e-7, "-2.5e-7"),
            (1.8446744073709552e19, "1.8446744073709552e19"),
            (f64::NAN, "NaN"),
            (f64::INFINITY, "inf"),
        ] {
            assert_eq!(num(v), want);
            if v.is_finite() {
                assert_eq!(num(v).parse::<f64>().unwrap(), v);
            }
        }
    }
}
