//! Measured rod properties (`[effects] rod_properties_csv`): a table of EA/EI
//! per rod overrides the nominal tube of the rods it names, in every truss
//! model; the response follows the stiffnesses as the physics says; the rods
//! are named as documented; bad tables are refused naming file and line.

mod common;

use std::path::{Path, PathBuf};

use ringmesh::effects::SceneEffects;
use ringmesh::geometry::build_mesh;
use ringmesh::mechanics::Section;
use ringmesh::scene::{Scene, SceneError, TrussModel};
use ringmesh::truss::{RingTruss, RodKind, RodProperties, TrussRod};

fn small_hex() -> Scene {
    let path = common::problem("small-hex.toml");
    Scene::read(&path).expect("shipped scene")
}

fn nominal(scene: &Scene) -> Section {
    let t = &scene.truss;
    Section::tube(
        t.tube_outer_diameter_m,
        t.tube_inner_diameter_m,
        t.youngs_modulus_pa,
        t.shear_modulus_pa,
    )
}

/// `scene` with the table `csv` (parsed for its bays).
fn with_table(scene: &Scene, csv: &str) -> Scene {
    let mut s = scene.clone();
    s.effects.rod_properties = Some(RodProperties::parse(csv, "test.csv", s.truss.bays).unwrap());
    s
}

/// A table giving every rod of the kinds `kinds` the nominal stiffnesses
/// times `[EA, EI, GJ, GA]` factors.
fn scaled_table(scene: &Scene, kinds: &[RodKind], factors: [f64; 4]) -> String {
    let n = nominal(scene);
    let mut csv = String::from(
        "rod,axial_stiffness_n,bending_stiffness_nm2,torsion_stiffness_nm2,shear_stiffness_n\n",
    );
    for rod in TrussRod::all(scene.truss.bays).filter(|r| kinds.contains(&r.kind)) {
        csv += &format!(
            "{rod},{:e},{:e},{:e},{:e}\n",
            factors[0] * n.axial_n,
            factors[1] * n.bending_nm2[0],
            factors[2] * n.torsion_nm2,
            factors[3] * n.shear_n[0],
        );
    }
    csv
}

/// Attachment displacements, m: 2N × 3.
fn displacements(scene: &Scene, model: TrussModel, loads: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let mesh = build_mesh(scene).unwrap();
    let mut oracle = common::scene_oracle(model, scene, &mesh);
    let moved = oracle.respond(loads).unwrap().positions_m;
    moved
        .iter()
        .zip(oracle.attachments())
        .map(|(p, r)| std::array::from_fn(|c| p[c] - r[c]))
        .collect()
}

fn largest(u: &[[f64; 3]]) -> f64 {
    u.iter()
        .map(|d| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt())
        .fold(0.0, f64::max)
}

/// Work of the loads on the displacements, `Σ f·u`, J (twice the
/// complementary energy of a linear frame: its compliance).
fn work(loads: &[[f64; 3]], u: &[[f64; 3]]) -> f64 {
    loads
        .iter()
        .zip(u)
        .map(|(f, d)| f[0] * d[0] + f[1] * d[1] + f[2] * d[2])
        .sum()
}

