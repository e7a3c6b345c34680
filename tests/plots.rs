//! Every plot is drawn for every shipped scene (issue 20): `front`'s
//! front, `study`'s accuracy against time, and `design`'s convergence and
//! surface error. Pixels are not asserted; each picture must be written,
//! non-empty, beside the table it draws. `design`'s plots of the other
//! scenes are drawn by `tests/scenes.rs` and `tests/super_large.rs`;
//! `apertures`' by `tests/apertures.rs`.

mod common;

use std::path::{Path, PathBuf};

use ringmesh::design::DesignSettings;
use ringmesh::run::{self, Silent, StudyOptions};
use ringmesh::scene::TrussModel;
use ringmesh::study::Knob;
use ringmesh::uniformity::SolverKind;

/// Front rings of the super-large scenes here: their plots, not their size,
/// are under test (the full scenes run in `results/`).
const COARSE_RINGS: usize = 8;

/// Every shipped scene, the super-large ones coarsened to [`COARSE_RINGS`]
/// (written into `dir`).
fn scenes(dir: &Path) -> Vec<PathBuf> {
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(common::problem(""))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    scenes.sort();
    for path in &mut scenes {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if name.starts_with("super-") {
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
