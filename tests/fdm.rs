//! The force density method against closed forms, symmetry, global balance,
//! finite differences and an independent implementation's data.

mod common;

use ringmesh::fdm::{solve_network, FdmStructure};
use ringmesh::geometry::build_mesh;
use ringmesh::{Network, Scene};

/// A scene with the given bays and rings, on a 26 m aperture.
fn sized_scene(bays: usize, rings: usize) -> Scene {
    let mut s = common::scene("realistic-26m");
    s.truss.bays = bays;
    s.front_net.rings = rings;
    s
}

#[test]
fn single_node_pulled_by_four_cables_matches_closed_form() {
    // One free node, four fixed anchors, loaded: x = (Σ q_k x_k + p) / Σ q_k.
    let anchors = [
        [2.0, 0.0, 0.5],
        [0.0, 3.0, -1.0],
        [-1.5, 0.0, 0.25],
        [0.0, -2.5, 2.0],
    ];
    let q = [1.5, 0.7, 2.2, 3.1];
    let p = [0.3, -1.1, 4.0];
    let mut nodes = vec![[9.0, 9.0, 9.0]];
    nodes.extend_from_slice(&anchors);
    let network = Network {
        nodes,
        edges: vec![[0, 1], [0, 2], [3, 0], [0, 4]],
        fixed: vec![1, 2, 3, 4],
        q: q.to_vec(),
        loads: Some(vec![p, [0.0; 3], [0.0; 3], [0.0; 3], [0.0; 3]]),
        groups: None,
    };
    let (_, eq) = solve_network(&network).unwrap();
    let sum_q: f64 = q.iter().sum();
    let expected: [f64; 3] = std::array::from_fn(|c| {
        (anchors.iter().zip(&q).map(|(a, qk)| qk * a[c]).sum::<f64>() + p[c]) / sum_q
    });
    let x = eq.nodes_xyz_m[0];
    for c in 0..3 {
        assert!(
            (x[c] - expected[c]).abs() <= 1e-12,
            "coordinate {c}: {} vs {}",
            x[c],
            expected[c]
        );
    }
    for (k, a) in anchors.iter().enumerate() {
        let length = ((0..3).map(|c| (x[c] - a[c]).powi(2)).sum::<f64>()).sqrt();
        assert!((eq.edges_lengths_m[k] - length).abs() <= 1e-12);
        assert!((eq.edges_forces_n[k] - q[k] * length).abs() <= 1e-12);
    }
}

#[test]
fn symmetric_star_sags_by_load_over_total_force_density() {
    // A free hub on a horizontal ring of n anchors at radius r, load P down:
    // the hub stays on the axis at depth z = −P/(n q).
    let (n, r, q, load) = (7usize, 2.0, 3.0, 10.0);
    let mut nodes = vec![[0.4, -0.2, 1.0]];
    for k in 0..n {
        let a = std::f64::consts::TAU * k as f64 / n as f64;
        nodes.push([r * a.cos(), r * a.sin(), 0.0]);
    }
    let mut loads = vec![[0.0; 3]; n + 1];
    loads[0] = [0.0, 0.0, -load];
    let network = Network {
        nodes,
        edges: (1..=n).map(|k| [0, k]).collect(),
        fixed: (1..=n).collect(),
        q: vec![q; n],
        loads: Some(loads),
        groups: None,
    };
    let (_, eq) = solve_network(&network).unwrap();
    let hub = eq.nodes_xyz_m[0];
    assert!(hub[0].abs() <= 1e-14 && hub[1].abs() <= 1e-14, "{hub:?}");
    assert!((hub[2] + load / (n as f64 * q)).abs() <= 1e-14, "{hub:?}");
    let tension = q * (r * r + hub[2] * hub[2]).sqrt();
    assert!(eq
        .edges_forces_n
        .iter()
        .all(|t| (t - tension).abs() <= 1e-12));
}

#[test]
fn residual_is_tiny_on_generated_nets_up_to_ten_thousand_nodes() {
    for (bays, rings) in [(6, 3), (30, 4), (30, 18), (6, 57)] {
        let mesh = build_mesh(&sized_scene(bays, rings)).unwrap();
        let (_, eq) = solve_network(&mesh.network).unwrap();
        let n = mesh.network.n_nodes();
        let relative = eq.max_residual_n() / eq.max_force_n();
        assert!(
            relative <= 1e-9,
            "{n} nodes: residual {relative:e} × max force"
        );
        if bays == 6 && rings == 57 {
            assert!(n >= 10_000, "largest net has {n} nodes");
        }
    }
}

