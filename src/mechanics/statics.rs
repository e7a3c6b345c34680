//! Static equilibrium, the solver's entry points: [`StaticSolver::solve`]
//! and [`StaticSolver::solve_from`] follow the dead loads by load control
//! (`load_control`: Newton–Raphson with adaptive load stepping) or by arc
//! length (`arc_length`, through limit points) — paper §3.5 solves dynamics;
//! we solve statics, DESIGN §5. Also the small-displacement response and the
//! stability of a state (`stability`). Failing to converge is a
//! [`StaticTermination`](super::StaticTermination) in the solution, never a
//! silently wrong state.

use super::arc_length;
use super::assembly::{Factor, Forces, Precision, State, System};
use super::cable::SLACK_STIFFNESS_RATIO;
use super::load_control;
use super::model::MechanicsError;
use super::model::Model;
use super::settings::{PathControl, StaticSettings, StaticSolution};
use super::solver::{wdot, StaticSolver};
use super::stability::{self, Stability};
use crate::algebra::norm2;
use std::sync::Mutex;

impl StaticSolver {
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
        self.check_resolvable()?;
        match settings.path {
            PathControl::Load => Ok(load_control::follow(
                self,
                start,
                start_load_factor,
                settings,
            )),
            PathControl::ArcLength => {
                Ok(arc_length::follow(self, start, start_load_factor, settings))
            }
            PathControl::Displacement => Err(MechanicsError::invalid(
                "solver.path",
                "displacement control names the controlled node: follow the path \
                 (StaticSolver::follow_path) instead",
            )),
        }
    }

    /// The small-displacement response: one linear solve with the tangent of
    /// the unstressed reference configuration, `K₀ u = f` (joints linearised).
    ///
    /// # Errors
    /// [`MechanicsError::Mechanism`] when `K₀` is singular.
    pub fn linear_response(&self) -> Result<State, MechanicsError> {
        let mut state = self.reference_state();
        let ev = self.system().evaluate(self.model(), &state, 1.0);
        let lu = self.system().factor(&ev.values)?;
        if let Some(i) = ev.forces.residual.iter().position(|r| !r.is_finite()) {
            return Err(MechanicsError::NotFinite {
                detail: format!("the load or residual of unknown {i} is not finite"),
            });
        }
        let mut rhs = self.system().column(&ev.forces.residual);
        System::solve_in_place(&lu, rhs.as_mut());
        let delta: Vec<f64> = (0..self.system().n_rows).map(|i| -rhs[(i, 0)]).collect();
        if !delta.iter().all(|d| d.is_finite()) {
            return Err(MechanicsError::Mechanism {
                detail: "the linear solve gave non-finite displacements".into(),
            });
        }
        self.system().apply(&mut state, &delta, 1.0);
        Ok(state)
    }

    /// The first-order response of the equilibrium `state` (at load factor
    /// `lambda`) to changes of the model: its tangent factored once, one
    /// solve per change ([`Linearisation::respond`]).
    ///
    /// # Errors
    /// A tangent that cannot be factored (a mechanism).
    pub fn linearise(
        &self,
        state: &State,
        lambda: f64,
    ) -> Result<Linearisation<'_>, MechanicsError> {
        let ev = self.system().evaluate(self.model(), state, lambda);
        let factor = self.system().factor(&ev.values)?;
        Ok(Linearisation {
            solver: self,
            state: state.clone(),
            lambda,
            residual: ev.forces.residual,
            factor,
            spare: Mutex::new(Vec::new()),
        })
    }

    /// The stability of `state`, an equilibrium at load factor `lambda`: is
    /// the stiffness positive definite on the joints' constraints (inverse
    /// iteration with the tangent's factor)?
    ///
    /// # Errors
    /// A tangent that cannot be factored (a mechanism, or exactly critical).
    pub fn stability(&self, state: &State, lambda: f64) -> Result<Stability, MechanicsError> {
        stability::stability(self, state, lambda)
    }
}

