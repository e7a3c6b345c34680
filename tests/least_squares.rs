//! The `least-squares` solver: its results satisfy their optimality conditions,
//! the Tikhonov family moves monotonically between equilibrium and uniformity,
//! and an optimum outside `0 < q ≤ [q]` is reported, naming the cables, never
//! returned.

mod common;

use faer::Mat;
use ringmesh::algebra::norm2;
use ringmesh::uniformity::{
    LeastSquares, Lp, SurfaceTarget, Termination, UniformityError, UniformityProblem,
    UniformitySet, UniformitySolver,
};
use ringmesh::Network;

fn scene_problem(name: &str) -> UniformityProblem {
    common::front_problem(&common::scene(name))
}

/// The reference front net with uniformity sets `(groups joined by '+', target)`;
/// cables of other groups (the ties) are in no set.
fn hex5_problem(sets: &[(&str, f64)]) -> UniformityProblem {
    let network = common::reference_network();
    let sets = sets
        .iter()
        .map(|&(name, mean_tension_n)| UniformitySet {
            name: name.into(),
            edges: (0..network.n_edges())
                .filter(|&k| name.split('+').any(|g| g == network.group_of(k)))
                .collect(),
            mean_tension_n,
        })
        .collect();
    let fixed = network.fixed_mask();
    let surface_nodes = (0..network.n_nodes()).filter(|&i| !fixed[i]).collect();
    UniformityProblem::new(network, sets, surface_nodes, SurfaceTarget::Prescribed, 1e6).unwrap()
}

/// One free node in the plane z = 0 with five cables of unit length at 0°, 15°,
/// 30°, 45° and 185°, all in one set (70 N). The directions leave no half-plane
/// empty, so strictly positive self-stresses exist, but the least-squares one,
/// the projection of the targets onto the self-stresses, compresses the 45°
/// cable (≈ −7.7 N).
fn star_problem() -> UniformityProblem {
    let angles_deg = [0.0f64, 15.0, 30.0, 45.0, 185.0];
    let mut nodes = vec![[0.0; 3]];
    nodes.extend(angles_deg.iter().map(|a| {
        let a = a.to_radians();
        [a.cos(), a.sin(), 0.0]
    }));
    let network = Network {
        nodes,
        edges: (1..=5).map(|j| [0, j]).collect(),
        fixed: (1..=5).collect(),
        q: vec![1.0; 5],
        loads: None,
        groups: None,
    };
    UniformityProblem::new(
        network,
        vec![UniformitySet {
            name: "star".into(),
            edges: (0..5).collect(),
            mean_tension_n: 70.0,
        }],
        vec![0],
        SurfaceTarget::Prescribed,
        1e6,
    )
    .unwrap()
}

/// `A` as a dense matrix (3·n_free × n_edges).
fn dense_a(problem: &UniformityProblem) -> Mat<f64> {
    problem
        .structure()
        .equilibrium_matrix(&problem.network().nodes)
        .to_dense()
}

fn matvec(a: &Mat<f64>, x: &[f64]) -> Vec<f64> {
    (0..a.nrows())
        .map(|i| (0..a.ncols()).map(|j| a[(i, j)] * x[j]).sum())
        .collect()
}

fn matvec_t(a: &Mat<f64>, y: &[f64]) -> Vec<f64> {
    (0..a.ncols())
        .map(|j| (0..a.nrows()).map(|i| a[(i, j)] * y[i]).sum())
        .collect()
}

/// `A q − p`.
fn equilibrium_residual(problem: &UniformityProblem, a: &Mat<f64>, q: &[f64]) -> Vec<f64> {
    let p = problem.free_loads();
    matvec(a, q).iter().zip(&p).map(|(x, p)| x - p).collect()
}

/// The gradient of `½‖L q − T̄‖²` over the sets, `Lᵀ(L q − T̄)`.
fn uniformity_gradient(problem: &UniformityProblem, q: &[f64]) -> Vec<f64> {
    let lengths = problem.lengths_m();
    let mut g = vec![0.0; q.len()];
    for set in problem.sets() {
        for &k in &set.edges {
            g[k] += lengths[k] * (lengths[k] * q[k] - set.mean_tension_n);
        }
    }
    g
}

/// `‖L q − T̄‖²` over the sets.
fn deviation_squared(problem: &UniformityProblem, q: &[f64]) -> f64 {
    let lengths = problem.lengths_m();
    problem
        .sets()
        .iter()
        .flat_map(|set| {
            set.edges
                .iter()
                .map(move |&k| (lengths[k] * q[k] - set.mean_tension_n).powi(2))
        })
        .sum()
}

