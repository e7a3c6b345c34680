//! What the interior-point method returns: how it stopped ([`IpmStatus`]),
//! its last iterate ([`IpmSolution`]), and why it could not start
//! ([`IpmError`]).

use super::normal::NormalError;

/// How the interior-point method stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum IpmStatus {
    /// Relative residuals and gap are below the tolerance.
    Converged,
    /// The iterate stopped improving with residuals and gap below
    /// [`super::IpmSettings::reduced_tolerance`] (clarabel's `AlmostSolved`);
    /// its best iterate.
    ReducedAccuracy,
    /// The iteration limit came first.
    MaxIterations,
    /// A factorisation failed or the iterate stopped being finite or interior.
    NumericalFailure,
}

/// The outcome of [`super::solve`]: the last iterate, unscaled (the smallest
/// set tension is ≈ 1), and how the method stopped.
#[derive(Debug, Clone)]
pub(crate) struct IpmSolution {
    /// Force densities, N/m per unit tension: n_edges.
    pub q: Vec<f64>,
    /// Interior-point iterations.
    pub iterations: usize,
    /// How the method stopped.
    pub status: IpmStatus,
    /// Final relative primal residual, dual residual and gap.
    pub residuals: [f64; 3],
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
