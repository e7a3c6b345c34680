//! `ringmesh fdm`: forward equilibrium of an interchange-format network.

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::Summary;
use crate::fdm::solve_network;
use crate::network::Network;
use crate::report::{json_bytes, readable, OutputPath, OutputSet};
use crate::resources::{check_network, SceneCommand};
use crate::Error;

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

/// What `ringmesh fdm` made.
#[derive(Debug, Clone, PartialEq)]
pub struct FdmOutcome {
    /// The output (also in the file written).
    pub output: FdmOutput,
    /// The file written.
    pub written: PathBuf,
}

impl FdmOutcome {
    /// What `ringmesh fdm` prints: the largest residual, the file written.
    pub fn summary(&self) -> Summary {
        let mut s = Summary::default();
        say!(
            s,
            "max residual: {} N",
            readable(self.output.max_residual, 4)
        );
        s.written(std::slice::from_ref(&self.written));
        s
    }
}

/// `ringmesh fdm`: forward equilibrium of an interchange-format network,
/// written to `output_path` (a `.json` file, or a folder that receives
/// `fdm.json`: [`OutputPath`]), whose folder is checked before computing.
pub fn fdm(network_path: &Path, output_path: &Path) -> Result<FdmOutcome, Error> {
    let (dir, name) = OutputPath::resolve(output_path)?.folder_and_name("fdm.json");
    OutputSet::check_folder(&dir)?;
    let network = Network::read_json(network_path)?;
    check_network(
        network_path,
        network.n_nodes(),
        network.edges.len(),
        SceneCommand::Mesh,
    )?;
    let (_, equilibrium) = solve_network(&network)?;
    let output = FdmOutput {
        max_residual: equilibrium.max_residual_n(),
        nodes: equilibrium.nodes_xyz_m,
        lengths: equilibrium.edges_lengths_m,
        forces: equilibrium.edges_forces_n,
        reactions: equilibrium.reactions_n,
    };
    let bytes = json_bytes(&dir.join(&name), &output)?;
    let written = OutputSet::write_one(&dir, &name, &bytes)?;
    Ok(FdmOutcome { output, written })
}
