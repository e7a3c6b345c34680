//! `ringmesh size`: the lightest tube section that carries a scene's net
//! with a margin ([`crate::sizing::size_truss`]), and its files.

use std::path::{Path, PathBuf};

use super::default_output_dir;
use crate::design::DesignSettings;
use crate::report::{sizing_csv, write_atomic, OutputSet};
use crate::resources::{check_scene, SceneCommand};
use crate::scene::Scene;
use crate::sizing::{catalogue, size_truss, SectionTrial, Sections, Sizing};
use crate::Error;

/// What `ringmesh size` made.
#[derive(Debug)]
pub struct SizeOutcome {
    /// The sizing.
    pub sizing: Sizing,
    /// Files written.
    pub written: Vec<PathBuf>,
}

/// `ringmesh size`: reads the scene (and the catalogue `sections`, if
/// given; else the outer diameter is searched at the scene's `d/D`), sizes
/// its truss for `margin` and writes `sizing.csv` (every section tried) and
/// `<scene>-sized.toml` (the scene with the chosen section, named
/// `<scene>-sized`) into `output_dir` (default `results/<scene>/`).
/// `observe` sees each section tried.
///
/// # Errors
/// The scene's, the catalogue's and the sizing's errors, and the writers';
/// nothing is written unless a section was found.
pub fn size(
    scene_path: &Path,
    margin: f64,
    sections: Option<&Path>,
    settings: &DesignSettings,
    output_dir: Option<&Path>,
    observe: &mut dyn FnMut(&SectionTrial),
) -> Result<SizeOutcome, Error> {
    let scene = Scene::read(scene_path)?;
    let sections = match sections {
        Some(path) => Sections::Catalogue(catalogue::read(path, &scene.truss)?),
        None => Sections::Continuous {
            start_m: scene.truss.tube_outer_diameter_m,
        },
    };
    let dir = output_dir.map_or_else(|| default_output_dir(&scene), Path::to_path_buf);
    let sized_name = format!("{}-sized", scene.name);
    let toml_name = format!("{sized_name}.toml");
    check_scene(&scene, SceneCommand::Design, 1)?;
    let set = OutputSet::begin(&dir, &["sizing.csv", &toml_name])?;
    let mut sizing = size_truss(&scene, &sections, margin, settings, observe)?;
    sizing.scene.name = sized_name;
    let text = format!(
        "# {} with its truss sized by `ringmesh size` for a limit margin of {}.\n{}",
        scene.name,
        margin,
        sizing.scene.to_toml()?
    );
    write_atomic(
        &set.path("sizing.csv"),
        sizing_csv(&sizing.trials).as_bytes(),
    )?;
    write_atomic(&set.path(&toml_name), text.as_bytes())?;
    Ok(SizeOutcome {
        sizing,
        written: set.commit()?,
    })
}