/// An equilibrium's tangent, factored: the first-order response of the
/// equilibrium to a change of its model's parameters
/// ([`StaticSolver::linearise`]).
pub struct Linearisation<'a> {
    solver: &'a StaticSolver,
    state: State,
    lambda: f64,
    /// The residual of the equilibrium (its roundoff), subtracted so that an
    /// unchanged model responds by exactly nothing.
    residual: Vec<f64>,
    factor: Factor,
    /// The last factors [`Linearisation::solve`] refactored, whose storage
    /// the next solves' refactorisations reuse (one a solve running at
    /// once): at 10⁵ nodes a fresh factor's first touch of its pages cost
    /// ≈ 0.3 s, as much as the factorisation.
    spare: Mutex<Vec<Factor>>,
}

/// The factor [`Linearisation::solve`] refactors, and a spare one whose
/// storage its first refactorisation reuses; returned to the
/// linearisation's spares when the solve ends.
struct Refreshed<'a> {
    factor: Option<Factor>,
    spare: Option<Factor>,
    pool: &'a Mutex<Vec<Factor>>,
}

impl Refreshed<'_> {
    /// The storage for the next refactorisation.
    fn storage(&mut self) -> Option<Factor> {
        self.factor.take().or_else(|| self.spare.take())
    }
}

impl Drop for Refreshed<'_> {
    fn drop(&mut self) {
        if let (Some(factor), Ok(mut pool)) = (self.storage(), self.pool.lock()) {
            pool.push(factor);
        }
    }
}

