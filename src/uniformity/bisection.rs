//! Quasi-convex ratio bisection (DESIGN §4): for a trial ratio `r`, is there a `q`
//! with `A q = p` (or `‖A q − p‖₂ ≤ ε`, an SOCP), `t_g ≤ ℓ_k q_k ≤ r t_g` for every
//! cable `k` of set `g`, `q ≤ [q]`, the first set's mean tension at its target,
//! the other sets' levels and the other cables' tensions at least
//! `min_tension_fraction · t_0`? Each trial is one clarabel solve; infeasibility is
//! read from clarabel's status. Handles several sets and nodal loads.

use std::time::Instant;

use super::conic::{infeasible, Class, Cone, ConicProgram};
use super::{Design, Termination, UniformityError, UniformityProblem, UniformitySolver};

/// Ratio bisection over LP (ε = 0) or SOCP (ε > 0) feasibility.
#[derive(Debug, Clone)]
pub struct Bisection {
    /// Allowed equilibrium residual `‖A q − p‖₂`, N (0: exact equilibrium, an LP).
    pub epsilon_n: f64,
    /// Stop when the bracket `[r_lo, r_hi]` is narrower than this × `r_hi`.
    pub relative_tolerance: f64,
    /// Largest ratio tried before the geometry is declared infeasible.
    pub max_ratio: f64,
    /// Most feasibility solves.
    pub max_iterations: usize,
}

impl Default for Bisection {
    fn default() -> Self {
        Bisection {
            epsilon_n: 0.0,
            relative_tolerance: 1e-8,
            max_ratio: 1e6,
            max_iterations: 200,
        }
    }
}

impl Bisection {
    /// The feasibility program for ratio `r`: variables `[q (m), t (sets)]`.
    fn trial(&self, problem: &UniformityProblem, r: f64) -> super::conic::ConicOutcome {
        let lengths = problem.lengths_m();
        let m = problem.network().n_edges();
        let sets = problem.sets();
        let level = |g: usize| m + g;
        let fraction = problem.min_tension_fraction;
        let mut program = ConicProgram::new(m + sets.len());
        program.equilibrium(problem, self.epsilon_n);
        // Pretension level: mean tension of the first set at its target.
        let first = &sets[0];
        let mean_row: Vec<(usize, f64)> = first
            .edges
            .iter()
            .map(|&k| (k, lengths[k] / first.edges.len() as f64))
            .collect();
        program.row(Cone::Zero, &mean_row, first.mean_tension_n);
        for (g, set) in sets.iter().enumerate() {
            for &k in &set.edges {
                program.row(Cone::Nonnegative, &[(k, -lengths[k]), (level(g), 1.0)], 0.0);
                program.row(Cone::Nonnegative, &[(k, lengths[k]), (level(g), -r)], 0.0);
            }
            if g > 0 {
                program.row(
                    Cone::Nonnegative,
                    &[(level(g), -1.0), (level(0), fraction)],
                    0.0,
                );
            } else {
                program.row(
                    Cone::Nonnegative,
                    &[(level(0), -1.0)],
                    -fraction * first.mean_tension_n,
                );
            }
        }
        for k in problem.other_edges() {
            program.row(
                Cone::Nonnegative,
                &[(k, -lengths[k]), (level(0), fraction)],
                0.0,
            );
        }
        for k in 0..m {
            program.row(
                Cone::Nonnegative,
                &[(k, 1.0)],
                problem.max_force_density_n_per_m,
            );
        }
        program.solve(&vec![0.0; m + sets.len()])
    }

    /// The largest set ratio of a trial solution.
    fn achieved_ratio(problem: &UniformityProblem, q: &[f64]) -> f64 {
        let lengths = problem.lengths_m();
        problem
            .sets()
            .iter()
            .map(|set| {
                let (lo, hi) = set
                    .edges
                    .iter()
                    .fold((f64::INFINITY, 0.0f64), |(lo, hi), &k| {
                        let t = lengths[k] * q[k];
                        (lo.min(t), hi.max(t))
                    });
                hi / lo
            })
            .fold(1.0, f64::max)
    }
}

impl UniformitySolver for Bisection {
    fn name(&self) -> &'static str {
        "bisection"
    }

    fn knob(&self) -> Option<f64> {
        Some(self.epsilon_n)
    }

    fn solve(&self, problem: &UniformityProblem) -> Result<Design, UniformityError> {
        let start = Instant::now();
        if !(self.epsilon_n >= 0.0 && self.epsilon_n.is_finite()) {
            return Err(UniformityError::Invalid(format!(
                "epsilon {} must be ≥ 0",
                self.epsilon_n
            )));
        }
        let m = problem.network().n_edges();
        let mut warnings = Vec::new();
        let mut iterations = 0;
        let mut best: Option<Vec<f64>> = None;
        let (mut lo, mut hi) = (1.0, 2.0);
        // Grow the bracket until a trial is feasible.
        while best.is_none() {
            if hi > self.max_ratio {
                return Err(infeasible(problem));
            }
            let outcome = self.trial(problem, hi);
            iterations += 1;
            warnings.extend(outcome.warning(&format!("ratio {hi:.6}")));
            match outcome.class {
                Class::Feasible => {
                    let q = outcome.x[..m].to_vec();
                    hi = Self::achieved_ratio(problem, &q).min(hi);
                    best = Some(q);
                }
                Class::Infeasible => {
                    lo = hi;
                    hi *= 4.0;
                }
                Class::Failed => {
                    return Err(UniformityError::SolverFailed {
                        solver: "bisection",
                        status: format!("at ratio {hi}: {}", outcome.status),
                    })
                }
            }
        }
        let mut termination = Termination::Converged;
        while hi - lo > self.relative_tolerance * hi {
            if iterations >= self.max_iterations {
                termination = Termination::MaxIterations;
                break;
            }
            let r = 0.5 * (lo + hi);
            let outcome = self.trial(problem, r);
            iterations += 1;
            warnings.extend(outcome.warning(&format!("ratio {r:.9}")));
            match outcome.class {
                Class::Feasible => {
                    let q = outcome.x[..m].to_vec();
                    hi = Self::achieved_ratio(problem, &q).clamp(lo, r);
                    best = Some(q);
                }
                Class::Infeasible => lo = r,
                Class::Failed => {
                    // Keep the bracket; the best feasible q stands.
                    warnings.push(format!(
                        "ratio {r:.9}: stopped, clarabel status {}",
                        outcome.status
                    ));
                    termination = Termination::NumericalError;
                    break;
                }
            }
        }
        let q = best.expect("a feasible trial was found");
        Design::evaluate(
            problem,
            self.name(),
            q,
            termination,
            iterations,
            start.elapsed(),
            warnings,
        )
    }
}