/// The part of `g` outside the row space of `A` (dense SVD; the rank is read
/// from the singular values with the usual `max(m, n) · ε · σ_max` cut).
fn outside_row_space(a: &Mat<f64>, g: &[f64]) -> Vec<f64> {
    let svd = a.svd().unwrap();
    let s = svd.S().column_vector();
    let v = svd.V();
    let sigma_max = (0..s.nrows()).map(|i| s[i]).fold(0.0, f64::max);
    let cut = a.nrows().max(a.ncols()) as f64 * f64::EPSILON * sigma_max;
    let mut rest = g.to_vec();
    for i in (0..s.nrows()).filter(|&i| s[i] > cut) {
        let coefficient: f64 = (0..g.len()).map(|k| v[(k, i)] * g[k]).sum();
        for (k, r) in rest.iter_mut().enumerate() {
            *r -= coefficient * v[(k, i)];
        }
    }
    rest
}

#[test]
fn equality_optimum_satisfies_its_kkt_conditions() {
    for (name, problem) in [
        ("small-hex", scene_problem("small-hex")),
        ("small-offset", scene_problem("small-offset")),
        ("hex5 front", hex5_problem(&[("front", 70.0)])),
        (
            "hex5 front, boundary",
            hex5_problem(&[("front", 70.0), ("boundary", 1000.0)]),
        ),
    ] {
        let design = LeastSquares::default().solve(&problem).unwrap();
        assert_eq!(design.termination, Termination::Converged, "{name}");
        // Primal feasibility: A q = p.
        assert!(
            design.max_residual_n <= 1e-8 * design.max_tension_n,
            "{name}: residual {:e} N, max tension {} N",
            design.max_residual_n,
            design.max_tension_n
        );
        // Stationarity: Lᵀ(L q − T̄) + Aᵀ μ = 0 for some μ, i.e. the gradient
        // of the uniformity objective (sets only: no trace of the
        // regularisation remains) lies in the row space of A.
        let a = dense_a(&problem);
        let g = uniformity_gradient(&problem, &design.q);
        let rest = outside_row_space(&a, &g);
        assert!(
            norm2(&rest) <= 1e-8 * norm2(&g),
            "{name}: |g outside row space| = {:e}, |g| = {:e}",
            norm2(&rest),
            norm2(&g)
        );
    }
}

#[test]
fn equality_optimum_does_not_depend_on_the_regularisation() {
    let problem = scene_problem("small-hex");
    let solve = |other_weight| {
        LeastSquares {
            other_weight,
            ..LeastSquares::default()
        }
        .solve(&problem)
        .unwrap()
    };
    let (a, b) = (solve(1e-6), solve(1e-8));
    let largest = a.q.iter().copied().fold(0.0, f64::max);
    for (k, (qa, qb)) in a.q.iter().zip(&b.q).enumerate() {
        assert!((qa - qb).abs() <= 1e-9 * largest, "cable {k}: {qa} vs {qb}");
    }
    // Without proximal steps the regularisation pulls the cables outside the
    // set towards τ, which costs uniformity.
    let biased = LeastSquares {
        other_weight: 1e-3,
        max_proximal_steps: 0,
        ..LeastSquares::default()
    }
    .solve(&problem)
    .unwrap();
    assert!(deviation_squared(&problem, &biased.q) > deviation_squared(&problem, &a.q));
}

#[test]
fn tikhonov_optimum_satisfies_its_normal_equations() {
    for name in ["small-hex", "small-offset"] {
        let problem = scene_problem(name);
        let a = dense_a(&problem);
        for lambda in [1e-3, 1e-1, 1.0] {
            let design = LeastSquares {
                lambda: Some(lambda),
                ..LeastSquares::default()
            }
            .solve(&problem)
            .unwrap();
            assert_eq!(
                design.termination,
                Termination::Converged,
                "{name} λ {lambda}"
            );
            // ∇ = Aᵀ(A q − p) + λ Lᵀ(L q − T̄) = 0.
            let equilibrium = matvec_t(&a, &equilibrium_residual(&problem, &a, &design.q));
            let uniformity = uniformity_gradient(&problem, &design.q);
            let gradient: Vec<f64> = equilibrium
                .iter()
                .zip(&uniformity)
                .map(|(e, u)| e + lambda * u)
                .collect();
            let scale = norm2(&equilibrium) + lambda * norm2(&uniformity);
            assert!(
                norm2(&gradient) <= 1e-8 * scale,
                "{name} λ {lambda}: |∇| = {:e}, scale {scale:e}",
                norm2(&gradient)
            );
        }
    }
}

