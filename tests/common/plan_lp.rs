//! clarabel on the plan LP of a tied net, written here from the network alone
//! (independently of `src/uniformity/plan.rs`): the net is the set's cables
//! and every other cable joining two of their nodes (a boundary outside the
//! set), two equilibrium rows per free net node (the ties, vertical, carry
//! no plan force),
//!
//! ```text
//! min s  s.t.  Σ_k ±q_k (p_i − p_j) = 0 per free net node,
//!              1 ≤ ℓ_k q_k ≤ s (k in the set),
//!              f ≤ ℓ_k q_k     (the net's other cables; f the problem's
//!                               least tension fraction),
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
    let (net, in_set) = net_cables(problem);
    let fixed = network.fixed_mask();
    let mut row_of = vec![usize::MAX; network.n_nodes()];
    let mut n_rows = 0;
    for &k in &net {
        for i in network.edges[k] {
            if !fixed[i] && row_of[i] == usize::MAX {
                row_of[i] = n_rows;
                n_rows += 2;
            }
        }
    }
    let m = net.len();
    let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
    for (col, &k) in net.iter().enumerate() {
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
    for (col, &k) in net.iter().enumerate() {
        // −ℓ q ≤ −1 (−f off the set), and ℓ q − s ≤ 0 on the set.
        rows.push(b.len());
        cols.push(col);
        vals.push(-lengths[k]);
        b.push(if in_set[k] {
            -1.0
        } else {
            -problem.min_tension_fraction
        });
        if in_set[k] {
            rows.push(b.len());
            cols.push(col);
            vals.push(lengths[k]);
            rows.push(b.len());
            cols.push(m);
            vals.push(-1.0);
            b.push(0.0);
        }
    }
    let a = CscMatrix::new_from_triplets(b.len(), m + 1, rows, cols, vals);
    let cones = vec![
        SupportedConeT::ZeroConeT(equalities),
        SupportedConeT::NonnegativeConeT(b.len() - equalities),
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
    let (net, in_set) = net_cables(problem);
    let lengths = problem.lengths_m();
    let tensions = net
        .iter()
        .enumerate()
        .filter(|&(_, &k)| in_set[k])
        .map(|(col, &k)| lengths[k] * x[col]);
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

/// The net's cables (the set's and every other cable joining two of their
/// nodes, in network order) and whether each cable of the network is in
/// the set.
fn net_cables(problem: &UniformityProblem) -> (Vec<usize>, Vec<bool>) {
    let network = problem.network();
    let mut in_set = vec![false; network.n_edges()];
    let mut on_net = vec![false; network.n_nodes()];
    for &k in &problem.sets()[0].edges {
        in_set[k] = true;
        for i in network.edges[k] {
            on_net[i] = true;
        }
    }
    let net = (0..network.n_edges())
        .filter(|&k| in_set[k] || network.edges[k].iter().all(|&i| on_net[i]))
        .collect();
    (net, in_set)
}
