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
