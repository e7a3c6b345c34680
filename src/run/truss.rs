//! `ringmesh truss`: a scene's truss model under the pull of its net or the
//! loads of a file.

use std::path::{Path, PathBuf};

use super::{default_output_dir, read_scene, Summary};
use crate::report::{decimal, json_bytes, readable, OutputPath, OutputSet};
use crate::scene::TrussModel;
use crate::truss::SceneTrussResponse;
use crate::Error;

/// What `ringmesh truss` made.
#[derive(Debug, Clone)]
pub struct TrussOutcome {
    /// The response (also in the file written).
    pub response: SceneTrussResponse,
    /// The file written.
    pub written: PathBuf,
}

impl TrussOutcome {
    /// What `ringmesh truss` prints: the model, the loads, the largest
    /// displacement and the solver's statistics, each attachment's
    /// displacement, the file written.
    pub fn summary(&self) -> Summary {
        let r = &self.response;
        let mut s = Summary::default();
        say!(
            s,
            "{} truss under loads from {}: max displacement {} m, {} Newton iterations, {} load \
             steps, {} s",
            r.model,
            r.loads_from,
            readable(r.max_displacement_m, 7),
            r.newton_iterations,
            r.load_steps,
            decimal(r.time_s, 3)
        );
        for a in &r.attachments {
            let d = a.displacement_m;
            say!(
                s,
                "  {:<10} u = [{}, {}, {}] m",
                a.hinge,
                readable(d[0], 5),
                readable(d[1], 5),
                readable(d[2], 5)
            );
        }
        s.written(std::slice::from_ref(&self.written));
        s
    }
}

/// `ringmesh truss`: the scene's truss model (default: the scene's
/// `[effects] truss`) under the pull of its net (forward FDM with the initial
/// q) or under the loads of a file; writes `truss-<model>.json` beside the
/// scene's other results, or to `output_path` (a `.json` file, or a folder
/// that receives `truss-<model>.json`: [`OutputPath`]), whose folder is
/// checked before computing.
pub fn truss(
    scene_path: &Path,
    model: Option<TrussModel>,
    loads_path: Option<&Path>,
    output_path: Option<&Path>,
) -> Result<TrussOutcome, Error> {
    let scene = read_scene(scene_path)?;
    let target = match output_path {
        Some(p) => OutputPath::resolve(p)?,
        None => OutputPath::Folder(default_output_dir(&scene)),
    };
    OutputSet::check_folder(&target.folder_and_name("").0)?;
    let model = model.unwrap_or(scene.effects.truss);
    crate::resources::check_scene(&scene, crate::resources::SceneCommand::Truss, 1)?;
    let loads = match loads_path {
        Some(p) => Some((p.display().to_string(), crate::truss::read_loads(p)?)),
        None => None,
    };
    let response = crate::truss::respond(&scene, model, loads)?;
    let (dir, name) = target.folder_and_name(&format!("truss-{}.json", response.model));
    let bytes = json_bytes(&dir.join(&name), &response)?;
    let written = OutputSet::write_one(&dir, &name, &bytes)?;
    Ok(TrussOutcome { response, written })
}
