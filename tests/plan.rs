//! The plan route of `lp` on nets that are not ours: an independent generator
//! (`tests/common/hexnet.rs`: shuffled nodes and cables, other group names,
//! every free node tied to its own fixed anchor) reproduces the reference
//! net's kind; `lp` takes the plan route on it and agrees with clarabel on the
//! full problem; tilted ties are refused by name and solved in full, with the
//! reason in the warnings; the command line prints the route.

mod common;

use common::hexnet::{self, HexNet};
use ringmesh::network::Network;
use ringmesh::uniformity::{Bisection, Design, Lp, Route, UniformityProblem, UniformitySolver};

/// The uniformity problem of a generated net: `surface` and `rim` together.
fn problem(network: Network) -> UniformityProblem {
    hexnet::tied_net_problem(network, "hangers", 50.0, 1e9)
}

/// Clarabel on the full problem: ratio bisection of full LP feasibility.
fn full_ratio(problem: &UniformityProblem) -> f64 {
    Bisection {
        relative_tolerance: 1e-10,
        ..Bisection::default()
    }
    .solve(problem)
    .unwrap()
    .ratio
}

fn assert_balanced(design: &Design) {
    assert!(
        design.max_residual_n <= 1e-8 * design.max_tension_n,
        "residual {:e} vs {:e}",
        design.max_residual_n,
        design.max_tension_n
    );
    assert!(design.q.iter().all(|&q| q > 0.0));
}

#[test]
fn the_generator_reproduces_the_reference_net() {
    let generated = HexNet::like_hex5(5).build();
    let reference = common::reference_network();
    assert_eq!(generated.n_nodes(), reference.n_nodes());
    assert_eq!(generated.n_edges(), reference.n_edges());
    assert_eq!(generated.fixed.len(), reference.fixed.len());
    // The same points, in another order.
    let nearest = |p: &[f64; 3]| {
        reference
            .nodes
            .iter()
            .map(|r| common::max_abs_diff(&[*p], &[*r]))
            .fold(f64::INFINITY, f64::min)
    };
    let difference = generated.nodes.iter().map(nearest).fold(0.0, f64::max);
    assert!(difference <= 1e-9, "{difference:e} m");
    // And the reference's optimum (its README: 20.4503), by the plan route.
    let design = Lp.solve(&problem(generated)).unwrap();
    assert_eq!(
        design.route,
        Some(Route::PlanInteriorPoint),
        "{:?}",
        design.warnings
    );
    assert!((design.ratio - 20.4503).abs() <= 5e-4, "{}", design.ratio);
}

#[test]
fn the_reference_net_takes_the_plan_route() {
    let problem = hexnet::tied_net_problem(common::reference_network(), "tie", 70.0, 1e6);
    let design = Lp.solve(&problem).unwrap();
    assert_eq!(
        design.route,
        Some(Route::PlanInteriorPoint),
        "{:?}",
        design.warnings
    );
    assert!(design.warnings.is_empty(), "{:?}", design.warnings);
    assert!((design.ratio - 20.4503).abs() <= 5e-4, "{}", design.ratio);
}

#[test]
fn an_independent_net_takes_the_plan_route_and_matches_the_full_lp() {
    for spec in [
        HexNet::like_hex5(9),
        HexNet {
            seed: 7,
            ..HexNet::with_free_nodes(300, 100.0)
        },
    ] {
        let problem = problem(spec.build());
        let design = Lp.solve(&problem).unwrap();
        assert_eq!(
            design.route,
            Some(Route::PlanInteriorPoint),
            "{spec:?}: {:?}",
            design.warnings
        );
        assert!(design.warnings.is_empty(), "{:?}", design.warnings);
        assert_balanced(&design);
        let full = full_ratio(&problem);
        assert!(
            (design.ratio - full).abs() <= 1e-6 * full,
            "{spec:?}: plan {} vs full {full}",
            design.ratio
        );
    }
}

#[test]
fn tilted_ties_are_refused_by_name_and_solved_in_full() {
    let spec = HexNet {
        tilt_deg: 1.0,
        ..HexNet::like_hex5(6)
    };
    let network = spec.build();
    let problem = problem(network.clone());
    let design = Lp.solve(&problem).unwrap();
    assert_eq!(design.route, Some(Route::FullClarabel));
    assert_balanced(&design);
    let warning = design
        .warnings
        .iter()
        .find(|w| w.contains("off vertical"))
        .unwrap_or_else(|| panic!("no reason in {:?}", design.warnings));
    // "… tie K at node I is 1.000° off vertical …": K a hanger, I its free end.
    let words: Vec<&str> = warning
        .split_whitespace()
        .map(|w| w.trim_start_matches('('))
        .collect();
    let at = words
        .iter()
        .position(|&w| w == "tie")
        .expect("names the tie");
    let tie: usize = words[at + 1].parse().expect("tie index");
    assert_eq!(words[at + 2], "at");
    assert_eq!(words[at + 3], "node");
    let node: usize = words[at + 4].parse().expect("node index");
    assert_eq!(network.group_of(tie), "hangers");
    assert!(network.edges[tie].contains(&node));
    assert!(!network.fixed_mask()[node]);
    assert!(warning.contains("1.000°"), "{warning}");
    let full = full_ratio(&problem);
    assert!(
        (design.ratio - full).abs() <= 1e-6 * full,
        "{} vs {full}",
        design.ratio
    );
}

#[test]
fn the_command_line_prints_the_route() {
    let dir = tempfile::tempdir().unwrap();
    for (tilt_deg, route, warning) in [
        (0.0, "route: plan LP, interior point", None),
        (
            1.0,
            "route: full 3-D LP, clarabel",
            Some("warning: lp: not a tied net's plan problem (tie "),
        ),
    ] {
        let net = dir.path().join(format!("net-{tilt_deg}.json"));
        let out = dir.path().join(format!("out-{tilt_deg}.json"));
        let spec = HexNet {
            tilt_deg,
            ..HexNet::like_hex5(4)
        };
        std::fs::write(&net, serde_json::to_string(&spec.build()).unwrap()).unwrap();
        let output = common::ringmesh(&[
            "uniformity",
            net.to_str().unwrap(),
            "--solver",
            "lp",
            "--groups",
            "surface,rim",
            "-o",
            out.to_str().unwrap(),
        ]);
        let stdout = String::from_utf8_lossy(&output.stdout);
        assert!(output.status.success(), "{stdout}");
        assert!(stdout.contains(route), "{stdout}");
        match warning {
            Some(w) => assert!(stdout.contains(w), "{stdout}"),
            None => assert!(!stdout.contains("warning"), "{stdout}"),
        }
    }
}
