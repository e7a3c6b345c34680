//! Load control: Newton–Raphson with adaptive load stepping.
//!
//! The dead loads are scaled by a load factor `λ` ramped to 1. A step that
//! does not converge is undone and cut (÷4); a step that converges in few
//! iterations lets the next one grow (×2). Newton must converge from the
//! step's tangent prediction without moving away from it; a step that does
//! not — past a limit point Newton bounces through unstable states to a
//! snapped-through branch — is undone and cut too, so a structure loaded
//! beyond its limit load ends at the limit ([`StaticTermination::LimitPoint`])
//! instead of on a snapped-through equilibrium.

use std::time::Instant;

use super::assembly::{FactorError, State, System};
use super::settings::{StaticSettings, StaticSolution, StaticTermination, StepRecord};
use super::solver::{wdot, StaticSolver};
use crate::algebra::norm2;

/// Largest ratio of a Newton correction to the increment before it (weighted
/// norm) for a load step to count as converging on its branch: with every
/// ratio at most ½ the corrections sum to at most the predictor, so the
/// converged point lies within `‖δ₀‖` of the predicted one, `u + K⁻¹ Δλ f̂`,
/// and the step's increment within twice the predictor — the most a smooth
/// branch gives over a step that ends before a fold (`u − u* ∝ √(λ* − λ)`).
/// Newton across a limit point bounces: a correction past the fold is larger
/// than the increment that reached it. ½ is the usual contraction bound of
/// affine-invariant Newton monitors (Deuflhard, Newton Methods for Nonlinear
/// Problems, 2004).
const CONTRACTION: f64 = 0.5;

/// Corrections below this fraction of the predictor are not tested for
/// contraction. A correction that changes branch moves Newton by about the
/// distance between the branches, as large as the predictor or larger (a von
/// Mises truss past its limit: 0.76–0.95 of it in the first correction),
/// while Newton on a stable but strongly nonlinear path wanders by a few per
/// cent (a cantilever rolled up by a quarter turn per step: 9 %, after which
/// it converges quadratically). Measured: 0.2 lets a truss at 30 × its limit
/// load snap through, 0.1 stops every overload from 1.01 × to 30 ×, and the
/// full-circle cantilever needs 4 steps with it, 13 with 0.01.
const CONTRACTION_FLOOR: f64 = 0.1;

/// Largest ratio of a step's tangent predictor per unit load to the previous
/// step's increment per unit load. Next to a fold the tangent is nearly
/// singular and throws Newton across the unstable states to the far branch,
/// where it may converge with contraction. A smooth path's slope changes
/// little from one step to the next: approaching a quadratic fold, the
/// tangent's slope over the previous step's secant is `½(1 + √(d₀/d₁))`,
/// `d₀`, `d₁` the distances in λ to the fold before and after that step, and
/// reaches 10 only when the step cut the distance by 361.
const BRANCH_RATIO: f64 = 10.0;

/// A curvature `vᵀ H v` counts as negative below `−CURVATURE_NOISE` times its
/// roundoff scale `‖v‖ ‖J v‖`: the LU solve of a tangent of condition up to
/// ~1e8 (thin tubes, `EA·L²/EI`) leaves ~1e-8 relative error in the Newton
/// increment.
const CURVATURE_NOISE: f64 = 1e-6;

/// Smallest fraction of a Newton increment the damped iteration of a step
/// without branch tests takes (it then takes it even if the residual grows).
const MIN_DAMPING: f64 = 1.0 / 1024.0;

/// How far above the convergence tolerance a residual that no fraction of
/// the Newton increment can lower still counts as converged: a rounding
/// floor the roundoff estimate of [`StaticSolver::converged`] undercounts,
/// or a kink of a cable's force law (slack/taut) within the step.
const FLOOR_FACTOR: f64 = 16.0;

/// How Newton iterations at fixed λ ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum NewtonEnd {
    Converged,
    /// No convergence within the budget, divergence, or a singular tangent.
    Failed,
    /// The tangent predictor (first increment) exceeded the bound it was
    /// given: the path's slope jumped.
    Overshoot,
    /// A correction was more than [`CONTRACTION`] times the increment before
    /// it: Newton left the neighbourhood of the predicted point.
    Expanding,
}

/// The outcome of Newton iterations at fixed λ.
struct NewtonRun {
    end: NewtonEnd,
    iterations: usize,
    residuals: Vec<f64>,
    reactions: Vec<[f64; 6]>,
    /// Weighted norm of the sum of the increments: the step's secant.
    secant: f64,
    /// Some increment `δ` had negative curvature `δuᵀ H δu`: Newton passed
    /// through a state where the structure is unstable.
    negative_curvature: bool,
    /// Newton failed on a residual, tangent or increment that is not finite.
    non_finite: bool,
}

/// Why a load step was undone.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Rejection {
    /// Newton did not converge, with no sign of instability.
    NotConverged,
    /// The step left its branch: a snap-through, a jump of the path's slope,
    /// or a failure through unstable states.
    OffBranch,
}

