//! The extension points of docs/ARCHITECTURE.md, used from outside the
//! library: a relaxation policy and an effect, each defined in one place in
//! this file, run through the outer design loop without touching the crate;
//! and the truss models' registry, which the study and sizing ask rather
//! than list models themselves.

mod common;

use ringmesh::design::{
    design_loop, design_loop_with, LoopSettings, Relaxation, RelaxationKind, SceneNets, Step,
};
use ringmesh::effects::{Effect, SceneEffects};
use ringmesh::network::CableGroup;
use ringmesh::scene::TrussModel;
use ringmesh::study::StudySettings;
use ringmesh::truss::{self, layout_points};
use ringmesh::uniformity::SolverKind;
use ringmesh::Termination;

/// A toy relaxation: a fixed under-relaxation `x + ω r`.
struct Damped {
    omega: f64,
}

impl Relaxation for Damped {
    fn name(&self) -> &str {
        "damped"
    }

    fn next(&mut self, x: &[f64], _image: &[f64], residual: &[f64], _xi: f64) -> Step {
        Step {
            x: x.iter()
                .zip(residual)
                .map(|(c, r)| c + self.omega * r)
                .collect(),
            factor: self.omega,
        }
    }
}

/// A toy effect: a load along the reflector's axis on every free node of the
/// front net (the push of a feed's radiation, say), `newtons` on each.
#[derive(Debug)]
struct AxialPush {
    front_nodes: Vec<usize>,
    newtons: f64,
}

impl Effect for AxialPush {
    fn name(&self) -> &str {
        "axial push"
    }

    fn net_loads_n(&self, nodes_m: &[[f64; 3]], _edges: &[[usize; 2]]) -> Option<Vec<[f64; 3]>> {
        let mut loads = vec![[0.0; 3]; nodes_m.len()];
        for &i in &self.front_nodes {
            loads[i][2] = -self.newtons;
        }
        Some(loads)
    }
}

/// The toy policy converges to the fixed point Anderson finds, reporting its
/// own factor at every iteration.
#[test]
fn a_relaxation_policy_defined_outside_the_crate_runs_the_loop() {
    let (scene, mesh, nets) = common::small_hex_nets();
    let solver = SolverKind::Lp.build(None);
    let settings = LoopSettings {
        tolerance_m: 1e-7,
        max_iterations: 60,
        ..LoopSettings::default()
    };
    let effects = SceneEffects::of(&scene);
    let mut oracle = truss::oracle(TrussModel::Exact, &scene, &mesh.truss, &effects).unwrap();
    let mut damped = Damped { omega: 0.5 };
    let toy = design_loop_with(
        &nets,
        solver.as_ref(),
        oracle.as_mut(),
        &mut damped,
        &settings,
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(toy.termination, Termination::Converged);
    assert!(toy.history.iter().all(|r| r.relaxation_factor == 0.5));

    let mut oracle = truss::oracle(TrussModel::Exact, &scene, &mesh.truss, &effects).unwrap();
    let anderson = LoopSettings {
        relaxation: RelaxationKind::Anderson,
        ..settings.clone()
    };
    let reference = design_loop(
        &nets,
        solver.as_ref(),
        oracle.as_mut(),
        &anderson,
        &mut |_| {},
    )
    .unwrap();
    // Both within 1e-7 m of their images; the map contracts, so their
    // boundaries are a few tolerances apart at most.
    let apart = common::max_abs_diff(&toy.boundary_m, &reference.boundary_m);
    assert!(apart <= 1e-6, "{apart} m apart");
    // Half steps converge more slowly than Anderson's mixing.
    assert!(toy.history.len() > reference.history.len());
}

/// The toy effect reaches the nets through the bundle: the vertical ties
/// absorb the axial push exactly (each tie pulls less by the push on its
/// front node), the front net's plan problem — its ratio — is untouched, and
/// the outer loop converges under it with the push balanced.
#[test]
fn an_effect_defined_outside_the_crate_acts_on_the_nets_and_the_loop() {
    let scene = common::scene("small-hex");
    let mesh = ringmesh::geometry::build_mesh(&scene).unwrap();
    let fixed = mesh.network.fixed_mask();
    let push = AxialPush {
        front_nodes: (0..mesh.n_front_nodes).filter(|&i| !fixed[i]).collect(),
        newtons: 0.05 * scene.front_net.mean_tension_n,
    };
    let newtons = push.newtons;
    let plain = SceneNets::new(&scene).unwrap();
    let pushed = SceneNets::with_effects(&scene, SceneEffects::of(&scene).with(push)).unwrap();
    assert_eq!(pushed.effects.names(), vec!["axial push"]);

    // Loads need a solver that takes them.
    let solver = SolverKind::Bisection.build(None);
    let boundary = layout_points(&mesh.truss);
    let d0 = plain
        .nets
        .design(solver.as_ref(), &boundary)
        .unwrap()
        .design;
    let d1 = pushed
        .nets
        .design(solver.as_ref(), &boundary)
        .unwrap()
        .design;
    assert!(
        (d1.ratio - d0.ratio).abs() <= 1e-6 * d0.ratio,
        "{} vs {}",
        d1.ratio,
        d0.ratio
    );
    let ties: Vec<usize> = (0..mesh.network.n_edges())
        .filter(|&k| mesh.groups[k] == CableGroup::Tie)
        .collect();
    let largest_tie = ties.iter().map(|&k| d0.tensions_n[k]).fold(0.0, f64::max);
    assert!(!ties.is_empty());
    for &k in &ties {
        let shift = d0.tensions_n[k] - d1.tensions_n[k];
        assert!(
            (shift - newtons).abs() <= 1e-6 * largest_tie,
            "tie {k}: shift {shift} N, push {newtons} N"
        );
    }

    // The loop under the push, on the linear truss.
    let settings = LoopSettings::default();
    let outcome = pushed
        .design_loop(solver.as_ref(), TrussModel::Linear, &settings, &mut |_| {})
        .unwrap();
    assert_eq!(outcome.termination, Termination::Converged);
    let design = &outcome.design;
    assert!(
        design.max_residual_n <= 1e-8 * design.max_tension_n,
        "residual {} N, max tension {} N",
        design.max_residual_n,
        design.max_tension_n
    );
}

/// The registry lists every truss model a scene can name, and the study
/// sweeps that list: a variant added to `TrussModel` without its place in
/// `truss::MODELS` fails here. Every model listed builds its oracle, and a
/// model sizing may use (one with a limit load) deforms.
#[test]
fn the_registry_lists_every_truss_model_and_the_study_sweeps_them_all() {
    let variants = <TrussModel as clap::ValueEnum>::value_variants();
    assert_eq!(
        truss::MODELS,
        variants,
        "truss::MODELS must list every TrussModel variant, in declaration order"
    );
    let (scene, mesh, _) = common::small_hex_nets();
    assert_eq!(StudySettings::for_scene(&scene).truss_models, variants);

    let effects = SceneEffects::of(&scene);
    for &model in truss::MODELS {
        let oracle = truss::oracle(model, &scene, &mesh.truss, &effects).unwrap();
        if truss::has_limit_load(model) {
            assert!(
                oracle.deforms(),
                "{model:?} has a limit load but does not deform"
            );
        }
    }
    assert!(
        truss::MODELS.iter().any(|&m| truss::has_limit_load(m)),
        "sizing needs a model with a limit load"
    );
    assert!(!truss::has_limit_load(TrussModel::Rigid));
}