impl Linearisation<'_> {
    /// The equilibrium to first order of `changed`, a model of the same
    /// structure (nodes, supports, elements, cables and joints, in the same
    /// order: only their parameters differ): `x* + δ` with
    /// `J δ = −(R_changed(x*) − R(x*))`, `J` the tangent at `x*`.
    ///
    /// # Errors
    /// A model of another structure, or a non-finite response.
    pub fn respond(&self, changed: &Model) -> Result<State, MechanicsError> {
        self.solver.check_structure(changed)?;
        let system = self.solver.system();
        let forces = system.forces(changed, &self.state, self.lambda);
        let change: Vec<f64> = forces
            .residual
            .iter()
            .zip(&self.residual)
            .map(|(r, r0)| r - r0)
            .collect();
        let mut rhs = system.column(&change);
        System::solve_in_place(&self.factor, rhs.as_mut());
        let delta: Vec<f64> = (0..system.n_rows).map(|i| -rhs[(i, 0)]).collect();
        if !delta.iter().all(|d| d.is_finite()) {
            return Err(MechanicsError::NotFinite {
                detail: "the linearised response is not finite".into(),
            });
        }
        let mut state = self.state.clone();
        system.apply(&mut state, &delta, 1.0);
        Ok(state)
    }

    /// The equilibrium of `changed` (as [`Linearisation::respond`]) solved
    /// to `settings.tolerance` from `x*`, by chord iterations — Newton's
    /// with the tangent factored at `x*` kept, `x ← x − J⁻¹ R_changed(x)`;
    /// the first iterate is the linear response. Each is one residual and
    /// one solve, no factorisation: near `x*` the error contracts by about
    /// `‖J⁻¹ (J_changed − J)‖` an iteration. Where an increment does not
    /// shrink to [`CHORD_CONTRACTION`] of the one before (cables going
    /// slack change the tangent), the tangent is refactored at the current
    /// state — numerically only, the symbolic analysis is `x*`'s, the
    /// structure being the same — and the iterations go on with it (Newton's
    /// where every step refactors), at most [`CHORD_REFACTORISATIONS`]
    /// times; right after a refactorisation past which the slack cables
    /// have not settled, without trying the chord step first (the tangent
    /// has changed by every cable that changed). The net's LDLᵀ of a
    /// refactorisation is single precision: the residual is double and
    /// the factor only sets the steps, so the equilibrium is the same. (Eight
    /// super-100m tolerance samples, two threads: the same iterations and
    /// refactorisations, 8–14 each, as in double, and 46.7 s against 76.4
    /// s — the two samples' factorisations beside each other are bound by
    /// memory, which single precision halves.) The refactored matrix
    /// keeps [`SLACK_ITERATION_RATIO`] of a slack cable's axial stiffness:
    /// the exact tangent (1e-9 of it) throws a node held by slack cables
    /// far across their taut kink. Once the
    /// slack cables have settled — at most [`SETTLED_SLACK_CHANGE`] of them
    /// changed by the last step — the exact tangent is factored instead:
    /// the kept stiffness, wrong by 1e-2 EA/L on every slack cable, makes
    /// Newton's convergence linear there (should the exact tangent not
    /// factor, the iteration matrix is). A step whose residual grows more
    /// than [`ACCEPTED_RESIDUAL_GROWTH`]-fold is halved, at most
    /// [`LINE_SEARCH_HALVINGS`] times, and the least residual tried kept: a
    /// full step past cables going slack overshoots. (super-60m's tolerance
    /// samples, ≈ 800 cables slackening each, measured when any growth was
    /// halved: 12–14 iterations with the halving, 16–33 without, and with
    /// at most 4 refactorisations the chord failed and load steps took
    /// over, 3.7× the time.) The growth is not capped beyond that: the
    /// iterations and refactorisations are, and a step that raised the
    /// residual never ends them by the increment test. `None` (the caller
    /// follows the change by load steps instead) when that does not
    /// converge within `settings.max_iterations`, or a refactorisation
    /// fails; otherwise the state and the iterations it took. The state is
    /// an equilibrium by the solver's own tests
    /// ([`StaticSolver::converged`]).
    ///
    /// # Errors
    /// A model of another structure, or invalid settings.
    pub fn solve(
        &self,
        changed: &Model,
        settings: &StaticSettings,
    ) -> Result<Option<(State, usize)>, MechanicsError> {
        settings.validate()?;
        self.solver.check_structure(changed)?;
        let system = self.solver.system();
        let weights = self.solver.weights();
        let step = |factor: &Factor, residual: &[f64]| {
            let mut rhs = system.column(residual);
            System::solve_in_place(factor, rhs.as_mut());
            let delta: Vec<f64> = (0..system.n_rows).map(|i| -rhs[(i, 0)]).collect();
            let size = wdot(&weights, &delta, &delta).sqrt();
            (delta, size)
        };
        let mut state = self.state.clone();
        let mut refreshed = Refreshed {
            factor: None,
            spare: self.spare.lock().ok().and_then(|mut spare| spare.pop()),
            pool: &self.spare,
        };
        let mut refactorisations = 0;
        let mut previous = f64::INFINITY;
        let mut forces = system.forces(changed, &state, self.lambda);
        // The tangent values of the last refactorisation: its buffer is
        // reused, as the factor's storage is (at 10⁵ nodes a fresh one's
        // first touch of each page cost as much as the numbers in it).
        let mut values = Vec::new();
        // The current iterate's slack cables, and how many the last step
        // changed. (Counting only full steps, a shortened one leaving the
        // slack cables unsettled, slowed super-100m's four samples 31.2 →
        // 37.4 s: the exact tangent came later.)
        let mut slack = slack_cables(changed, &state, self.lambda);
        let mut slack_changed = usize::MAX;
        // Whether the last step was Newton's (the tangent refactored where
        // it was taken), and whether it was taken after the force test
        // passed: after a chord step that test alone is not enough — the
        // iterations converge linearly, so the state is only as good as the
        // test (the budget's scaled-dish test asks tensions to 1e-9, which a
        // chord iterate passing the force test missed by 10×) — so chord
        // steps go on, cheap, to the increment test, at most
        // [`POLISHING_STEPS`] and with no refactorisation (once at the
        // roundoff, an increment need not shrink: on super-100m's design
        // that refactored at every iteration, 40 times).
        let (mut newton, mut polished) = (true, 0);
        // Whether the last step was taken with a factor refactored for it.
        let mut refactored = false;
        for iteration in 0..=settings.max_iterations {
            let converged = self.solver.converged(&forces, self.lambda, settings).1;
            if converged && (newton || polished == POLISHING_STEPS) {
                return Ok(Some((state, iteration)));
            }
            if iteration == settings.max_iterations {
                return Ok(converged.then_some((state, iteration)));
            }
            let settled = slack_changed as f64
                <= SETTLED_SLACK_CHANGE * slack.iter().filter(|&&s| s).count() as f64;
            // A factor refactored for the last step, past which the slack
            // cables have not settled, is not tried for a chord step: the
            // tangent has changed by as many cables' stiffness as changed
            // (each super-100m sample tried four such steps, every one
            // refused, 0.07 s a solve).
            let stale = refactored && !settled && !converged;
            let chord = (!stale).then(|| {
                step(
                    refreshed.factor.as_ref().unwrap_or(&self.factor),
                    &forces.residual,
                )
            });
            newton = false;
            refactored = false;
            polished += usize::from(converged);
            let contracts = chord
                .as_ref()
                .is_some_and(|&(_, size)| size <= CHORD_CONTRACTION * previous);
            let (delta, size) = match chord {
                Some(chord) if converged || contracts => chord,
                _ => {
                    if refactorisations == CHORD_REFACTORISATIONS {
                        return Ok(None);
                    }
                    let tangent = |ratio, values: &mut Vec<f64>| {
                        system.tangent_into(changed, &state, self.lambda, ratio, values);
                    };
                    let ratio = if settled {
                        SLACK_STIFFNESS_RATIO
                    } else {
                        SLACK_ITERATION_RATIO
                    };
                    tangent(ratio, &mut values);
                    // The exact tangent keeps 1e-9 EA on slack cables: should it
                    // not factor, the iteration matrix does; should that not
                    // factor in single precision, in double (its pivots below
                    // f32's roundoff, or beyond its range).
                    let factored = system.refactor(&values, Precision::Single, refreshed.storage());
                    let factored = if settled {
                        factored.or_else(|_| {
                            tangent(SLACK_ITERATION_RATIO, &mut values);
                            system.refactor(&values, Precision::Single, None)
                        })
                    } else {
                        factored
                    };
                    let factored =
                        factored.or_else(|_| system.refactor(&values, Precision::Double, None));
                    let Ok(factor) = factored else {
                        return Ok(None);
                    };
                    refactorisations += 1;
                    let newton_step = step(&factor, &forces.residual);
                    refreshed.factor = Some(factor);
                    newton = true;
                    refactored = true;
                    newton_step
                }
            };
            if !size.is_finite() {
                return Ok(None);
            }
            // The step, halved while the residual grows too much: a full
            // step past cables going slack (or taut again) can overshoot by
            // far; one that brings the slack cables nearer their set raises
            // the residual a little for an iteration.
            let norm = norm2(&forces.residual);
            let mut best: Option<(f64, f64, State, Forces)> = None;
            let mut fraction = 1.0;
            for _ in 0..=LINE_SEARCH_HALVINGS {
                let mut trial = state.clone();
                system.apply(&mut trial, &delta, fraction);
                let trial_forces = system.forces(changed, &trial, self.lambda);
                let trial_norm = norm2(&trial_forces.residual);
                let decreases = trial_norm < ACCEPTED_RESIDUAL_GROWTH * norm;
                if trial_norm.is_finite() && best.as_ref().is_none_or(|b| trial_norm < b.1) {
                    best = Some((fraction, trial_norm, trial, trial_forces));
                }
                if decreases {
                    break;
                }
                fraction *= 0.5;
            }
            let Some((fraction, trial_norm, trial, trial_forces)) = best else {
                return Ok(None);
            };
            state = trial;
            forces = trial_forces;
            let now = slack_cables(changed, &state, self.lambda);
            slack_changed = now.iter().zip(&slack).filter(|(a, b)| a != b).count();
            slack = now;
            newton &= fraction == 1.0;
            // The increment test ends the iterations only after a step that
            // lowered the residual (one that raised it is not converging).
            if fraction == 1.0
                && trial_norm < norm
                && self.solver.increment_converged(&delta, &weights, settings)
            {
                return Ok(Some((state, iteration + 1)));
            }
            previous = fraction * size;
        }
        Ok(None)
    }
}

