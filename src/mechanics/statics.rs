//! Static equilibrium: Newton–Raphson with adaptive load stepping, and an
//! arc-length (Crisfield) path for limit points (paper §3.5 solves dynamics;
//! we solve statics, DESIGN §5).
//!
//! Load stepping: the dead loads are scaled by a load factor `λ` ramped to 1.
//! A step that does not converge is undone and cut (÷4); a step that converges
//! in few iterations lets the next one grow (×2). Failing to converge is a
//! [`StaticTermination`] in the solution, never a silently wrong state.

use std::time::Instant;

use serde::Serialize;

use super::assembly::{Evaluation, State, System};
use super::model::{MechanicsError, Model};

/// How a static solve ended.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum StaticTermination {
    /// Equilibrium at the full load (λ = 1).
    Converged,
    /// The load step fell below the minimum before λ = 1: the last converged
    /// load factor is in the solution.
    Stalled {
        /// Last converged load factor.
        load_factor: f64,
    },
    /// The arc-length path passed a maximum of the load factor below 1: the
    /// structure's limit load is `limit_load_factor` × the applied loads.
    LimitPoint {
        /// The largest load factor on the path.
        limit_load_factor: f64,
    },
    /// The step budget ran out.
    MaxSteps {
        /// Last converged load factor.
        load_factor: f64,
    },
}

/// How the load is followed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PathControl {
    /// Load control: λ ramped to 1 with adaptive steps.
    #[default]
    Load,
    /// Arc-length control (cylindrical, Crisfield): follows the path through
    /// limit points.
    ArcLength,
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
    /// Load or arc-length control.
    pub path: PathControl,
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
        self.termination == StaticTermination::Converged
    }
}

/// A static solver for one model: the structure is analysed once, then any
/// number of solves (new loads through [`StaticSolver::model_mut`]).
pub struct StaticSolver {
    model: Model,
    system: System,
    /// Size of the frame, m.
    length_scale: f64,
    /// Largest coordinate magnitude, m (sets the roundoff of positions).
    coordinate_scale: f64,
}

/// The outcome of Newton iterations at fixed λ.
struct NewtonRun {
    converged: bool,
    iterations: usize,
    residuals: Vec<f64>,
    reactions: Vec<[f64; 6]>,
}

impl StaticSolver {
    /// Analyse the structure of `model`.
    ///
    /// # Errors
    /// A pattern faer cannot analyse.
    pub fn new(model: Model) -> Result<Self, MechanicsError> {
        let system = System::new(&model)?;
        let (mut lo, mut hi) = (
            nalgebra::Vector3::repeat(f64::MAX),
            nalgebra::Vector3::repeat(f64::MIN),
        );
        for f in &model.reference {
            lo = lo.inf(&f.position_m);
            hi = hi.sup(&f.position_m);
        }
        let length_scale = (hi - lo).norm().max(1e-9);
        let coordinate_scale = lo.amax().max(hi.amax());
        Ok(StaticSolver {
            model,
            system,
            length_scale,
            coordinate_scale,
        })
    }

    /// The model.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The model, to change its loads.
    pub fn model_mut(&mut self) -> &mut Model {
        &mut self.model
    }

    /// Largest component of the reference loads.
    fn load_scale(&self) -> f64 {
        self.model
            .loads
            .iter()
            .map(|l| l.force_n.amax().max(l.moment_nm.amax()))
            .fold(0.0, f64::max)
    }

    /// The unstressed reference state.
    pub fn reference_state(&self) -> State {
        self.system.reference_state(&self.model)
    }

    /// Newton iterations at fixed load factor `lambda`, updating `state`.
    fn newton(&self, state: &mut State, lambda: f64, settings: &StaticSettings) -> NewtonRun {
        let mut residuals = Vec::new();
        let mut first = f64::NAN;
        for it in 0..=settings.max_iterations {
            let ev = self.system.evaluate(&self.model, state, lambda);
            let (force, converged) = self.converged(&ev, lambda, settings);
            residuals.push(force);
            if !force.is_finite() {
                break;
            }
            if converged {
                return NewtonRun {
                    converged: true,
                    iterations: it,
                    residuals,
                    reactions: ev.reactions,
                };
            }
            if it == 0 {
                first = force;
            } else if force > 1e8 * first {
                break; // diverging
            }
            if it == settings.max_iterations {
                break;
            }
            let Ok(lu) = self.system.factor(&ev.values) else {
                break;
            };
            let mut rhs = self.system.column(&ev.residual);
            System::solve_in_place(&lu, rhs.as_mut());
            let delta: Vec<f64> = (0..self.system.n_rows).map(|i| -rhs[(i, 0)]).collect();
            if !delta.iter().all(|d| d.is_finite()) {
                break;
            }
            self.system.apply(state, &delta, 1.0);
        }
        NewtonRun {
            converged: false,
            iterations: residuals.len().saturating_sub(1),
            residuals,
            reactions: vec![],
        }
    }

