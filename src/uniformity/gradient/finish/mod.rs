//! The exact finish ([`super::Gradient::exact_finish`]): sequential quadratic
//! programming on the objective the soft max/min smooths,
//!
//! $$J_{\text{exact}} = \frac{1}{n_s}\Big(\sum_i \frac{e_i^2}{ε^2} + λ_{\text{lay}}
//!   \sum_i \frac{d_i^2}{ε^2}\Big) + w \sum_g \ln\frac{T_{\max,g}}{T_{\min,g}}
//!   + κ \Big(\frac{\ln(\bar T_0/t_0)}{10^{-3}}\Big)^2 ,$$
//!
//! nonsmooth at every change of the cables at a set's extremes, where L-BFGS on
//! the smoothed objective spends its iterations. Each step linearises, about
//! the forward equilibrium `x(q)`, the equilibrium of the free nodes (eq. 2:
//! `δq_k u_k + q_k (δx_i − δx_j)` summed at each free node is zero), the
//! surface errors (Gauss–Newton) and `s_k = ln(T_k/t_g)`,
//!
//! $$δs_k = δq_k/q_k + u_k·(δx_i − δx_j)/ℓ_k^2 ,$$
//!
//! and solves the quadratic program in `(δq, δx, u_g, l_g)` (`model.rs`: `ē`
//! and `v` below are linear in them)
//!
//! $$\min\ \frac{1}{n_s ε^2}\Big(\sum ē^2 + λ_{\text{lay}}\sum (d + δx)^2\Big)
//!   \;+\; w \sum_g (u_g − l_g) \;+\; κ' (L + v)^2 \;+\; \frac12 \sum_k c_k p_k^2
//!   \quad\text{s.t.}\quad l_g ≤ s_k + δs_k ≤ u_g,$$
//!
//! the linearised equilibrium, `ē = e + ∇e·δx`, `v` the linearised change of
//! `ln T̄₀`, the box `f t₀/ℓ̂_k ≤ q_k + δq_k ≤ 0.99 [q]` (the barrier's) and the
//! trust region `|δq_k| ≤ r q_k` (`−min(4r, 0.9) q_k ≤ δq_k` for a cable
//! outside the sets). The max/min enter exactly, as the bounds
//! `u_g`, `l_g` of every cable of the set: the step sees which cables are at
//! the extremes, as `lp` does, and the geometry's reply to `δq` at once.
//! `p_k = δq_k/q_k`, and `c_k` is the curvature the linearisation leaves
//! out: `ln(1 + p) = p − p²/2`, weighted by the previous program's
//! multipliers of cable `k`'s rows (the Lagrangian's Hessian of sequential
//! quadratic programming, `ipm::add_log_curvature`; zero at the first step).
//! Without it the model is linear along the extremes: on a 38 876-node net
//! every other step ran to the trust radius, lost `≈ p²/2` on the lowest
//! tensions and was rejected (26 programs, J still 2e-3 above the end);
//! with it the model predicts each decrease to 1 % and no step is refused
//! (15 programs to the certificate, 6 with the reach of
//! [`FinishSettings::outside_reach`]; 4 on 10⁴ nodes, as before).
//!
//! The step is taken on `q` alone (the geometry follows by a forward solve)
//! when `J_exact` falls by more than a tenth of the decrease the model
//! predicts; the radius doubles (to at most ½) when the model predicts well
//! (three quarters of it) and shrinks ×4 when it does not. The finish has
//! converged when the model predicts a decrease of at most
//! [`FinishSettings::tolerance`]`·J`: no step of the linearised problem
//! lowers `J_exact` further, a stationarity certificate of the nonsmooth
//! problem that does not depend on the net's size.
//!
//! A step that falls short of three quarters is first corrected
//! ([`FinishSettings::second_order_correction`]): the tensions at the trial
//! say what the linearised `s_k + δs_k` missed (the bilinear `δq δx` of
//! equilibrium, the second order of `ℓ_k` — the model's `ln(Tmax/Tmin)` was
//! 1e-3 off at a radius of 0.05 on the jittered grid), the program is
//! solved again about the same point with each set row's `s_k` shifted by
//! that miss, and the better of the two trials is judged against the first
//! prediction: the second-order correction of SQP against the Maratos
//! effect, where the linearised max/min refuses steps that lower `J`. On
//! the jittered grid most corrected trials met their prediction to a few
//! per cent (0.93–1.06 of it, where the first trials had met −2…0.7). A
//! corrected trial that meets three quarters of the prediction doubles the
//! radius like any other: the step, not the model, is what is judged. The
//! correction's multipliers replace the step's only with its trial.
//!
//! The program is solved by the crate's interior point (`uniformity/ipm`)
//! on its structure (`ipm.rs`, with the Newton systems reduced to the node
//! graph in `kkt.rs`, settings [`IpmSettings::finish`]): 6–10
//! iterations of one sparse LDLᵀ of `6 n_free` unknowns a program on the
//! hexagonal and sector nets of issue 38, warm from the previous step's
//! multipliers, 17–24 on the jittered one — 7–13× faster than clarabel on
//! the program stated generically (measured when programs took 5–11). clarabel remains the fallback, and the
//! cross-check of the tests; a program neither solves ([`ProgramFailed`])
//! ends the finish as `Stalled`, with both reasons in a warning. Either
//! solver's point is made feasible before its value is read
//! ([`StepModel::feasible_point`]).
//!
//! The trust region and the stopping test are [`FinishSettings`]
//! (`Gradient::finish`).