/// Whether each cable of `model` is slack at `state`.
fn slack_cables(model: &Model, state: &State, lambda: f64) -> Vec<bool> {
    model
        .cables()
        .iter()
        .map(|c| {
            let [a, b] = c.nodes();
            let at = |n: usize| &state.frames[n].position_m;
            c.state(at(a), at(b), lambda).slack
        })
        .collect()
}

/// The fraction of the slack cables whose change by the last step says the
/// slack cables have settled, [`Linearisation::solve`] then factoring the
/// exact tangent. A super-100m tolerance sample (≈ 5 800 cables ending
/// slack) has ≈ 27 500 slack after the chord steps, then ≈ 10 600, 7 400,
/// 6 300, 5 950, 5 780, then changes of a few cables an iteration, where
/// the kept stiffness converged linearly (≈ 0.55 a step; one sample 23
/// iterations and 17 refactorisations). `cargo bench --bench budget`, two
/// threads, never (the iteration matrix throughout) / 0.01 / 0.05 / 0.1 /
/// 0.25: four samples of super-100m 42.8 / 35.7 / 34.9 / 32.4 / 39.8 s;
/// eight of super-60m (≈ 800 slack each) 14.7 / 14.9 / 13.6–14.0 /
/// 13.5–13.7 / 13.3–13.4 s.
pub const SETTLED_SLACK_CHANGE: f64 = 0.1;

