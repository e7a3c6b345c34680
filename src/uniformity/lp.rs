//! The baseline: the single-set homogeneous problem as one LP,
//! `min s` s.t. `A q = 0`, `1 ≤ ℓ_k q_k ≤ s` (k in the set), others
//! `ℓ_k q_k ≥ f` (f = `min_tension_fraction`), then rescaled to the target mean.
//!
//! A tied net's problem (`plan.rs`: the uniformity set's net, each free net
//! node on one vertical tie to a fixed anchor or a mirrored rear net) is solved
//! as its plan problem by the structured interior-point method (`ipm/`) and
//! completed with the ties and the rear net; should the method stop short,
//! clarabel (QDLDL) solves the same plan problem. Any other network, or a plan
//! optimum that does not complete, goes to clarabel on the full problem. The
//! design says which ([`Route`]) and, for every route but the first, why in
//! its warnings. A geometry with no strictly positive equilibrium makes the
//! LP infeasible: the design is then [`Termination::Infeasible`], its
//! warnings naming the slack nodes.

use std::sync::Arc;
use std::time::Instant;

use super::conic::{infeasible_design, Class, Cone, ConicProgram};
use super::ipm::{self, IpmError, IpmSettings, WarmStart};
use super::plan::{CompletionError, PlanReduction};
use super::{Design, Route, Termination, UniformityError, UniformityProblem, UniformitySolver};

/// clarabel's backends for the plan problem: QDLDL first (measured on a
/// 9 913-node tied net: 5.2 s against faer's 12.4 s), faer with stronger
/// regularisation on a numerical failure.
const PLAN_ATTEMPTS: [(&str, f64); 2] = [("qdldl", 1e-8), ("faer", 1e-7)];

/// One LP, rescaled. Needs a homogeneous problem (no loads) with one set; the
/// bound `[q]` is checked after rescaling.
#[derive(Debug, Clone, Default)]
pub struct Lp;

impl UniformitySolver for Lp {
    fn name(&self) -> &'static str {
        "lp"
    }

    /// The optimum is a face, but every route is an interior-point method
    /// run to a small gap, whose iterates follow the central path to the
    /// analytic centre of the optimal face: a unique point, continuous in
    /// the geometry (measured: the pull moves linearly with the boundary from
    /// 1e-8 to 1e-4 m, `tests/design.rs`; the outer loop converges in the
    /// same iterations as with the most-uniform selection on every shipped
    /// scene, and super-60m's loop takes 7 s instead of 61 s). A solve from
    /// a neighbouring design ([`UniformitySolver::solve_from`]) follows the
    /// central path from the neighbour's iterate at a gap of 1e-5, where
    /// the two LPs' paths are micrometres apart, to the same face.
    fn unique_design(&self) -> bool {
        true
    }

    fn solve(&self, problem: &UniformityProblem) -> Result<Design, UniformityError> {
        self.solve_warm(problem, None)
    }

    /// Starts the plan interior point from `start`'s kept iterate (the
    /// previous outer iteration's LP, see [`WarmStart`]) when it has one,
    /// with that LP's symbolic analysis of the normal matrix.
    fn solve_from(
        &self,
        problem: &UniformityProblem,
        start: &Design,
    ) -> Result<Design, UniformityError> {
        self.solve_warm(problem, start.warm_start.as_deref())
    }
}

impl Lp {
    /// [`UniformitySolver::solve`], the plan interior point from `warm`
    /// when given.
    fn solve_warm(
        &self,
        problem: &UniformityProblem,
        warm: Option<&WarmStart>,
    ) -> Result<Design, UniformityError> {
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
        let mut warnings = Vec::new();
        let Routed {
            q,
            iterations,
            route,
            kept,
        } = solve_routes(problem, warm, &mut warnings)?;
        let Some(q) = q else {
            let mut design = infeasible_design(problem, self.name(), iterations, start, warnings)?;
            design.route = Some(route);
            return Ok(design);
        };
        let mean: f64 =
            set.edges.iter().map(|&k| lengths[k] * q[k]).sum::<f64>() / set.edges.len() as f64;
        let scale = set.mean_tension_n / mean;
        let q: Vec<f64> = q.iter().map(|v| v * scale).collect();
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
        let mut design = Design::evaluate(
            problem,
            self.name(),
            q,
            Termination::Converged,
            iterations,
            start.elapsed(),
            warnings,
        )?;
        design.route = Some(route);
        design.warm_start = kept.map(Arc::new);
        Ok(design)
    }
}

/// What the routes found: unscaled `q` (`None`: infeasible), iterations,
/// the route taken, and what the plan interior point keeps for a
/// neighbouring LP (its iterate, its normal matrix's analysis).
struct Routed {
    q: Option<Vec<f64>>,
    iterations: usize,
    route: Route,
    kept: Option<WarmStart>,
}