/// Doubling every stiffness of every rod doubles the frame's stiffness
/// matrix, while the joints and supports are kinematic: `2K u' = f` and
/// `u' = u/2` exactly for the linear model. For the exact model the same
/// scaling maps the equilibrium equations `f_int(u; 2C) = 2 f_int(u; C) = P`
/// onto the nominal truss under `P/2`: the stiffer truss under the pull
/// stands where the nominal one stands under half the pull, to the
/// solver's tolerance (measured: to the bit, ×2 being exact in binary
/// floating point) — and, geometric nonlinearity aside, at about half the
/// displacement (measured ×0.50072).
#[test]
fn every_rod_twice_as_stiff_halves_the_linear_displacement_and_is_the_exact_truss_at_half_load() {
    let scene = small_hex();
    let mesh = build_mesh(&scene).unwrap();
    let pull = common::net_pull(&mesh);
    let stiff = with_table(
        &scene,
        &scaled_table(&scene, &RodKind::ALL, [2.0, 2.0, 2.0, 2.0]),
    );
    assert_eq!(
        stiff.effects.rod_properties.as_ref().unwrap().len(),
        5 * scene.truss.bays
    );

    let u = displacements(&scene, TrussModel::Linear, &pull);
    let u2 = displacements(&stiff, TrussModel::Linear, &pull);
    let scale = largest(&u);
    let halved: Vec<[f64; 3]> = u.iter().map(|d| d.map(|v| 0.5 * v)).collect();
    let error = common::max_abs_diff(&u2, &halved);
    println!(
        "linear: largest displacement {scale:.4e} m → {:.4e} m, {error:.1e} m off u/2",
        largest(&u2)
    );
    // Roundoff of one sparse solve on coordinates of a few metres.
    assert!(
        error <= 1e-9 * scale,
        "linear: {error:e} m off u/2 (displacement {scale:e} m)"
    );

    let e = displacements(&scene, TrussModel::Exact, &common::scaled(&pull, 0.5));
    let e2 = displacements(&stiff, TrussModel::Exact, &pull);
    let exact_scale = largest(&e2);
    let error = common::max_abs_diff(&e2, &e);
    // Both stop at the force tolerance 1e-10 of the pull.
    assert!(
        error <= 1e-6 * exact_scale,
        "exact: 2C under P and C under P/2 differ by {error:e} m (displacement {exact_scale:e} m)"
    );
    let full = displacements(&scene, TrussModel::Exact, &pull);
    let ratio = exact_scale / largest(&full);
    println!("exact: 2C under P is C under P/2 to {error:.1e} m; displacement ×{ratio:.5}");
    assert!(
        (ratio - 0.5).abs() < 0.05,
        "exact: stiffer/nominal displacement {ratio}"
    );
}

/// Stiffening rods can only lower a linear frame's compliance `fᵀK⁻¹f`
/// (the work of the pull) under the same loads — K grows in the positive
/// semi-definite order — and softening can only raise it; halving some
/// stiffnesses keeps `K ≥ K/2`, so the compliance at most doubles. The ring
/// carries the nets' pull at its hinges as hoop force in its longerons: a
/// hinge moves by about `R·H/EA`, so longerons of ×4 EA and EI pull the
/// hinges in less, and bottom longerons of half the EA (the rear net pulls
/// hardest) nearly double the largest hinge motion. The exact model, near
/// linear at this load, agrees.
#[test]
fn stiffer_longerons_move_the_hinges_less_and_softer_ones_more() {
    let scene = small_hex();
    let mesh = build_mesh(&scene).unwrap();
    let pull = common::net_pull(&mesh);
    let stiff = with_table(
        &scene,
        &scaled_table(
            &scene,
            &[RodKind::TopLongeron, RodKind::BottomLongeron],
            [4.0, 4.0, 1.0, 1.0],
        ),
    );
    let soft = with_table(
        &scene,
        &scaled_table(&scene, &[RodKind::BottomLongeron], [0.5, 1.0, 1.0, 1.0]),
    );
    for model in [TrussModel::Linear, TrussModel::Exact] {
        let u = displacements(&scene, model, &pull);
        let (w, d) = (work(&pull, &u), largest(&u));
        let us = displacements(&stiff, model, &pull);
        let (ws, ds) = (work(&pull, &us), largest(&us));
        let uw = displacements(&soft, model, &pull);
        let (ww, dw) = (work(&pull, &uw), largest(&uw));
        println!(
            "{model:?}: nominal {d:.4e} m ({w:.4e} J); longerons ×4 {ds:.4e} m (work ×{:.4}, \
             max ×{:.4}); bottom longerons ×½ EA {dw:.4e} m (work ×{:.4}, max ×{:.4})",
            ws / w,
            ds / d,
            ww / w,
            dw / d
        );
        assert!(w > 0.0, "{model:?}: the pull does work {w:e} J");
        assert!(
            ws < w && ds < d,
            "{model:?}: stiffer longerons {ws:e} J {ds:e} m"
        );
        assert!(
            ww > w && ww <= 2.0 * w * (1.0 + 1e-9),
            "{model:?}: softer longerons {ww:e} J against {w:e} J"
        );
        assert!(
            dw > 1.8 * d,
            "{model:?}: softer longerons {dw:e} m against {d:e} m"
        );
    }
}