/// Chord steps [`Linearisation::solve`] takes past its force test, to its
/// increment test.
const POLISHING_STEPS: usize = 3;

/// The axial stiffness, as a fraction of EA, a slack cable keeps in the
/// matrix [`Linearisation::solve`] refactors (its residual is exact, so its
/// equilibrium is the same). Measured when this matrix was refactored to the
/// end and every growth of the residual halved, on a super-100m tolerance
/// sample (σ = 2 µm on cut lengths, ≈ 5 800 cables ending slack), one
/// thread: the exact tangent
/// (1e-9) took 19 iterations and 15 refactorisations, 19.8 s; 1e-3: 17 and
/// 10, 14.7 s; 1e-2: 12 and 9, 12.3 s; 3e-2: 15 and 9, 12.9 s; 1e-1: 16
/// and 12, 16.3 s. (A ratio adapted per step, ×10 on a halved step and ÷10
/// on a full one, took 36–39 iterations.)
///
/// Measured again with [`SETTLED_SLACK_CHANGE`] and
/// [`ACCEPTED_RESIDUAL_GROWTH`], four super-100m samples on two threads:
/// 3e-3 34.0 s, 1e-2 30.4–32.4 s, 3e-2 29.2–31.4 s, 1e-1 42.6 s; eight of
/// super-60m 12.8 s at 1e-2 against 14.3 s at 3e-2, so 1e-2 stays.
pub const SLACK_ITERATION_RATIO: f64 = 1e-2;

/// The growth of the residual by which [`Linearisation::solve`] still takes
/// a step (not monotone: the first Newton steps through cables going slack
/// raise the residual while the slack set settles, and halving them slowed
/// that). `cargo bench --bench budget`, two threads, growth 1 / 2 / 3 / 10
/// (no growth ↔ halving while the residual grows): four samples of
/// super-100m 32.4 / 30.6 / 29.8 / 32.7 s, eight of super-60m 13.5 /
/// 12.7 / 13.3 / 12.7 s; 1 000 of realistic-26m 20.0 / 20.4 s (1, 2). Two
/// super-100m samples, one thread, iterations (refactorisations): 12 (9)
/// and 16 (10) at 1; 12 (7) and 15 (9) at 3; 14 (8) each with no halving.
/// 2 rather than 3: the totals are alike, and it strays less. (Capped at
/// twice the least residual so far instead of the last: 36.3 s.)
pub const ACCEPTED_RESIDUAL_GROWTH: f64 = 2.0;

/// Halvings of a step of [`Linearisation::solve`] whose residual grows
/// more than [`ACCEPTED_RESIDUAL_GROWTH`]-fold.
const LINE_SEARCH_HALVINGS: usize = 3;

/// Largest ratio of a chord increment to the one before that
/// [`Linearisation::solve`] accepts: slower, and a step with the tangent
/// refactored where the iterations are (quadratic, one numeric
/// factorisation) is the cheaper path.
pub const CHORD_CONTRACTION: f64 = 0.5;

/// Refactorisations [`Linearisation::solve`] makes before it gives up: as
/// many as its iterations may take (at 4, super-60m's samples gave up
/// after 8 s of chord iterations and took 28 s more of load steps).
pub const CHORD_REFACTORISATIONS: usize = 40;
