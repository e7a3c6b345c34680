//! Frame files: the shipped problems solve to what they claim (the full-circle
//! cantilever, a ring truss without reactions), malformed files are rejected
//! with the key at fault named, and the `frame` and `cantilever` commands
//! write what they document.

mod common;

use nalgebra::Vector3;
use ringmesh::frame::{cantilever, FrameFile};
use ringmesh::mechanics::{StaticSolver, StaticTermination};
use serde_json::Value;

#[test]
fn cantilever_file_rolls_up_into_the_full_circle() {
    let file = FrameFile::read(&common::problem("frames/cantilever-moment.toml")).unwrap();
    let tip = file.rod("cantilever").unwrap().end();
    let solver = StaticSolver::new(file.model.clone()).unwrap();
    let solution = solver.solve(&file.settings).unwrap();
    assert_eq!(solution.termination, StaticTermination::Converged);
    // ML/(πEI) = 2: the closed form puts the tip back on the root.
    let (axial, vertical) = cantilever::analytic(2.0);
    let expected = Vector3::new(cantilever::LENGTH_M - axial, vertical, 0.0);
    let got = solution.state.frames[tip].position_m;
    let error = (got - expected).norm() / cantilever::LENGTH_M;
    assert!(
        error < 1e-8,
        "tip {got:?}, expected {expected:?}: {error:e}"
    );
    // The root is clamped: its reaction balances the tip moment.
    let reaction = solution.reactions[file.rod("cantilever").unwrap().start()];
    let moment = 2.0 * std::f64::consts::PI * cantilever::BENDING_NM2 / cantilever::LENGTH_M;
    assert!((reaction[5] + moment).abs() < 1e-8 * moment, "{reaction:?}");
}

#[test]
fn ring_truss_under_self_equilibrated_loads_on_an_isostatic_support_has_no_reactions() {
    let file = FrameFile::read(&common::problem("frames/ring-truss-frame.toml")).unwrap();
    assert_eq!(file.bodies.len(), 12);
    assert_eq!(file.model.rods().len(), 24);
    let solver = StaticSolver::new(file.model.clone()).unwrap();
    let solution = solver.solve(&file.settings).unwrap();
    assert_eq!(solution.termination, StaticTermination::Converged);

    let loads = file.model.loads();
    let load_sum: f64 = loads.iter().map(|l| l.force_n.norm()).sum();
    let max_load = loads.iter().map(|l| l.force_n.norm()).fold(0.0, f64::max);
    let reference = file.model.reference();
    let displacement = solution
        .state
        .frames
        .iter()
        .zip(reference)
        .map(|(f, r)| (f.position_m - r.position_m).norm())
        .fold(0.0, f64::max);
    assert!(displacement > 0.0);
    let reactions: Vec<Vector3<f64>> = file
        .supported_nodes
        .iter()
        .map(|&n| Vector3::from_column_slice(&solution.reactions[n][..3]))
        .collect();
    assert_eq!(reactions.len(), 3);
    // Dead loads at displaced points are self-equilibrated in force, and in
    // moment up to Σ|f|·u_max; the support takes that moment over a lever arm
    // of the ring's size (the 3 m radius, b0–b2 = 5.2 m).
    let radius = 3.0;
    let bound = 2.0 * load_sum * displacement / radius + 1e-8 * max_load;
    let largest = reactions.iter().map(|r| r.norm()).fold(0.0, f64::max);
    assert!(
        largest <= bound && largest < 1e-3 * max_load,
        "largest reaction {largest:e} N, bound {bound:e} N (u_max {displacement:e} m)"
    );
    // Force balance of the whole: Σ reactions = −Σ loads.
    let total: Vector3<f64> = reactions.iter().sum::<Vector3<f64>>()
        + loads.iter().map(|l| l.force_n).sum::<Vector3<f64>>();
    assert!(total.norm() < 1e-8 * load_sum, "{total:?}");
}