/// The names of the table are the rods the module docs promise: each rod
/// index `5k + j` runs between the documented hinges, and softening the
/// axial stiffness of `top longeron 2` (×1e-2) lets a pair of forces pulling
/// top hinges 2 and 3 apart stretch that chord many times more, while
/// softening its neighbour `top longeron 3` barely does.
#[test]
fn rods_are_named_by_bay_in_build_order() {
    let scene = small_hex();
    let mesh = build_mesh(&scene).unwrap();
    let layout = &mesh.truss;
    let n = layout.bays();
    let ring = RingTruss::new(&scene, layout, &SceneEffects::of(&scene)).unwrap();
    let rods = ring.model.rods();
    assert_eq!(rods.len(), 5 * n);
    let at = |node: usize| {
        let p = ring.model.reference()[node].position_m;
        [p.x, p.y, p.z]
    };
    let mid = |a: [f64; 3], b: [f64; 3]| std::array::from_fn(|c| 0.5 * (a[c] + b[c]));
    for rod in TrussRod::all(n) {
        let (k, next) = (rod.bay, (rod.bay + 1) % n);
        let (top, bottom) = (&layout.top_m, &layout.bottom_m);
        let ends = match rod.kind {
            RodKind::Batten => [bottom[k], top[k]],
            RodKind::TopLongeron => [top[k], top[next]],
            RodKind::BottomLongeron => [bottom[k], bottom[next]],
            RodKind::DiagonalThick => [bottom[k], mid(bottom[k], top[next])],
            RodKind::DiagonalThin => [mid(bottom[k], top[next]), top[next]],
        };
        let r = &rods[rod.index()];
        let found = [at(r.start()), at(r.end())];
        assert!(
            common::max_abs_diff(&found, &ends) <= 1e-12,
            "{rod} (rod {}) runs {found:?}, not {ends:?}",
            rod.index()
        );
    }

    let chord = |u: &[[f64; 3]], a: usize, b: usize| {
        let (pa, pb) = (layout.top_m[a], layout.top_m[b]);
        let d0: [f64; 3] = std::array::from_fn(|c| pb[c] - pa[c]);
        let d: [f64; 3] = std::array::from_fn(|c| d0[c] + u[b][c] - u[a][c]);
        let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        norm(d) - norm(d0)
    };
    // 1 kN pulling top hinges 2 and 3 apart along their chord.
    let (a, b) = (2, 3);
    let mut pair = vec![[0.0; 3]; 2 * n];
    let d0: [f64; 3] = std::array::from_fn(|c| layout.top_m[b][c] - layout.top_m[a][c]);
    let length = (d0[0] * d0[0] + d0[1] * d0[1] + d0[2] * d0[2]).sqrt();
    pair[b] = d0.map(|v| 1e3 * v / length);
    pair[a] = d0.map(|v| -1e3 * v / length);
    let soft = |bay: usize| {
        let e = nominal(&scene).axial_n * 1e-2;
        with_table(
            &scene,
            &format!("rod,axial_stiffness_n\ntop longeron {bay},{e:e}\n"),
        )
    };
    let stretch = chord(&displacements(&scene, TrussModel::Linear, &pair), a, b);
    let named = chord(&displacements(&soft(2), TrussModel::Linear, &pair), a, b);
    let neighbour = chord(&displacements(&soft(3), TrussModel::Linear, &pair), a, b);
    println!("stretch: nominal {stretch:e} m, top longeron 2 soft {named:e} m, top longeron 3 soft {neighbour:e} m");
    assert!(stretch > 0.0);
    assert!(
        named > 10.0 * stretch,
        "softening top longeron 2: {stretch:e} → {named:e} m"
    );
    assert!(
        neighbour < 2.0 * stretch,
        "softening top longeron 3: {stretch:e} → {neighbour:e} m"
    );
}

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("rod-properties-{name}"));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `small-hex` with `[effects] rod_properties_csv = file`, written to `dir`.
fn write_scene(dir: &Path, file: &str) -> PathBuf {
    let text = std::fs::read_to_string(common::problem("small-hex.toml")).unwrap();
    let path = dir.join("scene.toml");
    std::fs::write(
        &path,
        format!("{text}\n[effects]\nrod_properties_csv = \"{file}\"\n"),
    )
    .unwrap();
    path
}

