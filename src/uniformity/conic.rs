//! Conic programs for the clarabel-based solvers: assembly of `s = b − A x ∈ K`
//! block by block, the equilibrium rows `A(x) q = p`, status classification, and
//! the slack analysis that names the nodes of an infeasible geometry.

use std::time::Instant;

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};

use super::{Design, SlackNodes, Termination, UniformityError, UniformityProblem};

/// Constraint rows `s = b − A x`, grouped into cones in order.
#[derive(Debug, Default)]
pub(crate) struct ConicProgram {
    n_vars: usize,
    rows: Vec<usize>,
    cols: Vec<usize>,
    vals: Vec<f64>,
    b: Vec<f64>,
    cones: Vec<SupportedConeT<f64>>,
    /// Kind of the cone being filled and its row count so far.
    open: Option<(Cone, usize)>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Cone {
    Zero,
    Nonnegative,
}

impl ConicProgram {
    pub(crate) fn new(n_vars: usize) -> Self {
        ConicProgram {
            n_vars,
            ..Default::default()
        }
    }

    /// The pretension level the ratio programs hold: the first set's mean
    /// tension `Σ_k ℓ_k q_k / n` at its target (one zero-cone row).
    pub(crate) fn first_set_mean_tension(&mut self, problem: &UniformityProblem) {
        let lengths = problem.lengths_m();
        let first = &problem.sets()[0];
        let row: Vec<(usize, f64)> = first
            .edges
            .iter()
            .map(|&k| (k, lengths[k] / first.edges.len() as f64))
            .collect();
        self.row(Cone::Zero, &row, first.mean_tension_n);
    }

    /// Appends one row `b − a·x` to a cone of `kind` (merging consecutive rows of
    /// the same kind into one cone).
    pub(crate) fn row(&mut self, kind: Cone, entries: &[(usize, f64)], b: f64) {
        let row = self.b.len();
        for &(col, val) in entries {
            debug_assert!(col < self.n_vars);
            self.rows.push(row);
            self.cols.push(col);
            self.vals.push(val);
        }
        self.b.push(b);
        match &mut self.open {
            Some((open, count)) if *open == kind => *count += 1,
            _ => {
                self.close();
                self.open = Some((kind, 1));
            }
        }
    }

    fn close(&mut self) {
        if let Some((kind, count)) = self.open.take() {
            self.cones.push(match kind {
                Cone::Zero => SupportedConeT::ZeroConeT(count),
                Cone::Nonnegative => SupportedConeT::NonnegativeConeT(count),
            });
        }
    }

    /// Appends the equilibrium rows `p − A(x) q` (3 per free node, `q` the first
    /// n_edges variables) as a zero cone, or — with `epsilon > 0` — as the
    /// second-order cone `‖A q − p‖₂ ≤ ε`.
    pub(crate) fn equilibrium(&mut self, problem: &UniformityProblem, epsilon: f64) {
        self.close();
        let a = problem
            .structure()
            .equilibrium_matrix(&problem.network().nodes);
        let p = problem.free_loads();
        let first = self.b.len();
        let offset = if epsilon > 0.0 {
            self.b.push(epsilon);
            1
        } else {
            0
        };
        self.b.extend_from_slice(&p);
        let (symbolic, values) = a.parts();
        for col in 0..a.ncols() {
            let range = symbolic.col_range(col);
            for (&row, &val) in symbolic.row_idx()[range.clone()].iter().zip(&values[range]) {
                self.rows.push(first + offset + row);
                self.cols.push(col);
                self.vals.push(val);
            }
        }
        self.cones.push(if epsilon > 0.0 {
            SupportedConeT::SecondOrderConeT(1 + p.len())
        } else {
            SupportedConeT::ZeroConeT(p.len())
        });
    }

    /// Solves `min cᵀx` subject to the rows. The KKT systems of these programs
    /// are often degenerate near the optimum, so a solve that ends in a numerical
    /// failure is retried with the other LDLᵀ backend and stronger static
    /// regularisation; the outcome says which attempt answered.
    pub(crate) fn solve(self, c: &[f64]) -> ConicOutcome {
        self.solve_quadratic(&[], c)
    }

