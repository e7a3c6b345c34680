//! How an iterative computation ends: one vocabulary for every solver, the
//! outer loop and the statics engine (argmin's `TerminationReason`,
//! Clarabel's `SolverStatus`). Not converging is a status in a result, never
//! an `Err`: `Err` is for invalid input, I/O and a broken invariant.
//!
//! The shared reasons are [`Termination`]'s. A layer whose ending carries
//! more than a reason keeps its own type and says which reason it is through
//! [`Status`]; a layer with nothing to add uses [`Termination`] itself:
//!
//! | layer | its status | extra detail |
//! |---|---|---|
//! | uniformity solvers (`Design::termination`) | [`Termination`] | the route, slack nodes and warnings sit beside it in the design |
//! | the plan interior point, the gradient's exact finish | [`Termination`] | residuals beside it |
//! | the outer loop (`LoopOutcome::termination`) | [`Termination`] | the residual history beside it |
//! | a static solve (`mechanics::StaticTermination`) | its own enum, [`Status`] | the load factor reached, the limit load |
//!
//! Each layer documents which reasons it produces. This file depends on
//! nothing else in the crate.

use serde::{Deserialize, Serialize};

/// Why an iterative computation stopped. The serialised names are the
/// snake-case variant names (`converged`, `max_iterations`, …) in JSON and
/// CSV; `{:?}` prints the variant name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Termination {
    /// The computation's own convergence test holds (a solver's optimality
    /// test, the outer loop's `‖G(C) − C‖∞ ≤ tol`, equilibrium at the full
    /// load).
    Converged,
    /// The iteration (or step) budget ran out first.
    MaxIterations,
    /// No further progress was possible before the convergence test held;
    /// the last point is the best one, usable with its warnings (an interior
    /// point accepted at reduced accuracy, a line search that cannot go on,
    /// a load step cut below its minimum).
    Stalled,
    /// The problem as posed has no solution: no feasible force densities
    /// (for that solver's formulation), or no equilibrium at the full load
    /// on the branch followed (a limit point below it).
    Infeasible,
    /// The iteration ran away: the outer loop's residual grew past a
    /// multiple of its first value.
    Diverged,
    /// A numerical failure: a factorisation failed, or a number stopped
    /// being finite.
    NumericalError,
}

/// A layer's own status, read as one of the shared reasons.
pub trait Status {
    /// The shared reason this status stands for.
    fn termination(&self) -> Termination;

    /// True when the computation's convergence test held.
    fn converged(&self) -> bool {
        self.termination() == Termination::Converged
    }
}

impl Status for Termination {
    fn termination(&self) -> Termination {
        *self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn serialised_names_are_the_snake_case_variant_names() {
        let names = [
            (Termination::Converged, "converged"),
            (Termination::MaxIterations, "max_iterations"),
            (Termination::Stalled, "stalled"),
            (Termination::Infeasible, "infeasible"),
            (Termination::Diverged, "diverged"),
            (Termination::NumericalError, "numerical_error"),
        ];
        for (termination, name) in names {
            let json = serde_json::to_value(termination).unwrap();
            assert_eq!(json, serde_json::Value::String(name.into()));
            let back: Termination = serde_json::from_value(json).unwrap();
            assert_eq!(back, termination);
        }
        assert!(Termination::Converged.converged());
        assert!(!Termination::Stalled.converged());
    }
}