/// The table is found beside the scene file, not in the current directory;
/// an absent key reads nothing; a bad table is a scene error naming the
/// key, the file, the line and the rod, and a missing one names its path.
#[test]
fn scene_reads_its_table_beside_it_and_refuses_bad_ones() {
    let dir = scratch("read");
    std::fs::create_dir_all(dir.join("measured")).unwrap();
    std::fs::write(
        dir.join("measured/rods.csv"),
        "# lot 7\nrod,bending_stiffness_nm2\nbatten 1,1e5\ntop longeron 4,2e5\n",
    )
    .unwrap();
    let scene = Scene::read(&write_scene(&dir, "measured/rods.csv")).unwrap();
    let table = scene.effects.rod_properties.as_ref().expect("table read");
    assert_eq!(table.len(), 2);
    assert!(table.source().ends_with("rods.csv"));
    let batten = table.get(TrussRod::new(RodKind::Batten, 1)).unwrap();
    assert_eq!(batten.bending_stiffness_nm2, Some(1e5));
    assert_eq!(batten.axial_stiffness_n, None);
    assert!(small_hex().effects.rod_properties.is_none());

    // from_toml_in: the same relative to a given folder.
    let text = std::fs::read_to_string(dir.join("scene.toml")).unwrap();
    let again = Scene::from_toml_in(&text, "x", &dir).unwrap();
    assert_eq!(again.effects.rod_properties.as_ref(), Some(table));

    std::fs::write(
        dir.join("bad.csv"),
        "rod,axial_stiffness_n\nbatten 1,1e8\nbatten 9,1e8\n",
    )
    .unwrap();
    let e = Scene::read(&write_scene(&dir, "bad.csv")).unwrap_err();
    let message = e.to_string();
    assert!(matches!(e, SceneError::RodProperties(_)), "{message}");
    assert_eq!(e.key(), Some("effects.rod_properties_csv"));
    for w in [
        "effects.rod_properties_csv",
        "bad.csv",
        "line 3",
        "`batten 9`",
    ] {
        assert!(message.contains(w), "{message} lacks {w}");
    }

    let e = Scene::read(&write_scene(&dir, "missing.csv")).unwrap_err();
    assert!(e.to_string().contains("missing.csv"), "{e}");
    let e = Scene::read(&write_scene(&dir, "")).unwrap_err();
    assert_eq!(e.key(), Some("effects.rod_properties_csv"), "{e}");

    // A scene changed to fewer bays than its table is refused by validate.
    let mut fewer = scene.clone();
    fewer.truss.bays = 4;
    let e = fewer.validate().unwrap_err();
    assert!(e.to_string().contains("`top longeron 4`"), "{e}");
}

fn ringmesh_truss(scene: &Path, out: &Path) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_ringmesh"))
        .args(["truss", "--model", "linear", "-o"])
        .arg(out)
        .arg(scene)
        .output()
        .expect("run ringmesh")
}

fn max_displacement_m(json: &Path) -> f64 {
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(json).unwrap()).unwrap();
    v["max_displacement_m"].as_f64().unwrap()
}

/// The command line reads the table beside the scene: `ringmesh truss` with
/// bottom longerons of half the EA moves the hinges twice as far as the
/// nominal truss; a bad table exits with code 2, names file, line, rod and
/// column, and writes nothing.
#[test]
fn truss_command_applies_the_table_and_refuses_a_bad_one() {
    let dir = scratch("cli");
    let nominal_json = dir.join("nominal.json");
    let run = ringmesh_truss(&common::problem("small-hex.toml"), &nominal_json);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let half = 0.5 * nominal(&small_hex()).axial_n;
    let rows: String = (0..6)
        .map(|k| format!("bottom longeron {k},{half:e}\n"))
        .collect();
    std::fs::write(
        dir.join("rods.csv"),
        format!("rod,axial_stiffness_n\n{rows}"),
    )
    .unwrap();
    let soft_json = dir.join("soft.json");
    let run = ringmesh_truss(&write_scene(&dir, "rods.csv"), &soft_json);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let ratio = max_displacement_m(&soft_json) / max_displacement_m(&nominal_json);
    assert!((1.9..=2.0).contains(&ratio), "displacement ×{ratio}");

    std::fs::write(
        dir.join("bad.csv"),
        "rod,axial_stiffness_n\nbatten 2,-5e7\n",
    )
    .unwrap();
    let bad_json = dir.join("bad.json");
    let run = ringmesh_truss(&write_scene(&dir, "bad.csv"), &bad_json);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{stderr}");
    for w in [
        "effects.rod_properties_csv",
        "bad.csv",
        "line 2",
        "`batten 2`",
        "axial_stiffness_n",
        "`-5e7`",
    ] {
        assert!(stderr.contains(w), "{stderr} lacks {w}");
    }
    assert!(!bad_json.exists());
}