    /// Solves `min ½ xᵀ diag(p) x + cᵀx` subject to the rows; `p` may be
    /// shorter than `x` (the rest of the diagonal is zero). Retries as
    /// [`Self::solve`].
    pub(crate) fn solve_quadratic(self, p_diagonal: &[f64], c: &[f64]) -> ConicOutcome {
        self.solve_with(p_diagonal, c, &ATTEMPTS)
    }

    /// [`Self::solve_quadratic`] with the LDLᵀ backends and static
    /// regularisations of `attempts`, in order (see [`ATTEMPTS`]).
    pub(crate) fn solve_with(
        mut self,
        p_diagonal: &[f64],
        c: &[f64],
        attempts: &[(&str, f64)],
    ) -> ConicOutcome {
        self.close();
        let n_rows = self.b.len();
        let a = CscMatrix::new_from_triplets(n_rows, self.n_vars, self.rows, self.cols, self.vals);
        let diagonal: Vec<usize> = (0..p_diagonal.len()).collect();
        let p = CscMatrix::new_from_triplets(
            self.n_vars,
            self.n_vars,
            diagonal.clone(),
            diagonal,
            p_diagonal.to_vec(),
        );
        let mut outcome = None;
        for (attempt, (method, regularisation)) in attempts.iter().enumerate() {
            let settings = DefaultSettingsBuilder::default()
                .verbose(false)
                .direct_solve_method(method.to_string())
                .static_regularization_constant(*regularisation)
                .build()
                .expect("valid clarabel settings");
            let mut solver = match DefaultSolver::new(&p, c, &a, &self.b, &self.cones, settings) {
                Ok(s) => s,
                Err(e) => {
                    return ConicOutcome {
                        class: Class::Failed,
                        status: format!("setup: {e}"),
                        x: Vec::new(),
                        iterations: 0,
                        retried: attempt > 0,
                    }
                }
            };
            solver.solve();
            let solution = &solver.solution;
            let class = match solution.status {
                SolverStatus::Solved | SolverStatus::AlmostSolved => Class::Feasible,
                SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
                    Class::Infeasible
                }
                _ => Class::Failed,
            };
            outcome = Some(ConicOutcome {
                class,
                status: format!("{:?}", solution.status),
                x: solution.x.clone(),
                iterations: solution.iterations as usize,
                retried: attempt > 0,
            });
            if class != Class::Failed {
                break;
            }
        }
        outcome.expect("at least one attempt")
    }
}

/// clarabel's LDLᵀ backend and static regularisation, in the order tried.
pub(crate) const ATTEMPTS: [(&str, f64); 2] = [("faer", 1e-7), ("qdldl", 1e-6)];

/// What a conic solve says, in the terms the solvers act on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Class {
    /// `Solved` or `AlmostSolved`.
    Feasible,
    /// `PrimalInfeasible` or `AlmostPrimalInfeasible`.
    Infeasible,
    /// Any other status.
    Failed,
}

#[derive(Debug, Clone)]
pub(crate) struct ConicOutcome {
    pub class: Class,
    /// clarabel's status, verbatim.
    pub status: String,
    pub x: Vec<f64>,
    pub iterations: usize,
    /// The first attempt failed numerically and a retry answered.
    pub retried: bool,
}

impl ConicOutcome {
    /// A reduced-accuracy status (`Almost…`) or a retried solve, for the design's
    /// warnings, with what the user can check and do about it.
    pub(crate) fn warning(&self, context: &str) -> Option<String> {
        let retried = if self.retried {
            " after a numerical failure and retry"
        } else {
            ""
        };
        let advice = if self.status.starts_with("Almost") {
            " (solved only to clarabel's reduced tolerances, gap and residuals about 1e-4 relative: check the \
             design's max residual and surface RMS; force densities spread over many decades \
             or a bound [q] far above the design's are the usual cause, and another solver \
             (--solver) a cross-check)"
        } else {
            ""
        };
        (self.status.starts_with("Almost") || self.retried).then(|| {
            format!(
                "{context}: clarabel status {}{retried}{advice}",
                self.status
            )
        })
    }
}