/// A valid small frame: an arm clamped at the root with a rigid hub fixed to
/// its tip and a force on the hub. Each malformed file changes one thing.
const BASE: &str = r#"
[[nodes]]
name = "root"
position_m = [0.0, 0.0, 0.0]
[[nodes]]
name = "tip"
position_m = [1.0, 0.0, 0.0]

[[rods]]
name = "arm"
start = "root"
end = "tip"
axial_n = 1e4
shear_n = [1e4, 1e4]
torsion_nm2 = 100.0
bending_nm2 = [100.0, 100.0]
elements = 2

[[bodies]]
name = "hub"
at = "tip"

[[joints]]
kind = "fixed"
a = { rod = "arm", end = "end" }
b = { body = "hub" }

[[supports]]
on = { node = "root" }
fixed = ["all"]

[[loads]]
on = { body = "hub" }
force_n = [0.0, 1.0, 0.0]
"#;

fn with(from: &str, to: &str) -> String {
    assert!(BASE.contains(from), "the base file has {from:?}");
    BASE.replacen(from, to, 1)
}

#[test]
fn the_base_of_the_malformed_files_is_valid_and_solves() {
    let file = FrameFile::from_toml(BASE).unwrap();
    let solution = StaticSolver::new(file.model)
        .unwrap()
        .solve(&file.settings)
        .unwrap();
    assert_eq!(solution.termination, StaticTermination::Converged);
}

#[test]
fn malformed_frame_files_name_the_key_at_fault() {
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "unknown key",
            with("elements = 2", "elements = 2\nlenght_m = 3.0"),
            "lenght_m",
        ),
        (
            "zero-length rod",
            with("end = \"tip\"", "end = \"root\""),
            "rods[0].end: node \"root\" is where the rod starts",
        ),
        (
            "unknown node",
            with("start = \"root\"", "start = \"nowhere\""),
            "rods[0].start: unknown node \"nowhere\"",
        ),
        (
            "node index out of range",
            with("start = \"root\"", "start = 7"),
            "rods[0].start: node 7 does not exist",
        ),
        (
            "unknown rod",
            with("a = { rod = \"arm\"", "a = { rod = \"x\""),
            "joints[0].a.rod: unknown rod \"x\"",
        ),
        (
            "unknown body",
            with("on = { body = \"hub\" }", "on = { body = \"wheel\" }"),
            "loads[0].on.body: unknown body \"wheel\"",
        ),
        (
            "rod end missing",
            with("a = { rod = \"arm\", end = \"end\" }", "a = { rod = \"arm\" }"),
            "joints[0].a.end: missing",
        ),
        (
            "no elements",
            with("elements = 2", "elements = 0"),
            "rods[0].elements: must be at least 1",
        ),
        (
            "negative stiffness",
            with("axial_n = 1e4", "axial_n = -1e4"),
            "rods[0].axial_n: -10000 must be finite and positive",
        ),
        (
            "negative bending stiffness",
            with("bending_nm2 = [100.0, 100.0]", "bending_nm2 = [100.0, -1.0]"),
            "rods[0].bending_nm2[1]",
        ),
        (
            "incomplete stiffnesses",
            with("torsion_nm2 = 100.0\n", ""),
            "rods[0].torsion_nm2: missing",
        ),
        (
            "unknown section",
            with("axial_n = 1e4\nshear_n = [1e4, 1e4]\ntorsion_nm2 = 100.0\nbending_nm2 = [100.0, 100.0]", "section = \"steel\""),
            "rods[0].section: unknown section \"steel\"",
        ),
        (
            "tube inner diameter not below the outer",
            with(
                "axial_n = 1e4\nshear_n = [1e4, 1e4]\ntorsion_nm2 = 100.0\nbending_nm2 = [100.0, 100.0]",
                "tube = { outer_diameter_m = 0.02, inner_diameter_m = 0.02, youngs_modulus_pa = 2e11, shear_modulus_pa = 8e10 }",
            ),
            "rods[0].tube.inner_diameter_m",
        ),
        (
            "revolute axis zero",
            with("kind = \"fixed\"", "kind = \"revolute\"\naxis = [0.0, 0.0, 0.0]"),
            "joints[0].axis: must be a non-zero vector",
        ),
        (
            "revolute without axis",
            with("kind = \"fixed\"", "kind = \"revolute\""),
            "joints[0].axis: missing",
        ),
        (
            "joint to itself",
            with("b = { body = \"hub\" }", "b = { rod = \"arm\", end = \"end\" }"),
            "joints[0].b: is the same member as joints[0].a",
        ),
        (
            "ambiguous node",
            with("on = { body = \"hub\" }", "on = { node = \"tip\" }"),
            "loads[0].on.node: 2 members are at node \"tip\"",
        ),
        (
            "support fixing nothing",
            with("fixed = [\"all\"]", "fixed = []"),
            "supports[0].fixed: names no component",
        ),
        (
            "unknown component",
            with("fixed = [\"all\"]", "fixed = [\"w\"]"),
            "unknown variant `w`",
        ),
        (
            "non-finite load",
            with("force_n = [0.0, 1.0, 0.0]", "force_n = [0.0, nan, 0.0]"),
            "loads[0].force_n: a component is not finite",
        ),
        (
            "duplicate name",
            with("name = \"tip\"", "name = \"root\""),
            "nodes[1].name: node \"root\" is already nodes[0]",
        ),
        (
            "bad solver setting",
            format!("{BASE}\n[solver]\ntolerance = 0.0\n"),
            "solver.tolerance: must be in (0, 1)",
        ),
    ];
    for (what, text, expected) in cases {
        common::frames::assert_refused(what, &text, expected);
    }
}

