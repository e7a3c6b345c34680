//! `ringmesh apertures`: the aperture study ([`crate::study::run_aperture_study`])
//! and its files.

use std::path::{Path, PathBuf};

use super::{read_scene, Summary};
use crate::report::{aperture_csv, aperture_plot, readable, write_atomic, write_json, OutputSet};
use crate::resources::{check_scene_for, SceneCommand};
use crate::study::{
    run_aperture_study, scaled_scenes, value_name, ApertureResult, ApertureSettings,
};
use crate::Error;

/// What `ringmesh apertures` made.
#[derive(Debug)]
pub struct AperturesOutcome {
    /// One result per aperture.
    pub results: Vec<ApertureResult>,
    /// Files written.
    pub written: Vec<PathBuf>,
}

impl AperturesOutcome {
    /// What `ringmesh apertures` prints: one line per aperture
    /// ([`aperture_line`]), the files written.
    pub fn summary(&self) -> Summary {
        let mut s = Summary::default();
        for r in &self.results {
            say!(s, "{}", aperture_line(r));
        }
        s.written(&self.written);
        s
    }
}

/// One aperture of the aperture study, on one line: its net, its sized
/// tube, and each design model's RMS and tension change as built.
pub fn aperture_line(r: &ApertureResult) -> String {
    let models: Vec<String> = r
        .models
        .iter()
        .map(|m| {
            format!(
                "{} {} mm / {} %",
                value_name(&m.model),
                readable(m.rms_mm, 3),
                readable(m.tension_change_pct, 3)
            )
        })
        .collect();
    format!(
        "{} m: {} rings, {:.1}/{:.1} mm tube ({:.0} kg, margin {:.3}), hinges move {:.1} mm; \
         RMS / tension change as built: {} ({:.0} s sizing)",
        r.aperture_m,
        r.rings,
        1e3 * r.section.outer_diameter_m,
        1e3 * r.section.inner_diameter_m,
        r.truss_mass_kg,
        r.margin,
        r.hinge_motion_mm,
        models.join(", "),
        r.sizing_time_s
    )
}

/// `ringmesh apertures`: reads the scene, runs the aperture study and
/// writes into `output_dir` (default `runs/<scene>/apertures/`)
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
    let scene = read_scene(scene_path)?;
    let dir = output_dir.map_or_else(
        || super::default_output_dir(&scene).join("apertures"),
        Path::to_path_buf,
    );
    let table = [
        "apertures.png",
        "apertures.svg",
        "apertures.csv",
        "apertures.json",
    ];
    // One aperture at a time: the sweep's peak is its largest aperture's
    // design, each checked before anything is computed.
    for scaled in scaled_scenes(&scene, &settings.apertures_m)? {
        let key = format!("--apertures {}", scaled.reflector.aperture_diameter_m);
        check_scene_for(&scaled, SceneCommand::Design, &key)?;
    }
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
