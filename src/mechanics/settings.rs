//! What a static solve takes and returns, as plain data: the settings
//! ([`StaticSettings`], [`PathControl`]) and the solution ([`StaticSolution`],
//! its [`StepRecord`]s and how it ended, [`StaticTermination`]).

use serde::Serialize;

use super::assembly::State;
use super::model::MechanicsError;
use crate::status::{Status, Termination};

/// How a static solve ended: the crate's shared reason ([`Status`]) with the
/// load factor it reached.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum StaticTermination {
    /// Equilibrium at the full load (λ = 1).
    Converged,
    /// The load step fell below the minimum before λ = 1, Newton failing to
    /// converge without a sign of instability: the last converged load factor
    /// is in the solution.
    Stalled {
        /// Last converged load factor.
        load_factor: f64,
    },
    /// The structure cannot carry the full load on the branch it started on:
    /// its limit load is about `limit_load_factor` × the applied loads.
    ///
    /// Arc length: the path passed a maximum of the load factor below 1, and
    /// `limit_load_factor` is the largest on the path. Load control: the step
    /// was cut below the minimum because every try beyond `limit_load_factor`
    /// left the branch — Newton moved away from the tangent's prediction
    /// (towards a snapped-through branch), the path's slope jumped tenfold, or
    /// Newton failed through unstable states; the limit lies within a few
    /// minimum steps above it.
    LimitPoint {
        /// The largest load factor reached on the branch.
        limit_load_factor: f64,
    },
    /// The step budget ran out.
    MaxSteps {
        /// Last converged load factor.
        load_factor: f64,
    },
    /// Beyond `load_factor` every step, down to the smallest, gave a
    /// residual or an increment that is not a finite number: loads or
    /// stiffnesses beyond double precision (a 1e200 N·m moment), not a
    /// failure to converge.
    Overflow {
        /// Last converged load factor.
        load_factor: f64,
    },
}

impl Status for StaticTermination {
    /// `LimitPoint` is [`Termination::Infeasible`] (no equilibrium at the
    /// full load on the branch followed), `MaxSteps`
    /// [`Termination::MaxIterations`], `Overflow`
    /// [`Termination::NumericalError`]; the others their namesakes.
    fn termination(&self) -> Termination {
        match self {
            StaticTermination::Converged => Termination::Converged,
            StaticTermination::Stalled { .. } => Termination::Stalled,
            StaticTermination::LimitPoint { .. } => Termination::Infeasible,
            StaticTermination::MaxSteps { .. } => Termination::MaxIterations,
            StaticTermination::Overflow { .. } => Termination::NumericalError,
        }
    }
}

impl std::fmt::Display for StaticTermination {
    /// One clause a person can read: `passed a limit point at load factor
    /// 0.6555 (the structure carries about 0.6555 × the applied loads)`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StaticTermination::Converged => f.write_str("converged at the full load"),
            StaticTermination::Stalled { load_factor } => write!(
                f,
                "stalled: Newton stopped converging at load factor {load_factor:.4}, with no \
                 sign of instability"
            ),
            StaticTermination::LimitPoint { limit_load_factor } => write!(
                f,
                "passed a limit point at load factor {limit_load_factor:.4} (the structure \
                 carries about {limit_load_factor:.4} × the applied loads)"
            ),
            StaticTermination::MaxSteps { load_factor } => {
                write!(f, "ran out of load steps at load factor {load_factor:.4}")
            }
            StaticTermination::Overflow { load_factor } => write!(
                f,
                "overflowed: beyond load factor {load_factor:.4} the residual or the \
                 displacements are not finite numbers (loads or stiffnesses beyond double \
                 precision)"
            ),
        }
    }
}

/// How the load is followed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PathControl {
    /// Load control: λ ramped to 1 with adaptive steps.
    #[default]
    Load,
    /// Arc-length control: follows the path through limit points in load
    /// and in displacement (cylindrical in [`StaticSolver::solve`], the
    /// limit search; spherical in [`StaticSolver::follow_path`]).
    ///
    /// [`StaticSolver::solve`]: super::StaticSolver::solve
    /// [`StaticSolver::follow_path`]: super::StaticSolver::follow_path
    ArcLength,
    /// Displacement control of one node's translation component
    /// ([`PathSpec::control`](super::PathSpec::control)): follows the path
    /// through limit points in load, not in that displacement. Path
    /// following only.
    Displacement,
}