#[test]
fn frame_command_writes_positions_rotations_reactions_and_solver_stats() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cantilever.json");
    let run = common::ringmesh_in(
        &[
            "frame",
            common::problem("frames/cantilever-moment.toml")
                .to_str()
                .unwrap(),
            "-o",
            out.to_str().unwrap(),
        ],
        dir.path(),
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        stdout.contains("reached its target at load factor 1.000000"),
        "{stdout}"
    );
    let json: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(json["termination"]["status"], "converged");
    // The path: the unloaded frame and every load step, and its files.
    let points = json["path"]["points"].as_array().unwrap();
    assert_eq!(
        points.len() as u64,
        json["load_steps"].as_u64().unwrap() + 1
    );
    assert_eq!(points[0]["load_factor"], 0.0);
    assert_eq!(points.last().unwrap()["load_factor"], 1.0);
    // Named after the JSON file they are beside (`-o DIR/cantilever.json`).
    let csv = std::fs::read_to_string(out.with_file_name("cantilever-path.csv")).unwrap();
    assert_eq!(csv.lines().count(), points.len() + 1, "{csv}");
    for plot in ["cantilever-path.png", "cantilever-path.svg"] {
        assert!(
            out.with_file_name(plot).metadata().unwrap().len() > 0,
            "{plot}"
        );
    }
    assert_eq!(json["load_factor"], 1.0);
    for key in ["load_steps", "newton_iterations", "rejected_steps"] {
        assert!(json[key].is_u64(), "{key}");
    }
    assert!(json["time_s"].as_f64().unwrap() >= 0.0);
    let steps = json["steps"].as_array().unwrap();
    assert_eq!(steps.len() as u64, json["load_steps"].as_u64().unwrap());
    for step in steps {
        assert!(step["residuals"].as_array().unwrap().len() >= 2);
        assert!(step["load_factor"].is_f64() && step["iterations"].is_u64());
    }
    let nodes = json["nodes"].as_array().unwrap();
    assert_eq!(nodes.len(), 11);
    for node in nodes {
        for key in ["position_m", "displacement_m", "rotation_rad"] {
            assert_eq!(node[key].as_array().unwrap().len(), 3, "{key}");
        }
        assert_eq!(node["rod"], "cantilever");
    }
    // The tip is back at the root: displacement (−10, 0, 0).
    let tip = &nodes[10]["displacement_m"];
    assert!((tip[0].as_f64().unwrap() + 10.0).abs() < 1e-7, "{tip}");
    // Mid-rod the section has turned by π about z (rotation vector of angle π).
    let mid = &nodes[5]["rotation_rad"];
    let angle = (0..3)
        .map(|i| mid[i].as_f64().unwrap().powi(2))
        .sum::<f64>()
        .sqrt();
    assert!((angle - std::f64::consts::PI).abs() < 1e-6, "{mid}");
    let reactions = json["reactions"].as_array().unwrap();
    assert_eq!(reactions.len(), 1);
    assert_eq!(reactions[0]["node"], 0);
    assert!(reactions[0]["force_n"].is_array() && reactions[0]["moment_nm"].is_array());
}

