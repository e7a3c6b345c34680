//! What a run of the outer loop says about itself ([`LoopSummary`]): how it
//! ended, how many designs it made, its final fixed-point residual and its
//! wall time — built in one place from a finished loop
//! ([`LoopSummary::of`]) or from the history of one that failed
//! ([`LoopSummary::failed`]). The design's runs, the study's rows and
//! sizing's trials hold it.

use serde::Serialize;

use super::outer_loop::{IterationRecord, LoopOutcome};
use crate::status::Termination;

/// A run of the outer loop, summed up. Serialised flat (its keys beside its
/// holder's: `termination`, `outer_iterations`, `boundary_residual_m`,
/// `time_s`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LoopSummary {
    /// How the loop ended.
    pub termination: Termination,
    /// Outer iterations (designs made).
    pub outer_iterations: usize,
    /// Final fixed-point residual `‖G(C) − C‖∞`, m.
    pub boundary_residual_m: f64,
    /// Wall time of the loop, s.
    pub time_s: f64,
}

impl LoopSummary {
    /// The summary of a loop that ran to its end.
    pub fn of(outcome: &LoopOutcome) -> LoopSummary {
        LoopSummary {
            termination: outcome.termination,
            outer_iterations: outcome.history.len(),
            boundary_residual_m: outcome.boundary_residual_m(),
            time_s: outcome.time_s,
        }
    }

    /// The summary of a loop that stopped without a result (the truss found
    /// no equilibrium once the iteration ran away, say) after the iterations
    /// of `history`: [`Termination::Diverged`], the last residual recorded
    /// (NaN before the first) and the time to it (0 before the first).
    pub fn failed(history: &[IterationRecord]) -> LoopSummary {
        LoopSummary {
            termination: Termination::Diverged,
            outer_iterations: history.len(),
            boundary_residual_m: history.last().map_or(f64::NAN, |r| r.boundary_change_max_m),
            time_s: history.last().map_or(0.0, |r| r.elapsed_s),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(iteration: usize, residual_m: f64, elapsed_s: f64) -> IterationRecord {
        IterationRecord {
            iteration,
            boundary_change_max_m: residual_m,
            boundary_change_rms_m: residual_m / 2.0,
            xi_change_m: None,
            ratio: 1.5,
            relaxation_factor: 1.0,
            oracle_newton_iterations: 3,
            design_time_s: 0.01,
            truss_time_s: 0.02,
            elapsed_s,
        }
    }

    #[test]
    fn a_failed_loop_is_summed_up_from_its_last_iteration() {
        let history = [record(0, 1e-3, 0.5), record(1, 4e-2, 1.25)];
        let s = LoopSummary::failed(&history);
        assert_eq!(s.termination, Termination::Diverged);
        assert_eq!(s.outer_iterations, 2);
        assert_eq!(s.boundary_residual_m, 4e-2);
        assert_eq!(s.time_s, 1.25);
        let none = LoopSummary::failed(&[]);
        assert_eq!(none.outer_iterations, 0);
        assert!(none.boundary_residual_m.is_nan());
        assert_eq!(none.time_s, 0.0);
    }

    #[test]
    fn the_summary_serialises_to_the_keys_of_its_holders_in_their_order() {
        let s = LoopSummary::failed(&[record(0, 2e-3, 0.5)]);
        assert_eq!(
            serde_json::to_string(&s).unwrap(),
            r#"{"termination":"diverged","outer_iterations":1,"boundary_residual_m":0.002,"time_s":0.5}"#
        );
    }
}