#[test]
fn symmetric_net_with_symmetric_q_has_rotational_symmetry() {
    // Initial q is uniform per group, so it shares the N-fold symmetry of the
    // sector grid; rotating node (ring i, sector k, j) by 2π/N must land on node
    // (i, k+1, j).
    let mesh = build_mesh(&common::scene("small-hex")).unwrap();
    let (bays, rings) = (6usize, 3usize);
    let (_, eq) = solve_network(&mesh.network).unwrap();
    let x = &eq.nodes_xyz_m;
    let (sin, cos) = (std::f64::consts::TAU / bays as f64).sin_cos();
    let rotate = |p: [f64; 3]| [cos * p[0] - sin * p[1], sin * p[0] + cos * p[1], p[2]];
    let n_front = mesh.n_front_nodes;
    let mut worst: f64 = 0.0;
    for net in [0, n_front] {
        for i in 1..=rings {
            let first = 1 + bays * i * (i - 1) / 2;
            for local in 0..bays * i {
                let image = first + (local + i) % (bays * i);
                let (a, b) = (rotate(x[net + first + local]), x[net + image]);
                worst = worst.max(common::max_abs_diff(&[a], &[b]));
            }
        }
    }
    assert!(worst <= 1e-12, "asymmetry {worst:e} m");
    // And the shape is not trivially the input geometry: the hub moved.
    assert!(common::max_abs_diff(&x[..1], &mesh.network.nodes[..1]) > 1e-6);
}

#[test]
fn reactions_balance_loads_in_force_and_moment() {
    let mut network = build_mesh(&common::scene("small-offset")).unwrap().network;
    let loads: Vec<[f64; 3]> = (0..network.n_nodes())
        .map(|i| {
            let t = i as f64;
            [
                (0.7 * t).sin() * 3.0,
                (1.3 * t).cos() * 2.0,
                -5.0 - (0.3 * t).sin(),
            ]
        })
        .collect();
    network.loads = Some(loads.clone());
    let (structure, eq) = solve_network(&network).unwrap();
    let mut force = [0.0; 3];
    let mut moment = [0.0; 3];
    let mut scale: f64 = 0.0;
    let mut add = |x: [f64; 3], f: [f64; 3]| {
        for c in 0..3 {
            force[c] += f[c];
        }
        let m = [
            x[1] * f[2] - x[2] * f[1],
            x[2] * f[0] - x[0] * f[2],
            x[0] * f[1] - x[1] * f[0],
        ];
        for c in 0..3 {
            moment[c] += m[c];
        }
        scale = scale.max(f.iter().map(|v| v.abs()).fold(0.0, f64::max));
    };
    for (i, p) in loads.iter().enumerate() {
        add(eq.nodes_xyz_m[i], *p);
    }
    for (&i, r) in structure.fixed_nodes().iter().zip(&eq.reactions_n) {
        add(eq.nodes_xyz_m[i], *r);
    }
    let arm = 10.0; // m, the size of the scene
    for c in 0..3 {
        assert!(force[c].abs() <= 1e-10 * scale, "force {force:?}");
        assert!(moment[c].abs() <= 1e-10 * scale * arm, "moment {moment:?}");
    }
}

#[test]
fn d_matrix_equals_cft_q_cf() {
    let network = build_mesh(&common::scene("small-hex")).unwrap().network;
    let structure = FdmStructure::new(&network).unwrap();
    let q: Vec<f64> = (0..network.n_edges())
        .map(|k| 1.0 + (k % 7) as f64)
        .collect();
    let c = network.branch_node_matrix().to_dense();
    let free = structure.free_nodes();
    let d = structure.d_matrix(&q).to_dense();
    for (a, &i) in free.iter().enumerate() {
        for (b, &j) in free.iter().enumerate().filter(|&(b, _)| b >= a) {
            let expected: f64 = (0..network.n_edges())
                .map(|k| c[(k, i)] * q[k] * c[(k, j)])
                .sum();
            // d holds the lower triangle: row b ≥ column a.
            assert_eq!(d[(b, a)], expected, "D[{b},{a}]");
        }
    }
}

#[test]
fn equilibrium_matrix_times_q_is_the_load_at_equilibrium() {
    let mut network = build_mesh(&common::scene("small-offset")).unwrap().network;
    let loads: Vec<[f64; 3]> = (0..network.n_nodes())
        .map(|i| [0.0, 0.1 * (i % 3) as f64, -1.0])
        .collect();
    network.loads = Some(loads.clone());
    let (structure, eq) = solve_network(&network).unwrap();
    let a = structure.equilibrium_matrix(&eq.nodes_xyz_m);
    assert_eq!(
        (a.nrows(), a.ncols()),
        (3 * structure.free_nodes().len(), network.n_edges())
    );
    let q = faer::Col::<f64>::from_fn(network.n_edges(), |k| network.q[k]);
    let aq = &a * &q;
    for (f, &i) in structure.free_nodes().iter().enumerate() {
        for c in 0..3 {
            assert!(
                (aq[3 * f + c] - loads[i][c]).abs() <= 1e-9,
                "node {i} coordinate {c}"
            );
        }
    }
}

