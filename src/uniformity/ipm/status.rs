//! What the interior-point method returns ([`IpmSolution`]): its last
//! iterate and how it stopped, in the crate's shared vocabulary
//! ([`Termination`]; why it could not start is `error.rs`'s), and the
//! iterate it kept for a neighbouring LP ([`WarmStart`]).

use std::fmt;

use super::system::Point;
use crate::status::Termination;

/// An interior iterate of a ratio LP kept at a moderate gap
/// (`IpmSettings::keep_at_gap`, crate-private): the start of the LP of a
/// neighbouring geometry of the same net — the outer loop's next boundary,
/// micrometres away — which then follows its own central path from there.
/// Opaque: only the ratio LP reads it, and only when its sizes match.
#[derive(Clone)]
pub struct WarmStart(pub(crate) Point);

impl fmt::Debug for WarmStart {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("WarmStart")
            .field("pairs", &self.0.primal.len())
            .field("free", &(self.0.free_primal.len() + self.0.free_dual.len()))
            .finish()
    }
}

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
    /// The iterate kept for a neighbouring LP, when the settings ask for one
    /// and the method got that far.
    pub kept: Option<WarmStart>,
}
