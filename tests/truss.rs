//! The ring truss and its oracles: a self-equilibrated net pull on an isostatic
//! support leaves no reactions; the linear and exact models agree under tiny
//! loads and part under the paper's; bad loads are refused.

mod common;

use nalgebra::Vector3;
use ringmesh::effects::SceneEffects;
use ringmesh::geometry::build_mesh;
use ringmesh::mechanics::{NodalLoad, StaticSettings, StaticSolver};
use ringmesh::scene::TrussModel;
use ringmesh::truss::{self, RingTruss, TrussError};

fn max_displacement(positions: &[[f64; 3]], reference: &[[f64; 3]]) -> Vec<f64> {
    positions
        .iter()
        .zip(reference)
        .map(|(p, r)| {
            ((p[0] - r[0]).powi(2) + (p[1] - r[1]).powi(2) + (p[2] - r[2]).powi(2)).sqrt()
        })
        .collect()
}

#[test]
fn isostatic_ring_truss_under_self_equilibrated_pull_has_no_reactions() {
    let scene = common::scene("small-hex");
    let mesh = build_mesh(&scene).unwrap();
    let pull = common::net_pull(&mesh);
    let ring = RingTruss::new(&scene, &mesh.truss, &SceneEffects::of(&scene)).unwrap();
    let loads: Vec<NodalLoad> = ring
        .attachments
        .iter()
        .zip(&pull)
        .map(|(&node, f)| NodalLoad {
            node,
            force_n: Vector3::new(f[0], f[1], f[2]),
            moment_nm: Vector3::zeros(),
        })
        .collect();
    let mut solver = StaticSolver::new(ring.model.clone()).unwrap();
    solver.model_mut().set_loads(loads).unwrap();
    let solution = solver.solve(&StaticSettings::default()).unwrap();
    assert!(solution.converged(), "{:?}", solution.termination);
    let largest_pull = pull.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    // The net's pull sums to zero force and moment on the undeformed hinges, so
    // the 3-2-1 support carries only what the displaced points of application
    // add: a moment of order pull × displacement, i.e. reactions of order
    // pull × displacement / ring radius, and exact global balance.
    let frames = &solution.state.frames;
    let mut force = Vector3::zeros();
    let mut moment = Vector3::zeros();
    for (&node, f) in ring.attachments.iter().zip(&pull) {
        let f = Vector3::new(f[0], f[1], f[2]);
        force += f;
        moment += frames[node].position_m.cross(&f);
    }
    for (node, r) in solution.reactions.iter().enumerate() {
        let r = Vector3::new(r[0], r[1], r[2]);
        force += r;
        moment += frames[node].position_m.cross(&r);
    }
    let radius = scene.aperture_radius_m();
    assert!(
        force.amax() <= 1e-8 * largest_pull,
        "force balance {force:?}"
    );
    assert!(
        moment.amax() <= 1e-8 * largest_pull * radius,
        "moment balance {moment:?}"
    );
    let displacement = ring
        .attachments
        .iter()
        .map(|&n| (frames[n].position_m - ring.model.reference()[n].position_m).norm())
        .fold(0.0f64, f64::max);
    let largest_reaction = solution
        .reactions
        .iter()
        .flatten()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    let second_order = largest_pull * ring.attachments.len() as f64 * displacement / radius;
    assert!(
        largest_reaction <= second_order,
        "reaction {largest_reaction:e} N above the second-order bound {second_order:e} N"
    );
    // Newton converged quadratically in the last step: the final residual is
    // far below the square-root of the one before it (relative to the load).
    let last = solution.steps.last().unwrap();
    let r: Vec<f64> = last.residuals.iter().map(|v| v / largest_pull).collect();
    assert!(r.len() >= 2 && r[r.len() - 1] < 1e-9, "residuals {r:?}");
}

