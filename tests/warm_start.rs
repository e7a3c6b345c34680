//! `lp`'s warm start ([`ringmesh::uniformity::WarmStart`]) on nets the
//! project's mesher did not make: the three families of issue 38
//! (`tests/common/nets.rs`), their boundary moved as the outer loop moves
//! it. From the neighbour's iterate the plan LP must reach the cold
//! solve's optimum in fewer iterations. `RINGMESH_WARM_FREE` sets the
//! size (free nodes, default 1 000); with `--nocapture` each family's
//! iterations and wall times, cold and warm, are printed.

#[path = "common/hexnet.rs"]
mod hexnet;
#[path = "common/nets.rs"]
mod nets;

use std::time::Instant;

use ringmesh::uniformity::{Design, Lp, Route, UniformityProblem, UniformitySolver};

/// `problem` with every boundary attachment (a fixed node no vertical tie
/// holds) moved radially inward by `h`, m.
fn boundary_moved_inward(problem: &UniformityProblem, h: f64) -> UniformityProblem {
    let net = problem.network();
    let mut attachment = net.fixed_mask();
    for e in &net.edges {
        let (a, b) = (net.nodes[e[0]], net.nodes[e[1]]);
        if (a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9 {
            attachment[e[0]] = false;
            attachment[e[1]] = false;
        }
    }
    let nodes = net
        .nodes
        .iter()
        .zip(&attachment)
        .map(|(p, &moved)| {
            let r = p[0].hypot(p[1]);
            let s = if moved && r > 0.0 { 1.0 - h / r } else { 1.0 };
            [p[0] * s, p[1] * s, p[2]]
        })
        .collect();
    problem.with_positions(nodes).expect("moved boundary")
}

fn timed(solve: impl Fn() -> Design) -> (Design, f64) {
    let clock = Instant::now();
    let design = solve();
    (design, clock.elapsed().as_secs_f64())
}

#[test]
fn from_the_neighbours_iterate_the_plan_lp_reaches_the_cold_optimum_on_every_family() {
    let free = std::env::var("RINGMESH_WARM_FREE").map_or(1000, |v| v.parse().expect("a count"));
    for family in nets::Family::ALL {
        let problem = family.problem(nets::rings_for(free));
        let first = Lp.solve(&problem).expect("solves");
        assert!(
            first.warm_start.as_ref().is_some_and(|w| w.has_iterate()),
            "{}: no iterate kept",
            family.name()
        );
        let moved = boundary_moved_inward(&problem, 1e-5);
        let (cold, cold_s) = timed(|| Lp.solve(&moved).expect("solves"));
        let (warm, warm_s) = timed(|| Lp.solve_from(&moved, &first).expect("solves"));
        let context = format!(
            "{} at {free} free nodes: {} iterations cold ({cold_s:.3} s), {} warm \
             ({warm_s:.3} s); Tmax/Tmin {} cold, {} warm; warnings {:?}",
            family.name(),
            cold.iterations,
            warm.iterations,
            cold.ratio,
            warm.ratio,
            warm.warnings
        );
        eprintln!("{context}");
        assert_eq!(warm.route, Some(Route::PlanInteriorPoint), "{context}");
        assert!(warm.warnings.is_empty(), "{context}");
        assert!(warm.iterations < cold.iterations, "{context}");
        // Both are the LP's optimum to its accuracy after the final
        // projection onto equilibrium (about 1e-7–1e-6 of the ratio on
        // these nets, `docs/benchmarks.md`).
        assert!((warm.ratio / cold.ratio - 1.0).abs() <= 1e-5, "{context}");
    }
}
