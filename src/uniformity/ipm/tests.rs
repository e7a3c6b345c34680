//! The kernel against clarabel on the full problem of the small test scenes,
//! and the settings check.

use super::*;
use crate::status::Termination;
use crate::uniformity::lp::solve_full;
use crate::uniformity::UniformityProblem;

fn problem(path: &str) -> UniformityProblem {
    let scene = crate::Scene::read(std::path::Path::new(path)).expect("scene");
    crate::design::scene_problem(&scene).expect("problem").1
}

/// `Tmax/Tmin` of `q` over the problem's first set.
pub(crate) fn set_ratio(problem: &UniformityProblem, q: &[f64]) -> f64 {
    let lengths = problem.lengths_m();
    let (min, max) = problem.sets()[0]
        .edges
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(min, max), &k| {
            (min.min(q[k] * lengths[k]), max.max(q[k] * lengths[k]))
        });
    max / min
}

/// The full (three-dimensional) ratio LP of a problem.
fn full_lp(problem: &UniformityProblem) -> RatioLp<3> {
    let structure = problem.structure();
    let network = problem.network();
    let mut in_set = vec![false; network.n_edges()];
    for &k in &problem.sets()[0].edges {
        in_set[k] = true;
    }
    RatioLp {
        n_free: structure.free_nodes().len(),
        ends: network
            .edges
            .iter()
            .map(|e| e.map(|i| structure.free_index(i)))
            .collect(),
        vectors: network.edges_vectors(),
        lengths: problem.lengths_m().to_vec(),
        in_set,
        min_other_tension: problem.min_tension_fraction,
    }
}

/// The kernel on the full 3-D problem (mechanisms and all) reaches clarabel's
/// optimum, balances the geometry, and keeps the bounds it was given.
fn matches_clarabel(path: &str) {
    let problem = problem(path);
    let solution = solve(&full_lp(&problem), &IpmSettings::default(), None).expect("ipm");
    assert_eq!(solution.termination, Termination::Converged);
    let lengths = problem.lengths_m();
    let set = &problem.sets()[0].edges;
    let tension = |k: usize| solution.q[k] * lengths[k];
    let min = set
        .iter()
        .map(|&k| tension(k))
        .fold(f64::INFINITY, f64::min);
    let ratio = set_ratio(&problem, &solution.q);
    let q = solve_full(&problem, &mut Vec::new())
        .expect("clarabel")
        .0
        .expect("feasible");
    let reference = set_ratio(&problem, &q);
    assert!(
        (ratio - reference).abs() <= 1e-6 * reference,
        "{ratio} vs {reference}"
    );
    assert!(min >= 1.0 - 1e-8, "smallest set tension {min}");
    let max_tension = (0..lengths.len()).map(tension).fold(0.0, f64::max);
    let floor = problem.min_tension_fraction * (1.0 - 1e-8);
    assert!(problem.other_edges().iter().all(|&k| tension(k) >= floor));
    let residual = problem.prescribed_residual_n(&solution.q);
    assert!(
        residual <= 1e-9 * max_tension,
        "{residual} vs {max_tension}"
    );
}

#[test]
fn full_problem_matches_clarabel_small_hex() {
    matches_clarabel("problems/small-hex.toml");
}

#[test]
fn full_problem_matches_clarabel_small_offset() {
    matches_clarabel("problems/small-offset.toml");
}