#[test]
fn linear_and_exact_trusses_agree_under_tiny_loads_and_part_under_the_papers() {
    let scene = common::scene("paper-26m");
    let mesh = build_mesh(&scene).unwrap();
    let pull = common::net_pull(&mesh);
    let reference: Vec<[f64; 3]> = mesh
        .truss
        .top_m
        .iter()
        .chain(&mesh.truss.bottom_m)
        .copied()
        .collect();
    let mut linear = common::scene_oracle(TrussModel::Linear, &scene, &mesh);
    let mut exact = common::scene_oracle(TrussModel::Exact, &scene, &mesh);
    let relative_difference =
        |s: f64,
         linear: &mut Box<dyn truss::TrussOracle>,
         exact: &mut Box<dyn truss::TrussOracle>| {
            let loads = common::scaled(&pull, s);
            let dl = max_displacement(&linear.respond(&loads).unwrap().positions_m, &reference);
            let de = exact.respond(&loads).unwrap().positions_m;
            let lin = linear.respond(&loads).unwrap().positions_m;
            let largest = dl.iter().fold(0.0f64, |m, v| m.max(*v));
            let diff = max_displacement(&de, &lin)
                .iter()
                .fold(0.0f64, |m, v| m.max(*v));
            diff / largest
        };
    // Geometric nonlinearity grows in proportion to the load, relative to the
    // ring's limit (≈ 0.07 × the pull here): 9.3e-6 at 1e-6 of the pull,
    // 9.3e-5 at 1e-5, 9.4e-4 at 1e-4 (measured, with the exact model's cold
    // start in two steps; in one step it stopped after one Newton iteration,
    // the linear answer, its residual under the roundoff floor).
    let tiny = relative_difference(1e-6, &mut linear, &mut exact);
    let full = relative_difference(1.0, &mut linear, &mut exact);
    assert!(
        tiny < 1e-3,
        "tiny loads: linear and exact differ by {tiny:e}"
    );
    assert!(
        full > 1e-2,
        "paper loads: linear and exact differ by only {full:e}"
    );
    assert!(
        full > 100.0 * tiny,
        "the difference must grow with the load: {tiny:e} → {full:e}"
    );
}

#[test]
fn rigid_truss_never_moves_and_every_model_refuses_bad_loads() {
    let scene = common::scene("small-hex");
    let mesh = build_mesh(&scene).unwrap();
    let pull = common::net_pull(&mesh);
    for model in [TrussModel::Rigid, TrussModel::Linear, TrussModel::Exact] {
        let mut oracle = common::scene_oracle(model, &scene, &mesh);
        let short = &pull[1..];
        assert!(
            matches!(oracle.respond(short), Err(TrussError::LoadCount { .. })),
            "{model:?}"
        );
        let mut bad = pull.clone();
        bad[3][1] = f64::NAN;
        assert!(
            matches!(
                oracle.respond(&bad),
                Err(TrussError::NonFiniteLoad { point: 3 })
            ),
            "{model:?}"
        );
    }
    let mut rigid = common::scene_oracle(TrussModel::Rigid, &scene, &mesh);
    let r = rigid.respond(&pull).unwrap();
    assert_eq!(r.positions_m, rigid.attachments());
}

#[test]
fn exact_truss_warm_start_reproduces_the_cold_solution() {
    let scene = common::scene("small-hex");
    let mesh = build_mesh(&scene).unwrap();
    let pull = common::net_pull(&mesh);
    let mut warm = common::scene_oracle(TrussModel::Exact, &scene, &mesh);
    warm.respond(&common::scaled(&pull, 0.5)).unwrap();
    let from_warm = warm.respond(&pull).unwrap().positions_m;
    let mut cold = common::scene_oracle(TrussModel::Exact, &scene, &mesh);
    let from_cold = cold.respond(&pull).unwrap().positions_m;
    let d = max_displacement(
        &from_cold,
        &mesh
            .truss
            .top_m
            .iter()
            .chain(&mesh.truss.bottom_m)
            .copied()
            .collect::<Vec<_>>(),
    );
    let scale = d.iter().fold(0.0f64, |m, v| m.max(*v));
    let diff = max_displacement(&from_warm, &from_cold)
        .iter()
        .fold(0.0f64, |m, v| m.max(*v));
    // Both stop at the force tolerance; positions agree to ~1e-6 of the
    // displacement (measured 6e-7: the roundoff floor of 13 m coordinates).
    assert!(
        diff <= 1e-5 * scale,
        "warm and cold solutions differ by {diff:e} m (displacement {scale:e} m)"
    );
}
