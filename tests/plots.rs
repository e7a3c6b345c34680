//! Every plot is drawn for every shipped scene (issue 20): `front`'s
//! front, `study`'s accuracy against time, and `design`'s convergence and
//! surface error; `front` and `study` drawn against the total RMS put each
//! point where the surface budget's root-sum-square does (issue 34).
//! Pixels are not asserted; each picture must be written, non-empty,
//! beside the table it draws. `design`'s plots of the other
//! scenes are drawn by `tests/scenes.rs` and `tests/super_large.rs`;
//! `apertures`' by `tests/apertures.rs`.

mod common;

use std::path::{Path, PathBuf};

use ringmesh::design::DesignSettings;
use ringmesh::geometry::build_mesh;
use ringmesh::report::{strategy_series, FrontRms, FrontRow, RmsAxis, StudyRms};
use ringmesh::run::{self, Silent, StudyOptions};
use ringmesh::scene::TrussModel;
use ringmesh::study::Knob;
use ringmesh::surface::design_surface_facets;
use ringmesh::uniformity::SolverKind;

/// Front rings of the super-large scenes here: their plots, not their size,
/// are under test (the full scenes run in `results/`).
const COARSE_RINGS: usize = 8;

/// Every shipped scene, the super-large ones coarsened to [`COARSE_RINGS`]
/// and the ones stated by a surface target given a coarse one (written into
/// `dir`).
fn scenes(dir: &Path) -> Vec<PathBuf> {
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(common::problem(""))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    scenes.sort();
    for path in &mut scenes {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if name.starts_with("target-") {
            // A net chosen for a coarse target: the choice is exercised, the
            // net stays small.
            let text = std::fs::read_to_string(&*path).unwrap();
            let target = text
                .lines()
                .find(|l| l.starts_with("rms_mm = "))
                .unwrap_or_else(|| panic!("{name}: no target"));
            let coarse = text.replacen(target, "rms_mm = 50.0", 1);
            *path = dir.join(name);
            std::fs::write(&*path, coarse).unwrap();
        } else if name.starts_with("super-") {
            let text = std::fs::read_to_string(&*path).unwrap();
            let rings = text
                .lines()
                .find(|l| l.starts_with("rings = "))
                .unwrap_or_else(|| panic!("{name}: no rings"));
            let coarse = text.replacen(rings, &format!("rings = {COARSE_RINGS}"), 1);
            *path = dir.join(name);
            std::fs::write(&*path, coarse).unwrap();
        }
    }
    assert!(scenes.len() >= 6, "{scenes:?}");
    scenes
}

/// The pictures `stem`.png and `stem`.svg exist in `dir` and are not empty.
fn assert_drawn(dir: &Path, stem: &str, scene: &Path) {
    for ext in ["png", "svg"] {
        let path = dir.join(format!("{stem}.{ext}"));
        let bytes = std::fs::metadata(&path)
            .unwrap_or_else(|e| panic!("{}: {}: {e}", scene.display(), path.display()))
            .len();
        assert!(bytes > 1000, "{}: {} bytes", path.display(), bytes);
    }
}

#[test]
fn every_plot_is_drawn_for_every_shipped_scene() {
    let dir = tempfile::tempdir().unwrap();
    for scene in scenes(dir.path()) {
        let out = tempfile::tempdir_in(dir.path()).unwrap();
        let name = scene.display();

        // The front: a solver without a knob (one point) and one with.
        let front = run::front(
            &scene,
            &[SolverKind::Lp, SolverKind::LeastSquares],
            3,
            RmsAxis::Design,
            Some(out.path()),
            None,
            &Silent,
        )
        .unwrap_or_else(|e| panic!("{name}: front: {e}"));
        assert_eq!(front.points.len(), 4, "{name}");
        assert_drawn(out.path(), "front", &scene);

        // The study: the rigid-truss design judged against the reference.
        let options = StudyOptions {
            knobs: vec![Knob::Truss],
            truss_models: Some(vec![TrussModel::Rigid]),
            ..StudyOptions::default()
        };
        let study = run::study(&scene, &options, Some(out.path()), None, &Silent)
            .unwrap_or_else(|e| panic!("{name}: study: {e}"));
        assert!(
            study.rows.iter().all(|(_, r)| r.error.is_none()),
            "{name}: {:?}",
            study.rows
        );
        assert_drawn(out.path(), run::STUDY_STEM, &scene);
        assert_drawn(out.path(), run::STRATEGIES_STEM, &scene);

        // The design's plots, for the scenes no other test designs.
        if scene.starts_with(dir.path()) {
            run::design(
                &scene,
                &DesignSettings::default(),
                Some(out.path()),
                &mut |_, _| {},
            )
            .unwrap_or_else(|e| panic!("{name}: design: {e}"));
            assert_drawn(out.path(), "convergence", &scene);
            let png = out.path().join("surface-error.png");
            assert!(std::fs::metadata(&png).unwrap().len() > 1000, "{name}");
        }
    }
}