#[test]
fn settings_out_of_range_are_named() {
    let problem = problem("problems/small-hex.toml");
    for (settings, name) in [
        (
            IpmSettings {
                gap_tolerance: 0.0,
                ..IpmSettings::default()
            },
            "gap_tolerance",
        ),
        (
            IpmSettings {
                max_regularization: 1e-15,
                ..IpmSettings::default()
            },
            "max_regularization",
        ),
        (
            IpmSettings {
                regularization_growth: 1.0,
                ..IpmSettings::default()
            },
            "regularization_growth",
        ),
        (
            IpmSettings {
                stall_iterations: 0,
                ..IpmSettings::default()
            },
            "stall_iterations",
        ),
        (
            IpmSettings {
                min_centring: f64::NAN,
                ..IpmSettings::default()
            },
            "min_centring",
        ),
        (
            IpmSettings {
                krylov_stagnation: 1.0,
                ..IpmSettings::default()
            },
            "krylov_stagnation",
        ),
    ] {
        match solve(&full_lp(&problem), &settings, None) {
            Err(IpmError::Setting { name: found, .. }) => assert_eq!(found, name),
            other => panic!("{name}: expected a setting error, got {other:?}"),
        }
    }
    assert!(IpmSettings::default().validate().is_ok());
    assert!(IpmSettings::plan().validate().is_ok());
}

/// `Tmax/Tmin` of a ratio LP's set for its (unscaled) `q`.
fn lp_ratio<const D: usize>(lp: &RatioLp<D>, q: &[f64]) -> f64 {
    let (min, max) = (0..q.len())
        .filter(|&k| lp.in_set[k])
        .map(|k| q[k] * lp.lengths[k])
        .fold((f64::INFINITY, 0.0f64), |(a, b), t| (a.min(t), b.max(t)));
    max / min
}

/// Gondzio's centrality correctors (off by default) reach the plan optimum of
/// the default plan settings: a correction's FGMRES, which stops at the
/// corrector's residual, leaves the direction as exact as the corrector.
#[test]
fn centrality_correctors_reach_the_same_plan_optimum() {
    let problem = problem("problems/paper-26m.toml");
    let plan = crate::uniformity::plan::PlanReduction::new(&problem).expect("a reflector mesh");
    let reference = solve(plan.lp(), &IpmSettings::plan(), None).expect("plan");
    assert_eq!(reference.termination, Termination::Converged);
    let reference_ratio = lp_ratio(plan.lp(), &reference.q);
    for correctors in 1..=3 {
        let settings = IpmSettings {
            centrality_correctors: correctors,
            ..IpmSettings::plan()
        };
        let solution = solve(plan.lp(), &settings, None).expect("plan");
        assert_eq!(solution.termination, Termination::Converged, "{correctors}");
        let ratio = lp_ratio(plan.lp(), &solution.q);
        assert!(
            (ratio / reference_ratio - 1.0).abs() <= 1e-8,
            "{correctors} correctors: {ratio} vs {reference_ratio}"
        );
    }
}

/// The normal matrix's analysis travels with the kept iterate: an LP of the
/// same net factors numerically with it and reaches, bit for bit, what its
/// own analysis reaches; an LP of another net makes its own.
#[test]
fn a_neighbouring_lps_analysis_is_reused_only_where_it_fits() {
    use crate::uniformity::plan::PlanReduction;
    use std::sync::Arc;
    let plan_of = |path: &str| PlanReduction::new(&problem(path)).expect("a reflector mesh");
    let settings = IpmSettings::plan();
    let paper = plan_of("problems/paper-26m.toml");
    let first = solve(paper.lp(), &settings, None).expect("plan");
    let kept = first.kept;
    assert!(kept.has_iterate());
    let analysis = kept.without_iterate();
    let again = solve(paper.lp(), &settings, Some(&analysis)).expect("plan");
    let reused = again.kept.pattern;
    assert!(Arc::ptr_eq(&reused, &kept.pattern), "not reused");
    assert_eq!(again.iterations, first.iterations);
    assert_eq!(again.q, first.q);

    let hex = plan_of("problems/small-hex.toml");
    let own = solve(hex.lp(), &settings, None).expect("plan");
    let given = solve(hex.lp(), &settings, Some(&analysis)).expect("plan");
    let made = given.kept.pattern;
    assert!(
        !Arc::ptr_eq(&made, &kept.pattern),
        "another net's analysis used"
    );
    assert_eq!(given.termination, Termination::Converged);
    assert_eq!(given.q, own.q);
}
