//! The fixed-point iteration of the outer loop (paper §4, DESIGN §6): the
//! iterate is the boundary `C` (attachment points); its image `G(C) = M` is
//! the truss's response to the pull of the design for `C`.

use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::relaxation::{Relaxation, RelaxationKind};
use super::tied_nets::{TiedDesign, TiedNets};
use super::DesignError;
use crate::algebra::norm3;
use crate::status::Termination;
use crate::truss::{TrussEquilibrium, TrussOracle};
use crate::uniformity::{Design, UniformityProblem, UniformitySolver};

/// Settings of the outer loop: plain data with defaults.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LoopSettings {
    /// Relaxation policy ([`design_loop`] builds it; [`design_loop_with`]
    /// takes any [`Relaxation`] instead).
    pub relaxation: RelaxationKind,
    /// Stop when `‖G(C_k) − C_k‖∞ ≤ tolerance_m`, m.
    pub tolerance_m: f64,
    /// Most outer iterations (designs).
    pub max_iterations: usize,
    /// Anderson depth m (differences kept).
    pub anderson_depth: usize,
}

impl Default for LoopSettings {
    fn default() -> Self {
        LoopSettings {
            relaxation: RelaxationKind::default(),
            tolerance_m: 1e-6,
            max_iterations: 50,
            anderson_depth: 10,
        }
    }
}

impl LoopSettings {
    /// Check the settings.
    ///
    /// # Errors
    /// A tolerance that is not finite and positive, zero iterations, or a zero
    /// Anderson depth, named.
    pub fn validate(&self) -> Result<(), DesignError> {
        if !(self.tolerance_m.is_finite() && self.tolerance_m > 0.0) {
            return Err(DesignError::Setting {
                key: "tolerance_m",
                reason: format!("{} m must be finite and positive", self.tolerance_m),
            });
        }
        if self.max_iterations == 0 {
            return Err(DesignError::Setting {
                key: "max_iterations",
                reason: "must be at least 1".into(),
            });
        }
        if self.anderson_depth == 0 {
            return Err(DesignError::Setting {
                key: "anderson_depth",
                reason: "must be at least 1".into(),
            });
        }
        Ok(())
    }
}

/// One outer iteration.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IterationRecord {
    /// Iteration number, from 0.
    pub iteration: usize,
    /// `‖G(C_k) − C_k‖∞`: the fixed-point residual (the paper's `ξ_k,max`), m.
    pub boundary_change_max_m: f64,
    /// RMS over attachment points of `|G(C_k) − C_k|`, m.
    pub boundary_change_rms_m: f64,
    /// The paper's criterion `|ξ_k,max − ξ_{k−1},max|` (none at k = 0), m.
    pub xi_change_m: Option<f64>,
    /// The design's largest set ratio `Tmax/Tmin`.
    pub ratio: f64,
    /// The relaxation factor used for the next boundary (1: full step; Anderson: 1).
    pub relaxation_factor: f64,
    /// Newton iterations of the truss response.
    pub oracle_newton_iterations: usize,
    /// Wall time of the uniformity solve, s.
    pub design_time_s: f64,
    /// Wall time of the truss response, s.
    pub truss_time_s: f64,
    /// Wall time since the loop started, s.
    pub elapsed_s: f64,
}

/// A residual this many times the first iteration's ends the loop as
/// [`Termination::Diverged`].
pub const DIVERGENCE_FACTOR: f64 = 100.0;

/// The converged (or last) design of the outer loop.
#[derive(Debug, Clone)]
pub struct LoopOutcome {
    /// The design for the final boundary `C_k`.
    pub design: Design,
    /// The uniformity problem on the final boundary (its network holds `C_k`).
    pub problem: UniformityProblem,
    /// The design of iteration 0, for the undeformed attachment points: the
    /// conventional (rigid-truss) design.
    pub initial: TiedDesign,
    /// Whether the loop's truss deforms ([`TrussOracle::deforms`]): its design
    /// is then verified on the flexible truss.
    pub truss_deforms: bool,
    /// The final boundary `C_k` (attachment order), m.
    pub boundary_m: Vec<[f64; 3]>,
    /// The truss's attachment points under that design's pull, `G(C_k)`, m.
    pub deformed_m: Vec<[f64; 3]>,
    /// The truss's equilibrium under that pull, when its model has a frame
    /// state ([`TrussOracle::equilibrium`]): the assembly's start.
    pub truss_equilibrium: Option<TrussEquilibrium>,
    /// One record per outer iteration.
    pub history: Vec<IterationRecord>,
    /// How the loop ended: `Converged` (`‖G(C_k) − C_k‖∞ ≤ tol`),
    /// `MaxIterations` (the budget ran out first) or `Diverged` (the residual
    /// grew past [`DIVERGENCE_FACTOR`] × its first value: the policy cannot
    /// converge on this problem).
    pub termination: Termination,
    /// Wall time, s.
    pub time_s: f64,
}

impl LoopOutcome {
    /// The final fixed-point residual `‖G(C_k) − C_k‖∞`, m.
    pub fn boundary_residual_m(&self) -> f64 {
        self.history.last().map_or(0.0, |r| r.boundary_change_max_m)
    }
}

