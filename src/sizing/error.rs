//! Why a truss cannot be sized ([`SizingError`]).

use crate::design::DesignError;
use crate::scene::SceneError;

/// A sizing that cannot run, or finds nothing.
#[derive(Debug, thiserror::Error)]
pub enum SizingError {
    /// An invalid margin.
    #[error(
        "sizing: margin {value} must be at least 1 and at most {max} (the limit search's end)"
    )]
    Margin {
        /// The margin asked for.
        value: f64,
        /// The largest margin the limit search certifies.
        max: f64,
    },
    /// A bad catalogue.
    #[error("{path}{}: {reason}", line.map(|l| format!(", line {l}")).unwrap_or_default())]
    Catalogue {
        /// The file.
        path: String,
        /// The line at fault, from 1.
        line: Option<usize>,
        /// What is wrong.
        reason: String,
    },
    /// A scene whose truss cannot be sized.
    #[error("sizing: `{key}`: {reason}")]
    Scene {
        /// The scene key at fault.
        key: &'static str,
        /// Why.
        reason: String,
    },
    /// No section carries the net with the margin.
    #[error(
        "no section carries the net with a margin of {margin}: the stiffest tried ({outer_mm:.1}/{inner_mm:.1} mm) reaches {best:.3}{}",
        detail.as_ref().map(|d| format!(" ({d})")).unwrap_or_default()
    )]
    NoSection {
        /// The margin asked for.
        margin: f64,
        /// The stiffest section tried, its outer and inner diameter, mm.
        outer_mm: f64,
        /// Its inner diameter, mm.
        inner_mm: f64,
        /// Its margin.
        best: f64,
        /// Why its design failed, if it did.
        detail: Option<String>,
    },
    /// A section's scene is invalid.
    #[error(transparent)]
    SectionScene(#[from] SceneError),
    /// A design failed for a reason no section would mend.
    #[error(transparent)]
    Design(#[from] DesignError),
}

impl SizingError {
    /// True when the error is the user's input (exit code 2).
    pub fn is_bad_input(&self) -> bool {
        match self {
            SizingError::NoSection { .. } => false,
            SizingError::Design(e) => e.is_bad_input(),
            _ => true,
        }
    }
}
