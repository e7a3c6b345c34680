//! Surface accuracy as a user meets it (issue 34): a target in the scene
//! chooses the net, and every place that reports a surface RMS reports the
//! same number for the same design.

mod common;

use std::path::Path;

use ringmesh::geometry::build_mesh;
use ringmesh::report::readable;
use ringmesh::surface::{design_surface_facet_rms_mm, resolve_front_rings, ruze_gain_loss_db};
use ringmesh::Scene;

/// The facet RMS of `scene`'s design surface with `rings` rings, mm.
fn facet_rms_mm(scene: &Scene, rings: usize) -> f64 {
    let scene = scene.clone().with_rings(rings).unwrap();
    design_surface_facet_rms_mm(&build_mesh(&scene).unwrap()).unwrap()
}

/// A scene whose file leaves its rings to a facet RMS target gets the
/// coarsest net that meets it: its facets meet the target, one ring fewer
/// does not — on a 26 m and a 60 m dish.
#[test]
fn a_target_chooses_the_coarsest_net_that_meets_it() {
    for (name, target_mm) in [
        ("paper-26m", 2.0),
        ("realistic-26m", 5.0),
        ("super-60m", 1.5),
    ] {
        let mut scene = common::scene(name);
        scene.front_net.rings = 0;
        scene.surface.rms_mm = Some(target_mm);
        let resolved = resolve_front_rings(&scene).unwrap();
        let rings = resolved.front_net.rings;
        let chosen = resolved
            .front_net
            .chosen
            .as_ref()
            .expect("the rings were chosen");
        let met = facet_rms_mm(&scene, rings);
        let missed = facet_rms_mm(&scene, rings - 1);
        assert!(met <= target_mm, "{name}: {rings} rings give {met} mm");
        assert!(
            missed > target_mm,
            "{name}: {} rings give {missed} mm",
            rings - 1
        );
        assert!((chosen.facet_rms_mm - met).abs() <= 1e-12 * met, "{name}");
        assert_eq!(chosen.next_coarser.map(|(r, _)| r), Some(rings - 1));
        // A membrane stress is resolved for the chosen net, as for given rings.
        if let Some(stress) = scene.front_net.membrane_stress_n_per_m {
            let given = common::scene(name).with_rings(rings).unwrap();
            assert_eq!(
                resolved.front_net.mean_tension_n, given.front_net.mean_tension_n,
                "{name}: {stress} N/m"
            );
        }
    }
}

/// super-60m's own 28 rings are the coarsest net for 1.5 mm (27 give
/// 1.51 mm): the README's figure and the scene's comment agree with the one
/// definition.
#[test]
fn super_60m_is_the_coarsest_net_for_one_and_a_half_millimetres() {
    let scene = common::scene("super-60m");
    let mut target = scene.clone();
    target.front_net.rings = 0;
    target.surface.rms_mm = Some(1.5);
    let chosen = resolve_front_rings(&target).unwrap().front_net.rings;
    assert_eq!(chosen, scene.front_net.rings);
}

/// Text after `prefix` on the first line of `text` that has it, up to `end`.
fn field<'a>(text: &'a str, prefix: &str, end: &str) -> &'a str {
    let line = text
        .lines()
        .find(|l| l.contains(prefix))
        .unwrap_or_else(|| panic!("no line with {prefix:?} in:\n{text}"));
    let rest = &line[line.find(prefix).unwrap() + prefix.len()..];
    rest[..rest.find(end).unwrap_or(rest.len())].trim()
}