/// Newton iterations at fixed load factor `lambda`, updating `state`;
/// increments measured in the weighted norm `w`, the first one bounded
/// by `max_predictor`, each later one by [`CONTRACTION`] times the one
/// before.
///
/// Each increment `δ` solves `J δ = −R`; its curvature
/// `δuᵀ H δu = −δuᵀF + δμᵀ(s g)` follows from the two block rows of `J`
/// at no cost.
fn newton(
    solver: &StaticSolver,
    state: &mut State,
    lambda: f64,
    settings: &StaticSettings,
    w: &[f64],
    max_predictor: Option<f64>,
) -> NewtonRun {
    let n_free = solver.system().n_free;
    let mut run = NewtonRun {
        end: NewtonEnd::Failed,
        iterations: 0,
        residuals: Vec::new(),
        reactions: vec![],
        secant: 0.0,
        negative_curvature: false,
        non_finite: false,
    };
    let mut increment = vec![0.0; solver.system().n_rows];
    let (mut predictor, mut previous) = (0.0, 0.0);
    let mut first = f64::NAN;
    let mut damped = None;
    // The last increment passed the increment test: the state it reached
    // is converged whatever the force test says.
    let mut increment_small = false;
    for it in 0..=settings.max_iterations {
        let ev = damped
            .take()
            .unwrap_or_else(|| solver.system().evaluate(solver.model(), state, lambda));
        let (force, converged) = solver.converged(&ev.forces, lambda, settings);
        run.residuals.push(force);
        run.iterations = it;
        if !force.is_finite() {
            run.non_finite = true;
            break;
        }
        if converged || increment_small {
            run.end = NewtonEnd::Converged;
            run.reactions = ev.forces.reactions;
            break;
        }
        if it == 0 {
            first = force;
        } else if force > 1e8 * first {
            break; // diverging
        }
        if it == settings.max_iterations {
            break;
        }
        let lu = match solver.system().factor(&ev.values) {
            Ok(lu) => lu,
            Err(e) => {
                run.non_finite = matches!(e, FactorError::NotFinite { .. });
                break;
            }
        };
        let mut rhs = solver.system().column(&ev.forces.residual);
        System::solve_in_place(&lu, rhs.as_mut());
        let delta: Vec<f64> = (0..solver.system().n_rows).map(|i| -rhs[(i, 0)]).collect();
        if !delta.iter().all(|d| d.is_finite()) {
            run.non_finite = true;
            break;
        }
        let curvature: f64 = delta
            .iter()
            .zip(&ev.forces.residual)
            .enumerate()
            .map(|(i, (d, r))| if i < n_free { -d * r } else { d * r })
            .sum();
        if curvature < -CURVATURE_NOISE * norm2(&delta) * norm2(&ev.forces.residual) {
            run.negative_curvature = true;
        }
        let size = wdot(w, &delta, &delta).sqrt();
        let small = solver.increment_converged(&delta, w, settings);
        let Some(max_predictor) = max_predictor else {
            // No branch tests (the step is not driven by dead loads):
            // damped Newton, the step halved while it raises the residual.
            // A node held only by slack cables' regularisation has a tangent
            // so soft that a full step throws it across a cable's taut kink
            // (measured on `small-hex` with every cable at its centre node
            // cut 5 % long: 1e-5 N → 1e7 N, and the ramp stalled).
            // When no fraction of the increment lowers the residual, it sits
            // on its rounding floor or at a kink of the cable law within the
            // step (the floating node: 8.4e-5 N, 8 × the tolerance): the
            // state is converged if within [`FLOOR_FACTOR`] × the tolerance
            // (an equilibrium to that looser bound), else failed — never a
            // step that raises the residual.
            let start = state.clone();
            let mut step = 1.0;
            while step >= MIN_DAMPING {
                solver.system().apply(state, &delta, step);
                let trial = solver.system().evaluate(solver.model(), state, lambda);
                let (after, _) = solver.converged(&trial.forces, lambda, settings);
                if after < force {
                    damped = Some(trial);
                    increment_small = small && step == 1.0;
                    break;
                }
                state.clone_from(&start);
                step *= 0.5;
            }
            if damped.is_none() {
                if solver
                    .converged_within(&ev.forces, lambda, settings, FLOOR_FACTOR)
                    .1
                {
                    run.end = NewtonEnd::Converged;
                    run.reactions = ev.forces.reactions;
                }
                break;
            }
            continue;
        };
        if it == 0 {
            predictor = size;
            if predictor > max_predictor {
                run.iterations = 1;
                run.end = NewtonEnd::Overshoot;
                break;
            }
        } else if size > CONTRACTION * previous && size > CONTRACTION_FLOOR * predictor {
            run.iterations = it + 1;
            run.end = NewtonEnd::Expanding;
            break;
        }
        previous = size;
        for (a, d) in increment.iter_mut().zip(&delta) {
            *a += d;
        }
        solver.system().apply(state, &delta, 1.0);
        increment_small = small;
    }
    run.secant = wdot(w, &increment, &increment).sqrt();
    run
}

