//! Path following (`StaticSolver::follow_path`) against closed forms: the
//! von Mises truss through snap-through (both limit loads, the descending
//! branch across λ ≤ 0 and back), by arc length and by displacement
//! control.

mod common;

use common::frames::{von_mises, von_mises_limit, von_mises_load, VM_RISE_M};
use ringmesh::mechanics::{
    CriticalKind, PathControl, PathSolution, PathSpec, PathTarget, StaticSettings,
    StaticTermination,
};

/// Every recorded point of the von Mises path lies on `P(y) = λ P_applied`
/// to `1e-6 P_lim`; returns the largest misfit over `P_lim`.
fn misfit_on_von_mises_path(path: &PathSolution, applied: f64, p_lim: f64) -> f64 {
    path.points
        .iter()
        .map(|p| {
            let y = VM_RISE_M + p.displacements_m[0][1];
            (von_mises_load(y) - p.load_factor * applied).abs() / p_lim
        })
        .fold(0.0, f64::max)
}

/// Both limit points of the von Mises path: a maximum at `P_lim/P_applied`
/// and a minimum at its negative, each to 1e-6, with the apex at `±y_lim`.
fn assert_both_limits(path: &PathSolution, applied: f64) {
    let (p_lim, y_lim) = von_mises_limit();
    let limits: Vec<_> = path
        .critical_points
        .iter()
        .filter(|c| c.kind.family() == "limit")
        .collect();
    assert_eq!(limits.len(), 2, "{:?}", path.critical_points);
    assert_eq!(limits[0].kind, CriticalKind::LimitMaximum);
    assert_eq!(limits[1].kind, CriticalKind::LimitMinimum);
    for (c, sign) in limits.iter().zip([1.0, -1.0]) {
        let exact = sign * p_lim / applied;
        assert!(
            (c.load_factor - exact).abs() <= 1e-6 * exact.abs(),
            "{:?} at λ {} vs {exact}",
            c.kind,
            c.load_factor
        );
        let y = VM_RISE_M + c.displacements_m[0][1];
        assert!(
            (y - sign * y_lim).abs() <= 1e-3 * y_lim,
            "{:?} at y {y} vs {}",
            c.kind,
            sign * y_lim
        );
    }
}

#[test]
fn arc_length_follows_the_von_mises_truss_through_snap_through() {
    // Loaded at 1.5 × its limit load: up to the limit, down through λ = 0
    // (apex level with the supports) to the minimum −P_lim, back up through
    // λ = 0 (the mirrored truss) and on to λ = 1 with the bars in tension.
    let (p_lim, _) = von_mises_limit();
    let applied = 1.5 * p_lim;
    let (solver, apex) = von_mises(applied);
    let spec = PathSpec {
        target: PathTarget::LoadFactor(1.0),
        control: None,
        record: vec![apex],
    };
    let settings = StaticSettings {
        path: PathControl::ArcLength,
        ..StaticSettings::default()
    };
    let path = solver.follow_path(&spec, &settings).unwrap();
    assert_eq!(path.solution.termination, StaticTermination::Converged);
    assert!((path.solution.load_factor - 1.0).abs() <= 1e-12);
    let misfit = misfit_on_von_mises_path(&path, applied, p_lim);
    assert!(misfit <= 1e-6, "off the closed form by {misfit:e} P_lim");
    assert_both_limits(&path, applied);
    // The descending branch: below zero and back.
    let lambdas: Vec<f64> = path.points.iter().map(|p| p.load_factor).collect();
    let lowest = lambdas.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(lowest < -0.6, "never went below zero: {lambdas:?}");
    // The end: the inverted truss, bars in tension, y < −h.
    let y_end = VM_RISE_M + path.points.last().unwrap().displacements_m[0][1];
    assert!(y_end < -VM_RISE_M, "end at y = {y_end}");
    let x = path.solution.state.frames[apex].position_m;
    assert!(x.x.abs() <= 1e-9 && x.z.abs() <= 1e-9, "{x:?}");
    eprintln!(
        "arc length: {} points, misfit {misfit:e} P_lim, limits {:?}, end y {y_end}",
        path.points.len(),
        path.critical_points
            .iter()
            .map(|c| c.load_factor)
            .collect::<Vec<_>>()
    );
}

#[test]
fn displacement_control_follows_the_von_mises_truss_to_a_displacement() {
    // The apex driven down to y = −1.5 h: the load passes both limit
    // points, which displacement control goes through (the apex moves
    // monotonically).
    let (p_lim, _) = von_mises_limit();
    let applied = p_lim;
    let (solver, apex) = von_mises(applied);
    let target = -2.5 * VM_RISE_M;
    let spec = PathSpec {
        target: PathTarget::Displacement {
            node: apex,
            component: 1,
            value_m: target,
        },
        control: Some((apex, 1)),
        record: vec![apex],
    };
    let settings = StaticSettings {
        path: PathControl::Displacement,
        ..StaticSettings::default()
    };
    let path = solver.follow_path(&spec, &settings).unwrap();
    assert_eq!(path.solution.termination, StaticTermination::Converged);
    let end = path.points.last().unwrap().displacements_m[0][1];
    assert!((end - target).abs() <= 1e-9, "ended at {end} for {target}");
    let misfit = misfit_on_von_mises_path(&path, applied, p_lim);
    assert!(misfit <= 1e-6, "off the closed form by {misfit:e} P_lim");
    assert_both_limits(&path, applied);
    // Monotone in the controlled displacement.
    assert!(path
        .points
        .windows(2)
        .all(|w| w[1].displacements_m[0][1] < w[0].displacements_m[0][1]));
}