#[test]
fn larger_lambda_trades_equilibrium_for_uniformity() {
    // Proved in the module docs: ‖A q − p‖² non-decreasing and ‖L q − T̄‖²
    // non-increasing in λ; λ → 0 gives the equality-constrained optimum.
    for name in ["small-hex", "small-offset"] {
        let problem = scene_problem(name);
        let a = dense_a(&problem);
        let exact = LeastSquares::default().solve(&problem).unwrap();
        let mut previous = (0.0, deviation_squared(&problem, &exact.q));
        for lambda in [1e-4, 1e-3, 1e-2, 1e-1, 1.0] {
            let design = LeastSquares {
                lambda: Some(lambda),
                ..LeastSquares::default()
            }
            .solve(&problem)
            .unwrap();
            let f = norm2(&equilibrium_residual(&problem, &a, &design.q)).powi(2);
            let g = deviation_squared(&problem, &design.q);
            let slack = 1e-9;
            assert!(
                f >= previous.0 * (1.0 - slack),
                "{name} λ {lambda}: f {f} < {}",
                previous.0
            );
            assert!(
                g <= previous.1 * (1.0 + slack),
                "{name} λ {lambda}: g {g} > {}",
                previous.1
            );
            assert!(
                g < previous.1,
                "{name} λ {lambda}: uniformity did not improve"
            );
            previous = (f, g);
        }
        // The λ → 0 limit: q(λ) − q(0) = O(λ).
        let near = LeastSquares {
            lambda: Some(1e-9),
            ..LeastSquares::default()
        }
        .solve(&problem)
        .unwrap();
        let largest = exact.q.iter().copied().fold(0.0, f64::max);
        for (qa, qb) in exact.q.iter().zip(&near.q) {
            assert!((qa - qb).abs() <= 1e-6 * largest, "{name}: {qa} vs {qb}");
        }
    }
}

#[test]
fn positivity_failure_is_reported_naming_the_cables() {
    let problem = star_problem();
    let error = LeastSquares::default().solve(&problem).unwrap_err();
    assert!(
        matches!(
            error,
            UniformityError::Unsupported {
                solver: "least-squares",
                ..
            }
        ),
        "{error}"
    );
    let message = error.to_string();
    assert!(message.contains("positivity fails"), "{message}");
    assert!(message.contains("1 of 5 cables"), "{message}");
    assert!(message.contains("cable 3 (all, nodes 0–4)"), "{message}");
    // Not an infeasible geometry: the LP finds strictly positive force densities.
    let design = Lp.solve(&problem).unwrap();
    assert_eq!(design.termination, Termination::Converged);
    assert!(design.q.iter().all(|&q| q > 0.0));
    // And Tikhonov with a large λ stays near the (positive) targets.
    let design = LeastSquares {
        lambda: Some(1e3),
        ..LeastSquares::default()
    }
    .solve(&problem)
    .unwrap();
    assert!(design.q.iter().all(|&q| q > 0.0));
    let error = LeastSquares {
        lambda: Some(1e-3),
        ..LeastSquares::default()
    }
    .solve(&problem)
    .unwrap_err();
    assert!(error.to_string().contains("a larger λ"), "{error}");
}

#[test]
fn positivity_failure_of_a_set_spanning_front_and_boundary_is_reported() {
    // One target for interior and boundary cables, whose equilibrium tensions
    // differ twentyfold: the closest self-stress compresses interior cables.
    let problem = hex5_problem(&[("front+boundary", 70.0)]);
    let message = LeastSquares::default()
        .solve(&problem)
        .unwrap_err()
        .to_string();
    assert!(message.contains("positivity fails"), "{message}");
    assert!(message.contains("(front, nodes "), "{message}");
    // The optimal-ratio design exists (reference: ratio 20.4503).
    let design = Lp.solve(&problem).unwrap();
    assert!(
        (design.ratio / 20.4503 - 1.0).abs() < 1e-4,
        "{}",
        design.ratio
    );
}

#[test]
fn force_density_bound_violation_is_reported_naming_the_cables() {
    let mut problem = scene_problem("small-hex");
    let q_max = LeastSquares::default()
        .solve(&problem)
        .unwrap()
        .q
        .into_iter()
        .fold(0.0, f64::max);
    problem.max_force_density_n_per_m = 0.5 * q_max;
    let message = LeastSquares::default()
        .solve(&problem)
        .unwrap_err()
        .to_string();
    assert!(message.contains("exceeds the bound"), "{message}");
    assert!(message.contains("cable "), "{message}");
}

#[test]
fn every_returned_design_has_positive_bounded_q() {
    for problem in [
        scene_problem("small-hex"),
        scene_problem("small-offset"),
        hex5_problem(&[("front", 70.0)]),
        hex5_problem(&[("front+boundary", 70.0)]),
        star_problem(),
    ] {
        for lambda in [None, Some(1e-3), Some(1.0), Some(1e3)] {
            let solver = LeastSquares {
                lambda,
                ..LeastSquares::default()
            };
            match solver.solve(&problem) {
                Ok(design) => assert!(design
                    .q
                    .iter()
                    .all(|&q| q > 0.0 && q <= problem.max_force_density_n_per_m)),
                Err(UniformityError::Unsupported { reason, .. }) => {
                    assert!(reason.contains("positivity fails"), "{reason}")
                }
                Err(e) => panic!("λ {lambda:?}: {e}"),
            }
        }
    }
}

#[test]
fn least_squares_never_beats_the_optimal_ratio() {
    for problem in [
        scene_problem("small-hex"),
        scene_problem("small-offset"),
        hex5_problem(&[("front", 70.0)]),
    ] {
        let optimal = Lp.solve(&problem).unwrap().ratio;
        let design = LeastSquares::default().solve(&problem).unwrap();
        assert!(
            design.ratio >= optimal * (1.0 - 1e-6),
            "{} < {optimal}",
            design.ratio
        );
    }
}