#[test]
fn frame_command_writes_under_runs_by_default() {
    let dir = tempfile::tempdir().unwrap();
    let run = common::ringmesh_in(
        &[
            "frame",
            common::problem("frames/ring-truss-frame.toml")
                .to_str()
                .unwrap(),
        ],
        dir.path(),
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let out = dir.path().join("runs/ring-truss-frame/frame.json");
    let json: Value = serde_json::from_str(&std::fs::read_to_string(out).unwrap()).unwrap();
    assert_eq!(json["termination"]["status"], "converged");
    assert_eq!(json["reactions"].as_array().unwrap().len(), 3);
    assert_eq!(json["counts"]["bodies"], 12);
}

#[test]
fn frame_command_rejects_a_bad_file_with_exit_code_2_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, with("elements = 2", "elements = 0")).unwrap();
    let out = dir.path().join("out.json");
    let run = common::ringmesh_in(
        &["frame", bad.to_str().unwrap(), "-o", out.to_str().unwrap()],
        dir.path(),
    );
    assert_eq!(run.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        stderr.contains("rods[0].elements: must be at least 1"),
        "{stderr}"
    );
    assert!(!out.exists());
    assert!(!dir.path().join("runs").exists());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn cantilever_command_json_has_every_load_converged() {
    let dir = tempfile::tempdir().unwrap();
    let run = common::ringmesh_in(&["cantilever", "--json"], dir.path());
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let json: Value = serde_json::from_slice(&run.stdout).unwrap();
    assert_eq!(json["elements"], 10);
    assert_eq!(json["element"], "se3");
    let rows = json["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 7);
    for (row, m) in rows.iter().zip(cantilever::M_RATIOS) {
        assert_eq!(row["m_ratio"], m);
        assert_eq!(row["converged"], true);
        for key in [
            "axial_m",
            "vertical_m",
            "analytic_axial_m",
            "analytic_vertical_m",
            "relative_error",
            "time_s",
        ] {
            assert!(row[key].is_f64(), "{key}: {row}");
        }
        assert!(row["newton_iterations"].as_u64().unwrap() >= 1);
        assert!(row["load_steps"].as_u64().unwrap() >= 1);
        assert!(row["relative_error"].as_f64().unwrap() < 1e-8, "{row}");
    }
    assert_eq!(rows[4]["paper_axial_m"], 9.96377);
    assert!(rows[0].get("paper_axial_m").is_none());
}

#[test]
fn cantilever_command_prints_the_table_with_the_paper_column() {
    let dir = tempfile::tempdir().unwrap();
    let run = common::ringmesh_in(
        &[
            "cantilever",
            "--elements",
            "10",
            "--element",
            "crisfield-jelenic",
        ],
        dir.path(),
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        stdout.contains("crisfield-jelenic") && stdout.contains("9.96377"),
        "{stdout}"
    );
    assert_eq!(stdout.lines().count(), 3 + 7, "{stdout}");
    assert!(!stdout.contains("NOT CONVERGED"), "{stdout}");
    let zero = common::ringmesh_in(&["cantilever", "--elements", "0"], dir.path());
    assert_eq!(zero.status.code(), Some(2));
}