/// The study's strategies figure: one series per solver the study ran —
/// every solver here —, each in the legend of the figure written, which
/// says how a zero RMS is drawn.
#[test]
fn the_strategies_figure_draws_one_series_per_solver_run() {
    let out = tempfile::tempdir().unwrap();
    let scene = common::problem("small-hex.toml");
    let options = StudyOptions {
        knobs: vec![Knob::Solver],
        solvers: Some(SolverKind::ALL.to_vec()),
        ..StudyOptions::default()
    };
    let study = run::study(&scene, &options, Some(out.path()), None, &Silent).unwrap();
    assert_drawn(out.path(), run::STRATEGIES_STEM, &scene);
    let rows: Vec<_> = study.rows.iter().map(|(_, r)| r.clone()).collect();
    let run: Vec<SolverKind> = rows
        .iter()
        .filter(|r| r.knob == Knob::Solver)
        .map(|r| r.settings.solver)
        .collect();
    assert_eq!(run, SolverKind::ALL);
    let series = strategy_series(&rows);
    assert_eq!(series.len(), run.len());
    for (s, solver) in series.iter().zip(&run) {
        assert_eq!(s.solver, *solver);
        assert_eq!(s.rows.len(), 1, "{solver:?}");
    }
    let svg = std::fs::read_to_string(out.path().join("strategies.svg")).unwrap();
    for solver in &run {
        assert!(
            svg.contains(&format!(">\n{}\n</text>", solver.name())),
            "{solver:?} has no legend entry"
        );
    }
    assert!(svg.contains("an exact 0 among them"), "no zero convention");
    // A study without the solver knob draws no series and says why.
    assert!(strategy_series(&rows[..1]).is_empty());
}

/// The facet RMS of the design surface of small-hex's net with `rings`
/// rings, mm, from the scene file and [`ringmesh::surface`] alone.
fn small_hex_facets_mm(rings: usize) -> f64 {
    let mut scene = common::scene("small-hex");
    scene.front_net.rings = rings;
    design_surface_facets(&build_mesh(&scene).unwrap())
        .unwrap()
        .raw_mm
}

/// `√(f² + d²)` is the total to a few roundings, and at least each term.
fn assert_total(total: f64, facets: f64, design: f64) {
    let expected = (facets * facets + design * design).sqrt();
    assert!(
        (total - expected).abs() <= 4.0 * f64::EPSILON * expected,
        "total {total}, √(facets² + design²) {expected}"
    );
    assert!(
        total >= design && total >= facets,
        "{total} {facets} {design}"
    );
}

#[test]
fn front_and_study_drawn_against_total_rms_add_the_net_s_facet_rms() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::problem("small-hex.toml");
    let rings = common::scene("small-hex").front_net.rings;
    let facets = small_hex_facets_mm(rings);
    assert!(facets > 1.0, "small-hex's facets: {facets} mm");

    let solvers = [SolverKind::Lp, SolverKind::LeastSquares];
    let design = run::front(
        &scene,
        &solvers,
        3,
        RmsAxis::Design,
        Some(dir.path()),
        None,
        &Silent,
    )
    .unwrap();
    assert_eq!(design.rms, FrontRms::Design);
    let total = run::front(
        &scene,
        &solvers,
        3,
        RmsAxis::Total,
        Some(dir.path()),
        None,
        &Silent,
    )
    .unwrap();
    assert_eq!(total.rms, FrontRms::Total { facets_mm: facets });
    assert!(total
        .summary()
        .lines
        .iter()
        .any(|l| l.contains("total RMS")));
    assert!(!design
        .summary()
        .lines
        .iter()
        .any(|l| l.contains("total RMS")));
    let rows: Vec<FrontRow> = total.points.iter().filter_map(FrontRow::of).collect();
    assert_eq!(rows.len(), 4);
    for row in &rows {
        assert_eq!(design.rms.of(row), row.rms_mm);
        assert_total(total.rms.of(row), facets, row.rms_mm);
    }
    // Least squares trades accuracy for uniformity: its loosest point's
    // total is above the facets by its own error, not lost under them.
    let loosest = rows.iter().map(|r| total.rms.of(r)).fold(0.0, f64::max);
    assert!(
        loosest > facets * (1.0 + 1e-3),
        "{loosest} against {facets}"
    );

    // The study: each point with the facets of its own net.
    let options = StudyOptions {
        knobs: vec![Knob::Rings],
        truss_models: Some(vec![TrussModel::Rigid]),
        rms: RmsAxis::Total,
        ..StudyOptions::default()
    };
    let study = run::study(&scene, &options, Some(dir.path()), None, &Silent).unwrap();
    let StudyRms::Total { facets_mm } = &study.rms else {
        panic!("{:?}", study.rms);
    };
    let mut nets: Vec<usize> = study.rows.iter().map(|(_, r)| r.settings.rings).collect();
    nets.sort_unstable();
    nets.dedup();
    assert!(nets.len() >= 3, "{nets:?}");
    assert_eq!(facets_mm.iter().map(|f| f.0).collect::<Vec<_>>(), nets);
    for &(r, f) in facets_mm {
        assert_eq!(f, small_hex_facets_mm(r), "{r} rings");
    }
    // A finer net has smaller facets.
    assert!(
        facets_mm.windows(2).all(|w| w[1].1 < w[0].1),
        "{facets_mm:?}"
    );
    for (_, row) in &study.rows {
        assert!(row.error.is_none(), "{row:?}");
        let f = small_hex_facets_mm(row.settings.rings);
        assert_total(study.rms.of(row), f, row.rms_mm);
    }
    assert_drawn(dir.path(), run::STUDY_STEM, &scene);
}
