//! What every uniformity solver returns: a [`Design`] judged the same way for all
//! of them, by a forward FDM solve with the returned `q`. A problem a solver
//! proves infeasible is a design too, with [`Termination::Infeasible`] and the
//! reason in its warnings (and [`SlackNodes`]); [`Design::feasible`] turns it
//! into an error for callers that cannot go on without one.

use std::fmt;
use std::sync::Arc;
use std::time::Duration;

use serde::Serialize;

use super::{UniformityError, UniformityProblem, WarmStart};
use crate::status::Termination;

/// Relative miss of a set's mean tension within which a design holds its
/// pretension level ([`Design::at_level`]).
const LEVEL_TOLERANCE: f64 = 1e-9;

/// How the `lp` solver reached its design (reported with the design; every
/// route but the first also leaves its reason in the warnings).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Route {
    /// The plan problem of a tied net (two rows per free net node) by the
    /// structured interior-point method, completed with the ties (and a rear
    /// net).
    PlanInteriorPoint,
    /// The plan problem by clarabel (QDLDL), after the interior-point method
    /// stopped short, completed the same way.
    PlanClarabel,
    /// The full three-dimensional LP by clarabel: the network is not a tied
    /// net, or the plan optimum does not complete.
    FullClarabel,
}

impl fmt::Display for Route {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Route::PlanInteriorPoint => "plan LP, interior point",
            Route::PlanClarabel => "plan LP, clarabel (fallback)",
            Route::FullClarabel => "full 3-D LP, clarabel",
        })
    }
}

/// The free nodes whose cables are slack in every equilibrium of the
/// prescribed geometry: why it has no strictly positive force densities.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SlackNodes {
    /// The first few such nodes, ascending.
    pub nodes: Vec<usize>,
    /// How many there are.
    pub count: usize,
}

impl fmt::Display for SlackNodes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.nodes.is_empty() {
            return write!(
                f,
                "no strictly positive force densities balance the prescribed geometry within \
                 the bounds, though no node's cables need be slack: the bound [q] \
                 (cables.max_force_density_n_per_m) or the tension floor is too tight"
            );
        }
        let nodes: Vec<String> = self.nodes.iter().map(usize::to_string).collect();
        write!(
            f,
            "no strictly positive force densities balance the prescribed geometry: cables at \
             nodes {} can only be slack ({} nodes in all; e.g. boundary nodes on a straight \
             chord between attachments: sag the boundary inward)",
            nodes.join(", "),
            self.count
        )
    }
}

/// Tension statistics of a set of cables.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TensionSpread {
    /// A uniformity set's name or a group label.
    pub name: String,
    /// Number of cables.
    pub cables: usize,
    /// Smallest tension, N.
    pub min_tension_n: f64,
    /// Largest tension, N.
    pub max_tension_n: f64,
    /// Mean tension, N.
    pub mean_tension_n: f64,
    /// `Tmax/Tmin`.
    pub ratio: f64,
}

impl TensionSpread {
    fn of(name: &str, edges: impl Iterator<Item = usize>, tensions: &[f64]) -> Self {
        let (mut min, mut max, mut sum, mut count) = (f64::INFINITY, 0.0f64, 0.0, 0usize);
        for k in edges {
            min = min.min(tensions[k]);
            max = max.max(tensions[k]);
            sum += tensions[k];
            count += 1;
        }
        TensionSpread {
            name: name.to_string(),
            cables: count,
            min_tension_n: min,
            max_tension_n: max,
            mean_tension_n: sum / count.max(1) as f64,
            ratio: max / min,
        }
    }
}

