//! What the interior-point method returns ([`IpmSolution`]): its last
//! iterate and how it stopped, in the crate's shared vocabulary
//! ([`Termination`]; why it could not start is `error.rs`'s), and the
//! iterate it kept for a neighbouring LP ([`WarmStart`]).

use std::fmt;
use std::sync::Arc;

use super::system::Point;
use crate::status::Termination;
use crate::uniformity::block_pattern::BlockPattern;

/// What a ratio LP leaves to the LP of a neighbouring geometry of the same
/// net — the outer loop's next boundary, micrometres away: an interior
/// iterate kept at a moderate gap (`IpmSettings::keep_at_gap`,
/// crate-private), from which that LP follows its own central path, and
/// its normal matrix's ordering and symbolic factorisation, so that LP
/// factors numerically only (the analysis once per design). Opaque: only
/// the ratio LP reads it, and only what fits its own sizes and net.
#[derive(Clone)]
pub struct WarmStart {
    /// The kept iterate (`None` when the LP did not keep one).
    pub(crate) point: Option<Point>,
    /// The normal matrix's pattern and analysis.
    pub(crate) pattern: Arc<BlockPattern>,
}

impl WarmStart {
    /// Whether an iterate was kept (the analysis always is).
    pub fn has_iterate(&self) -> bool {
        self.point.is_some()
    }

    /// The analysis alone: an LP of the same net started from its own
    /// point (a cold start that still refactors numerically only).
    pub(crate) fn without_iterate(&self) -> WarmStart {
        WarmStart {
            point: None,
            pattern: Arc::clone(&self.pattern),
        }
    }
}

impl fmt::Debug for WarmStart {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let point = self.point.as_ref();
        f.debug_struct("WarmStart")
            .field("pairs", &point.map(|p| p.primal.len()))
            .field(
                "free",
                &point.map(|p| p.free_primal.len() + p.free_dual.len()),
            )
            .field(
                "pattern_rows",
                &self.pattern.col_ptr.len().saturating_sub(1),
            )
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
    /// What a neighbouring LP starts from: the iterate kept (when the
    /// settings ask for one and the method got that far) and the normal
    /// matrix's analysis.
    pub kept: WarmStart,
}
