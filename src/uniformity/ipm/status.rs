//! What the interior-point method returns ([`IpmSolution`]): its last
//! iterate and how it stopped, in the crate's shared vocabulary
//! ([`Termination`]; why it could not start is `error.rs`'s).

use crate::status::Termination;

/// The outcome of [`super::solve`]: the last iterate, unscaled (the smallest
/// set tension is ≈ 1), and how the method stopped.
#[derive(Debug, Clone)]
pub(crate) struct IpmSolution {
    /// Force densities, N/m per unit tension: n_edges.
    pub q: Vec<f64>,
    /// Interior-point iterations.
    pub iterations: usize,
    /// How the method stopped:
    /// * `Converged`: relative residuals and gap below the tolerance;
    /// * `Stalled`: the iterate stopped improving with residuals and gap
    ///   below [`super::IpmSettings::reduced_tolerance`] (clarabel's
    ///   `AlmostSolved`): its best iterate, usable at reduced accuracy;
    /// * `MaxIterations`: the iteration limit came first;
    /// * `NumericalError`: a factorisation failed or the iterate stopped
    ///   being finite or interior.
    pub termination: Termination,
    /// Final relative primal residual, dual residual and gap.
    pub residuals: [f64; 3],
}
