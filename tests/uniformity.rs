//! The clarabel-based uniformity solvers: LP and bisection agree with each other
//! and with an independent implementation, satisfy equilibrium and bounds, and
//! report infeasible geometry by node.

mod common;

use ringmesh::geometry::build_mesh;
use ringmesh::uniformity::{
    Bisection, Design, Gradient, Lp, SurfaceTarget, Termination, UniformityError,
    UniformityProblem, UniformitySet, UniformitySolver,
};
use ringmesh::CableGroup;

fn reference_problem() -> UniformityProblem {
    let network = common::reference_network();
    let edges = (0..network.n_edges())
        .filter(|&k| matches!(network.group_of(k), "front" | "boundary"))
        .collect();
    let fixed = network.fixed_mask();
    let surface = (0..91).filter(|&i| !fixed[i]).collect();
    let set = UniformitySet {
        name: "front+boundary".into(),
        edges,
        mean_tension_n: 70.0,
    };
    UniformityProblem::new(network, vec![set], surface, SurfaceTarget::Prescribed, 1e6).unwrap()
}

/// Equilibrium on the prescribed geometry, bounds, and an exact forward solve.
fn assert_sound(problem: &UniformityProblem, design: &Design) {
    assert_eq!(
        design.termination,
        Termination::Converged,
        "{:?}",
        design.warnings
    );
    assert!(
        design.max_residual_n <= 1e-8 * design.max_tension_n,
        "residual {:e} vs max force {:e}",
        design.max_residual_n,
        design.max_tension_n
    );
    assert!(design
        .q
        .iter()
        .all(|&q| q > 0.0 && q <= problem.max_force_density_n_per_m));
    assert!(
        design.surface_rms_m <= 1e-9,
        "surface RMS {:e} m",
        design.surface_rms_m
    );
}

#[test]
fn lp_and_bisection_agree_on_the_test_scenes() {
    for name in ["small-hex", "small-offset", "paper-26m"] {
        let s = common::scene(name);
        let problem = common::front_problem(&s);
        let lp = Lp.solve(&problem).unwrap();
        let bisection = Bisection::default().solve(&problem).unwrap();
        assert_sound(&problem, &lp);
        assert_sound(&problem, &bisection);
        let relative = (lp.ratio - bisection.ratio).abs() / lp.ratio;
        assert!(
            relative <= 1e-6,
            "{name}: lp {} vs bisection {}",
            lp.ratio,
            bisection.ratio
        );
        // The pretension level is the scene's.
        let mean = bisection.sets[0].mean_tension_n;
        assert!(
            (mean - s.front_net.mean_tension_n).abs() <= 1e-6 * mean,
            "{name}: mean {mean}"
        );
        assert!((lp.sets[0].mean_tension_n - mean).abs() <= 1e-6 * mean);
    }
}

#[test]
fn lp_and_bisection_reproduce_the_reference_optimum() {
    let problem = reference_problem();
    let lp = Lp.solve(&problem).unwrap();
    let bisection = Bisection::default().solve(&problem).unwrap();
    for design in [&lp, &bisection] {
        assert!(design.max_residual_n <= 1e-8 * design.max_tension_n);
        assert!(
            (design.ratio - 20.4503).abs() <= 5e-4,
            "{}: {}",
            design.solver,
            design.ratio
        );
    }
    assert!(
        (lp.ratio - bisection.ratio).abs() <= 1e-6 * lp.ratio,
        "{} vs {}",
        lp.ratio,
        bisection.ratio
    );
}

#[test]
fn bisection_handles_several_sets_and_loads() {
    let s = common::scene("small-hex");
    let mut mesh = build_mesh(&s).unwrap();
    // A downward load on every free front node: not scale-free any more.
    let n = mesh.network.n_nodes();
    let fixed = mesh.network.fixed_mask();
    mesh.network.loads = Some(
        (0..n)
            .map(|i| {
                if i < mesh.n_front_nodes && !fixed[i] {
                    [0.0, 0.0, -2.0]
                } else {
                    [0.0; 3]
                }
            })
            .collect(),
    );
    let groups = [(CableGroup::Front, 70.0), (CableGroup::Rear, 140.0)];
    let problem =
        UniformityProblem::from_mesh(&mesh, &groups, s.cables.max_force_density_n_per_m).unwrap();
    assert!(matches!(
        Lp.solve(&problem),
        Err(UniformityError::Unsupported { .. })
    ));
    let design = Bisection::default().solve(&problem).unwrap();
    assert_eq!(design.sets.len(), 2);
    assert!(
        design.max_residual_n <= 1e-8 * design.max_tension_n,
        "{:e}",
        design.max_residual_n
    );
    assert!((design.sets[0].mean_tension_n - 70.0).abs() <= 1e-6 * 70.0);
    // Both sets are held to the common ratio.
    for set in &design.sets {
        assert!(set.ratio <= design.ratio * (1.0 + 1e-9), "{set:?}");
    }
}

#[test]
fn tightening_epsilon_never_improves_the_ratio() {
    let problem = common::front_problem(&common::scene("small-hex"));
    let mut previous = 0.0;
    for epsilon in [10.0, 3.0, 1.0, 0.3, 0.1, 0.0] {
        let design = Bisection {
            epsilon_n: epsilon,
            ..Bisection::default()
        }
        .solve(&problem)
        .unwrap();
        assert!(
            design.ratio >= previous * (1.0 - 1e-6),
            "ε = {epsilon}: {} < {previous}",
            design.ratio
        );
        previous = design.ratio;
    }
}

#[test]
fn boundary_node_on_a_straight_chord_is_reported_infeasible_by_name() {
    let s = common::scene("small-hex");
    let mut mesh = build_mesh(&s).unwrap();
    // Ring 3, sector 0, j = 1: one third along the chord from hinge 0 to hinge 1.
    let node = 1 + 6 * 3 * 2 / 2 + 1;
    let (a, b) = (mesh.truss.top_m[0], mesh.truss.top_m[1]);
    let [x, y] = [a[0] + (b[0] - a[0]) / 3.0, a[1] + (b[1] - a[1]) / 3.0];
    mesh.network.nodes[node] = [x, y, mesh.paraboloid.z(x, y)];
    let rear = node + mesh.n_front_nodes;
    mesh.network.nodes[rear][0] = x;
    mesh.network.nodes[rear][1] = y;
    let problem =
        UniformityProblem::from_mesh(&mesh, &[(CableGroup::Front, 70.0)], 5000.0).unwrap();
    let (exact, smooth) = (Gradient::default(), Gradient::smooth());
    let solvers: [&dyn UniformitySolver; 4] = [&Lp, &Bisection::default(), &exact, &smooth];
    for solver in solvers {
        // Infeasibility is a design's termination; a caller that needs a
        // design gets it as the error naming the nodes.
        match solver.solve(&problem).and_then(Design::feasible) {
            Err(UniformityError::Infeasible {
                slack_nodes: Some(slack),
                ..
            }) => {
                let nodes = slack.nodes;
                assert!(
                    nodes.contains(&node),
                    "{}: named {nodes:?}, not {node}",
                    solver.name()
                );
            }
            other => panic!(
                "{}: expected infeasible, got {:?}",
                solver.name(),
                other.map(|d| d.ratio)
            ),
        }
    }
}
