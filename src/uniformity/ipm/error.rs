//! Why the interior-point method could not start ([`IpmError`]) and why its
//! normal system could not be set up or factored ([`NormalError`]): the
//! base of the method's files, depending on none of them (the data, the
//! normal system and the driver all return these).

use faer::linalg::solvers::LltError;

use crate::uniformity::block_pattern::PatternError;

/// Why the normal matrix could not be set up or factored.
#[derive(Debug, thiserror::Error)]
pub(crate) enum NormalError {
    /// A workspace could not be allocated.
    #[error("out of memory for {0}")]
    OutOfMemory(&'static str),
    /// The pattern, its ordering or its symbolic factorisation.
    #[error(transparent)]
    Pattern(#[from] PatternError),
    /// The numeric factorisation failed even with the largest diagonal shift.
    #[error("numeric factorisation with a diagonal shift of {shift:.1e}: {error:?}")]
    Numeric {
        /// The last shift tried.
        shift: f64,
        /// faer's error.
        error: LltError,
    },
}

/// Why the interior-point method could not start.
#[derive(Debug, thiserror::Error)]
pub(crate) enum IpmError {
    /// A setting is out of its range.
    #[error("interior point: setting `{name}` = {value} must be {range}")]
    Setting {
        /// The field of [`super::IpmSettings`].
        name: &'static str,
        /// Its value.
        value: f64,
        /// The range it must be in.
        range: &'static str,
    },
    /// The tension floor of the cables outside the set is not positive.
    #[error("interior point: minimum tension fraction {value} must be > 0")]
    MinTensionFraction {
        /// The fraction given.
        value: f64,
    },
    /// The uniformity set is empty.
    #[error("interior point: the uniformity set has no cable")]
    EmptySet,
    /// The normal system could not be set up.
    #[error("interior point: {0}")]
    Normal(#[from] NormalError),
}
