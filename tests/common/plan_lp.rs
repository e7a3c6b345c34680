//! clarabel on the plan LP of a tied net, written here from the network alone
//! (independently of `src/uniformity/plan.rs`): the net is the set's cables,
//! two equilibrium rows per free net node (the ties, vertical, carry no plan
//! force),
//!
//! ```text
//! min s  s.t.  Σ_k ±q_k (p_i − p_j) = 0 per free net node,
//!              1 ≤ ℓ_k q_k ≤ s (k in the set),
//! ```
//!
//! solved with a chosen LDLᵀ backend (`"qdldl"`, `"faer"`). Self-contained
//! (`ringmesh` and `clarabel`) so that a bench and an example can include it
//! with `#[path]`.
#![allow(dead_code)]

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use ringmesh::uniformity::UniformityProblem;

/// The optimum clarabel finds: `Tmax/Tmin` over the set, its status and
/// iterations.
#[derive(Debug, Clone)]
pub struct PlanOptimum {
    /// `Tmax/Tmin` over the set.
    pub ratio: f64,
    /// clarabel's status, `Debug`-printed.
    pub status: String,
    /// clarabel's iterations.
    pub iterations: u32,
}

/// The plan LP of `problem` (one set, every free node of the set's cables
/// tied vertically) in clarabel's form `A x + s = b`, `s ∈ K`: `(A, b, cones,
/// c)` over `x = (q_net, s)`.
pub fn plan_program(
    problem: &UniformityProblem,
) -> (CscMatrix<f64>, Vec<f64>, Vec<SupportedConeT<f64>>, Vec<f64>) {
    let network = problem.network();
    let set = &problem.sets()[0].edges;
    let fixed = network.fixed_mask();
    let mut row_of = vec![usize::MAX; network.n_nodes()];
    let mut n_rows = 0;
    for &k in set {
        for i in network.edges[k] {
            if !fixed[i] && row_of[i] == usize::MAX {
                row_of[i] = n_rows;
                n_rows += 2;
            }
        }
    }
    let m = set.len();
    let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
    for (col, &k) in set.iter().enumerate() {
        let [i, j] = network.edges[k];
        let (pi, pj) = (network.nodes[i], network.nodes[j]);
        for (end, sign) in [(i, 1.0), (j, -1.0)] {
            if row_of[end] != usize::MAX {
                for c in 0..2 {
                    rows.push(row_of[end] + c);
                    cols.push(col);
                    vals.push(sign * (pi[c] - pj[c]));
                }
            }
        }
    }
    let equalities = n_rows;
    let lengths = problem.lengths_m();
    let mut b = vec![0.0; equalities];
    for (col, &k) in set.iter().enumerate() {
        // −ℓ q ≤ −1 and ℓ q − s ≤ 0.
        rows.push(b.len());
        cols.push(col);
        vals.push(-lengths[k]);
        b.push(-1.0);
        rows.push(b.len());
        cols.push(col);
        vals.push(lengths[k]);
        rows.push(b.len());
        cols.push(m);
        vals.push(-1.0);
        b.push(0.0);
    }
    let a = CscMatrix::new_from_triplets(b.len(), m + 1, rows, cols, vals);
    let cones = vec![
        SupportedConeT::ZeroConeT(equalities),
        SupportedConeT::NonnegativeConeT(2 * m),
    ];
    let mut c = vec![0.0; m + 1];
    c[m] = 1.0;
    (a, b, cones, c)
}

/// clarabel with the LDLᵀ backend `method` on the plan LP of `problem`.
pub fn solve_plan(problem: &UniformityProblem, method: &str) -> PlanOptimum {
    let (a, b, cones, c) = plan_program(problem);
    let n = c.len();
    let p = CscMatrix::zeros((n, n));
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .direct_solve_method(method.to_string())
        .build()
        .expect("valid clarabel settings");
    let mut solver = DefaultSolver::new(&p, &c, &a, &b, &cones, settings).expect("clarabel setup");
    solver.solve();
    let solution = &solver.solution;
    let x = &solution.x;
    let set = &problem.sets()[0].edges;
    let lengths = problem.lengths_m();
    let tensions = set.iter().enumerate().map(|(col, &k)| lengths[k] * x[col]);
    let (min, max) = tensions.fold((f64::INFINITY, 0.0f64), |(lo, hi), t| {
        (lo.min(t), hi.max(t))
    });
    PlanOptimum {
        ratio: if solution.status == SolverStatus::Solved {
            max / min
        } else {
            f64::NAN
        },
        status: format!("{:?}", solution.status),
        iterations: solution.iterations,
    }
}