#[test]
fn adjoint_sensitivities_match_central_differences() {
    let network = build_mesh(&common::scene("small-offset")).unwrap().network;
    let structure = FdmStructure::new(&network).unwrap();
    let target: Vec<f64> = network.nodes.iter().map(|p| p[2]).collect();
    let weights: Vec<f64> = (0..network.n_edges())
        .map(|k| 1e-3 * (1.0 + (k % 5) as f64))
        .collect();
    // J = ½ Σ_i (z_i − z_i*)² + Σ_i 0.1·x_i + Σ_k w_k q_k².
    let objective = |q: &[f64]| {
        let eq = structure.solve(q, &network.nodes, None).unwrap();
        let j: f64 = eq
            .nodes_xyz_m
            .iter()
            .zip(&target)
            .map(|(p, z)| 0.5 * (p[2] - z).powi(2) + 0.1 * p[0])
            .sum::<f64>()
            + q.iter()
                .zip(&weights)
                .map(|(qk, w)| w * qk * qk)
                .sum::<f64>();
        (j, eq)
    };
    let q = network.q.clone();
    let (_, eq) = objective(&q);
    let dj_dx: Vec<[f64; 3]> = eq
        .nodes_xyz_m
        .iter()
        .zip(&target)
        .map(|(p, z)| [0.1, 0.0, p[2] - z])
        .collect();
    let dj_dq: Vec<f64> = q.iter().zip(&weights).map(|(qk, w)| 2.0 * w * qk).collect();
    let gradient = eq.sensitivities(&structure, &dj_dx, Some(&dj_dq));
    let mut worst: f64 = 0.0;
    for k in (0..q.len()).step_by(7) {
        let h = 1e-5 * q[k];
        let mut plus = q.clone();
        plus[k] += h;
        let mut minus = q.clone();
        minus[k] -= h;
        let fd = (objective(&plus).0 - objective(&minus).0) / (2.0 * h);
        let relative = (gradient[k] - fd).abs() / gradient[k].abs().max(1e-8);
        worst = worst.max(relative);
    }
    assert!(worst <= 1e-6, "worst relative error {worst:e}");
}

#[test]
fn reference_q_reproduces_reference_geometry() {
    let network = common::reference_network();
    let (_, eq) = solve_network(&network).unwrap();
    let error = common::max_abs_diff(&eq.nodes_xyz_m, &network.nodes);
    assert!(
        error <= 1e-11,
        "forward FDM moved the reference nodes by {error:e} m"
    );
}

#[test]
fn generator_reproduces_reference_front_net() {
    let reference = common::reference_network();
    // The reference: hexagon, 5 rings, D = 26 m, F = 4 m, sag 5 % of the bay chord.
    let mut s = common::scene("small-hex");
    s.reflector.aperture_diameter_m = 26.0;
    s.front_net.rings = 5;
    s.front_net.boundary_sag_ratio = 0.05;
    s.truss.height_m = 20.0;
    let mesh = build_mesh(&s).unwrap();
    assert_eq!(mesh.n_front_nodes, 91);
    let error = common::max_abs_diff(&mesh.network.nodes[..91], &reference.nodes[..91]);
    assert!(
        error <= 1e-12,
        "front net differs from the reference by {error:e} m"
    );
    // Same cables (as unordered pairs) and groups within the front net.
    let pairs = |net: &Network| {
        let mut v: Vec<(usize, usize, String)> = net
            .edges
            .iter()
            .enumerate()
            .filter(|(_, e)| e[0] < 91 && e[1] < 91)
            .map(|(k, e)| (e[0].min(e[1]), e[0].max(e[1]), net.group_of(k).to_string()))
            .collect();
        v.sort();
        v
    };
    assert_eq!(pairs(&mesh.network), pairs(&reference));
}

/// Force densities near the top of double precision (issue 19): at 1e300
/// N/m the solve keeps its relative accuracy and reports a finite residual
/// (it printed `inf`, from squaring the residual's components); at 1e308 the
/// tensions overflow and the solve is an error naming the cable, never a
/// result with `inf` or `null` in it (it put the node at the origin: the
/// sum of three 1e308 in `D` is infinite).
#[test]
fn force_densities_near_overflow_give_finite_results_or_an_error() {
    let star = |q: f64| Network {
        nodes: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.4, 0.3, 0.2],
        ],
        edges: vec![[0, 3], [1, 3], [2, 3]],
        fixed: vec![0, 1, 2],
        q: vec![q; 3],
        loads: Some(vec![[0.0; 3], [0.0; 3], [0.0; 3], [0.0, 0.0, -1.0]]),
        groups: None,
    };
    let (_, eq) = solve_network(&star(1e300)).unwrap();
    let largest = eq.edges_forces_n.iter().copied().fold(0.0, f64::max);
    assert!(largest > 1e299 && largest.is_finite());
    let residual = eq.max_residual_n();
    assert!(
        residual.is_finite() && residual <= 1e-14 * largest,
        "{residual:e}"
    );
    let e = solve_network(&star(1e308)).unwrap_err().to_string();
    assert!(
        e.contains("D = C_fᵀ Q C_f") && e.contains("overflow"),
        "{e}"
    );
}
