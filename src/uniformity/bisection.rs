//! Quasi-convex ratio bisection (DESIGN §4): for a trial ratio `r`, is there a `q`
//! with `A q = p` (or `‖A q − p‖₂ ≤ ε`, an SOCP), `t_g ≤ ℓ_k q_k ≤ r t_g` for every
//! cable `k` of set `g`, `q ≤ [q]`, the first set's mean tension at its target,
//! the other sets' levels and the other cables' tensions at least
//! `min_tension_fraction · t_0`? Handles several sets and nodal loads.
//!
//! Each trial is one clarabel solve of the *elastic* form: `min σ` with the upper
//! ratio bound relaxed to `ℓ_k q_k ≤ r t_g + σ T̄_0`. It is strictly feasible and
//! bounded whenever a positive equilibrium exists, so the interior-point method
//! stays well conditioned right at the optimal ratio (a plain feasibility problem
//! degenerates there); the trial ratio is feasible iff `σ* ≤ 0`. A geometry with
//! no strictly positive equilibrium makes the elastic form itself infeasible,
//! which clarabel's status reports at the first trial: the design is then
//! [`Termination::Infeasible`], its warnings naming the slack nodes.

use std::time::Instant;

use super::conic::{infeasible_design, Class, Cone, ConicProgram};
use super::{Design, KnobRange, Termination, UniformityError, UniformityProblem, UniformitySolver};

/// What one trial of a ratio says.
enum Trial {
    /// The ratio is attainable: the trial's `q`.
    Feasible(Vec<f64>),
    /// The ratio is below the optimum.
    TooLow,
    /// No strictly positive `q` balances the geometry at any ratio.
    NoPositiveEquilibrium,
}

/// Ratio bisection over LP (ε = 0) or SOCP (ε > 0) feasibility.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
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
    /// Checks the settings.
    ///
    /// # Errors
    /// [`UniformityError::Setting`] naming the first field out of its range.
    pub fn validate(&self) -> Result<(), UniformityError> {
        let bad = |name: &'static str, value: f64, range: &'static str| {
            Err(UniformityError::Setting {
                solver: "bisection",
                name,
                value,
                range,
            })
        };
        if !(self.epsilon_n >= 0.0 && self.epsilon_n.is_finite()) {
            return bad("epsilon_n", self.epsilon_n, "finite and ≥ 0");
        }
        if !(self.relative_tolerance > 0.0 && self.relative_tolerance < 1.0) {
            return bad("relative_tolerance", self.relative_tolerance, "in (0, 1)");
        }
        if !(self.max_ratio > 1.0 && self.max_ratio.is_finite()) {
            return bad("max_ratio", self.max_ratio, "finite and > 1");
        }
        if self.max_iterations == 0 {
            return bad("max_iterations", 0.0, "≥ 1");
        }
        Ok(())
    }

    /// The elastic program for ratio `r`: variables `[q (m), t (sets), σ]`.
    fn trial(&self, problem: &UniformityProblem, r: f64) -> super::conic::ConicOutcome {
        let lengths = problem.lengths_m();
        let m = problem.network().n_edges();
        let sets = problem.sets();
        let level = |g: usize| m + g;
        let sigma = m + sets.len();
        let scale = sets[0].mean_tension_n;
        let fraction = problem.min_tension_fraction;
        let mut program = ConicProgram::new(m + sets.len() + 1);
        program.equilibrium(problem, self.epsilon_n);
        program.first_set_mean_tension(problem);
        for (g, set) in sets.iter().enumerate() {
            for &k in &set.edges {
                program.row(Cone::Nonnegative, &[(k, -lengths[k]), (level(g), 1.0)], 0.0);
                program.row(
                    Cone::Nonnegative,
                    &[(k, lengths[k]), (level(g), -r), (sigma, -scale)],
                    0.0,
                );
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
                    -fraction * sets[0].mean_tension_n,
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
        let mut c = vec![0.0; m + sets.len() + 1];
        c[sigma] = 1.0;
        program.solve(&c)
    }

    /// Runs the trial of ratio `r`.
    fn feasible(
        &self,
        problem: &UniformityProblem,
        r: f64,
        iterations: &mut usize,
        warnings: &mut Vec<String>,
    ) -> Result<Trial, UniformityError> {
        let m = problem.network().n_edges();
        let outcome = self.trial(problem, r);
        *iterations += 1;
        warnings.extend(outcome.warning(&format!("ratio {r:.9}")));
        match outcome.class {
            Class::Feasible => {
                let sigma = outcome.x[m + problem.sets().len()];
                Ok(if sigma <= 0.0 {
                    Trial::Feasible(outcome.x[..m].to_vec())
                } else {
                    Trial::TooLow
                })
            }
            Class::Infeasible => Ok(Trial::NoPositiveEquilibrium),
            Class::Failed => Err(UniformityError::SolverFailed {
                solver: "bisection",
                status: format!("at ratio {r}: {}", outcome.status),
            }),
        }
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

    fn unique_design(&self) -> bool {
        false
    }

    /// ε = 0 (exact equilibrium), then ε from 1e-3·T̄ to T̄ (N), `T̄` the
    /// first set's target mean tension.
    fn knob_range(&self, problem: &UniformityProblem) -> Option<KnobRange> {
        let level = problem.sets()[0].mean_tension_n;
        Some(KnobRange {
            name: "epsilon_n",
            exact: Some(0.0),
            low: 1e-3 * level,
            high: level,
        })
    }

    fn solve(&self, problem: &UniformityProblem) -> Result<Design, UniformityError> {
        let start = Instant::now();
        self.validate()?;
        let mut warnings = Vec::new();
        let mut iterations = 0;
        let (mut lo, mut hi) = (1.0, 2.0);
        // Grow the bracket until a trial is feasible.
        let mut best = loop {
            match self.feasible(problem, hi, &mut iterations, &mut warnings)? {
                Trial::Feasible(q) => {
                    hi = Self::achieved_ratio(problem, &q).min(hi);
                    break q;
                }
                Trial::TooLow => {}
                Trial::NoPositiveEquilibrium => {
                    return infeasible_design(problem, self.name(), iterations, start, warnings)
                }
            }
            lo = hi;
            hi *= 4.0;
            if hi > self.max_ratio {
                return Err(UniformityError::RatioLimit {
                    max_ratio: self.max_ratio,
                });
            }
        };
        let mut termination = Termination::Converged;
        while hi - lo > self.relative_tolerance * hi {
            if iterations >= self.max_iterations {
                termination = Termination::MaxIterations;
                break;
            }
            let r = 0.5 * (lo + hi);
            match self.feasible(problem, r, &mut iterations, &mut warnings)? {
                Trial::Feasible(q) => {
                    hi = Self::achieved_ratio(problem, &q).clamp(lo, r);
                    best = q;
                }
                Trial::TooLow => lo = r,
                Trial::NoPositiveEquilibrium => {
                    return infeasible_design(problem, self.name(), iterations, start, warnings)
                }
            }
        }
        let q = best;
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
