//! The interior-point method's tuning as plain data: the tolerances and limits
//! of the Mehrotra iteration, the regularisation and refinement of the normal
//! system, the FGMRES completion of a Newton direction, and the one check of
//! their ranges ([`IpmSettings::validate`]).

use super::IpmError;

/// How the starting point is scaled (issue 38, measured on three net
/// families: `tests/ipm_families.rs`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Start {
    /// Mehrotra's heuristic in the LP's own variables `x = q − lb`: least norm
    /// with `Θ = I`, one shift for every `x_k`.
    Unscaled,
    /// The same in tensions above their floors (`ℓ_k x_k`, `z_k/ℓ_k`): least
    /// norm with `Θ = diag(1/ℓ²)`, one shift for every tension. Invariant
    /// under the nets' spread of cable lengths (the iteration itself is
    /// invariant under that diagonal scaling; only the start was not).
    TensionScaled,
}

/// Tolerances, limits and regularisation of the interior-point method;
/// [`Default`] holds the values it is tuned with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct IpmSettings {
    /// Relative tolerance on the dual residual and the duality gap.
    pub tolerance: f64,
    /// Relative primal residual accepted before the final projection (the
    /// driver's `polish`), which restores equilibrium to rounding: near the
    /// optimum `Θ = X Z⁻¹` spans some twenty orders of magnitude and the
    /// normal equations no longer resolve the primal residual, while the gap
    /// and the dual residual still converge.
    pub primal_tolerance: f64,
    /// Residuals and gap of an iterate accepted at reduced accuracy when the
    /// method stalls.
    pub reduced_tolerance: f64,
    /// Iterations without a better iterate after which the method counts as
    /// stalled.
    pub stall_iterations: usize,
    /// Relative primal residual after the final projection.
    pub polished: f64,
    /// Iteration limit.
    pub max_iterations: usize,
    /// Pivots of the unit-diagonal normal matrix below this are treated as
    /// zero …
    pub pivot_epsilon: f64,
    /// … and replaced by this, which drops the direction (dependent rows of
    /// `A`).
    pub pivot_delta: f64,
    /// Added to the unit diagonal of the normal matrix before it is factored.
    /// Cable nets are mechanisms (`A` has dependent rows: the infinitesimal
    /// mechanisms a prestress stiffens), so `M` is singular; the shift makes
    /// the factor well defined, and iterative refinement against the exact `M`
    /// removes its effect on the range, where every right-hand side lives.
    pub regularization: f64,
    /// Largest shift tried when a factorisation fails …
    pub max_regularization: f64,
    /// … the shift growing by this factor per failed attempt.
    pub regularization_growth: f64,
    /// Refinement steps per solve with the normal matrix (at most) …
    pub refinement_steps: usize,
    /// … and their relative residual target.
    pub refinement_tolerance: f64,
    /// FGMRES steps per Newton direction (at most) …
    pub krylov_steps: usize,
    /// … and their target for the rows the factor solves inexactly, relative
    /// to their right-hand side.
    pub krylov_tolerance: f64,
    /// The starting point's scaling.
    pub start: Start,
    /// Gondzio's centrality correctors per iteration (at most; each is one
    /// more Newton solve with the iteration's factor, kept while it lengthens
    /// the step by 1 %).
    pub centrality_correctors: usize,
}

impl Default for IpmSettings {
    fn default() -> Self {
        IpmSettings {
            tolerance: 1e-9,
            primal_tolerance: 1e-6,
            reduced_tolerance: 1e-6,
            stall_iterations: 8,
            polished: 1e-12,
            max_iterations: 100,
            pivot_epsilon: 1e-13,
            pivot_delta: 1e64,
            regularization: 1e-14,
            max_regularization: 1e-6,
            regularization_growth: 100.0,
            refinement_steps: 20,
            refinement_tolerance: 1e-12,
            krylov_steps: 8,
            krylov_tolerance: 1e-13,
            start: Start::Unscaled,
            centrality_correctors: 0,
        }
    }
}

impl IpmSettings {
    /// The settings of the plan problem of a tied net (`D = 2`, see
    /// `uniformity/plan.rs`): a static shift of 1e-12 of the unit diagonal and
    /// no dropped pivots. The plan equilibrium matrix of a triangulated net has
    /// independent rows, so a tiny pivot is never a mechanism: it is a
    /// direction that the optimum's degenerate face leaves to the border `a`
    /// (the cables at `Tmax` moving with `s`). Dropping it (a pivot replaced by
    /// [`Self::pivot_delta`], right for the mechanisms of the 3-D problem)
    /// loses exactly the direction `ds` depends on: measured on independent
    /// hexagonal nets, the reduction's residual reached 10¹⁰…10⁹¹ of its
    /// right-hand side near the optimum, FGMRES could not recover, and the
    /// method stalled (2·10³ nodes), failed to factor (2·10⁴) or gave up
    /// (2·10⁵). With the shift the border's elimination stays consistent and
    /// the method converges on all of them (shift 1e-10 already leaves too
    /// many directions damped at 2·10⁵ nodes for FGMRES to restore).
    ///
    /// Its start is [`Start::TensionScaled`]: on the three net families of
    /// issue 38 it saved 1–13 of 21–77 iterations in five of six nets at
    /// 10³/10⁴ free nodes (one more on the regular sector grid at 10⁴).
    pub(crate) fn plan() -> Self {
        IpmSettings {
            regularization: 1e-12,
            pivot_epsilon: 1e-30,
            start: Start::TensionScaled,
            ..IpmSettings::default()
        }
    }

    /// Checks every setting's range: the tolerances, the pivot threshold and
    /// the shifts in `(0, 1)`, the shift bound at least the first shift, a
    /// growth above 1, a replacement pivot above 1, and at least one stall
    /// iteration.
    pub(crate) fn validate(&self) -> Result<(), IpmError> {
        let fractions = [
            ("tolerance", self.tolerance),
            ("primal_tolerance", self.primal_tolerance),
            ("reduced_tolerance", self.reduced_tolerance),
            ("polished", self.polished),
            ("pivot_epsilon", self.pivot_epsilon),
            ("regularization", self.regularization),
            ("max_regularization", self.max_regularization),
            ("refinement_tolerance", self.refinement_tolerance),
            ("krylov_tolerance", self.krylov_tolerance),
        ];
        for (name, value) in fractions {
            if !(value > 0.0 && value < 1.0) {
                return Err(IpmError::Setting {
                    name,
                    value,
                    range: "in (0, 1)",
                });
            }
        }
        if self.max_regularization < self.regularization {
            return Err(IpmError::Setting {
                name: "max_regularization",
                value: self.max_regularization,
                range: "≥ regularization",
            });
        }
        for (name, value) in [
            ("regularization_growth", self.regularization_growth),
            ("pivot_delta", self.pivot_delta),
        ] {
            if !(value.is_finite() && value > 1.0) {
                return Err(IpmError::Setting {
                    name,
                    value,
                    range: "finite and > 1",
                });
            }
        }
        if self.stall_iterations == 0 {
            return Err(IpmError::Setting {
                name: "stall_iterations",
                value: 0.0,
                range: "≥ 1",
            });
        }
        Ok(())
    }
}
