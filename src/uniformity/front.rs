//! The design front (DESIGN §4): sweep each solver's accuracy knob and judge every
//! design by its *actual* surface RMS from a forward solve with its `q`.

use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use super::{Design, SolverKind, Termination, UniformityProblem};

/// One design of the front.
#[derive(Debug, Clone, PartialEq, Serialize)]
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
    /// How the solver stopped, or why it failed.
    pub outcome: Result<Termination, String>,
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

/// The knob values swept for `solver`, from accurate to uniform, scaled to the
/// problem's pretension level `T̄`:
/// * bisection: ε = 0 (exact equilibrium) and ε from 1e-3·T̄ to T̄, N;
/// * gradient: ratio weight from 1e-8 to 1 (the surface term is normalised,
///   so 1e-6 is already near the exact-equilibrium design);
/// * least squares: λ from 1e-6 to 1e2 (and the equality-constrained limit is
///   the `lp`-like exact point, run separately).
pub fn knob_values(solver: SolverKind, problem: &UniformityProblem, points: usize) -> Vec<f64> {
    let level = problem.sets()[0].mean_tension_n;
    match solver {
        SolverKind::Bisection => {
            let mut v = vec![0.0];
            v.extend(geometric(1e-3 * level, level, points.saturating_sub(1)));
            v
        }
        SolverKind::Lp => vec![0.0],
        SolverKind::Gradient => geometric(1e-8, 1.0, points),
        SolverKind::LeastSquares => geometric(1e-6, 1e2, points),
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
    design_front_points(problem, &front_jobs(problem, solvers, points), on_point)
}

/// Designs the front's points `jobs` in parallel, returned in their order;
/// `on_point` is called as each finishes (from worker threads).
pub fn design_front_points(
    problem: &UniformityProblem,
    jobs: &[(SolverKind, f64)],
    on_point: &(dyn Fn(&FrontPoint) + Sync),
) -> Vec<FrontPoint> {
    jobs.par_iter()
        .map(|&(solver, knob)| {
            let start = Instant::now();
            // A point without a feasible design is a failed point, as an error is.
            let result = solver
                .build(Some(knob))
                .solve(problem)
                .and_then(Design::feasible);
            let point = match result {
                Ok(design) => FrontPoint {
                    solver,
                    knob,
                    ratio: design.ratio,
                    rms_mm: 1e3 * design.surface_rms_m,
                    time_s: design.time_s,
                    outcome: Ok(design.termination),
                },
                Err(e) => FrontPoint {
                    solver,
                    knob,
                    ratio: f64::NAN,
                    rms_mm: f64::NAN,
                    time_s: start.elapsed().as_secs_f64(),
                    outcome: Err(e.to_string()),
                },
            };
            on_point(&point);
            point
        })
        .collect()
}