/// Load control: `λ` ramped from `lambda0` to 1 in adaptive steps.
///
/// A step is accepted when Newton converges *on the branch the step
/// started from*, that is from its tangent predictor `K⁻¹ Δλ f̂` (the
/// first Newton increment) without moving away from the predicted point.
/// Two tests, on increments Newton computes anyway (weighted norm of the
/// arc-length method, rotations × mean element length), stop a step:
///
/// 1. contraction: a correction more than [`CONTRACTION`] times the
///    increment before it. Passing it, the converged point lies within
///    the predictor's length of the predicted point. Past a limit point
///    Newton bounces through the unstable states to the snapped-through
///    branch, and fails it;
/// 2. slope jump: a predictor per unit load more than [`BRANCH_RATIO`]
///    times the previous step's increment per unit load — next to a fold
///    the tangent is nearly singular and throws Newton across the
///    unstable states, where it may then contract onto the far branch.
///
/// A stopped step is undone and cut ÷4 like one that does not converge;
/// a smooth branch always passes once the step is short enough. Beyond a
/// limit load no step passes, however short: when the step falls below
/// `min_step` the solve ends with [`StaticTermination::LimitPoint`] at the
/// last converged `λ` if the last try was stopped by a test or failed
/// through negative curvature `δuᵀ H δu < 0` (an unstable state), and
/// with [`StaticTermination::Stalled`] if Newton simply did not converge.
/// Without these tests Newton under a load beyond the limit converges on
/// a snapped-through equilibrium (a von Mises truss inverted) and reports
/// it as the answer.
///
/// What no finite step can see: a fold passed inside one step whose
/// predictor lands near the far branch — a load tens of times the limit
/// load applied in one step (a von Mises truss at 60 × its limit load
/// converges inverted). Ramp such loads (`initial_step`) or use arc
/// length.
///
/// What passes: large but stable rotations (a cantilever rolled up twice,
/// in steps short enough for Newton to contract), and a branch continued
/// smoothly past a bifurcation — a symmetric structure beyond a buckling
/// load stays on its unstable fundamental branch when Newton reaches it
/// where the tangent points. Load control does not certify stability;
/// arc length finds where the path turns.
pub(super) fn follow(
    solver: &StaticSolver,
    start: State,
    lambda0: f64,
    settings: &StaticSettings,
) -> StaticSolution {
    follow_observed(solver, start, lambda0, settings, &mut |_, _, _| {})
}

/// [`follow`], calling `observe(state, load factor, Newton iterations)` at
/// every accepted step.
pub(super) fn follow_observed(
    solver: &StaticSolver,
    start: State,
    lambda0: f64,
    settings: &StaticSettings,
    observe: &mut dyn FnMut(&State, f64, usize),
) -> StaticSolution {
    let clock = Instant::now();
    let w = solver.weights();
    let mut state = start;
    let mut lambda = lambda0;
    let mut step = settings.initial_step;
    let mut steps = Vec::new();
    let mut newton_iterations = 0;
    let mut rejected_steps = 0;
    let mut reactions = vec![[0.0; 6]; solver.model().node_count()];
    // The path's slope over the last accepted step (none yet: no bound).
    let mut previous_slope = f64::INFINITY;
    // The branch tests follow the path of dead loads; a structure loaded
    // only by its prestrain (an assembled cable net) has no such path.
    let dead_loads = solver.load_scale() > 0.0;
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
        let d_lambda = target - lambda;
        let mut trial = state.clone();
        let run = newton(
            solver,
            &mut trial,
            target,
            settings,
            &w,
            dead_loads.then_some(BRANCH_RATIO * previous_slope * d_lambda),
        );
        newton_iterations += run.iterations;
        let verdict = match run.end {
            NewtonEnd::Converged => Ok(run.secant / d_lambda),
            NewtonEnd::Overshoot | NewtonEnd::Expanding => Err(Rejection::OffBranch),
            NewtonEnd::Failed if run.negative_curvature && dead_loads => Err(Rejection::OffBranch),
            NewtonEnd::Failed => Err(Rejection::NotConverged),
        };
        match verdict {
            Ok(slope) => {
                // A step that converged at once says nothing of the slope.
                previous_slope = if slope > 0.0 { slope } else { f64::INFINITY };
                state = trial;
                lambda = target;
                reactions = run.reactions;
                observe(&state, lambda, run.iterations);
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
            }
            Err(why) => {
                rejected_steps += 1;
                step *= 0.25;
                if step < settings.min_step && run.non_finite {
                    break StaticTermination::Overflow {
                        load_factor: lambda,
                    };
                }
                if step < settings.min_step {
                    break match why {
                        Rejection::OffBranch => StaticTermination::LimitPoint {
                            limit_load_factor: lambda,
                        },
                        Rejection::NotConverged => StaticTermination::Stalled {
                            load_factor: lambda,
                        },
                    };
                }
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