    /// The force residual `‖F‖∞` at an evaluation and whether it is converged:
    /// `‖F‖∞ ≤ tol · max(λ‖f_ext‖∞, ‖reactions‖∞, cable forces)` and joint gaps `≤ tol · L`,
    /// where the force test never asks for less than the roundoff of the
    /// assembled forces, `ε · (EA/L)_max · |x|_max` (coordinates of tens of
    /// metres and stiff tubes put it near 1e-7 N).
    pub(crate) fn converged(
        &self,
        ev: &Evaluation,
        lambda: f64,
        settings: &StaticSettings,
    ) -> (f64, bool) {
        let n = self.system.n_free;
        let force = ev.residual[..n].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let gap = ev.residual[n..].iter().fold(0.0f64, |m, v| m.max(v.abs())) / self.system.scale;
        if !(force.is_finite() && gap.is_finite()) {
            return (f64::NAN, false);
        }
        let reaction_scale = ev
            .reactions
            .iter()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let roundoff =
            64.0 * f64::EPSILON * (ev.internal_scale + self.system.scale * self.coordinate_scale);
        let force_scale = (self.load_scale() * lambda.abs())
            .max(reaction_scale)
            .max(ev.prestress_scale);
        let tol = (settings.tolerance * force_scale).max(roundoff);
        (
            force,
            force <= tol && gap <= settings.tolerance * self.length_scale,
        )
    }

    /// Solve from the reference configuration under the model's loads.
    ///
    /// # Errors
    /// Invalid settings.
    pub fn solve(&self, settings: &StaticSettings) -> Result<StaticSolution, MechanicsError> {
        self.solve_from(self.reference_state(), 0.0, settings)
    }

    /// Solve starting from `start`, an equilibrium state at load factor
    /// `start_load_factor` of the *current* loads (0 for the reference state).
    /// A warm start: a nearby previous solution often converges in one step.
    ///
    /// # Errors
    /// Invalid settings.
    pub fn solve_from(
        &self,
        start: State,
        start_load_factor: f64,
        settings: &StaticSettings,
    ) -> Result<StaticSolution, MechanicsError> {
        settings.validate()?;
        match settings.path {
            PathControl::Load => Ok(self.load_control(start, start_load_factor, settings)),
            PathControl::ArcLength => Ok(self.arc_length(start, start_load_factor, settings)),
        }
    }

    fn load_control(
        &self,
        start: State,
        lambda0: f64,
        settings: &StaticSettings,
    ) -> StaticSolution {
        let clock = Instant::now();
        let mut state = start;
        let mut lambda = lambda0;
        let mut step = settings.initial_step;
        let mut steps = Vec::new();
        let mut newton_iterations = 0;
        let mut rejected_steps = 0;
        let mut reactions = vec![[0.0; 6]; self.model.node_count()];
        let termination = loop {
            if lambda >= 1.0 {
                break StaticTermination::Converged;
            }
            if steps.len() >= settings.max_steps {
                break StaticTermination::MaxSteps {
                    load_factor: lambda,
                };
            }
            let target = (lambda + step).min(1.0);
            let mut trial = state.clone();
            let run = self.newton(&mut trial, target, settings);
            newton_iterations += run.iterations;
            if run.converged {
                state = trial;
                lambda = target;
                reactions = run.reactions;
                if run.iterations <= 4 {
                    step = (2.0 * step).min(1.0);
                } else if run.iterations > 10 {
                    step *= 0.5;
                }
                steps.push(StepRecord {
                    load_factor: lambda,
                    iterations: run.iterations,
                    residuals: run.residuals,
                });
            } else {
                rejected_steps += 1;
                step *= 0.25;
                if step < settings.min_step {
                    break StaticTermination::Stalled {
                        load_factor: lambda,
                    };
                }
            }
        };
        StaticSolution {
            state,
            load_factor: lambda,
            termination,
            steps,
            newton_iterations,
            rejected_steps,
            reactions,
            time_s: clock.elapsed().as_secs_f64(),
        }
    }

    /// The small-displacement response: one linear solve with the tangent of
    /// the unstressed reference configuration, `K₀ u = f` (joints linearised).
    ///
    /// # Errors
    /// [`MechanicsError::Mechanism`] when `K₀` is singular.
    pub fn linear_response(&self) -> Result<State, MechanicsError> {
        let mut state = self.reference_state();
        let ev = self.system.evaluate(&self.model, &state, 1.0);
        let lu = self
            .system
            .factor(&ev.values)
            .map_err(|detail| MechanicsError::Mechanism { detail })?;
        let mut rhs = self.system.column(&ev.residual);
        System::solve_in_place(&lu, rhs.as_mut());
        let delta: Vec<f64> = (0..self.system.n_rows).map(|i| -rhs[(i, 0)]).collect();
        if !delta.iter().all(|d| d.is_finite()) {
            return Err(MechanicsError::Mechanism {
                detail: "the linear solve gave non-finite displacements".into(),
            });
        }
        self.system.apply(&mut state, &delta, 1.0);
        Ok(state)
    }

    fn arc_length(&self, start: State, lambda0: f64, settings: &StaticSettings) -> StaticSolution {
        super::arc_length::follow(self, &self.system, start, lambda0, settings)
    }

    pub(crate) fn length_scale(&self) -> f64 {
        self.length_scale
    }
}
