//! One function per CLI subcommand: read the inputs, call the pipeline, write the
//! outputs (atomically, and only once everything is computed), and return what
//! the command prints. `main.rs` only parses arguments and calls these.

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::fdm::solve_network;
use crate::geometry::build_mesh;
use crate::network::{Network, NetworkSummary};
use crate::report::{network_vtu, write_atomic, write_json};
use crate::scene::Scene;
use crate::Error;

/// Where a scene's results go by default: `results/<scene name>/`.
pub fn default_output_dir(scene: &Scene) -> PathBuf {
    Path::new("results").join(&scene.name)
}

/// What `ringmesh mesh` made.
#[derive(Debug, Clone)]
pub struct MeshOutcome {
    /// The scene's name.
    pub scene: String,
    /// Counts and extreme lengths.
    pub summary: NetworkSummary,
    /// Files written.
    pub written: Vec<PathBuf>,
}

/// `ringmesh mesh`: builds the nets of a scene and writes `network.json` (the
/// interchange format, design positions, initial q) and `mesh.vtu`.
pub fn mesh(scene_path: &Path, output_dir: Option<&Path>) -> Result<MeshOutcome, Error> {
    let scene = Scene::read(scene_path)?;
    let mesh = build_mesh(&scene)?;
    let dir = output_dir.map_or_else(|| default_output_dir(&scene), Path::to_path_buf);
    let summary = mesh.network.summary();
    let vtu = network_vtu(&mesh.network, None, None);
    let network_path = dir.join("network.json");
    let vtu_path = dir.join("mesh.vtu");
    write_json(&network_path, &mesh.network)?;
    write_atomic(&vtu_path, vtu.as_bytes())?;
    Ok(MeshOutcome {
        scene: scene.name,
        summary,
        written: vec![network_path, vtu_path],
    })
}

/// The output of `ringmesh fdm`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FdmOutput {
    /// Equilibrium positions, m: n_nodes × 3.
    pub nodes: Vec<[f64; 3]>,
    /// Cable lengths, m: n_edges.
    pub lengths: Vec<f64>,
    /// Cable tensions, N: n_edges.
    pub forces: Vec<f64>,
    /// Support reactions `C_gᵀ Q C x − p_g`, N, in the order of `fixed`.
    pub reactions: Vec<[f64; 3]>,
    /// Largest out-of-balance force at a free node, N.
    pub max_residual: f64,
}

/// `ringmesh fdm`: forward equilibrium of an interchange-format network.
pub fn fdm(network_path: &Path, output_path: &Path) -> Result<FdmOutput, Error> {
    let network = Network::read_json(network_path)?;
    let (_, equilibrium) = solve_network(&network)?;
    let output = FdmOutput {
        max_residual: equilibrium.max_residual_n(),
        nodes: equilibrium.nodes_xyz_m,
        lengths: equilibrium.edges_lengths_m,
        forces: equilibrium.edges_forces_n,
        reactions: equilibrium.reactions_n,
    };
    write_json(output_path, &output)?;
    Ok(output)
}
