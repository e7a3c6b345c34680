//! argmin's L-BFGS on the solver's variables (`θ`, or the preconditioned
//! `φ`): the cost adapter, the observer that makes the gradient test, and one
//! run from a start point.

use std::sync::{Arc, Mutex};

use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{
    CostFunction, Error as ArgminError, Executor, IterState, State, TerminationReason,
    TerminationStatus, KV,
};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;

use super::history::History;
use super::objective::Objective;
use super::preconditioner::Preconditioner;
use crate::algebra::norm2;
use crate::uniformity::{Termination, UniformityError};

/// Length of the first step of every L-BFGS run, in the solver's variables
/// (relative change of `q`, or metres of `b`); the line search extends it.
const FIRST_STEP: f64 = 1e-3;

/// Why the cost function or the observer stopped a run: set in [`Shared`]
/// before they return the error that ends argmin's loop, and read from there
/// (argmin's error is only a carrier).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Stop {
    /// An accepted iterate passed the gradient test.
    Converged,
    /// L-BFGS's update degenerated (`y = 0`: nothing changes any more).
    NoProgress,
}

impl Stop {
    /// The run's termination, with a warning for the user where it has one.
    fn termination(self) -> (Termination, Option<&'static str>) {
        match self {
            Stop::Converged => (Termination::Converged, None),
            Stop::NoProgress => (
                Termination::Stalled,
                Some("L-BFGS stopped: no further progress (non-finite update)"),
            ),
        }
    }
}

/// The solver's variables: `θ`, or the preconditioned `φ`.
pub(super) struct Variables<'a, 'p> {
    objective: &'a Objective<'p>,
    preconditioner: Option<&'a Preconditioner>,
    start: Vec<f64>,
}

impl<'a, 'p> Variables<'a, 'p> {
    pub(super) fn new(
        objective: &'a Objective<'p>,
        preconditioner: Option<&'a Preconditioner>,
        q: &[f64],
    ) -> Self {
        let start = match preconditioner {
            Some(p) => vec![0.0; p.dim()],
            None => q.iter().map(|&v| objective.map.theta(v)).collect(),
        };
        Variables {
            objective,
            preconditioner,
            start,
        }
    }

    pub(super) fn q(&self, phi: &[f64]) -> Vec<f64> {
        match self.preconditioner {
            Some(p) => p.q_exact(phi),
            None => phi.iter().map(|&t| self.objective.map.q(t)).collect(),
        }
    }

    /// `J`, `dJ/dφ` and `‖dJ/dθ‖`.
    pub(super) fn evaluate(&self, phi: &[f64]) -> Result<(f64, Vec<f64>, f64), UniformityError> {
        match self.preconditioner {
            Some(p) => {
                let (q, dq) = p.q(phi);
                let (j, mut g) = self.objective.evaluate_q(&q)?;
                let theta_norm = self.objective.theta_gradient_norm(&q, &g);
                for (g, d) in g.iter_mut().zip(&dq) {
                    *g *= d;
                }
                Ok((j, p.pull_back(&g), theta_norm))
            }
            None => {
                let (j, g) = self.objective.evaluate_theta(phi)?;
                let theta_norm = norm2(&g);
                Ok((j, g, theta_norm))
            }
        }
    }
}

/// What one L-BFGS run returns.
pub(super) struct Run {
    pub(super) q: Vec<f64>,
    pub(super) termination: Termination,
    pub(super) iterations: usize,
    pub(super) warnings: Vec<String>,
}

/// One L-BFGS run of at most `budget` iterations from the variables' start,
/// converged when `‖dJ/dθ‖ ≤ tolerance` at an accepted iterate. Appends the
/// accepted iterates to `history`.
pub(super) fn minimise(
    variables: &Variables,
    memory: usize,
    budget: usize,
    tolerance: f64,
    history: &mut History,
) -> Result<Run, UniformityError> {
    let phi0 = variables.start.clone();
    let (j0, g0, _) = variables.evaluate(&phi0)?;
    history.evaluations += 1;
    let g0_norm = norm2(&g0);
    if !(j0.is_finite() && g0_norm.is_finite()) {
        return Err(UniformityError::SolverFailed {
            solver: "gradient",
            status: format!("non-finite objective {j0} or gradient"),
        });
    }
    let q0 = variables.q(&phi0);
    if g0_norm == 0.0 {
        return Ok(Run {
            q: q0,
            termination: Termination::Converged,
            iterations: 0,
            warnings: Vec::new(),
        });
    }
    // argmin sees `scale · J`, scaled so that this run's first step, −∇, has
    // length FIRST_STEP. Its own tests are off (tolerances 0): the gradient
    // test is on `dJ/dθ`, made by the observer.
    let scale = FIRST_STEP / g0_norm;
    let shared = Arc::new(Mutex::new(Shared::default()));
    let cost = Scaled {
        variables,
        scale,
        shared: Arc::clone(&shared),
    };
    let solver = LBFGS::new(MoreThuenteLineSearch::new(), memory)
        .with_tolerance_grad(0.0)
        .and_then(|s| s.with_tolerance_cost(0.0))
        .map_err(|e| UniformityError::SolverFailed {
            solver: "gradient",
            status: format!("L-BFGS settings: {e}"),
        })?;
    let recorder = Recorder {
        shared: Arc::clone(&shared),
        tolerance,
        scale,
    };
    let result = Executor::new(cost, solver)
        .configure(|state| state.param(phi0.clone()).max_iters(budget as u64))
        .add_observer(recorder, ObserverMode::Always)
        .ctrlc(false)
        .run();
    let shared =
        std::mem::take(
            &mut *shared.lock().map_err(|_| UniformityError::SolverFailed {
                solver: "gradient",
                status: "poisoned lock".into(),
            })?,
        );
    history.evaluations += shared.evaluations;
    for &(j, g) in &shared.records {
        history.objective.push(j / scale);
        history.gradient_norm.push(g);
    }
    let mut warnings = Vec::new();
    let iterations = shared.records.len();
    let (phi, termination) = match result {
        Ok(mut result) => {
            let termination = match result.state.get_termination_status() {
                TerminationStatus::Terminated(TerminationReason::MaxItersReached) => {
                    Termination::MaxIterations
                }
                TerminationStatus::Terminated(TerminationReason::SolverConverged) => {
                    Termination::Converged
                }
                TerminationStatus::Terminated(TerminationReason::SolverExit(text)) => {
                    warnings.push(format!("L-BFGS stopped: {text}"));
                    Termination::Stalled
                }
                TerminationStatus::Terminated(reason) => {
                    warnings.push(format!("L-BFGS stopped: {}", reason.text()));
                    Termination::Stalled
                }
                TerminationStatus::NotTerminated => Termination::Stalled,
            };
            let phi = result
                .state
                .take_best_param()
                .or_else(|| result.state.take_param())
                .unwrap_or(phi0);
            (phi, termination)
        }
        Err(e) => {
            let phi = shared.best.map_or(phi0, |(_, p)| p);
            match shared.stop {
                Some(stop) => {
                    let (termination, warning) = stop.termination();
                    warnings.extend(warning.map(str::to_string));
                    (phi, termination)
                }
                None => {
                    warnings.push(format!("L-BFGS failed: {e}"));
                    (phi, Termination::NumericalError)
                }
            }
        }
    };
    Ok(Run {
        q: variables.q(&phi),
        termination,
        iterations,
        warnings,
    })
}

