//! Cable elasticity in verification (`[effects] cable_elasticity`): elastic
//! cables by default, inextensible ones on request — the same equilibrium
//! where the design is one of the truss, and on the flexible truss the
//! conventional design's net losing more of its prestress.

mod common;

use ringmesh::design::{design_loop, LoopSettings, RelaxationKind};
use ringmesh::effects::SceneEffects;
use ringmesh::geometry::ReflectorMesh;
use ringmesh::scene::{Scene, TrussModel};
use ringmesh::truss::layout_points;
use ringmesh::uniformity::{Design, SolverKind};
use ringmesh::verify::{verify, AssemblyTruss, CableModel, Verification, INEXTENSIBLE_STIFFENING};
use ringmesh::Network;
use ringmesh::Termination;

fn inextensible(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    s.effects.cable_elasticity = false;
    s
}

fn assemble(
    scene: &Scene,
    mesh: &ReflectorMesh,
    network: &Network,
    design: &Design,
    truss: AssemblyTruss,
) -> Verification {
    let v = verify(
        scene,
        mesh,
        &SceneEffects::of(scene),
        network,
        design,
        truss,
        None,
    )
    .unwrap();
    let expected = if scene.effects.cable_elasticity {
        (CableModel::Elastic, 1.0)
    } else {
        (CableModel::Inextensible, INEXTENSIBLE_STIFFENING)
    };
    assert_eq!(v.cable_model, expected.0);
    assert_eq!(
        v.cable_axial_stiffness_n,
        expected.1 * scene.cables.axial_stiffness_n()
    );
    v
}

/// Share of the design's total tension the assembled net keeps.
fn kept(v: &Verification, design: &Design) -> f64 {
    v.tensions_n.iter().map(|t| t.max(0.0)).sum::<f64>() / design.tensions_n.iter().sum::<f64>()
}

/// The key: elastic unless the scene says otherwise.
#[test]
fn cables_are_elastic_unless_the_scene_says_otherwise() {
    let text = std::fs::read_to_string(common::problem("small-hex.toml")).unwrap();
    let elastic = Scene::from_toml(&text, "x").unwrap();
    assert!(elastic.effects.cable_elasticity);
    assert_eq!(CableModel::of(&elastic), CableModel::Elastic);
    let off = Scene::from_toml(
        &format!("{text}\n[effects]\ncable_elasticity = false\n"),
        "x",
    )
    .unwrap();
    assert_eq!(CableModel::of(&off), CableModel::Inextensible);
    let e =
        Scene::from_toml(&format!("{text}\n[effects]\ncable_elasticity = 0\n"), "x").unwrap_err();
    assert!(e.to_string().contains("cable_elasticity"), "{e}");
}

/// When the physics agree — a design on a rigid truss, assembled on a rigid
/// truss — inextensible cables return the design as elastic ones do: the
/// design is an equilibrium of the assembly whatever the cables' stiffness.
/// The tension error is the penalty's roundoff: positions to ε·|x| make
/// tensions to `EA*·ε·|x|/ℓ`, κ times the elastic floor.
#[test]
fn inextensible_rigid_assembly_of_a_rigid_truss_design_returns_the_design() {
    let (scene, mesh, nets) = common::small_hex_nets();
    let solver = SolverKind::Lp.build(None);
    let d = nets
        .design(solver.as_ref(), &layout_points(&mesh.truss))
        .unwrap();
    let v = assemble(
        &inextensible(&scene),
        &mesh,
        d.problem.network(),
        &d.design,
        AssemblyTruss::Rigid,
    );
    println!(
        "rigid/rigid, inextensible: node shift {:.1e} mm, RMS {:.1e} mm, tension change {:.1e} %",
        v.max_node_shift_mm, v.rms_mm, v.max_tension_change_pct
    );
    assert!(v.max_node_shift_mm <= 1e-6, "{} mm", v.max_node_shift_mm);
    assert!(v.rms_mm <= 1e-6, "{} mm", v.rms_mm);
    assert!(
        v.max_tension_change_pct <= 1e-6,
        "{} %",
        v.max_tension_change_pct
    );
    assert!(v.slack_cables.is_empty());
}