mod ipm;
mod kkt;
mod model;

use super::objective::{pretension_level, Objective};
use super::settings::FinishSettings;
use crate::fdm::{Equilibrium, NONE};
use crate::status::Termination;
use crate::uniformity::ipm::IpmSettings;
use crate::uniformity::{SurfaceTarget, UniformityError};
use ipm::ProgramError;
use model::{Cable, ClarabelFailed, ErrorRow, StepModel};

/// Neither the interior point nor clarabel solved a step's program.
#[derive(Debug, thiserror::Error)]
#[error("interior point: {interior}; {clarabel}")]
struct ProgramFailed {
    /// Why the interior point stopped short.
    interior: ProgramError,
    /// Why clarabel did.
    clarabel: ClarabelFailed,
}

/// The step's optimum `z` at a feasible point (see
/// [`StepModel::feasible_point`]): the structured interior point
/// (`ipm.rs`) with `program`, warm from the previous step's `multipliers`
/// and leaving its own there, its iterations added to `iterations`;
/// clarabel where it fails (said in `warnings`).
///
/// # Errors
/// Both failed: each one's reason.
#[allow(clippy::too_many_arguments)]
fn solve(
    model: &StepModel,
    eq: &Equilibrium,
    program: &IpmSettings,
    multipliers: &mut Option<Vec<f64>>,
    iterations: &mut usize,
    step: usize,
    warnings: &mut Vec<String>,
) -> Result<Vec<f64>, ProgramFailed> {
    let z = match ipm::solve(model, multipliers.as_deref(), true, program) {
        Ok(solved) => {
            *multipliers = Some(solved.lambda);
            *iterations += solved.iterations;
            solved.z
        }
        Err(interior) => match model.solve_with_clarabel() {
            Ok(z) => {
                warnings.push(format!(
                    "the exact finish's interior point failed at step {step} ({interior}); \
                     clarabel solved the program"
                ));
                z
            }
            Err(clarabel) => return Err(ProgramFailed { interior, clarabel }),
        },
    };
    Ok(model.feasible_point(&z, |rhs| eq.solve_d(rhs)))
}

/// Agreement (the decrease over the predicted one) above which a step is
/// taken.
const ACCEPTED_AGREEMENT: f64 = 0.1;

/// Agreement above which the model predicts well: the trust radius doubles.
/// Below it a step is corrected (where [`FinishSettings::second_order_correction`]).
const GOOD_AGREEMENT: f64 = 0.75;

/// What the finish returns.
pub(super) struct Finished {
    /// The last accepted force densities.
    pub(super) q: Vec<f64>,
    /// `J_exact` there.
    pub(super) objective: f64,
    /// Quadratic programs solved for the steps.
    pub(super) steps: usize,
    /// Programs solved again as second-order corrections.
    pub(super) corrections: usize,
    /// Interior-point iterations of all programs, corrections included
    /// (clarabel's not counted).
    pub(super) interior_iterations: usize,
    pub(super) termination: Termination,
    pub(super) warnings: Vec<String>,
}