/// A pretension design: force densities and what they do to the network.
#[derive(Debug, Clone, Serialize)]
pub struct Design {
    /// The solver that made it.
    pub solver: String,
    /// Force densities, N/m: n_edges (the network's own when the solver
    /// found no feasible `q`, see [`Termination::Infeasible`]).
    pub q: Vec<f64>,
    /// Tensions of the forward solve with `q`, N: n_edges.
    pub tensions_n: Vec<f64>,
    /// Cable lengths of the forward solve, m: n_edges.
    pub lengths_m: Vec<f64>,
    /// Node positions of the forward solve, m: n_nodes × 3.
    pub nodes_xyz_m: Vec<[f64; 3]>,
    /// Support reactions, N, in the order of the network's `fixed`.
    pub reactions_n: Vec<[f64; 3]>,
    /// `Tmax/Tmin` over each uniformity set.
    pub sets: Vec<TensionSpread>,
    /// Tension spread of every group label.
    pub groups: Vec<TensionSpread>,
    /// The largest set ratio.
    pub ratio: f64,
    /// Out-of-balance force of `q` on the prescribed geometry, N.
    pub max_residual_n: f64,
    /// Largest cable tension, N.
    pub max_tension_n: f64,
    /// RMS surface error of the forward solve, m.
    pub surface_rms_m: f64,
    /// Largest surface error of the forward solve, m.
    pub surface_max_m: f64,
    /// How the solver stopped: `Converged`, `MaxIterations`, `Stalled`,
    /// `Infeasible` or `NumericalError` (never `Diverged`).
    pub termination: Termination,
    /// Iterations of the solver (bisection steps, L-BFGS iterations plus
    /// the exact finish's programs, …).
    pub iterations: usize,
    /// Wall time of the solve, s.
    pub time_s: f64,
    /// Everything the inner solvers reported other than plain success.
    pub warnings: Vec<String>,
    /// How the solver got there, when it has several routes (`lp`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub route: Option<Route>,
    /// When the prescribed geometry has no strictly positive force densities:
    /// the nodes whose cables can only be slack (also in `warnings`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slack_nodes: Option<SlackNodes>,
    /// What the interior point keeps for the solve of a neighbouring
    /// problem — its iterate, its normal matrix's analysis —
    /// ([`super::UniformitySolver::solve_from`]: `lp`'s plan route, the
    /// outer loop's next boundary). Not part of the design's files.
    #[serde(skip)]
    pub warm_start: Option<Arc<WarmStart>>,
}

impl Design {
    /// The net's pull on its supports, `−F_g`, N (the order of `fixed`):
    /// the loads a truss oracle takes.
    pub fn pull_n(&self) -> Vec<[f64; 3]> {
        self.reactions_n.iter().map(|r| r.map(|v| -v)).collect()
    }

    /// The design, or, when its solver proved the problem infeasible, the
    /// [`UniformityError::Infeasible`] that says why (its warnings and slack
    /// nodes): for callers that cannot go on without a design.
    ///
    /// # Errors
    /// A design with [`Termination::Infeasible`].
    pub fn feasible(self) -> Result<Design, UniformityError> {
        if self.termination == Termination::Infeasible {
            Err(UniformityError::Infeasible {
                solver: self.solver,
                slack_nodes: self.slack_nodes,
                warnings: self.warnings,
            })
        } else {
            Ok(self)
        }
    }

    /// The design at its first set's target mean tension (DESIGN §4: the
    /// pretension level). `lp` and `bisection` hold it already; least squares
    /// does not, and `gradient` only by a penalty. Without nodal loads the
    /// shape is invariant under `q → c q`, so scaling by `c = T̄₀/mean T`
    /// holds the level exactly for any solver (one forward solve). Under
    /// loads scaling would break equilibrium: a miss beyond
    /// `LEVEL_TOLERANCE` (1e-9, relative) is kept and said in a warning.
    ///
    /// # Errors
    /// The forward solve of the scaled `q` failed.
    pub fn at_level(mut self, problem: &UniformityProblem) -> Result<Design, UniformityError> {
        let (Some(set), Some(spread)) = (problem.sets().first(), self.sets.first()) else {
            return Ok(self);
        };
        let scale = set.mean_tension_n / spread.mean_tension_n;
        if !scale.is_finite() || (scale - 1.0).abs() <= LEVEL_TOLERANCE {
            return Ok(self);
        }
        if problem.has_loads() {
            self.warnings.push(format!(
                "{} holds the pretension level only to {:.2e} (relative) under nodal loads: `{}` \
                 has a mean tension of {} N for its target {} N (lp and bisection hold it exactly)",
                self.solver,
                1.0 / scale - 1.0,
                set.name,
                spread.mean_tension_n,
                set.mean_tension_n,
            ));
            return Ok(self);
        }
        let q = self.q.iter().map(|q| scale * q).collect();
        self.judged_again(problem, q)
    }