/// Settings of the static solver: plain data with defaults.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StaticSettings {
    /// Relative force tolerance: `‖F‖∞ ≤ tol · max(λ‖f_ext‖∞, ‖reactions‖∞,
    /// largest cable force)`.
    pub tolerance: f64,
    /// Newton iterations per step before the step is cut.
    pub max_iterations: usize,
    /// First load step Δλ (1: try the full load at once).
    pub initial_step: f64,
    /// Smallest load step before giving up.
    pub min_step: f64,
    /// Largest number of converged steps.
    pub max_steps: usize,
    /// Load, arc-length or displacement control.
    pub path: PathControl,
    /// Path following: the largest step, in load-factor units of the first
    /// (linear) step — an arc length of `max_step` is the length of the
    /// linear path from the start to `Δλ = max_step`; a displacement step
    /// of `max_step` that of the linear response to it.
    pub max_step: f64,
    /// Path following: the lowest eigenvalue of the stiffness on the joints'
    /// constraints at every converged step, and bifurcation points located
    /// where it crosses zero without a load extremum.
    pub stability: bool,
    /// Path following: at the first bifurcation point, leave the path for
    /// the bifurcated branch (a step along the buckling mode).
    pub branch_switch: bool,
}

impl Default for StaticSettings {
    fn default() -> Self {
        StaticSettings {
            tolerance: 1e-10,
            max_iterations: 20,
            initial_step: 1.0,
            min_step: 1e-5,
            max_steps: 500,
            path: PathControl::Load,
            max_step: 0.1,
            stability: true,
            branch_switch: false,
        }
    }
}

impl StaticSettings {
    /// Check the values.
    ///
    /// # Errors
    /// A value out of range, named.
    pub fn validate(&self) -> Result<(), MechanicsError> {
        let bad =
            |field: &str, why: &str| Err(MechanicsError::invalid(format!("solver.{field}"), why));
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return bad("tolerance", "must be in (0, 1)");
        }
        if self.max_iterations == 0 {
            return bad("max_iterations", "must be at least 1");
        }
        if !(self.initial_step > 0.0 && self.initial_step <= 1.0) {
            return bad("initial_step", "must be in (0, 1]");
        }
        if !(self.min_step > 0.0 && self.min_step <= self.initial_step) {
            return bad("min_step", "must be in (0, initial_step]");
        }
        if self.max_steps == 0 {
            return bad("max_steps", "must be at least 1");
        }
        if !(self.max_step > 0.0 && self.max_step <= 1e6) {
            return bad("max_step", "must be in (0, 1e6]");
        }
        Ok(())
    }
}

/// One converged load step.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StepRecord {
    /// Load factor at the end of the step.
    pub load_factor: f64,
    /// Newton iterations of the step.
    pub iterations: usize,
    /// `‖F‖∞` before each iteration (the last one converged).
    pub residuals: Vec<f64>,
}

/// The result of a static solve.
#[derive(Debug, Clone)]
pub struct StaticSolution {
    /// The last converged state.
    pub state: State,
    /// Its load factor.
    pub load_factor: f64,
    /// How the solve ended.
    pub termination: StaticTermination,
    /// Converged steps, in order.
    pub steps: Vec<StepRecord>,
    /// Newton iterations in all, failed steps included.
    pub newton_iterations: usize,
    /// Steps that were cut.
    pub rejected_steps: usize,
    /// Support reactions per node (force N, moment N·m; zero where free).
    pub reactions: Vec<[f64; 6]>,
    /// Wall time, s.
    pub time_s: f64,
}

impl StaticSolution {
    /// True at equilibrium under the full load.
    pub fn converged(&self) -> bool {
        self.termination.converged()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every static ending reads as one shared reason, and only equilibrium
    /// at the full load is `Converged`; the JSON keeps its `status` tag.
    #[test]
    fn static_terminations_read_as_the_shared_reasons() {
        let cases = [
            (StaticTermination::Converged, Termination::Converged),
            (
                StaticTermination::Stalled { load_factor: 0.5 },
                Termination::Stalled,
            ),
            (
                StaticTermination::LimitPoint {
                    limit_load_factor: 0.6555,
                },
                Termination::Infeasible,
            ),
            (
                StaticTermination::MaxSteps { load_factor: 0.9 },
                Termination::MaxIterations,
            ),
            (
                StaticTermination::Overflow { load_factor: 0.1 },
                Termination::NumericalError,
            ),
        ];
        for (ending, reason) in cases {
            assert_eq!(ending.termination(), reason, "{ending}");
            assert_eq!(ending.converged(), reason == Termination::Converged);
        }
        let json = serde_json::to_value(StaticTermination::LimitPoint {
            limit_load_factor: 0.5,
        })
        .unwrap();
        assert_eq!(json["status"], "limit_point");
        assert_eq!(json["limit_load_factor"], 0.5);
    }
}
