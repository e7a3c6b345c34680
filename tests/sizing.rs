//! `ringmesh size` (issue 16): the lightest tube section whose design has a
//! limit margin of at least M — checked against designs the test makes
//! itself, on `small-hex`.

mod common;

use ringmesh::design::{run, DesignSettings};
use ringmesh::scene::TrussModel;
use ringmesh::sizing::{catalogue, size_truss, Sections, TubeSection};
use ringmesh::{truss, Scene};

/// The margin asked for.
const MARGIN: f64 = 2.0;

/// The margin of `scene`'s design with its truss made of `section`
/// (0 when the truss cannot carry the pull at all).
fn margin_of(scene: &Scene, section: &TubeSection) -> f64 {
    let mut scene = scene.clone();
    scene.truss = section.apply(&scene.truss);
    match run(&scene, &DesignSettings::default(), &mut |_, _| {}) {
        Ok(r) => r.report.limit_margin.unwrap().stable_to,
        Err(e) => {
            assert!(e.to_string().contains("limit load"), "{e}");
            0.0
        }
    }
}

#[test]
fn the_lightest_catalogue_section_that_carries_is_chosen() {
    let scene = common::scene("small-hex");
    // Out of mass order, with a dominated section (40/30 mm: heavier than
    // 50/46 mm and less stiff).
    let text = "outer_diameter_m,inner_diameter_m\n\
                0.080,0.074\n0.030,0.027\n0.050,0.046\n0.040,0.030\n0.040,0.036\n0.060,0.056\n";
    let sections = catalogue::parse(text, "test.csv", &scene.truss).unwrap();
    let sizing = size_truss(
        &scene,
        &Sections::Catalogue(sections.clone()),
        MARGIN,
        &DesignSettings::default(),
        &mut |_| {},
    )
    .unwrap();
    let chosen = sizing.trials[sizing.chosen].section;
    assert_eq!(chosen.outer_diameter_m, 0.050, "{:?}", sizing.trials);

    // Its design carries the net with the margin, the next lighter tube's
    // does not (both designed here, independently of the search).
    let kept = catalogue::undominated(&sections);
    let at = kept.iter().position(|s| *s == chosen).unwrap();
    assert!(at > 0);
    let lighter = kept[at - 1];
    assert!(lighter.mass_per_length_kg_per_m() < chosen.mass_per_length_kg_per_m());
    let (m_chosen, m_lighter) = (margin_of(&scene, &chosen), margin_of(&scene, &lighter));
    assert!(m_chosen >= MARGIN, "{m_chosen}");
    assert!(m_lighter < MARGIN, "{m_lighter}");
    // The search's own figures are those designs'.
    let tried = |s: &TubeSection| sizing.trials.iter().find(|t| t.section == *s).unwrap();
    assert_eq!(tried(&chosen).margin, m_chosen);
    assert_eq!(tried(&lighter).margin, m_lighter);
    assert!(!tried(&lighter).carries);
    // Bisection: fewer designs than sections.
    assert!(sizing.trials.len() < kept.len(), "{:?}", sizing.trials);

    // The sized scene reads back as the scene with the chosen tube.
    let sized = Scene::from_toml(&sizing.scene.to_toml().unwrap(), "x").unwrap();
    assert_eq!(sized, sizing.scene);
    assert_eq!(sized.truss.tube_outer_diameter_m, 0.050);
    assert_eq!(sized.truss.tube_inner_diameter_m, 0.046);
    assert_eq!(sized.front_net, scene.front_net);
}

#[test]
fn the_continuous_search_stops_at_the_margin_or_next_to_a_diameter_that_does_not_carry() {
    let scene = common::scene("small-hex");
    let sizing = size_truss(
        &scene,
        &Sections::Continuous { start_m: 0.060 },
        MARGIN,
        &DesignSettings::default(),
        &mut |_| {},
    )
    .unwrap();
    let chosen = &sizing.trials[sizing.chosen];
    let d = chosen.section.outer_diameter_m;
    // The scene's d/D kept.
    let ratio = scene.truss.tube_inner_diameter_m / scene.truss.tube_outer_diameter_m;
    assert!((chosen.section.inner_diameter_m / d - ratio).abs() < 1e-12);
    assert!(chosen.carries && chosen.margin >= MARGIN);
    // Every lighter diameter tried does not carry.
    for t in &sizing.trials {
        assert_eq!(t.carries, t.section.outer_diameter_m >= d, "{t:?}");
    }
    let next_below = sizing
        .trials
        .iter()
        .filter(|t| !t.carries)
        .map(|t| t.section.outer_diameter_m)
        .fold(0.0, f64::max);
    assert!(
        chosen.margin <= 1.03 * MARGIN || d - next_below <= 0.005 * d + 1e-4,
        "{:?}",
        sizing.trials
    );
}

