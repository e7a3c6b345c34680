//! `ringmesh truss`: a scene's truss model under the pull of its net or the
//! loads of a file.

use std::path::{Path, PathBuf};

use super::default_output_dir;
use crate::report::write_json;
use crate::scene::{Scene, TrussModel};
use crate::truss::SceneTrussResponse;
use crate::Error;

/// `ringmesh truss`: the scene's truss model (default: the scene's
/// `[effects] truss`) under the pull of its net (forward FDM with the initial
/// q) or under the loads of a file; writes `truss-<model>.json` beside the
/// scene's other results.
pub fn truss(
    scene_path: &Path,
    model: Option<TrussModel>,
    loads_path: Option<&Path>,
    output_path: Option<&Path>,
) -> Result<(SceneTrussResponse, PathBuf), Error> {
    let scene = Scene::read(scene_path)?;
    let model = model.unwrap_or(scene.effects.truss);
    let loads = match loads_path {
        Some(p) => Some((p.display().to_string(), crate::truss::read_loads(p)?)),
        None => None,
    };
    let response = crate::truss::respond(&scene, model, loads)?;
    let path = output_path.map_or_else(
        || default_output_dir(&scene).join(format!("truss-{}.json", response.model)),
        Path::to_path_buf,
    );
    write_json(&path, &response)?;
    Ok((response, path))
}