/// What the cost function and the observer share during one run.
#[derive(Default)]
pub(super) struct Shared {
    /// The last evaluation (argmin asks for cost and gradient at the same point
    /// separately): `φ`, scaled `J`, scaled `dJ/dφ`, `‖dJ/dθ‖`.
    last: Option<(Vec<f64>, f64, Vec<f64>, f64)>,
    /// The best point seen: scaled `J`, `φ`.
    best: Option<(f64, Vec<f64>)>,
    /// Fresh evaluations.
    evaluations: usize,
    /// Scaled `J` and `‖dJ/dθ‖` of every accepted iterate.
    records: Vec<(f64, f64)>,
    /// Why the run was stopped from inside, if it was.
    stop: Option<Stop>,
}

/// `scale · J` of the solver's variables, as argmin sees it.
pub(super) struct Scaled<'a, 'v, 'p> {
    variables: &'a Variables<'v, 'p>,
    scale: f64,
    shared: Arc<Mutex<Shared>>,
}

impl Scaled<'_, '_, '_> {
    pub(super) fn eval(&self, phi: &[f64]) -> Result<(f64, Vec<f64>), ArgminError> {
        let mut shared = self
            .shared
            .lock()
            .map_err(|_| ArgminError::msg("poisoned lock"))?;
        if phi.iter().any(|v| !v.is_finite()) {
            // L-BFGS's update degenerates (y = 0) once nothing changes any more.
            shared.stop = Some(Stop::NoProgress);
            return Err(ArgminError::msg("stopped"));
        }
        if let Some((p, j, g, _)) = &shared.last {
            if p.as_slice() == phi {
                return Ok((*j, g.clone()));
            }
        }
        let (j, mut g, theta_norm) = self.variables.evaluate(phi)?;
        shared.evaluations += 1;
        let j = j * self.scale;
        for v in g.iter_mut() {
            *v *= self.scale;
        }
        if !j.is_finite() || g.iter().any(|v| !v.is_finite()) {
            return Err(ArgminError::msg("non-finite objective or gradient"));
        }
        if shared.best.as_ref().is_none_or(|(b, _)| j < *b) {
            shared.best = Some((j, phi.to_vec()));
        }
        shared.last = Some((phi.to_vec(), j, g.clone(), theta_norm));
        Ok((j, g))
    }
}

impl CostFunction for Scaled<'_, '_, '_> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, phi: &Vec<f64>) -> Result<f64, ArgminError> {
        self.eval(phi).map(|(j, _)| j)
    }
}

impl argmin::core::Gradient for Scaled<'_, '_, '_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;

    fn gradient(&self, phi: &Vec<f64>) -> Result<Vec<f64>, ArgminError> {
        self.eval(phi).map(|(_, g)| g)
    }
}

/// Records every accepted iterate and makes the gradient test on `‖dJ/dθ‖`
/// (argmin's own test sees only the solver's variables). The accepted iterate
/// is the last point evaluated: L-BFGS asks for its gradient after the line
/// search.
pub(super) struct Recorder {
    shared: Arc<Mutex<Shared>>,
    /// Of the stationarity `‖dJ/dθ‖∞ / J`.
    tolerance: f64,
    /// argmin's cost is `scale · J`.
    scale: f64,
}

pub(super) type LbfgsState = IterState<Vec<f64>, Vec<f64>, (), (), (), f64>;

impl Observe<LbfgsState> for Recorder {
    fn observe_iter(&mut self, state: &LbfgsState, _kv: &KV) -> Result<(), ArgminError> {
        let mut shared = self
            .shared
            .lock()
            .map_err(|_| ArgminError::msg("poisoned lock"))?;
        let theta_norm = shared.last.as_ref().map_or(f64::NAN, |l| l.3);
        let cost = state.get_cost();
        shared.records.push((cost, theta_norm));
        if theta_norm <= self.tolerance * (cost / self.scale).abs() {
            shared.stop = Some(Stop::Converged);
            return Err(ArgminError::msg("stopped"));
        }
        Ok(())
    }
}
