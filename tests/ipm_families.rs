//! The plan interior point on the three net families of issue 38
//! (`tests/common/nets.rs`: the hexagonal generator, the six-sector grid with
//! every row sagged, the graded grid jittered ±10 %): each takes the plan
//! route, reaches clarabel's optimum of the same plan LP to 1e-6 in ratio,
//! and needs no more interior-point iterations than the bound the method is
//! held to at every size; and `gradient`'s exact finish, whose programs the
//! same interior-point driver solves, converges on each.

mod common;

use common::nets::{rings_for, Family};
use common::plan_lp;
use ringmesh::uniformity::{
    Design, FinishSettings, Gradient, Lp, Route, UniformityProblem, UniformitySolver,
};
use ringmesh::Termination;

/// `lp`'s design of `problem` (a net of `family`), which must take the plan
/// interior point without a warning.
fn plan_design(family: Family, problem: &UniformityProblem) -> Design {
    let design = Lp.solve(problem).expect("lp");
    assert_eq!(
        design.route,
        Some(Route::PlanInteriorPoint),
        "{}: {:?}",
        family.name(),
        design.warnings
    );
    assert!(
        design.warnings.is_empty(),
        "{}: {:?}",
        family.name(),
        design.warnings
    );
    design
}

/// The plan interior point's result on `family` at `rings` rows against
/// clarabel's on the same plan LP.
fn matches_clarabel(family: Family, rings: usize) -> usize {
    let problem = family.problem(rings);
    let design = plan_design(family, &problem);
    let reference = plan_lp::solve_plan(&problem, "qdldl");
    assert_eq!(reference.status, "Solved", "{}", family.name());
    assert!(
        (design.ratio / reference.ratio - 1.0).abs() <= 1e-6,
        "{}: {} vs clarabel's {}",
        family.name(),
        design.ratio,
        reference.ratio
    );
    design.iterations
}

#[test]
fn the_hexagonal_generator_matches_clarabel() {
    let iterations = matches_clarabel(Family::Hex, 12);
    assert!(iterations <= 20, "{iterations} iterations");
}

#[test]
fn the_sector_grid_matches_clarabel() {
    let iterations = matches_clarabel(Family::Sector, 12);
    assert!(iterations <= 20, "{iterations} iterations");
}

/// Issue 38's target (≤ 20 iterations) is not reached on this family yet:
/// 24 at 463 free nodes, 33 at 10³ and 65 at 10⁴ (clarabel takes 66 on the
/// same LP there). The bound holds today's count so that a regression fails.
#[test]
fn the_jittered_grid_matches_clarabel() {
    let iterations = matches_clarabel(Family::Jitter, 12);
    assert!(iterations <= 32, "{iterations} iterations");
}

/// The iteration count per family at the largest size CI affords (28 rows,
/// 2 431 free net nodes; about 1 s per family): measured 18 (hex), 15
/// (sector) and 43 (jitter) with the plan settings of this commit (17, 13 and
/// 42 with a predictor completed by FGMRES and no least centring, which took
/// more time: `IpmSettings::plan`); each bound leaves 1–5 iterations of
/// margin, so a change to the driver, the start or the step rule that costs
/// iterations on any family fails here. (At 10⁴ free nodes the same method
/// takes 23, 18 and 65; at 10⁵ 39, 28 and 139.)
#[test]
fn iterations_stay_within_their_bounds_at_2431_free_nodes() {
    for (family, bound) in [
        (Family::Hex, 20),
        (Family::Sector, 16),
        (Family::Jitter, 48),
    ] {
        let problem = family.problem(28);
        assert_eq!(
            problem.structure().free_nodes().len(),
            2431,
            "{}",
            family.name()
        );
        let design = plan_design(family, &problem);
        assert!(
            design.iterations <= bound,
            "{}: {} iterations, bound {bound}",
            family.name(),
            design.iterations
        );
    }
}

/// The gradient's exact finish solves each of its programs with the
/// crate's interior point, not by falling back to clarabel, in a few
/// iterations each, on the hexagonal and the sector net at 1 021 free
/// nodes. On the hexagonal net the programs' primal residual stalled at
/// 1.3e-8 (against 1e-8) once the gap had converged (the reduced system's
/// static shift, then 1e-10); the driver kept an earlier iterate, inside the
/// primal tolerance but not the gap's, as its best, ran to its 80
/// iterations and handed all three programs to clarabel (6.8 s; 0.4 s now,
/// 7 iterations a program).
#[test]
fn the_exact_finish_solves_its_programs_itself() {
    for family in [Family::Hex, Family::Sector] {
        let problem = family.problem(18);
        let (design, history) = Gradient::default()
            .solve_with_history(&problem)
            .expect("gradient");
        assert!(
            design.warnings.is_empty(),
            "{}: {:?}",
            family.name(),
            design.warnings
        );
        assert_eq!(
            design.termination,
            Termination::Converged,
            "{}",
            family.name()
        );
        // 6–7 iterations a program measured; the limit is 80.
        let programs = history.finish_steps + history.finish_corrections;
        assert!(
            history.finish_steps >= 2 && history.finish_interior_iterations <= 12 * programs,
            "{}: {programs} programs, {} interior-point iterations",
            family.name(),
            history.finish_interior_iterations
        );
    }
}

