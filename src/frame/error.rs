//! The error of a frame file: every variant names the file or the key at
//! fault, or carries the engine's error naming the item.

use crate::mechanics::MechanicsError;

/// An invalid frame file: every variant names the file or the key.
#[derive(Debug, thiserror::Error)]
pub enum FrameFileError {
    /// Reading the file failed.
    #[error("reading {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// Not TOML of the frame format (unknown or missing key, wrong type); the
    /// parser's error names the key and the line.
    #[error("{path}: {source}")]
    Parse {
        /// The file.
        path: String,
        /// The parser's error.
        source: toml::de::Error,
    },
    /// A value is invalid.
    #[error("{key}: {reason}")]
    Invalid {
        /// The key, e.g. `rods[2].elements` or `joints[0].a`.
        key: String,
        /// Why it is rejected.
        reason: String,
    },
    /// The model could not be built or analysed (a mechanism, say).
    #[error(transparent)]
    Model(#[from] MechanicsError),
}

impl FrameFileError {
    /// The key at fault, when the error is about one value.
    pub fn key(&self) -> Option<&str> {
        match self {
            FrameFileError::Invalid { key, .. } => Some(key),
            _ => None,
        }
    }

    /// A frame-file error is the input's fault (exit code 2), but for numbers
    /// that overflow while solving and memory that runs out (exit code 1).
    pub fn is_bad_input(&self) -> bool {
        !matches!(
            self,
            FrameFileError::Model(
                MechanicsError::NotFinite { .. } | MechanicsError::OutOfMemory { .. }
            )
        )
    }

    pub(super) fn invalid(key: impl Into<String>, reason: impl Into<String>) -> Self {
        FrameFileError::Invalid {
            key: key.into(),
            reason: reason.into(),
        }
    }
}
