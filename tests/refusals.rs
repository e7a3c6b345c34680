//! What is accepted and what is refused, and what a refusal names (issue 40
//! items 8 and 9): one rule wherever a value can be written, and the key at
//! fault named — never a neighbour, never a value replaced silently.

mod common;

use ringmesh::frame::FrameFile;
use ringmesh::mechanics::{PathControl, StaticSolver};

/// A cantilever along `axis` with bending stiffnesses `bending` and the
/// extra rod keys `rod`, then the text `tail`.
fn cantilever(axis: [f64; 3], bending: [f64; 2], rod: &str, tail: &str) -> String {
    format!(
        r#"
[[nodes]]
name = "root"
position_m = [0.0, 0.0, 0.0]
[[nodes]]
name = "tip"
position_m = {axis:?}

[[rods]]
name = "post"
start = "root"
end = "tip"
axial_n = 1e4
shear_n = [1e4, 1e4]
torsion_nm2 = 100.0
bending_nm2 = {bending:?}
elements = 4
{rod}

[[supports]]
on = {{ node = "root" }}
fixed = ["all"]

[[loads]]
on = {{ node = "tip" }}
force_n = [0.1, 0.2, 0.0]
{tail}
"#
    )
}

fn refusal(text: &str) -> String {
    match FrameFile::from_toml(text) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// A rod's `up` along its axis orients no section: refused naming the
/// rod's `up`, not replaced by another axis (with unequal bending
/// stiffnesses the answer depended 100× on the replacement).
#[test]
fn an_up_along_the_rod_is_refused_naming_the_rod() {
    let e = refusal(&cantilever(
        [0.0, 0.0, 2.0],
        [100.0, 1.0],
        "up = [0.0, 0.0, -3.0]",
        "",
    ));
    assert!(e.contains("rods[0].up") && e.contains("\"post\""), "{e}");
    // The default `up` (z) on a rod along z: refused when the section's
    // orientation matters …
    let e = refusal(&cantilever([0.0, 0.0, 2.0], [100.0, 1.0], "", ""));
    assert!(e.contains("rods[0].up") && e.contains("missing"), "{e}");
    // … and accepted when it does not (equal stiffnesses), or given.
    for (bending, rod) in [([100.0, 100.0], ""), ([100.0, 1.0], "up = [1.0, 0.0, 0.0]")] {
        let text = cantilever([0.0, 0.0, 2.0], bending, rod, "");
        assert!(FrameFile::from_toml(&text).is_ok(), "{bending:?} {rod}");
    }
}

/// `[path] control` drives displacement control only: under load control
/// (or arc length) it is refused naming it, not ignored.
#[test]
fn a_path_control_the_solver_does_not_use_is_refused() {
    let control = "\n[path]\ncontrol = { on = { node = \"tip\" }, component = \"y\" }\n";
    for (path, used) in [
        ("load", false),
        ("arc_length", false),
        ("displacement", true),
    ] {
        let text = cantilever(
            [2.0, 0.0, 0.0],
            [100.0, 100.0],
            "up = [0.0, 1.0, 0.0]",
            &format!("{control}\n[solver]\npath = \"{path}\"\n"),
        );
        let file = FrameFile::from_toml(&text).unwrap();
        let followed = StaticSolver::new(file.model.clone())
            .unwrap()
            .follow_path(&file.path, &file.settings);
        match followed {
            Ok(_) => assert!(used, "{path}: control accepted"),
            Err(e) => {
                assert!(!used, "{path}: {e}");
                assert!(e.to_string().contains("path.control"), "{path}: {e}");
            }
        }
        if path == "load" {
            assert_eq!(file.settings.path, PathControl::Load);
        }
    }
}

/// A normal of any finite length is a direction: `[0, 0, 1e300]` (whose
/// norm overflows) builds the arc `[0, 0, 1]` does, instead of "start and
/// end are one point of the circle".
#[test]
fn an_arc_normal_of_huge_length_is_its_direction() {
    let arc = |normal: &str| {
        cantilever(
            [0.0, 2.0, 0.0],
            [100.0, 100.0],
            &format!(
                "up = [0.0, 0.0, 1.0]\narc = {{ centre_m = [0.0, 1.0, 0.0], normal = {normal} }}"
            ),
            "",
        )
    };
    let unit = FrameFile::from_toml(&arc("[0.0, 0.0, 1.0]")).unwrap();
    for big in ["[0.0, 0.0, 1e300]", "[0.0, 0.0, 1e-320]"] {
        let file = FrameFile::from_toml(&arc(big)).unwrap_or_else(|e| panic!("{big}: {e}"));
        for (a, b) in unit.model.reference().iter().zip(file.model.reference()) {
            assert!((a.position_m - b.position_m).norm() < 1e-12, "{big}");
        }
    }
}

/// A catalogue line with a modulus no material has is refused naming the
/// line, as a scene's is, instead of ending in a "mechanism"; a solid rod
/// (inner diameter 0) is a section in the catalogue as in a scene.
#[test]
fn catalogue_lines_follow_the_scenes_rules() {
    let scene = common::scene("small-hex");
    let parse = |text: &str| ringmesh::sizing::catalogue::parse(text, "tubes.csv", &scene.truss);
    let header = "outer_diameter_m,inner_diameter_m,youngs_modulus_pa\n";
    let e = parse(&format!("{header}0.05,0.046,1.6e11\n0.06,0.05,1e-300\n"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("tubes.csv, line 3") && e.contains("youngs_modulus_pa"),
        "{e}"
    );
    let solid = parse(&format!("{header}0.05,0,1.6e11\n")).unwrap();
    let area = std::f64::consts::PI * 0.05_f64.powi(2) / 4.0;
    assert!((solid[0].area_m2() - area).abs() <= 1e-15 * area);
    let inertia = std::f64::consts::PI * 0.05_f64.powi(4) / 64.0;
    let ei = solid[0].bending_stiffness_nm2();
    assert!((ei - 1.6e11 * inertia).abs() <= 1e-12 * ei);
    // The scene accepts the same solid rod, and refuses the same modulus.
    let text = std::fs::read_to_string(common::problem("small-hex.toml")).unwrap();
    let solid_scene = text.replace(
        "tube_inner_diameter_m = 0.056",
        "tube_inner_diameter_m = 0.0",
    );
    assert!(ringmesh::scene::Scene::from_toml(&solid_scene, "solid").is_ok());
    let soft = text.replacen("youngs_modulus_pa = 160e9", "youngs_modulus_pa = 1e-300", 1);
    assert_ne!(soft, text);
    let e = ringmesh::scene::Scene::from_toml(&soft, "soft")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("youngs_modulus_pa") && e.contains("softer"),
        "{e}"
    );
}

/// The aperture study names the aperture a value is wrong for: 1e-300 m
/// and 0.5 m are too small for the scene's net (not its `name`, not
/// `front_net.rings`).
#[test]
fn apertures_too_small_for_the_net_name_the_aperture() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ap");
    for (given, named) in [("1e-300", "1e-300 m"), ("0.5", "0.5 m")] {
        let run = common::ringmesh(&[
            "apertures",
            &common::problem_arg("small-hex.toml"),
            "--apertures",
            given,
            "-o",
            out.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8(run.stderr).unwrap();
        assert_eq!(run.status.code(), Some(2), "{stderr}");
        assert!(
            stderr.contains(&format!("`apertures`: {named}"))
                && stderr.contains("smallest aperture is 3 m")
                && stderr.len() < 400,
            "{stderr}"
        );
        assert!(!out.exists());
    }
}

/// `merge` on a shard that is not text is bad input (exit 2), naming the
/// file, not a failure of the machine (exit 1).
#[test]
fn merge_of_a_shard_that_is_not_text_exits_2_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let shard = dir.path().join("front.shard-1-of-2.csv");
    std::fs::write(&shard, b"\xff\xfe\x00 not text").unwrap();
    let run = common::ringmesh(&["merge", shard.to_str().unwrap()]);
    let stderr = String::from_utf8(run.stderr).unwrap();
    assert_eq!(run.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("front.shard-1-of-2.csv"), "{stderr}");
}