/// Sequential QP steps on `J_exact` from `q0` with the trust region and the
/// stopping test of `settings` (see the module documentation; checked by
/// [`FinishSettings::validate`] with the solver's settings), each program
/// solved with `program` ([`IpmSettings::finish`]).
pub(super) fn finish(
    objective: &Objective,
    q0: &[f64],
    settings: &FinishSettings,
    program: &IpmSettings,
) -> Result<Finished, UniformityError> {
    let exact = objective.exact();
    let mut q = q0.to_vec();
    let mut j = exact.evaluate_q(&q)?.0;
    let mut radius = settings.first_radius;
    let mut warnings = Vec::new();
    let mut steps = 0;
    let mut multipliers = None;
    let mut interior_iterations = 0;
    let mut corrections = 0;
    let termination = loop {
        if steps == settings.max_steps {
            warnings.push(format!(
                "the exact finish did not converge in {} steps",
                settings.max_steps
            ));
            break Termination::MaxIterations;
        }
        steps += 1;
        let (mut model, eq) = step_model(objective, &q, radius, settings)?;
        if let Some(lambda) = multipliers.as_deref() {
            ipm::add_log_curvature(&mut model, lambda);
        }
        let z = match solve(
            &model,
            &eq,
            program,
            &mut multipliers,
            &mut interior_iterations,
            steps,
            &mut warnings,
        ) {
            Ok(z) => z,
            Err(failed) => {
                warnings.push(format!(
                    "the exact finish stopped: its quadratic program failed at step {steps} \
                     ({failed})"
                ));
                break Termination::Stalled;
            }
        };
        let predicted = j - model.value(&z);
        if predicted <= settings.tolerance * j.abs() {
            break Termination::Converged;
        }
        // A trial whose forward solve fails is a rejected step.
        let evaluate = |trial: &[f64]| exact.evaluate_q(trial).map_or(f64::INFINITY, |(v, _)| v);
        let mut trial = model.force_densities(&q, &z);
        let mut j_trial = evaluate(&trial);
        if settings.second_order_correction && j - j_trial < GOOD_AGREEMENT * predicted {
            if let Some(corrected) = corrected_step(objective, &model, &z, &trial) {
                let mut corrected_multipliers = multipliers.clone();
                match solve(
                    &corrected,
                    &eq,
                    program,
                    &mut corrected_multipliers,
                    &mut interior_iterations,
                    steps,
                    &mut warnings,
                ) {
                    Ok(z) => {
                        corrections += 1;
                        let second = corrected.force_densities(&q, &z);
                        let j_second = evaluate(&second);
                        if j_second < j_trial {
                            (trial, j_trial) = (second, j_second);
                            multipliers = corrected_multipliers;
                        }
                    }
                    Err(failed) => warnings.push(format!(
                        "the exact finish's second-order correction failed at step {steps} \
                         ({failed})"
                    )),
                }
            }
        }
        let agreement = (j - j_trial) / predicted;
        if agreement > ACCEPTED_AGREEMENT {
            q = trial;
            j = j_trial;
            if agreement > GOOD_AGREEMENT {
                radius = (2.0 * radius).min(settings.max_radius);
            }
        } else {
            radius *= 0.25;
            if radius < settings.min_radius {
                warnings.push(format!(
                    "the exact finish stopped: no step within the trust radius lowers J \
                     (the model predicts {predicted:.2e})"
                ));
                break Termination::Stalled;
            }
        }
    };
    Ok(Finished {
        q,
        objective: j,
        steps,
        corrections,
        interior_iterations,
        termination,
        warnings,
    })
}

/// The program of a second-order correction of the step `z` whose force
/// densities `trial` fell short of the decrease `model` predicted (see the
/// module documentation): `model` with each set row's `s_k` shifted by what
/// its linearisation missed at the trial, `ln(T_k(trial)/t_g) − (s_k +
/// δs_k(z))`, about the same point. `None` when the trial has no forward
/// solve (its `J` is then already infinite) or a set cable without tension
/// there.
fn corrected_step(
    objective: &Objective,
    model: &StepModel,
    z: &[f64],
    trial: &[f64],
) -> Option<StepModel> {
    let problem = objective.problem;
    let reached = problem.forward(trial).ok()?;
    let mut corrected = model.clone();
    for (set, members) in problem.sets().iter().zip(corrected.sets.iter_mut()) {
        for (k, s) in members.iter_mut() {
            let at_trial = (reached.edges_forces_n[*k] / set.mean_tension_n).ln();
            if !at_trial.is_finite() {
                return None;
            }
            *s = at_trial - model.delta_s(*k, z);
        }
    }
    Some(corrected)
}