/// The design for the deforming truss is an equilibrium of the assembly for
/// any cable stiffness (only its cut lengths depend on EA): assembled with
/// inextensible cables it lands on the paraboloid as with elastic ones.
#[test]
fn the_design_for_the_deforming_truss_survives_inextensible_assembly() {
    let (scene, mesh, nets) = common::small_hex_nets();
    let solver = SolverKind::Lp.build(None);
    let mut truss = common::scene_oracle(TrussModel::Exact, &scene, &mesh);
    let settings = LoopSettings {
        relaxation: RelaxationKind::Anderson,
        tolerance_m: 1e-7,
        max_iterations: 40,
        ..LoopSettings::default()
    };
    let outcome = design_loop(
        &nets,
        solver.as_ref(),
        truss.as_mut(),
        &settings,
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(outcome.termination, Termination::Converged);
    let network = outcome.problem.network();
    for s in [scene.clone(), inextensible(&scene)] {
        let v = assemble(&s, &mesh, network, &outcome.design, AssemblyTruss::Flexible);
        println!(
            "exact design, {:?}: RMS {:.2e} mm, tension change {:.2e} %, boundary {:.2e} mm",
            v.cable_model, v.rms_mm, v.max_tension_change_pct, v.boundary_deviation_mm
        );
        assert!(v.slack_cables.is_empty());
        assert!(v.rms_mm <= 1e-3, "RMS {} mm", v.rms_mm);
        assert!(
            v.max_tension_change_pct <= 0.5,
            "{} %",
            v.max_tension_change_pct
        );
        assert!(v.boundary_deviation_mm <= 1e-3);
    }
}

/// The conventional design (cut for the rigid truss) on the flexible truss:
/// its cables, cut short by `T/EA` for their prestress, pull the ring in,
/// and the hinges' motion gives back part of that shortening. Cables and
/// truss act as springs in series: the net keeps `T ≈ T₀/(1 + k_cable/k_truss)`.
/// Stiffer cables turn the same hinge motion into more tension lost, so with
/// inextensible cables the net keeps less of its prestress, cables go
/// slack, the largest tension change is larger, and the hinges, pulled by
/// less, move less — in proportion to the prestress kept, the truss being
/// near linear at this load.
#[test]
fn inextensible_cables_leave_the_conventional_design_slacker_and_the_hinges_closer() {
    let (scene, mesh, nets) = common::small_hex_nets();
    let solver = SolverKind::Lp.build(None);
    let d = nets
        .design(solver.as_ref(), &layout_points(&mesh.truss))
        .unwrap();
    let network = d.problem.network();
    let elastic = assemble(&scene, &mesh, network, &d.design, AssemblyTruss::Flexible);
    let stiff = assemble(
        &inextensible(&scene),
        &mesh,
        network,
        &d.design,
        AssemblyTruss::Flexible,
    );
    let (ke, ki) = (kept(&elastic, &d.design), kept(&stiff, &d.design));
    println!(
        "conventional design on the flexible truss: elastic keeps {:.3} of the tension (change \
         {:.1} %, {} slack, hinges {:.4} mm), inextensible {:.3} ({:.1} %, {} slack, hinges \
         {:.4} mm); shortest cable {:.3} m",
        ke,
        elastic.max_tension_change_pct,
        elastic.slack_cables.len(),
        elastic.boundary_deviation_mm,
        ki,
        stiff.max_tension_change_pct,
        stiff.slack_cables.len(),
        stiff.boundary_deviation_mm,
        d.design
            .lengths_m
            .iter()
            .fold(f64::INFINITY, |m, l| m.min(*l)),
    );
    assert!(elastic.slack_cables.is_empty());
    assert!(!stiff.slack_cables.is_empty());
    assert!(ki < 0.5 * ke, "kept {ki} against {ke}");
    assert!(stiff.max_tension_change_pct > elastic.max_tension_change_pct);
    assert!(stiff.boundary_deviation_mm < 0.5 * elastic.boundary_deviation_mm);
    let motion = stiff.boundary_deviation_mm / elastic.boundary_deviation_mm;
    assert!(
        (motion / (ki / ke) - 1.0).abs() < 0.1,
        "hinge motion ×{motion:.3} against prestress kept ×{:.3}",
        ki / ke
    );
}
