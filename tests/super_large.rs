//! Super-large reflectors (issue 15): the membrane stress as the net's
//! tension level, the shipped 60 m and 100 m scenes, and a 60 m design.

mod common;

use ringmesh::design::{DesignSettings, LoopSettings, SceneNets};
use ringmesh::geometry::build_mesh;
use ringmesh::run::design;
use ringmesh::scene::{membrane_tension_n, Scene, TrussModel};
use ringmesh::uniformity::SolverKind;
use ringmesh::verify::{verify, AssemblyTruss};
use ringmesh::Termination;

/// `T = 2 N A / Σ ℓ` on the hexagon's three-direction grid tends to the
/// equilateral net's `T = N a/√3` (spacing `a = R/r`) as the grid is refined,
/// with the `1/(3r)` of its boundary: `T = √3 N R/(3r − 1)` exactly.
#[test]
fn the_membrane_tension_of_a_hexagonal_grid_is_the_equilateral_nets() {
    let mut scene = common::scene("small-hex");
    let radius = scene.aperture_radius_m();
    for rings in [2, 5, 40, 400] {
        scene.front_net.rings = rings;
        let exact = 3f64.sqrt() * radius / (3.0 * rings as f64 - 1.0);
        let t = membrane_tension_n(&scene, 1.0);
        assert!(
            (t - exact).abs() <= 1e-12 * exact,
            "{rings} rings: {t} vs {exact}"
        );
        let limit = radius / rings as f64 / 3f64.sqrt();
        assert!((t / limit - 1.0).abs() <= 1.0 / (3.0 * rings as f64 - 1.0) + 1e-12);
    }
}

/// A scene gives each net's tension level one way: the mean tension or the
/// membrane stress, which resolves to the mean tension that carries it.
#[test]
fn a_net_takes_a_mean_tension_or_a_membrane_stress_not_both() {
    let text = std::fs::read_to_string(common::problem("small-hex.toml")).unwrap();
    let plain = Scene::from_toml(&text, "x").unwrap();
    let per_stress = membrane_tension_n(&plain, 1.0);
    let stress = plain.front_net.mean_tension_n / per_stress;
    let by_stress = text.replacen(
        "mean_tension_n = 70.0",
        &format!("membrane_stress_n_per_m = {stress:?}"),
        1,
    );
    assert_ne!(by_stress, text);
    let resolved = Scene::from_toml(&by_stress, "x").unwrap();
    let t = resolved.front_net.mean_tension_n;
    assert!((t - 70.0).abs() <= 1e-12 * 70.0, "{t}");
    // The resolved scene (as a shard header stores it) stays valid.
    resolved.validate().unwrap();

    let both = by_stress.replacen(
        "membrane_stress_n_per_m",
        "mean_tension_n = 50.0\nmembrane_stress_n_per_m",
        1,
    );
    let e = Scene::from_toml(&both, "x").unwrap_err();
    assert_eq!(e.key(), Some("front_net.membrane_stress_n_per_m"), "{e}");
    let neither = text.replacen("mean_tension_n = 70.0", "", 1);
    let e = Scene::from_toml(&neither, "x").unwrap_err();
    assert_eq!(e.key(), Some("front_net.mean_tension_n"), "{e}");
    assert!(e.to_string().contains("membrane_stress_n_per_m"), "{e}");
}

/// The shipped super-large scenes: about 10⁴ and 10⁵ nodes, facets of
/// 1–2.5 mm RMS, the membrane stress of realistic-26m.
#[test]
fn the_super_large_scenes_are_dense_enough_for_their_surface() {
    let realistic = common::scene("realistic-26m");
    let stress = realistic.front_net.mean_tension_n / membrane_tension_n(&realistic, 1.0);
    for (name, nodes) in [("super-60m", 1e4), ("super-100m", 1e5)] {
        let scene = common::scene(name);
        let mesh = build_mesh(&scene).unwrap();
        let n = mesh.network.n_nodes() as f64;
        assert!(n >= nodes / 3.0 && n <= 3.0 * nodes, "{name}: {n} nodes");
        let facet_mm = ringmesh::surface::design_surface_facets(&mesh)
            .unwrap()
            .raw_mm;
        assert!(
            (1.0..=2.5).contains(&facet_mm),
            "{name}: facet RMS {facet_mm} mm"
        );
        let own = scene.front_net.membrane_stress_n_per_m.unwrap();
        assert!(
            (own / stress - 1.0).abs() <= 1e-3,
            "{name}: {own} vs {stress} N/m"
        );
    }
}