/// The quadratic model of `J_exact` about `q` with the trust radius `radius`
/// (a cable outside the sets falling as far as `settings` lets it).
fn step_model(
    objective: &Objective,
    q: &[f64],
    radius: f64,
    settings: &FinishSettings,
) -> Result<(StepModel, Equilibrium), UniformityError> {
    let problem = objective.problem;
    let structure = problem.structure();
    let design = &problem.network().nodes;
    let eq = problem.forward(q)?;
    let x = &eq.nodes_xyz_m;
    let tensions = &eq.edges_forces_n;
    let free = |i: usize| structure.free_index(i).unwrap_or(NONE);
    let n_free = structure.free_nodes().len();
    let mut row_sum = vec![0.0; n_free];
    let mut in_set = vec![false; q.len()];
    for set in problem.sets() {
        for &k in &set.edges {
            in_set[k] = true;
        }
    }
    let cables: Vec<Cable> = structure
        .edges()
        .iter()
        .enumerate()
        .map(|(k, &[a, b])| {
            let ends = [free(a), free(b)];
            for &f in &ends {
                if f != NONE {
                    row_sum[f] += q[k];
                }
            }
            let u = eq.edges_vectors_m[k];
            let l2 = eq.edges_lengths_m[k].powi(2);
            let reach = radius * q[k];
            let fall = if in_set[k] {
                reach
            } else {
                (settings.outside_reach * radius).min(settings.max_fall) * q[k]
            };
            let lo = (objective.q_low[k] - q[k]).clamp(-fall, reach);
            let hi = (objective.q_high - q[k]).clamp(lo, reach);
            Cable {
                ends,
                q: q[k],
                u,
                g: u.map(|c| c / l2),
                lo: lo / q[k],
                hi: hi / q[k],
                curvature: 0.0,
            }
        })
        .collect();

    // Surface errors ē = e + ∇e·ξ, and the layout drift.
    let mut errors = Vec::new();
    let mut drifts = Vec::new();
    let drift = |i: usize, d: usize| (3 * free(i) + d, x[i][d] - design[i][d]);
    for &i in problem.surface_nodes() {
        let point = x[i];
        match problem.surface() {
            SurfaceTarget::Paraboloid(parab) => {
                let two_f = 2.0 * parab.focal_length_m;
                errors.push(ErrorRow {
                    node: free(i),
                    gradient: [-point[0] / two_f, -point[1] / two_f, 1.0],
                    value: parab.axial_deviation(point),
                });
                if free(i) != NONE {
                    drifts.extend((0..2).map(|d| drift(i, d)));
                }
            }
            SurfaceTarget::Prescribed => {
                for d in 0..3 {
                    let mut gradient = [0.0; 3];
                    gradient[d] = 1.0;
                    errors.push(ErrorRow {
                        node: free(i),
                        gradient,
                        value: point[d] - design[i][d],
                    });
                }
            }
        }
    }
    for &i in &objective.other_free {
        if free(i) != NONE {
            drifts.extend((0..3).map(|d| drift(i, d)));
        }
    }
    let drift_weight = objective.layout_weight * objective.surface_scale;
    if drift_weight == 0.0 {
        drifts.clear();
    }

    // The level v = Σ_k T_k δs_k / (n₀ T̄₀) of the first set.
    let sets = problem.sets();
    let first = &sets[0];
    let n0 = first.edges.len() as f64;
    let (mean, level) = pretension_level(problem, tensions);
    let model = StepModel {
        cables,
        n_free,
        row_scale: row_sum
            .iter()
            .map(|&s| if s > 0.0 { 1.0 / s } else { 1.0 })
            .collect(),
        errors,
        error_weight: objective.surface_scale,
        drifts,
        drift_weight,
        sets: sets
            .iter()
            .map(|set| {
                set.edges
                    .iter()
                    .map(|&k| (k, (tensions[k] / set.mean_tension_n).ln()))
                    .collect()
            })
            .collect(),
        weight: objective.weight,
        level_terms: first
            .edges
            .iter()
            .map(|&k| (k, tensions[k] / (n0 * mean)))
            .collect(),
        level_weight: objective.level_weight,
        level,
    };
    Ok((model, eq))
}

#[cfg(test)]
mod tests;
