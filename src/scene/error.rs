//! The error of a scene: every variant names the file or the key at fault
//! (the measured-rods table's own error among them).

use super::rod_properties::RodPropertiesError;

/// An invalid scene: every variant names the file or the key.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// Reading the file failed.
    #[error("reading {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// The file is not valid TOML of the scene format (unknown or missing key, wrong
    /// type); the message names the key and the line.
    #[error("{path}: {message}")]
    Parse {
        /// The file.
        path: String,
        /// The parser's message.
        message: String,
    },
    /// The table of `effects.rod_properties_csv` cannot be read or is
    /// invalid; the message names the file, the line and the rod or column.
    #[error("`effects.rod_properties_csv`: {0}")]
    RodProperties(#[from] RodPropertiesError),
    /// A value is out of its valid range.
    #[error("`{key}`: {reason}")]
    Invalid {
        /// The dotted key, e.g. `truss.tube_inner_diameter_m`.
        key: &'static str,
        /// Why the value is rejected.
        reason: String,
    },
}

impl SceneError {
    /// The key at fault, when the error is about one value.
    pub fn key(&self) -> Option<&'static str> {
        match self {
            SceneError::Invalid { key, .. } => Some(key),
            SceneError::RodProperties(_) => Some("effects.rod_properties_csv"),
            _ => None,
        }
    }

    pub(crate) fn invalid(key: &'static str, reason: impl Into<String>) -> Self {
        SceneError::Invalid {
            key,
            reason: reason.into(),
        }
    }
}