/// `design` and `mesh` on a scene with a target and a band: design.json's
/// budget, the design printout and the mesh printout give the same facet
/// RMS, the budget's terms combine as stated, and the gain loss is Ruze's.
#[test]
fn every_report_of_a_facet_rms_gives_the_same_number() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(common::problem("small-hex.toml"))
        .unwrap()
        .replace(
            "[reflector]",
            "[surface]\nrms_mm = 20.0\nfrequency_ghz = 0.4\n\n[reflector]",
        );
    let scene = dir.path().join("small-hex.toml");
    std::fs::write(&scene, text).unwrap();
    let scene = scene.to_str().unwrap();
    let out = |sub: &str| dir.path().join(sub).to_str().unwrap().to_string();

    let design = common::ringmesh(&["design", scene, "-o", &out("d")]);
    assert!(design.status.success(), "{design:?}");
    let printed = String::from_utf8(design.stdout).unwrap();
    let mesh = common::ringmesh(&["mesh", scene, "-o", &out("m")]);
    assert!(mesh.status.success(), "{mesh:?}");
    let meshed = String::from_utf8(mesh.stdout).unwrap();
    let json: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(Path::new(&out("d")).join("design.json")).unwrap(),
    )
    .unwrap();
    let budget = &json["surface"];
    let number = |key: &str, which: &str| budget[key][which].as_f64().unwrap();

    let facets = number("facets", "raw_mm");
    let facets_fit = number("facets", "best_fit_mm");
    assert_eq!(
        field(&printed, "facets (design surface)", "/"),
        readable(facets, 4)
    );
    assert_eq!(
        field(&meshed, "facet RMS (design surface, axial):", " mm"),
        readable(facets, 4)
    );
    assert_eq!(
        field(&meshed, "mm, ", " mm about the best-fit"),
        readable(facets_fit, 4)
    );
    assert!(printed.contains("met by the front net's"), "{printed}");
    assert_eq!(budget["target_met"], serde_json::json!(true));

    // The design's node RMS is the verification's, under one definition.
    let design_rms = number("design_as_built", "raw_mm");
    assert_eq!(design_rms, json["verification"]["rms_mm"].as_f64().unwrap());
    // The total is the root-sum-square of its terms, raw and best fit.
    for which in ["raw_mm", "best_fit_mm"] {
        let total = number("total", which);
        let rss = number("facets", which).hypot(number("design_as_built", which));
        assert!((total - rss).abs() <= 1e-12 * rss, "{which}");
    }
    // A design exact to micrometres: the facets as built are the design
    // surface's facets to that.
    assert!((number("facets_as_built", "raw_mm") - facets).abs() < 1e-3);
    // The best fit lowers every RMS, and the loss is Ruze's at the band.
    assert!(facets_fit < facets);
    let eps_m = 1e-3 * budget["half_path_best_fit_mm"].as_f64().unwrap();
    let loss = budget["gain_loss_db"].as_f64().unwrap();
    // (The report holds ε in mm: back in metres it can differ by an ulp.)
    let ruze = ruze_gain_loss_db(eps_m, 0.4e9).unwrap();
    assert!(
        (loss - ruze).abs() <= 1e-12 * ruze,
        "{loss} dB against Ruze's {ruze} dB"
    );
    assert!(printed.contains(&format!("gain loss at 0.4 GHz: {} dB", readable(loss, 4))));
}

/// A target the scene's own rings miss is said, with the figure.
#[test]
fn given_rings_that_miss_the_target_are_reported_as_missing_it() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(common::problem("small-hex.toml"))
        .unwrap()
        .replace("[reflector]", "[surface]\nrms_mm = 1.0\n\n[reflector]");
    let scene = dir.path().join("small-hex.toml");
    std::fs::write(&scene, text).unwrap();
    let out = dir.path().join("m");
    let mesh = common::ringmesh(&["mesh", scene.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(mesh.status.success(), "{mesh:?}");
    let printed = String::from_utf8(mesh.stdout).unwrap();
    assert!(printed.contains("NOT met by the front net's"), "{printed}");
}

/// Bad targets are refused naming the key; a scene with neither rings nor
/// a target names the rings.
#[test]
fn bad_surface_input_names_its_key() {
    let dir = tempfile::tempdir().unwrap();
    let base = std::fs::read_to_string(common::problem("small-hex.toml")).unwrap();
    let without_rings: String = base
        .lines()
        .filter(|l| !l.trim_start().starts_with("rings"))
        .collect::<Vec<_>>()
        .join("\n");
    for (text, key) in [
        (
            base.replace("[reflector]", "[surface]\nrms_mm = -1.0\n\n[reflector]"),
            "surface.rms_mm",
        ),
        (
            base.replace(
                "[reflector]",
                "[surface]\nfrequency_ghz = 0.0\n\n[reflector]",
            ),
            "surface.frequency_ghz",
        ),
        (without_rings.clone(), "front_net.rings"),
        (
            without_rings.replace("[reflector]", "[surface]\nrms_mm = 1e-6\n\n[reflector]"),
            "surface.rms_mm",
        ),
        // A tension and a stress both, as refused with the rings given.
        (
            without_rings
                .replace("[reflector]", "[surface]\nrms_mm = 20.0\n\n[reflector]")
                .replace("[front_net]", "[front_net]\nmembrane_stress_n_per_m = 30.0"),
            "front_net.membrane_stress_n_per_m",
        ),
    ] {
        let scene = dir.path().join("bad.toml");
        std::fs::write(&scene, text).unwrap();
        let run = common::ringmesh(&[
            "mesh",
            scene.to_str().unwrap(),
            "-o",
            dir.path().join("out").to_str().unwrap(),
        ]);
        let stderr = String::from_utf8(run.stderr).unwrap();
        assert_eq!(run.status.code(), Some(2), "{key}: {stderr}");
        assert!(stderr.contains(key), "{key}: {stderr}");
    }
}