/// How many slack nodes a design names.
const SHOWN_SLACK_NODES: usize = 12;

/// Names the nodes of a geometry with no strictly positive self-stress: solves
/// `max Σ y_k` s.t. `A q = p`, `ℓ_k q_k ≥ y_k`, `0 ≤ y_k ≤ 1` — cables with
/// `y_k < ½` at the optimum are slack in every equilibrium — and returns the
/// free nodes at their ends (ascending; none when the geometry has strictly
/// positive equilibria).
pub(crate) fn slack_nodes(problem: &UniformityProblem) -> Result<SlackNodes, UniformityError> {
    let m = problem.network().n_edges();
    let lengths = problem.lengths_m();
    let mut program = ConicProgram::new(2 * m);
    program.equilibrium(problem, 0.0);
    for (k, &length) in lengths.iter().enumerate() {
        // ℓ q − y ≥ 0, y ≥ 0, 1 − y ≥ 0
        program.row(Cone::Nonnegative, &[(k, -length), (m + k, 1.0)], 0.0);
        program.row(Cone::Nonnegative, &[(m + k, -1.0)], 0.0);
        program.row(Cone::Nonnegative, &[(m + k, 1.0)], 1.0);
    }
    let mut c = vec![0.0; 2 * m];
    c[m..].fill(-1.0);
    let outcome = program.solve(&c);
    if outcome.class != Class::Feasible {
        return Err(UniformityError::SolverFailed {
            solver: "slack analysis",
            status: outcome.status,
        });
    }
    let structure = problem.structure();
    let mut nodes: Vec<usize> = (0..m)
        .filter(|&k| outcome.x[m + k] < 0.5)
        .flat_map(|k| problem.network().edges[k])
        .filter(|&i| structure.free_index(i).is_some())
        .collect();
    nodes.sort_unstable();
    nodes.dedup();
    Ok(SlackNodes {
        count: nodes.len(),
        nodes: nodes.into_iter().take(SHOWN_SLACK_NODES).collect(),
    })
}

/// The design of a conic solver that found its program infeasible: the
/// network's own `q`, judged like any design, with [`Termination::Infeasible`]
/// and the slack analysis (the nodes whose cables can only be slack) in its
/// warnings and its `slack_nodes`. When the geometry does have strictly
/// positive equilibria, the warning says that the solver's bounds exclude them.
pub(crate) fn infeasible_design(
    problem: &UniformityProblem,
    solver: &str,
    iterations: usize,
    start: Instant,
    warnings: Vec<String>,
) -> Result<Design, UniformityError> {
    let slack = slack_nodes(problem);
    infeasible_design_with(problem, solver, iterations, start, warnings, slack)
}

/// [`infeasible_design`] with the slack analysis already made.
pub(crate) fn infeasible_design_with(
    problem: &UniformityProblem,
    solver: &str,
    iterations: usize,
    start: Instant,
    mut warnings: Vec<String>,
    slack: Result<SlackNodes, UniformityError>,
) -> Result<Design, UniformityError> {
    let slack = match slack {
        Ok(slack) if slack.count > 0 => {
            warnings.push(slack.to_string());
            Some(slack)
        }
        Ok(_) => {
            warnings.push(format!(
                "the `{solver}` program is infeasible, but strictly positive force densities \
                 balance the prescribed geometry: its bounds exclude them"
            ));
            None
        }
        Err(e) => {
            warnings.push(format!(
                "the `{solver}` program is infeasible; naming the slack nodes failed: {e}"
            ));
            None
        }
    };
    let mut design = Design::evaluate(
        problem,
        solver,
        problem.network().q.clone(),
        Termination::Infeasible,
        iterations,
        start.elapsed(),
        warnings,
    )?;
    design.slack_nodes = slack;
    Ok(design)
}
