//! Cylindrical arc-length continuation (Crisfield 1981) on the static
//! equilibrium path `F(u) = λ f̂`: the load factor is an unknown, each step
//! moves a fixed distance `Δl` along the path, so the solve passes limit points
//! where load control stalls.
//!
//! Distances use the node increments, rotations weighted by the mean element
//! length so that both are lengths; multipliers do not count.

use std::time::Instant;

use faer::Mat;

use super::assembly::{State, System};
use super::corrector::reference_load;
use super::load_control;
use super::settings::{PathControl, StaticSettings, StaticSolution, StaticTermination, StepRecord};
use super::solver::{wdot, StaticSolver};

/// Iterations a step aims for; the arc length adapts as `√(target / used)`.
const TARGET_ITERATIONS: f64 = 5.0;

/// Follows the path from `start`, an equilibrium at load factor `lambda0`,
/// to λ = 1, or to a limit point.
pub(super) fn follow(
    solver: &StaticSolver,
    start: State,
    lambda0: f64,
    settings: &StaticSettings,
) -> StaticSolution {
    follow_observed(solver, start, lambda0, settings, &mut |_, _, _| {})
}

/// [`follow`], calling `observe(state, load factor, arc length)` at every
/// converged arc-length step (not at the landing on λ = 1), the arc length
/// being the step's distance along the path.
pub(super) fn follow_observed(
    solver: &StaticSolver,
    start: State,
    lambda0: f64,
    settings: &StaticSettings,
    observe: &mut dyn FnMut(&State, f64, f64),
) -> StaticSolution {
    let clock = Instant::now();
    let system = solver.system();
    let f_hat = reference_load(solver);
    let w = solver.weights();
    let n = system.n_rows;

    let mut state = start;
    let mut lambda = lambda0;
    let mut lambda_max = lambda0;
    let mut previous: Option<Vec<f64>> = None; // last step's increment, for the direction
    let mut arc: Option<f64> = None;
    let mut steps = Vec::new();
    let mut newton_iterations = 0;
    let mut rejected_steps = 0;
    let mut reactions = vec![[0.0; 6]; solver.model().node_count()];
    let mut attempts = 0;

    let termination = loop {
        if steps.len() >= settings.max_steps || attempts > 4 * settings.max_steps {
            break StaticTermination::MaxSteps {
                load_factor: lambda,
            };
        }
        attempts += 1;
        // Predictor: tangent direction at the converged state.
        let ev = system.evaluate(solver.model(), &state, lambda);
        let Ok(lu) = system.factor(&ev.values) else {
            break StaticTermination::Stalled {
                load_factor: lambda,
            };
        };
        let mut t = Mat::from_fn(n, 1, |i, _| f_hat[i]);
        System::solve_in_place(&lu, t.as_mut());
        let tangent: Vec<f64> = (0..n).map(|i| t[(i, 0)]).collect();
        let tn = wdot(&w, &tangent, &tangent).sqrt();
        if !(tn.is_finite() && tn > 0.0) {
            break StaticTermination::Stalled {
                load_factor: lambda,
            };
        }
        let dl = *arc.get_or_insert(settings.initial_step * tn);
        let sign = match &previous {
            Some(p) if wdot(&w, p, &tangent) < 0.0 => -1.0,
            _ => 1.0,
        };
        let d_lambda0 = sign * dl / tn;

        let mut trial = state.clone();
        let mut trial_lambda = lambda + d_lambda0;
        let mut increment: Vec<f64> = tangent.iter().map(|t| d_lambda0 * t).collect();
        system.apply(&mut trial, &increment, 1.0);

        // Corrector.
        let mut residuals = Vec::new();
        let mut converged = false;
        let mut iterations = 0;
        for it in 0..=settings.max_iterations {
            let ev = system.evaluate(solver.model(), &trial, trial_lambda);
            let (force, ok) = solver.converged(&ev.forces, trial_lambda, settings);
            residuals.push(force);
            iterations = it;
            if !force.is_finite() {
                break;
            }
            if ok {
                converged = true;
                reactions = ev.forces.reactions;
                break;
            }
            if it == settings.max_iterations {
                break;
            }
            let Ok(lu) = system.factor(&ev.values) else {
                break;
            };
            let mut rhs = Mat::from_fn(n, 2, |i, j| {
                if j == 0 {
                    -ev.forces.residual[i]
                } else {
                    f_hat[i]
                }
            });
            System::solve_in_place(&lu, rhs.as_mut());
            let du_f: Vec<f64> = (0..n).map(|i| rhs[(i, 0)]).collect();
            let du_t: Vec<f64> = (0..n).map(|i| rhs[(i, 1)]).collect();
            // ‖a + δu_F + δλ δu_T‖ = Δl with a the step's increment so far.
            let b: Vec<f64> = increment.iter().zip(&du_f).map(|(a, f)| a + f).collect();
            let a1 = wdot(&w, &du_t, &du_t);
            let a2 = 2.0 * wdot(&w, &b, &du_t);
            let a3 = wdot(&w, &b, &b) - dl * dl;
            let disc = a2 * a2 - 4.0 * a1 * a3;
            if !(disc >= 0.0 && a1 > 0.0) {
                break;
            }
            let roots = [
                (-a2 + disc.sqrt()) / (2.0 * a1),
                (-a2 - disc.sqrt()) / (2.0 * a1),
            ];
            // The root that keeps the step's direction.
            let d_lambda = roots
                .into_iter()
                .max_by(|x, y| {
                    let score = |r: f64| {
                        let next: Vec<f64> = b.iter().zip(&du_t).map(|(b, t)| b + r * t).collect();
                        wdot(&w, &next, &increment)
                    };
                    score(*x).total_cmp(&score(*y))
                })
                .expect("two roots");
            let delta: Vec<f64> = du_f
                .iter()
                .zip(&du_t)
                .map(|(f, t)| f + d_lambda * t)
                .collect();
            system.apply(&mut trial, &delta, 1.0);
            for (a, d) in increment.iter_mut().zip(&delta) {
                *a += d;
            }
            trial_lambda += d_lambda;
        }
        newton_iterations += iterations;

        if !converged {
            rejected_steps += 1;
            let cut = arc.map(|a| a * 0.25).unwrap_or(0.0);
            arc = Some(cut);
            if cut < settings.min_step * tn {
                break StaticTermination::Stalled {
                    load_factor: lambda,
                };
            }
            continue;
        }
        if trial_lambda > 1.0 && lambda < 1.0 {
            // Land exactly on λ = 1 by load control from the last state below it.
            let mut landing = state.clone();
            let run_settings = StaticSettings {
                initial_step: 1.0,
                ..settings.clone()
            };
            let landing_settings = StaticSettings {
                path: PathControl::Load,
                ..run_settings
            };
            // What `solver.solve_from` does for load control (it dispatches to
            // this file, which therefore calls load control itself).
            let landed = landing_settings
                .validate()
                .map(|()| load_control::follow(solver, landing.clone(), lambda, &landing_settings));
            if let Ok(sol) = landed {
                newton_iterations += sol.newton_iterations;
                if sol.converged() {
                    landing = sol.state;
                    steps.extend(sol.steps);
                    state = landing;
                    lambda = 1.0;
                    reactions = sol.reactions;
                    break StaticTermination::Converged;
                }
            }
            // Load control could not land (a limit point between): keep following.
        }
        previous = Some(increment);
        state = trial;
        lambda = trial_lambda;
        observe(&state, lambda, dl);
        lambda_max = lambda_max.max(lambda);
        steps.push(StepRecord {
            load_factor: lambda,
            iterations,
            residuals,
        });
        if (lambda - 1.0).abs() <= settings.tolerance {
            break StaticTermination::Converged;
        }
        if lambda < lambda_max - 1e-12 && lambda <= lambda0 {
            // The path has come back below its start: the limit load was passed
            // and the structure unloads.
            break StaticTermination::LimitPoint {
                limit_load_factor: lambda_max,
            };
        }
        let factor = (TARGET_ITERATIONS / iterations.max(1) as f64)
            .sqrt()
            .clamp(0.25, 2.0);
        arc = arc.map(|a| a * factor);
    };
    let termination = match termination {
        StaticTermination::MaxSteps { .. } | StaticTermination::Stalled { .. }
            if lambda_max > lambda + 1e-12 =>
        {
            StaticTermination::LimitPoint {
                limit_load_factor: lambda_max,
            }
        }
        t => t,
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