/// The plan route when the problem is a tied net (its interior point from
/// `warm` when given), with its fallbacks; every fallback leaves its reason
/// in `warnings`.
fn solve_routes(
    problem: &UniformityProblem,
    warm: Option<&WarmStart>,
    warnings: &mut Vec<String>,
) -> Result<Routed, UniformityError> {
    let routed = |(q, iterations), route| Routed {
        q,
        iterations,
        route,
        kept: None,
    };
    let plan = match PlanReduction::new(problem) {
        Ok(plan) => plan,
        Err(reason) => {
            warnings.push(format!(
                "lp: not a tied net's plan problem ({reason}); solved the full 3-D LP"
            ));
            return Ok(routed(solve_full(problem, warnings)?, Route::FullClarabel));
        }
    };
    let fallback = match solve_plan(&plan, problem, warm, warnings) {
        Ok((q, iterations, kept)) => {
            return Ok(Routed {
                q: Some(q),
                iterations,
                route: Route::PlanInteriorPoint,
                kept,
            })
        }
        Err(fallback) => fallback,
    };
    if let PlanFallback::Completion(reason) = fallback {
        warnings.push(format!("lp: {reason}; solved the full 3-D LP"));
        return Ok(routed(solve_full(problem, warnings)?, Route::FullClarabel));
    }
    warnings.push(format!(
        "lp: {fallback}; solved the plan LP with clarabel (QDLDL)"
    ));
    let (q_net, iterations) = match solve_plan_clarabel(&plan, warnings)? {
        (Some(q), iterations) => (q, iterations),
        // The plan LP relaxes the full one: the full LP is infeasible too.
        (None, iterations) => return Ok(routed((None, iterations), Route::PlanClarabel)),
    };
    match plan.complete(problem, &q_net) {
        Ok(q) => Ok(routed((Some(q), iterations), Route::PlanClarabel)),
        Err(reason) => {
            warnings.push(format!("lp: {reason}; solved the full 3-D LP"));
            let (q, more) = solve_full(problem, warnings)?;
            Ok(routed((q, iterations + more), Route::FullClarabel))
        }
    }
}

/// Why the plan path gave way to the full problem.
#[derive(Debug, thiserror::Error)]
enum PlanFallback {
    /// The interior-point method could not start.
    #[error(transparent)]
    Setup(#[from] IpmError),
    /// The interior-point method stopped short of its tolerance.
    #[error(
        "the plan interior-point method stopped with {termination:?} (relative primal residual \
         {:.1e}, dual {:.1e}, gap {:.1e})",
        .residuals[0],
        .residuals[1],
        .residuals[2]
    )]
    Stopped {
        /// How it stopped.
        termination: Termination,
        /// Relative primal residual, dual residual and gap.
        residuals: [f64; 3],
    },
    /// The completion is not the full optimum.
    #[error(transparent)]
    Completion(#[from] CompletionError),
}

/// The plan problem (interior point, `plan.rs`, from `warm` when given),
/// completed with the ties and the rear net: unscaled `q`, iterations, and
/// what it keeps for the next neighbouring LP. A warm start that does not
/// converge (stalled included) is said in `warnings` and the LP solved again
/// from its own start.
fn solve_plan(
    plan: &PlanReduction,
    problem: &UniformityProblem,
    warm: Option<&WarmStart>,
    warnings: &mut Vec<String>,
) -> Result<(Vec<f64>, usize, Option<WarmStart>), PlanFallback> {
    let settings = IpmSettings::plan();
    let mut solution = ipm::solve(plan.lp(), &settings, warm)?;
    if warm.is_some_and(WarmStart::has_iterate) && solution.termination != Termination::Converged {
        warnings.push(format!(
            "lp: the plan interior point from the neighbouring design's iterate stopped with \
             {:?} after {} iterations; solved again from its own start",
            solution.termination, solution.iterations
        ));
        let more = solution.iterations;
        let analysis = warm.map(WarmStart::without_iterate);
        solution = ipm::solve(plan.lp(), &settings, analysis.as_ref())?;
        solution.iterations += more;
    }
    let [primal, dual, gap] = solution.residuals;
    match solution.termination {
        Termination::Converged => {}
        Termination::Stalled => warnings.push(format!(
            "lp: interior point stalled at reduced accuracy (relative primal residual \
             {primal:.1e}, dual {dual:.1e}, gap {gap:.1e})"
        )),
        termination => {
            return Err(PlanFallback::Stopped {
                termination,
                residuals: solution.residuals,
            })
        }
    }
    let q = plan.complete(problem, &solution.q)?;
    Ok((q, solution.iterations, Some(solution.kept)))
}