#[test]
fn a_margin_the_search_cannot_certify_and_a_bad_catalogue_are_refused() {
    let out = common::ringmesh(&[
        "size",
        &common::problem_arg("small-hex.toml"),
        "--margin",
        "5",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("margin 5"));

    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("tubes.csv");
    std::fs::write(&csv, "outer_diameter_m,inner_diameter_m\n0.05,0.07\n").unwrap();
    let out = common::ringmesh(&[
        "size",
        &common::problem_arg("small-hex.toml"),
        "--sections",
        csv.to_str().unwrap(),
        "-o",
        dir.path().join("out").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("line 2") && stderr.contains("not below"),
        "{stderr}"
    );
    assert!(!dir.path().join("out").exists());
}

/// Sizing asks the registry which truss models have a limit load, and
/// refuses the others before designing anything, naming the key.
#[test]
fn a_truss_model_without_a_limit_load_is_refused() {
    let scene = common::scene("small-hex");
    let sections = Sections::Continuous { start_m: 0.05 };
    let without: Vec<TrussModel> = truss::MODELS
        .iter()
        .copied()
        .filter(|&m| !truss::has_limit_load(m))
        .collect();
    assert!(without.contains(&TrussModel::Linear), "{without:?}");
    for model in without {
        let settings = DesignSettings {
            truss: Some(model),
            ..DesignSettings::default()
        };
        let mut tried = 0;
        let e = size_truss(&scene, &sections, MARGIN, &settings, &mut |_| tried += 1)
            .expect_err("no limit load, no sizing");
        let message = e.to_string();
        assert!(
            message.contains("effects.truss") && message.contains("limit load"),
            "{model:?}: {message}"
        );
        assert_eq!(tried, 0, "{model:?}: a section was designed");
    }
}

/// `ringmesh size` writes the sized scene as the input file with its tube
/// lines changed: the input's comments stay, a net given by its membrane
/// stress is not given a mean tension too, and the file — with `rings`
/// edited, nothing else — designs again (issue 37: the written scene lost
/// every comment and held both tension keys, so that editing `rings` alone
/// was refused). The figure of the sections tried is written beside it.
#[test]
fn the_sized_scene_keeps_the_inputs_comments_and_designs_again_after_editing_rings() {
    let dir = tempfile::tempdir().unwrap();
    let input = std::fs::read_to_string(common::problem("small-hex.toml"))
        .unwrap()
        .replace(
            "mean_tension_n = 70.0",
            "membrane_stress_n_per_m = 40.0  # N/m: my own note",
        );
    let scene = dir.path().join("hex.toml");
    std::fs::write(&scene, &input).unwrap();
    let catalogue = dir.path().join("tubes.csv");
    std::fs::write(
        &catalogue,
        "outer_diameter_m,inner_diameter_m\n0.05,0.046\n",
    )
    .unwrap();
    let out = dir.path().join("out");
    let run = common::ringmesh(&[
        "size",
        scene.to_str().unwrap(),
        "--sections",
        catalogue.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    // Progress off a terminal: each outer iteration and stage of the
    // section's design on a line, then the section's own line.
    let stderr = String::from_utf8_lossy(&run.stderr);
    for line in [
        "  50.0/46.0 mm tube: anderson   0  boundary change",
        "  50.0/46.0 mm tube: limit margin: the truss's limit load",
        "  50.0/46.0 mm tube: the conventional design assembled",
        "\n50.0/46.0 mm tube: 31 kg, margin",
    ] {
        assert!(stderr.contains(line), "no {line:?} in:\n{stderr}");
    }
    let sized = std::fs::read_to_string(out.join("small-hex-sized.toml")).unwrap();
    for kept in [
        "# A small test scene: a hexagonal ring of 6 bays",
        "# 60/56 mm tubes: with 24/22 mm the ring buckles",
        "membrane_stress_n_per_m = 40.0  # N/m: my own note",
        "focal_length_m = 8.0         # rear tension level ≈ 2× front.",
    ] {
        assert!(sized.contains(kept), "lost {kept:?}:\n{sized}");
    }
    assert!(sized.contains("tube_outer_diameter_m = 0.05\n"), "{sized}");
    assert_eq!(
        sized.matches("mean_tension_n").count(),
        1,
        "only the rear net's, as given:\n{sized}"
    );
    assert!(out.join("sizing.png").is_file());

    let edited = dir.path().join("edited.toml");
    std::fs::write(&edited, sized.replace("rings = 3", "rings = 4")).unwrap();
    let design = common::ringmesh(&[
        "design",
        edited.to_str().unwrap(),
        "-o",
        dir.path().join("again").to_str().unwrap(),
    ]);
    assert!(
        design.status.success(),
        "{}",
        String::from_utf8_lossy(&design.stderr)
    );
}