/// On the jittered grid (463 free nodes) the exact finish converges by its
/// second-order correction, in fewer steps and to a lower `J_exact` than
/// without it (which crawled at a trust radius near 1e-2 to its 50-step
/// limit when this was written).
#[test]
fn the_exact_finish_converges_on_the_jittered_grid_by_its_correction() {
    let problem = Family::Jitter.problem(12);
    let solve = |second_order_correction: bool| {
        Gradient {
            finish: FinishSettings {
                second_order_correction,
                ..FinishSettings::default()
            },
            ..Gradient::default()
        }
        .solve_with_history(&problem)
        .expect("gradient")
    };
    let (corrected, history) = solve(true);
    assert_eq!(
        corrected.termination,
        Termination::Converged,
        "{:?}",
        corrected.warnings
    );
    assert!(corrected.warnings.is_empty(), "{:?}", corrected.warnings);
    assert!(
        history.finish_steps <= 15 && history.finish_corrections >= 1,
        "{} steps, {} corrections",
        history.finish_steps,
        history.finish_corrections
    );
    let (_, plain_history) = solve(false);
    assert_eq!(plain_history.finish_corrections, 0);
    assert!(
        history.finish_steps < plain_history.finish_steps,
        "{} steps against {} uncorrected",
        history.finish_steps,
        plain_history.finish_steps
    );
    let objective = |h: &ringmesh::uniformity::History| h.exact_objective.expect("finished");
    assert!(
        objective(&history) < objective(&plain_history),
        "{} against {} uncorrected",
        objective(&history),
        objective(&plain_history)
    );
}

/// Free-node counts from the comma-separated variable `var`, else `default`.
fn sizes(var: &str, default: &str) -> Vec<usize> {
    std::env::var(var)
        .unwrap_or_else(|_| default.into())
        .split(',')
        .filter_map(|s| s.trim().parse().ok())
        .collect()
}

/// The table of issue 38: iterations and ratio per family at the sizes of
/// `RINGMESH_IPM_FREE` (default 1 000 and 10 000 free nodes). Measurement,
/// not a check: `cargo test --release --test ipm_families -- --ignored
/// --nocapture`.
#[test]
#[ignore = "measurement: prints a table"]
fn iteration_table() {
    for free in sizes("RINGMESH_IPM_FREE", "1000,10000") {
        for family in Family::ALL {
            let rings = rings_for(free);
            let problem = family.problem(rings);
            let n_free = problem.structure().free_nodes().len();
            let design = Lp.solve(&problem).expect("lp");
            let reference = plan_lp::solve_plan(&problem, "qdldl");
            eprintln!(
                "{:>7} {:>7} free {:>3} it  ratio {:.10}  {:?} {:.2} s {:?} | clarabel {} it ratio {:.10} ({:+.1e})",
                family.name(),
                n_free,
                design.iterations,
                design.ratio,
                design.route,
                design.time_s,
                design.warnings,
                reference.iterations,
                reference.ratio,
                design.ratio / reference.ratio - 1.0
            );
        }
    }
}

/// The gradient's exact finish per family (`RINGMESH_FINISH_FAMILIES`,
/// comma-separated, default all) at `RINGMESH_FINISH_FREE` free nodes
/// (default 10 000): its programs, their interior-point iterations, `J`,
/// and its time over `lp`'s on the same net in the same run (issue 38's
/// ≤ 5× target). Measurement, not a check: `cargo test --release --test
/// ipm_families finish_table -- --ignored --nocapture`.
#[test]
#[ignore = "measurement: prints a table"]
fn finish_table() {
    let families = std::env::var("RINGMESH_FINISH_FAMILIES").unwrap_or_default();
    let chosen = |family: Family| {
        families.is_empty() || families.split(',').any(|f| f.trim() == family.name())
    };
    for free in sizes("RINGMESH_FINISH_FREE", "10000") {
        for family in Family::ALL.into_iter().filter(|&f| chosen(f)) {
            let problem = family.problem(rings_for(free));
            let lp = Lp.solve(&problem).expect("lp");
            let (design, history) = Gradient::default()
                .solve_with_history(&problem)
                .expect("gradient");
            eprintln!(
                "{:>7} {:>7} free  {:>2} programs + {:>2} corrections {:>4} interior iterations  J {:.12}  ratio {:.10}  {:?} {:.1} s ({:.1}× lp's {:.2} s) {:?}",
                family.name(),
                problem.structure().free_nodes().len(),
                history.finish_steps,
                history.finish_corrections,
                history.finish_interior_iterations,
                history.exact_objective.unwrap_or(f64::NAN),
                design.ratio,
                design.termination,
                design.time_s,
                design.time_s / lp.time_s,
                lp.time_s,
                design.warnings
            );
        }
    }
}

/// A shipped scene's own net, whose sagged boundary cables lie outside the
/// uniformity set (`plan.rs` keeps them in the net, bounded below by the
/// tension floor): the plan interior point reaches clarabel's optimum of the
/// same plan LP, posed independently (`tests/common/plan_lp.rs`), to 1e-6.
#[test]
fn a_shipped_scenes_net_with_its_boundary_outside_the_set_matches_clarabel() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/realistic-26m.toml");
    let scene = ringmesh::scene::Scene::read(&path).unwrap();
    let (_, problem) = ringmesh::design::scene_problem(&scene).unwrap();
    let set = &problem.sets()[0].edges;
    let network = problem.network();
    let mut on_set = vec![false; network.n_nodes()];
    for &k in set {
        network.edges[k].iter().for_each(|&i| on_set[i] = true);
    }
    let outside = (0..network.n_edges())
        .filter(|k| !set.contains(k) && network.edges[*k].iter().all(|&i| on_set[i]))
        .count();
    assert!(outside > 0, "the net has no cable outside its set");
    let design = Lp.solve(&problem).expect("lp");
    assert_eq!(design.route, Some(Route::PlanInteriorPoint));
    let reference = plan_lp::solve_plan(&problem, "qdldl");
    assert_eq!(reference.status, "Solved");
    assert!(
        (design.ratio / reference.ratio - 1.0).abs() <= 1e-6,
        "{} vs clarabel's {}",
        design.ratio,
        reference.ratio
    );
}