fn flatten(points: &[[f64; 3]]) -> Vec<f64> {
    points.iter().flatten().copied().collect()
}

fn unflatten(values: &[f64]) -> Vec<[f64; 3]> {
    values.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
}

/// The outer design loop with the policy `settings.relaxation` names: see
/// [`design_loop_with`].
///
/// # Errors
/// As [`design_loop_with`].
pub fn design_loop(
    nets: &TiedNets,
    solver: &dyn UniformitySolver,
    oracle: &mut dyn TrussOracle,
    settings: &LoopSettings,
    observe: &mut dyn FnMut(&IterationRecord),
) -> Result<LoopOutcome, DesignError> {
    let mut relaxation = settings.relaxation.build(settings.anderson_depth);
    design_loop_with(nets, solver, oracle, relaxation.as_mut(), settings, observe)
}

/// The outer design loop from the theoretical boundary (the undeformed
/// attachment points of `oracle`, in the order of the network's fixed nodes)
/// and the nominal rear net, choosing each next boundary by `relaxation`
/// (`settings.relaxation` is not read) and calling `observe` after every
/// iteration.
///
/// The iterate is the boundary `C` (attachment points); its image `G(C) = M`
/// is the truss's response to the pull of the design for `C` ([`TiedNets`]).
///
/// # Errors
/// Invalid settings, a design that fails or stops without a result, or a
/// truss that finds no equilibrium — each with the outer iteration.
pub fn design_loop_with(
    nets: &TiedNets,
    solver: &dyn UniformitySolver,
    oracle: &mut dyn TrussOracle,
    relaxation: &mut dyn Relaxation,
    settings: &LoopSettings,
    observe: &mut dyn FnMut(&IterationRecord),
) -> Result<LoopOutcome, DesignError> {
    settings.validate()?;
    let clock = Instant::now();
    let mut x = flatten(oracle.attachments());
    let mut history: Vec<IterationRecord> = Vec::new();
    let mut initial: Option<TiedDesign> = None;
    // The last boundary's design: each design starts from it, so that an
    // iterative solver's answer moves smoothly with the boundary.
    let mut previous: Option<TiedDesign> = None;
    for iteration in 0..settings.max_iterations {
        let uniformity = |source| DesignError::Uniformity { iteration, source };
        let tied = nets
            .design_from(solver, &unflatten(&x), previous.as_ref())
            .map_err(uniformity)?;
        let design = &tied.design;
        if !matches!(
            design.termination,
            Termination::Converged | Termination::MaxIterations | Termination::Stalled
        ) {
            return Err(DesignError::NoDesign {
                iteration,
                solver: design.solver.clone(),
                termination: design.termination,
            });
        }
        // The net pulls on its supports with −F_g.
        let pull = design.pull_n();
        let response = oracle
            .respond(&pull)
            .map_err(|source| DesignError::Truss { iteration, source })?;
        let image = flatten(&response.positions_m);
        let residual: Vec<f64> = image.iter().zip(&x).map(|(g, c)| g - c).collect();
        let distances: Vec<f64> = residual
            .chunks_exact(3)
            .map(|d| norm3([d[0], d[1], d[2]]))
            .collect();
        let xi = distances.iter().copied().fold(0.0, f64::max);
        let rms = (distances.iter().map(|d| d * d).sum::<f64>() / distances.len() as f64).sqrt();
        let previous_xi = history.last().map(|r| r.boundary_change_max_m);
        let converged = xi <= settings.tolerance_m;
        let first_xi = history.first().map_or(xi, |r| r.boundary_change_max_m);
        let diverged = xi > DIVERGENCE_FACTOR * first_xi;
        let step = relaxation.next(&x, &image, &residual, xi);
        let record = IterationRecord {
            iteration,
            boundary_change_max_m: xi,
            boundary_change_rms_m: rms,
            xi_change_m: previous_xi.map(|p| (xi - p).abs()),
            ratio: design.ratio,
            relaxation_factor: step.factor,
            oracle_newton_iterations: response.newton_iterations,
            design_time_s: design.time_s,
            truss_time_s: response.time_s,
            elapsed_s: clock.elapsed().as_secs_f64(),
        };
        observe(&record);
        history.push(record);
        if converged || diverged || iteration + 1 == settings.max_iterations {
            let initial = initial.unwrap_or_else(|| tied.clone());
            return Ok(LoopOutcome {
                design: tied.design,
                problem: tied.problem,
                initial,
                truss_deforms: oracle.deforms(),
                boundary_m: unflatten(&x),
                deformed_m: response.positions_m,
                truss_equilibrium: oracle.equilibrium(),
                history,
                termination: if converged {
                    Termination::Converged
                } else if diverged {
                    Termination::Diverged
                } else {
                    Termination::MaxIterations
                },
                time_s: clock.elapsed().as_secs_f64(),
            });
        }
        if initial.is_none() {
            initial = Some(tied.clone());
        }
        previous = Some(tied);
        x = step.x;
    }
    unreachable!("the loop returns at its last iteration")
}
