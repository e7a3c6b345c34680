//! The design front (DESIGN §4): sweep each solver's accuracy knob and judge every
//! design by its *actual* surface RMS from a forward solve with its `q`.

use std::ops::Range;
use std::sync::Arc;
use std::time::Instant;

use rayon::prelude::*;

use super::{Design, SolverKind, Termination, UniformityError, UniformityProblem};

/// One design of the front.
#[derive(Debug, Clone)]
pub struct FrontPoint {
    /// The solver.
    pub solver: SolverKind,
    /// Its accuracy knob (ε in N, weight, or λ).
    pub knob: f64,
    /// `Tmax/Tmin` over the uniformity sets (the largest).
    pub ratio: f64,
    /// RMS surface error of the forward solve, mm.
    pub rms_mm: f64,
    /// Wall time of the solve, s.
    pub time_s: f64,
    /// How the solver stopped, or why it failed (no feasible design among
    /// the reasons, [`Design::feasible`]).
    pub outcome: Result<Termination, Arc<UniformityError>>,
}

/// The accuracy knob a solver's design front sweeps, scaled to one problem
/// ([`super::UniformitySolver::knob_range`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KnobRange {
    /// The setting it is (`epsilon_n`, `weight`, `lambda`).
    pub name: &'static str,
    /// A value swept before the range, if any (bisection's exact equilibrium).
    pub exact: Option<f64>,
    /// The smallest value of the range …
    pub low: f64,
    /// … and the largest, swept evenly in log scale.
    pub high: f64,
}

impl KnobRange {
    /// `points` values, from accurate to uniform: the exact one (if any), then
    /// the rest from `low` to `high`, evenly in log scale.
    pub fn values(&self, points: usize) -> Vec<f64> {
        let mut values: Vec<f64> = self.exact.into_iter().collect();
        let rest = points.saturating_sub(values.len());
        values.extend(geometric(self.low, self.high, rest));
        values
    }
}

/// `n` values from `lo` to `hi`, evenly spaced in log scale.
fn geometric(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    match n {
        0 => Vec::new(),
        1 => vec![hi],
        _ => (0..n)
            .map(|i| lo * (hi / lo).powf(i as f64 / (n - 1) as f64))
            .collect(),
    }
}

/// The knob values swept for `solver`, from accurate to uniform: `points`
/// values of its [`super::UniformitySolver::knob_range`] for `problem`, or the one
/// point `0` for a solver without a knob.
pub fn knob_values(solver: SolverKind, problem: &UniformityProblem, points: usize) -> Vec<f64> {
    match solver.build(None).knob_range(problem) {
        Some(range) => range.values(points),
        None => vec![0.0],
    }
}

/// The front's points, `(solver, knob)`, in the deterministic order
/// solver-major (as listed), knob ascending ([`knob_values`]).
pub fn front_jobs(
    problem: &UniformityProblem,
    solvers: &[SolverKind],
    points: usize,
) -> Vec<(SolverKind, f64)> {
    solvers
        .iter()
        .flat_map(|&s| {
            knob_values(s, problem, points)
                .into_iter()
                .map(move |k| (s, k))
        })
        .collect()
}

/// Sweeps the knob of every solver in `solvers` over `points` values, in
/// parallel; `on_point` is called as each point finishes (from worker threads).
/// Points come back in the order of [`front_jobs`].
pub fn design_front(
    problem: &UniformityProblem,
    solvers: &[SolverKind],
    points: usize,
    on_point: &(dyn Fn(&FrontPoint) + Sync),
) -> Vec<FrontPoint> {
    let jobs = front_jobs(problem, solvers, points);
    let chains: Vec<&[(SolverKind, f64)]> =
        front_chains(&jobs).into_iter().map(|c| &jobs[c]).collect();
    design_front_chains(problem, &chains, on_point)
}

/// The chains of `jobs` (ranges of indices into it, in order): each run of
/// consecutive jobs of a solver that [`SolverKind::warm_starts`] is one chain
/// along its knob, every other job a chain of its own. A point of a chain
/// starts from its neighbour's design, so a chain is the unit a shard takes
/// whole: its points then come out as they do in the unsharded sweep.
pub fn front_chains(jobs: &[(SolverKind, f64)]) -> Vec<Range<usize>> {
    let mut start = 0;
    jobs.chunk_by(|a, b| a.0 == b.0 && a.0.warm_starts())
        .map(|chain| {
            start += chain.len();
            start - chain.len()..start
        })
        .collect()
}

/// Designs the front's `chains` (of [`front_chains`]), returned as one list
/// in their order; `on_point` is called as each point finishes (from worker
/// threads). The chains run in parallel, and each point of a chain starts
/// from its neighbour's design ([`super::UniformitySolver::solve_from`]), so
/// that an iterative solver's front moves smoothly (and monotonically) with
/// its knob.
pub fn design_front_chains(
    problem: &UniformityProblem,
    chains: &[&[(SolverKind, f64)]],
    on_point: &(dyn Fn(&FrontPoint) + Sync),
) -> Vec<FrontPoint> {
    chains
        .par_iter()
        .flat_map_iter(|chain| {
            let mut previous: Option<Design> = None;
            chain.iter().map(move |&(solver, knob)| {
                let point = front_point(problem, solver, knob, &mut previous);
                on_point(&point);
                point
            })
        })
        .collect()
}

/// One point of the front, started from `previous` (a neighbour's design),
/// which becomes this point's design when it has one.
fn front_point(
    problem: &UniformityProblem,
    solver: SolverKind,
    knob: f64,
    previous: &mut Option<Design>,
) -> FrontPoint {
    let start = Instant::now();
    let built = solver.build(Some(knob));
    // A point without a feasible design is a failed point, as an error is.
    let result = match previous.as_ref() {
        Some(neighbour) => built.solve_from(problem, neighbour),
        None => built.solve(problem),
    }
    .and_then(Design::feasible);
    match result {
        Ok(design) => {
            let point = FrontPoint {
                solver,
                knob,
                ratio: design.ratio,
                rms_mm: 1e3 * design.surface_rms_m,
                time_s: design.time_s,
                outcome: Ok(design.termination),
            };
            *previous = Some(design);
            point
        }
        Err(e) => FrontPoint {
            solver,
            knob,
            ratio: f64::NAN,
            rms_mm: f64::NAN,
            time_s: start.elapsed().as_secs_f64(),
            outcome: Err(Arc::new(e)),
        },
    }
}
