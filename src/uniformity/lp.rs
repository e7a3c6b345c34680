//! The baseline: the single-set homogeneous problem as one LP,
//! `min s` s.t. `A q = 0`, `1 ≤ ℓ_k q_k ≤ s` (k in the set), others
//! `ℓ_k q_k ≥ f` (f = `min_tension_fraction`), then rescaled to the target mean.

use std::time::Instant;

use super::conic::{infeasible, Class, Cone, ConicProgram};
use super::{Design, Termination, UniformityError, UniformityProblem, UniformitySolver};

/// One LP, rescaled. Needs a homogeneous problem (no loads) with one set; the
/// bound `[q]` is checked after rescaling.
#[derive(Debug, Clone, Default)]
pub struct Lp;

impl UniformitySolver for Lp {
    fn name(&self) -> &'static str {
        "lp"
    }

    fn solve(&self, problem: &UniformityProblem) -> Result<Design, UniformityError> {
        let start = Instant::now();
        if problem.has_loads() {
            return Err(UniformityError::Unsupported {
                solver: "lp",
                reason: "the problem carries loads, so it is not scale-free; use `bisection`"
                    .into(),
            });
        }
        if problem.sets().len() != 1 {
            return Err(UniformityError::Unsupported {
                solver: "lp",
                reason: format!(
                    "{} uniformity sets; `lp` takes one, use `bisection`",
                    problem.sets().len()
                ),
            });
        }
        let set = &problem.sets()[0];
        let lengths = problem.lengths_m();
        let m = problem.network().n_edges();
        let s = m;
        let mut program = ConicProgram::new(m + 1);
        program.equilibrium(problem, 0.0);
        for &k in &set.edges {
            program.row(Cone::Nonnegative, &[(k, -lengths[k])], -1.0);
            program.row(Cone::Nonnegative, &[(k, lengths[k]), (s, -1.0)], 0.0);
        }
        for k in problem.other_edges() {
            program.row(
                Cone::Nonnegative,
                &[(k, -lengths[k])],
                -problem.min_tension_fraction,
            );
        }
        let mut c = vec![0.0; m + 1];
        c[s] = 1.0;
        let outcome = program.solve(&c);
        match outcome.class {
            Class::Feasible => {}
            Class::Infeasible => return Err(infeasible(problem)),
            Class::Failed => {
                return Err(UniformityError::SolverFailed {
                    solver: "lp",
                    status: outcome.status,
                })
            }
        }
        let mean: f64 = set
            .edges
            .iter()
            .map(|&k| lengths[k] * outcome.x[k])
            .sum::<f64>()
            / set.edges.len() as f64;
        let scale = set.mean_tension_n / mean;
        let q: Vec<f64> = outcome.x[..m].iter().map(|v| v * scale).collect();
        let q_max = q.iter().copied().fold(0.0, f64::max);
        if q_max > problem.max_force_density_n_per_m {
            return Err(UniformityError::Unsupported {
                solver: "lp",
                reason: format!(
                    "the optimum needs q = {q_max:.4e} N/m, above the bound {:.4e} N/m; \
                     `bisection` enforces the bound",
                    problem.max_force_density_n_per_m
                ),
            });
        }
        let warnings = outcome.warning("lp").into_iter().collect();
        Design::evaluate(
            problem,
            self.name(),
            q,
            Termination::Converged,
            outcome.iterations,
            start.elapsed(),
            warnings,
        )
    }
}