/// super-60m with its net coarsened for CI (14 rings instead of 28, ≈ 7 000
/// nodes; the full scene runs in `results/super-60m/`): the exact-truss design
/// assembles on the paraboloid, holds its tensions, and the truss carries it
/// with a margin of 2 or more.
#[test]
fn super_60m_designs_assembles_and_keeps_its_margin() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(common::problem("super-60m.toml")).unwrap();
    let coarse = text.replacen("rings = 28", "rings = 14", 1);
    assert_ne!(coarse, text);
    let path = dir.path().join("super-60m.toml");
    std::fs::write(&path, coarse).unwrap();
    let outcome = design(
        &path,
        &DesignSettings::default(),
        Some(dir.path()),
        &mut |_, _| {},
    )
    .unwrap();
    let r = &outcome.report;
    assert!(r.boundary_residual_m <= 1e-6, "{}", r.boundary_residual_m);
    let v = &r.verification;
    assert!(v.rms_mm <= 1e-3, "RMS {} mm", v.rms_mm);
    assert!(
        v.max_tension_change_pct <= 0.05,
        "{} %",
        v.max_tension_change_pct
    );
    let margin = r.limit_margin.as_ref().unwrap();
    assert!(margin.stable_to >= 2.0, "{margin:?}");
    // model.vtu carries the buckling mode on the truss, zero on the net,
    // its largest translation 1.
    let vtu = std::fs::read_to_string(dir.path().join("model.vtu")).unwrap();
    let field = vtu
        .split("Name=\"buckling_mode\" NumberOfComponents=\"3\" format=\"ascii\">\n")
        .nth(1)
        .expect("a buckling_mode field")
        .split("</DataArray>")
        .next()
        .unwrap();
    let norms: Vec<f64> = field
        .lines()
        .map(|l| {
            let v: Vec<f64> = l.split(' ').map(|x| x.parse().unwrap()).collect();
            (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
        })
        .collect();
    let net_nodes = r.net.nodes_xyz_m.len();
    assert!(norms[..net_nodes].iter().all(|&n| n == 0.0));
    let largest = norms[net_nodes..].iter().copied().fold(0.0, f64::max);
    assert!(
        (largest - 1.0).abs() <= 1e-6,
        "largest translation {largest}"
    );
    // The net carries the membrane stress the scene asks for: the front
    // net's mean tension is the one it resolves to.
    let scene = Scene::read(&path).unwrap();
    let front = &r.net.sets[0];
    let target = scene.front_net.mean_tension_n;
    assert!(
        (front.mean_tension_n / target - 1.0).abs() <= 1e-9,
        "{} N for {target} N",
        front.mean_tension_n
    );
}

/// A 120-bay ring (the most issue 15 asks for) under super-60m's net at 20
/// rings (≈ 80 mm cables): two solves of its truss under one pull, each to
/// the force tolerance, differ by microns at the hinges — tens of newtons on
/// the net's short cables, from which the assembly's Newton diverged (it
/// stalled at prestrain 0 when the assembly re-solved the truss). Started
/// from the loop's own truss equilibrium, it converges at once onto the
/// design.
///
/// The loop runs to 1e-8 m, not the default 1e-6 m: the assembled tensions
/// read where the loop stopped, a boundary within 1e-6 m being up to 0.05 %
/// of an 80 mm cable's tension. Measured with the plan LP's node-block
/// scaling: 0.051 % at 1e-6 m (0.00074 % with the unit diagonal, whose
/// loop happened to stop nearer), 0.0004 % at 1e-8 m.
#[test]
fn a_120_bay_ring_assembles_from_the_loops_truss_equilibrium() {
    let text = std::fs::read_to_string(common::problem("super-60m.toml")).unwrap();
    let dense =
        text.replacen("\nbays = 36", "\nbays = 120", 1)
            .replacen("rings = 28", "rings = 20", 1);
    let scene = Scene::from_toml(&dense, "super-60m-120-bays").unwrap();
    assert_eq!((scene.truss.bays, scene.front_net.rings), (120, 20));
    let nets = SceneNets::new(&scene).unwrap();
    let solver = SolverKind::Lp.build(None);
    let settings = LoopSettings {
        tolerance_m: 1e-8,
        ..LoopSettings::default()
    };
    let outcome = nets
        .design_loop(solver.as_ref(), TrussModel::Exact, &settings, &mut |_| {})
        .unwrap();
    assert_eq!(outcome.termination, Termination::Converged);
    let equilibrium = outcome.truss_equilibrium.as_ref();
    assert!(equilibrium.is_some(), "the exact truss has a frame state");
    let v = verify(
        &scene,
        &nets.mesh,
        &nets.effects,
        outcome.problem.network(),
        &outcome.design,
        AssemblyTruss::Flexible,
        equilibrium,
    )
    .unwrap();
    assert!(
        v.newton_iterations <= 2,
        "{} iterations",
        v.newton_iterations
    );
    assert!(v.slack_cables.is_empty(), "{:?}", v.slack_cables);
    assert!(v.rms_mm <= 1e-3, "RMS {} mm", v.rms_mm);
    assert!(
        v.max_tension_change_pct <= 0.01,
        "{} %",
        v.max_tension_change_pct
    );
    assert!(
        v.boundary_deviation_mm <= 1e-3,
        "{} mm",
        v.boundary_deviation_mm
    );
}
