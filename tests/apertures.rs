//! The aperture study (issue 16): each aperture's scene is the scene scaled
//! by the study's rules, its columns are `design`'s own figures on that
//! scene, and its truss carries the net with the margin asked.

mod common;

use ringmesh::design::DesignSettings;
use ringmesh::scene::{membrane_tension_n, TrussModel};
use ringmesh::study::{scaled, ApertureSettings, ModelResult};
use ringmesh::Scene;

/// Relative agreement of two runs of the same design (the same code on the
/// same scene: only the threads' summation order may differ).
fn same(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-6 * a.abs().max(b.abs()) + 1e-12
}

#[test]
fn a_scaled_scene_keeps_fd_facet_size_and_membrane_stress() {
    let scene = common::scene("paper-26m");
    let big = scaled(&scene, 65.0).unwrap();
    let s = 2.5;
    let r = &big.reflector;
    assert_eq!(r.aperture_diameter_m, 65.0);
    assert!(same(r.focal_length_m / 65.0, 4.0 / 26.0));
    assert!(same(big.truss.height_m, s * scene.truss.height_m));
    assert!(same(
        big.rear_net.focal_length_m,
        s * scene.rear_net.focal_length_m
    ));
    assert_eq!(big.truss.bays, scene.truss.bays);
    assert_eq!(big.front_net.rings, 10);
    // The same stress; on facets of about the same size, about the same
    // tension (the grid's boundary counts for less in the larger net).
    let stress = |sc: &Scene| sc.front_net.mean_tension_n / membrane_tension_n(sc, 1.0);
    assert!(same(stress(&big), stress(&scene)));
    let change = big.front_net.mean_tension_n / scene.front_net.mean_tension_n;
    assert!((0.8..1.25).contains(&change), "{change}");
    let rear = |sc: &Scene| sc.rear_net.mean_tension_n / sc.front_net.mean_tension_n;
    assert!(same(rear(&big), rear(&scene)));
    // At its own aperture the scene is itself.
    let same_size = scaled(&scene, 26.0).unwrap();
    assert_eq!(same_size.front_net.rings, scene.front_net.rings);
    assert!(same(same_size.front_net.mean_tension_n, 70.0));
    assert!(scaled(&scene, f64::NAN).is_err());
    assert!(scaled(&scene, 0.0).is_err());
}

#[test]
fn the_studys_columns_are_designs_own_figures_on_each_aperture() {
    let dir = tempfile::tempdir().unwrap();
    let margin = 2.0;
    let settings = ApertureSettings {
        apertures_m: vec![6.0, 9.0],
        margin,
        design: DesignSettings::default(),
    };
    let outcome = ringmesh::run::apertures(
        &common::problem("small-hex.toml"),
        &settings,
        Some(dir.path()),
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(outcome.results.len(), 2);
    for file in [
        "apertures.csv",
        "apertures.json",
        "apertures.png",
        "apertures.svg",
    ] {
        assert!(dir.path().join(file).exists(), "{file}");
    }
    let csv = std::fs::read_to_string(dir.path().join("apertures.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 2 * 3);

    for r in &outcome.results {
        // The sized scene, as written, designed again by `design`.
        let path = dir
            .path()
            .join(format!("small-hex-at-{}m.toml", r.aperture_m));
        let scene = Scene::read(&path).unwrap();
        assert_eq!(
            scene.truss.tube_outer_diameter_m,
            r.section.outer_diameter_m
        );
        let exact = ringmesh::run::design(
            &path,
            &DesignSettings::default(),
            Some(&dir.path().join("design")),
            &mut |_, _| {},
        )
        .unwrap()
        .report;
        let linear = ringmesh::design::run(
            &scene,
            &DesignSettings {
                truss: Some(TrussModel::Linear),
                ..DesignSettings::default()
            },
            &mut |_, _| {},
        )
        .unwrap()
        .report;
        let column = |model: TrussModel| -> &ModelResult {
            r.models.iter().find(|m| m.model == model).unwrap()
        };
        let conventional = exact.conventional.as_ref().unwrap();
        for (model, built) in [
            (TrussModel::Rigid, conventional),
            (TrussModel::Linear, &linear.verification),
            (TrussModel::Exact, &exact.verification),
        ] {
            let c = column(model);
            let name = format!("{} m, {model:?}", r.aperture_m);
            assert!(
                same(c.rms_mm, built.rms_mm),
                "{name}: {} vs {}",
                c.rms_mm,
                built.rms_mm
            );
            assert!(
                same(c.tension_change_pct, built.max_tension_change_pct),
                "{name}: {} vs {}",
                c.tension_change_pct,
                built.max_tension_change_pct
            );
            assert!(
                same(c.boundary_deviation_mm, built.boundary_deviation_mm),
                "{name}"
            );
        }
        assert_eq!(
            column(TrussModel::Exact).outer_iterations,
            exact.outer_iterations
        );
        assert_eq!(column(TrussModel::Exact).cut_length_error_mm, 0.0);
        // The sized truss carries its net with the margin.
        let m = exact.limit_margin.as_ref().unwrap().stable_to;
        assert!(m >= margin && same(m, r.margin), "{m} vs {}", r.margin);
        // The conventional design ignores the give the others design for.
        assert!(column(TrussModel::Rigid).rms_mm > 10.0 * column(TrussModel::Exact).rms_mm);
    }
}
