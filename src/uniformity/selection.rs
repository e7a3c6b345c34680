//! A unique design among the ratio-optimal ones.
//!
//! The min-ratio programs (`lp`, `bisection`) fix only the extreme tensions of
//! a set: their optimum is a face, and which point of it an interior-point
//! method returns jumps with the geometry (measured on `small-hex`: a 1e-8 m
//! move of one hinge changes `q` by 3 % and the pull on the truss by 25 N).
//! The outer design loop needs the pull to be a function of the boundary, so
//! it asks for the design closest to uniform tension within the ratio bound:
//!
//! ```text
//! min ½ Σ_sets Σ_k (ℓ_k q_k − T̄_s)² + ½ δ Σ_others (ℓ_k q_k)²
//! s.t. A q = p,  mean_k∈s₁ ℓ_k q_k = T̄_s₁,  t_s ≤ ℓ_k q_k ≤ r_s t_s (k in set s),
//!      ℓ_k q_k ≥ τ (others),  0 < q ≤ [q],
//! ```
//!
//! strictly convex in the tensions, hence unique, and continuous in the
//! geometry for `r_s` above the optimal ratio (clarabel, one QP). The first
//! set's mean tension is held at its target, as the ratio solvers hold it.

use std::time::Instant;

use super::conic::{infeasible_design, Class, Cone, ConicProgram};
use super::{Design, Termination, UniformityError, UniformityProblem};

/// Weight of the cables outside every set, relative to the set cables.
const OTHER_WEIGHT: f64 = 1e-6;

/// The design closest to uniform tension with every set's ratio at most
/// `ratio_bounds[s]` (one per set, each ≥ that set's optimal ratio).
///
/// A bound below the optimum, or a geometry without strictly positive
/// equilibria, is a design with [`Termination::Infeasible`] (the reason in its
/// warnings, see [`Design::feasible`]).
///
/// # Errors
/// A solver failure.
///
/// # Panics
/// If `ratio_bounds` does not have one entry per set.
#[track_caller]
pub fn most_uniform(
    problem: &UniformityProblem,
    solver: &str,
    ratio_bounds: &[f64],
) -> Result<Design, UniformityError> {
    assert_eq!(
        ratio_bounds.len(),
        problem.sets().len(),
        "one bound per set"
    );
    let start = Instant::now();
    let lengths = problem.lengths_m();
    let m = problem.network().n_edges();
    let n_sets = problem.sets().len();
    let mut program = ConicProgram::new(m + n_sets);
    program.equilibrium(problem, 0.0);
    // Pretension level, as the ratio solvers hold it. Without it the
    // objective pulls the level below the target by `(mean T)²/mean(T²)` —
    // half of it at a ratio of 16.
    program.first_set_mean_tension(problem);
    let mut p = vec![0.0; m];
    let mut c = vec![0.0; m + n_sets];
    for (s, (set, &r)) in problem.sets().iter().zip(ratio_bounds).enumerate() {
        let t = m + s;
        for &k in &set.edges {
            let l = lengths[k];
            program.row(Cone::Nonnegative, &[(k, -l), (t, 1.0)], 0.0);
            program.row(Cone::Nonnegative, &[(k, l), (t, -r)], 0.0);
            p[k] += l * l;
            c[k] -= l * set.mean_tension_n;
        }
    }
    let floor = problem.min_other_tension_n();
    for k in problem.other_edges() {
        program.row(Cone::Nonnegative, &[(k, -lengths[k])], -floor);
        p[k] += OTHER_WEIGHT * lengths[k] * lengths[k];
    }
    if problem.max_force_density_n_per_m.is_finite() {
        for k in 0..m {
            program.row(
                Cone::Nonnegative,
                &[(k, 1.0)],
                problem.max_force_density_n_per_m,
            );
        }
    }
    let outcome = program.solve_quadratic(&p, &c);
    match outcome.class {
        Class::Feasible => {
            let warnings = outcome.warning(solver).into_iter().collect();
            Design::evaluate(
                problem,
                solver,
                outcome.x[..m].to_vec(),
                Termination::Converged,
                outcome.iterations,
                start.elapsed(),
                warnings,
            )
        }
        Class::Infeasible => {
            let warnings = outcome.warning(solver).into_iter().collect();
            infeasible_design(problem, solver, outcome.iterations, start, warnings)
        }
        Class::Failed => Err(UniformityError::SolverFailed {
            solver: "most-uniform selection",
            status: outcome.status,
        }),
    }
}