    /// The same solver's outcome (termination, iterations, time, warnings)
    /// judged afresh with `q` on `problem`.
    ///
    /// # Errors
    /// The forward solve failed.
    pub fn judged_again(
        self,
        problem: &UniformityProblem,
        q: Vec<f64>,
    ) -> Result<Design, UniformityError> {
        let mut design = Design::evaluate(
            problem,
            &self.solver,
            q,
            self.termination,
            self.iterations,
            Duration::from_secs_f64(self.time_s),
            self.warnings,
        )?;
        design.route = self.route;
        design.slack_nodes = self.slack_nodes;
        design.warm_start = self.warm_start;
        Ok(design)
    }

    /// Judges `q` on `problem`: forward solve, tensions, spreads, residual, surface
    /// error. The caller supplies how its solver stopped.
    pub fn evaluate(
        problem: &UniformityProblem,
        solver: &str,
        q: Vec<f64>,
        termination: Termination,
        iterations: usize,
        elapsed: Duration,
        warnings: Vec<String>,
    ) -> Result<Design, UniformityError> {
        let eq = problem.forward(&q)?;
        let tensions = eq.edges_forces_n.clone();
        let network = problem.network();
        let sets: Vec<TensionSpread> = problem
            .sets()
            .iter()
            .map(|s| TensionSpread::of(&s.name, s.edges.iter().copied(), &tensions))
            .collect();
        let mut labels: Vec<&str> = Vec::new();
        for k in 0..network.n_edges() {
            let g = network.group_of(k);
            if !labels.contains(&g) {
                labels.push(g);
            }
        }
        let groups = labels
            .iter()
            .map(|g| {
                TensionSpread::of(
                    g,
                    (0..network.n_edges()).filter(|&k| network.group_of(k) == *g),
                    &tensions,
                )
            })
            .collect();
        let errors = problem.surface_errors_m(&eq.nodes_xyz_m);
        let surface_max_m = errors.iter().map(|e| e.abs()).fold(0.0, f64::max);
        let max_residual_n = problem.prescribed_residual_n(&q);
        // A non-finite number is never a design (the forward solve checked
        // positions, tensions and reactions).
        let checks = [
            ("max_residual_n", max_residual_n),
            ("surface_max_m", surface_max_m),
        ];
        if let Some((what, value)) = checks.into_iter().find(|(_, v)| !v.is_finite()) {
            return Err(UniformityError::NonFinite {
                solver: solver.to_string(),
                what,
                value,
                max_q: q.iter().copied().fold(0.0, f64::max),
            });
        }
        Ok(Design {
            solver: solver.to_string(),
            ratio: sets.iter().map(|s| s.ratio).fold(0.0, f64::max),
            max_residual_n,
            max_tension_n: eq.max_force_n(),
            surface_rms_m: problem.surface_rms_m(&eq.nodes_xyz_m),
            surface_max_m,
            q,
            tensions_n: tensions,
            lengths_m: eq.edges_lengths_m,
            nodes_xyz_m: eq.nodes_xyz_m,
            reactions_n: eq.reactions_n,
            sets,
            groups,
            termination,
            iterations,
            time_s: elapsed.as_secs_f64(),
            warnings,
            route: None,
            slack_nodes: None,
            warm_start: None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slack_nodes_without_a_node_say_so() {
        let none = SlackNodes {
            nodes: vec![],
            count: 0,
        }
        .to_string();
        assert!(none.contains("no node's cables need be slack"), "{none}");
        assert!(!none.contains("nodes  "), "{none}");
        let some = SlackNodes {
            nodes: vec![3, 7],
            count: 2,
        }
        .to_string();
        assert!(some.contains("nodes 3, 7 can only be slack"), "{some}");
    }
}
