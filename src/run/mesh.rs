//! `ringmesh mesh`: a scene's nets in the interchange format and as VTK.

use std::path::{Path, PathBuf};

use super::{default_output_dir, read_scene, target_line, Summary};
use crate::geometry::build_mesh;
use crate::network::NetworkSummary;
use crate::report::{network_vtu, readable, write_atomic, write_json, OutputSet};
use crate::resources::{check_scene, SceneCommand};
use crate::surface::{design_surface_facets, RawAndBestFit};
use crate::Error;

/// What `ringmesh mesh` made.
#[derive(Debug, Clone)]
pub struct MeshOutcome {
    /// The scene's name.
    pub scene: String,
    /// Counts and extreme lengths.
    pub summary: NetworkSummary,
    /// Facet RMS of the front net's design surface (axial), raw and best fit.
    pub facets: RawAndBestFit,
    /// What the scene's surface target says of the net, if it has one.
    pub target: Option<String>,
    /// Files written.
    pub written: Vec<PathBuf>,
}

impl MeshOutcome {
    /// What `ringmesh mesh` prints: the scene, the net's counts and extreme
    /// lengths, the files written.
    pub fn summary(&self) -> Summary {
        let mut s = Summary::default();
        say!(s, "scene: {}", self.scene);
        say!(s, "{}", self.summary.to_string().trim_end());
        say!(
            s,
            "facet RMS (design surface, axial): {} mm, {} mm about the best-fit paraboloid",
            readable(self.facets.raw_mm, 4),
            readable(self.facets.best_fit_mm, 4)
        );
        if let Some(t) = &self.target {
            say!(s, "{t}");
        }
        s.written(&self.written);
        s
    }
}

/// `ringmesh mesh`: builds the nets of a scene and writes `network.json` (the
/// interchange format, design positions, initial q) and `mesh.vtu`.
pub fn mesh(scene_path: &Path, output_dir: Option<&Path>) -> Result<MeshOutcome, Error> {
    let scene = read_scene(scene_path)?;
    let dir = output_dir.map_or_else(|| default_output_dir(&scene), Path::to_path_buf);
    check_scene(&scene, SceneCommand::Mesh, 1)?;
    let set = OutputSet::begin(&dir, &["network.json", "mesh.vtu"])?;
    let mesh = build_mesh(&scene)?;
    let summary = mesh.network.summary();
    let facets = design_surface_facets(&mesh)?;
    let target = target_line(&scene, facets.raw_mm);
    let vtu = network_vtu(&mesh.network, None, None);
    write_json(&set.path("network.json"), &mesh.network)?;
    write_atomic(&set.path("mesh.vtu"), vtu.as_bytes())?;
    set.seal()?;
    Ok(MeshOutcome {
        scene: scene.name,
        summary,
        facets,
        target,
        written: set.commit()?,
    })
}
