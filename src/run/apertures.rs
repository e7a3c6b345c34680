//! `ringmesh apertures`: the aperture study ([`crate::study::run_aperture_study`])
//! and its files.

use std::path::{Path, PathBuf};

use crate::report::{aperture_csv, aperture_plot, write_atomic, write_json, OutputSet};
use crate::scene::Scene;
use crate::study::{run_aperture_study, ApertureResult, ApertureSettings};
use crate::Error;

/// What `ringmesh apertures` made.
#[derive(Debug)]
pub struct AperturesOutcome {
    /// One result per aperture.
    pub results: Vec<ApertureResult>,
    /// Files written.
    pub written: Vec<PathBuf>,
}

/// `ringmesh apertures`: reads the scene, runs the aperture study and
/// writes into `output_dir` (default `results/<scene>/apertures/`)
/// `apertures.csv` (one row per aperture and design model),
/// `apertures.json`, `apertures.png/.svg` and each aperture's sized scene,
/// `<scene>-at-<D>m.toml`, which `ringmesh design` runs again. `observe`
/// sees each aperture as it finishes.
///
/// # Errors
/// The scene's and the study's errors, and the writers'; nothing is written
/// unless every aperture was designed.
pub fn apertures(
    scene_path: &Path,
    settings: &ApertureSettings,
    output_dir: Option<&Path>,
    observe: &mut dyn FnMut(&ApertureResult),
) -> Result<AperturesOutcome, Error> {
    let scene = Scene::read(scene_path)?;
    let dir = output_dir.map_or_else(
        || Path::new("results").join(&scene.name).join("apertures"),
        Path::to_path_buf,
    );
    let table = [
        "apertures.png",
        "apertures.svg",
        "apertures.csv",
        "apertures.json",
    ];
    let mut set = OutputSet::begin(&dir, &table)?;
    let results = run_aperture_study(&scene, settings, observe)?;
    for r in &results {
        let path = set.add(&format!("{}.toml", r.scene.name))?;
        let text = format!(
            "# {} scaled to a {} m aperture and its truss sized for a limit margin of {} by \
             `ringmesh apertures`.\n{}",
            scene.name,
            r.aperture_m,
            settings.margin,
            r.scene.to_toml()?
        );
        write_atomic(&path, text.as_bytes())?;
    }
    let title = format!(
        "{} (F/D {:.3}): designs as built on the exact truss, tubes sized for a margin of {}",
        scene.name,
        scene.reflector.focal_length_m / scene.reflector.aperture_diameter_m,
        settings.margin
    );
    let [png, svg, csv, json] = table.map(|name| set.path(name));
    aperture_plot(&results, &title, &png, &svg)?;
    write_atomic(&csv, aperture_csv(&results).as_bytes())?;
    write_json(&json, &results)?;
    set.seal()?;
    let written = set.commit()?;
    Ok(AperturesOutcome { results, written })
}