/// The plan LP of `plan` as one conic program (clarabel, QDLDL first): two
/// equilibrium rows per free net node, the net's cables only. Unscaled net
/// `q` in the plan LP's order (`None`: infeasible) and iterations.
fn solve_plan_clarabel(
    plan: &PlanReduction,
    warnings: &mut Vec<String>,
) -> Result<(Option<Vec<f64>>, usize), UniformityError> {
    let lp = plan.lp();
    let m = lp.lengths.len();
    let s = m;
    let mut rows: Vec<Vec<(usize, f64)>> = vec![Vec::new(); 2 * lp.n_free];
    for (k, (ends, u)) in lp.ends.iter().zip(&lp.vectors).enumerate() {
        for (end, sign) in ends.iter().zip([1.0, -1.0]) {
            if let Some(f) = *end {
                for c in 0..2 {
                    rows[2 * f + c].push((k, sign * u[c]));
                }
            }
        }
    }
    let mut program = ConicProgram::new(m + 1);
    for row in &rows {
        program.row(Cone::Zero, row, 0.0);
    }
    drop(rows);
    for k in 0..m {
        let l = lp.lengths[k];
        if lp.in_set[k] {
            program.row(Cone::Nonnegative, &[(k, -l)], -1.0);
            program.row(Cone::Nonnegative, &[(k, l), (s, -1.0)], 0.0);
        } else {
            program.row(Cone::Nonnegative, &[(k, -l)], -lp.min_other_tension);
        }
    }
    let mut c = vec![0.0; m + 1];
    c[s] = 1.0;
    let outcome = program.solve_with(&[], &c, &PLAN_ATTEMPTS);
    match outcome.class {
        Class::Feasible => {
            warnings.extend(outcome.warning("lp (plan)"));
            Ok((Some(outcome.x[..m].to_vec()), outcome.iterations))
        }
        Class::Infeasible => Ok((None, outcome.iterations)),
        Class::Failed => Err(UniformityError::SolverFailed {
            solver: "lp",
            status: outcome.status,
        }),
    }
}

/// The full problem as one conic program (clarabel): every cable, three
/// equilibrium rows per free node. Unscaled `q` (`None` when the program is
/// infeasible: no strictly positive `q` balances the geometry) and iterations.
pub(super) fn solve_full(
    problem: &UniformityProblem,
    warnings: &mut Vec<String>,
) -> Result<(Option<Vec<f64>>, usize), UniformityError> {
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
        Class::Feasible => {
            warnings.extend(outcome.warning("lp"));
            Ok((Some(outcome.x[..m].to_vec()), outcome.iterations))
        }
        Class::Infeasible => Ok((None, outcome.iterations)),
        Class::Failed => Err(UniformityError::SolverFailed {
            solver: "lp",
            status: outcome.status,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uniformity::ipm::tests::set_ratio;

    /// The plan path (interior point on two rows per front node, then the ties
    /// and the rear net) and clarabel on the full problem find the same optimum,
    /// and the completed `q` balances every free node of both nets.
    fn plan_matches_full(path: &str) {
        let scene = crate::Scene::read(std::path::Path::new(path)).expect("scene");
        let problem = crate::design::scene_problem(&scene).expect("problem").1;
        let plan = PlanReduction::new(&problem).expect("a reflector mesh");
        let network = problem.network();
        let ties = (0..network.n_edges())
            .filter(|&k| network.group_of(k) == "tie")
            .count();
        assert_eq!(plan.lp().n_free, ties, "one plan node per tie");
        assert_eq!(plan.n_ties(), ties);
        assert!(
            plan.has_rear(),
            "the scene's rear net mirrors its front net"
        );
        let (q_plan, _, _) = solve_plan(&plan, &problem, None, &mut Vec::new()).expect("plan");
        let q_full = solve_full(&problem, &mut Vec::new())
            .expect("full")
            .0
            .expect("feasible");
        let (plan_ratio, full_ratio) = (set_ratio(&problem, &q_plan), set_ratio(&problem, &q_full));
        assert!(
            (plan_ratio - full_ratio).abs() <= 1e-6 * full_ratio,
            "{plan_ratio} vs {full_ratio}"
        );
        let max_tension = q_plan
            .iter()
            .zip(problem.lengths_m())
            .map(|(q, l)| q * l)
            .fold(0.0, f64::max);
        let residual = problem.prescribed_residual_n(&q_plan);
        assert!(
            residual <= 1e-9 * max_tension,
            "{residual} vs {max_tension}"
        );
    }

    #[test]
    fn plan_matches_full_small_hex() {
        plan_matches_full("problems/small-hex.toml");
    }

    #[test]
    fn plan_matches_full_small_offset() {
        plan_matches_full("problems/small-offset.toml");
    }

    #[test]
    fn plan_matches_full_paper_26m() {
        plan_matches_full("problems/paper-26m.toml");
    }
}
