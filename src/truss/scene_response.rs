//! The `truss` command's work: a scene's truss model (built by the registry,
//! [`super::oracle`]) under the pull of its net
//! (forward FDM with the net's initial q) or under loads read from a file,
//! reported per attachment point.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::registry::oracle;
use super::response::TrussError;
use crate::effects::SceneEffects;
use crate::fdm::{solve_network, FdmError};
use crate::geometry::build_mesh;
use crate::scene::{Scene, SceneError, TrussModel};

/// Attachment loads in a file: `{"loads_n": [[fx, fy, fz], …]}`, top hinges
/// `0..N` then bottom hinges, N.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadsFile {
    /// One force per attachment point, N.
    pub loads_n: Vec<[f64; 3]>,
}

/// One attachment point's response.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AttachmentResponse {
    /// `top 3`, `bottom 0`, …
    pub hinge: String,
    /// The load applied, N.
    pub load_n: [f64; 3],
    /// Undeformed position, m.
    pub reference_m: [f64; 3],
    /// Deformed position, m.
    pub position_m: [f64; 3],
    /// Displacement, m.
    pub displacement_m: [f64; 3],
}

/// A scene's truss under one set of attachment loads.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SceneTrussResponse {
    /// `rigid`, `linear` or `exact`.
    pub model: String,
    /// Where the loads came from: `net` (forward FDM with the initial q) or the file.
    pub loads_from: String,
    /// Per attachment point.
    pub attachments: Vec<AttachmentResponse>,
    /// Largest displacement magnitude, m.
    pub max_displacement_m: f64,
    /// Newton iterations (exact model).
    pub newton_iterations: usize,
    /// Load steps (exact model).
    pub load_steps: usize,
    /// Wall time of the response, s.
    pub time_s: f64,
}

/// Why the `truss` command's response cannot be computed.
#[derive(Debug, thiserror::Error)]
pub enum SceneResponseError {
    /// The scene's nets cannot be built, or its loads file not read.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The net's force densities do not solve.
    #[error(transparent)]
    Net(#[from] FdmError),
    /// Bad loads, or a truss that cannot respond.
    #[error(transparent)]
    Truss(#[from] TrussError),
}

impl SceneResponseError {
    /// True when the input is at fault.
    pub fn is_bad_input(&self) -> bool {
        match self {
            SceneResponseError::Scene(_) => true,
            SceneResponseError::Net(e) => e.is_bad_input(),
            SceneResponseError::Truss(e) => e.is_bad_input(),
        }
    }
}

/// Read a loads file.
///
/// # Errors
/// I/O or a malformed file, with the path.
pub fn read_loads(path: &Path) -> Result<LoadsFile, SceneResponseError> {
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
        path: path.display().to_string(),
        source,
    })?;
    serde_json::from_str(&text).map_err(|e| {
        TrussError::LoadsFile {
            path: path.display().to_string(),
            reason: e.to_string(),
        }
        .into()
    })
}

/// The response of `scene`'s truss as `model` to `loads` (or to its net's pull).
///
/// # Errors
/// An invalid scene, a net that does not solve, bad loads, or a truss that
/// finds no equilibrium.
pub fn respond(
    scene: &Scene,
    model: TrussModel,
    loads: Option<(String, LoadsFile)>,
) -> Result<SceneTrussResponse, SceneResponseError> {
    let mesh = build_mesh(scene)?;
    let (loads_from, loads_n) = match loads {
        Some((from, file)) => (from, file.loads_n),
        None => {
            let (_, eq) = solve_network(&mesh.network)?;
            // The net pulls on its supports with −F_g (no loads on fixed nodes).
            let pull = eq.reactions_n.iter().map(|r| r.map(|v| -v)).collect();
            ("net".to_string(), pull)
        }
    };
    let mut truss = oracle(model, scene, &mesh.truss, &SceneEffects::of(scene))?;
    let response = truss.respond(&loads_n)?;
    let n = mesh.truss.bays();
    let attachments: Vec<AttachmentResponse> = truss
        .attachments()
        .iter()
        .zip(&response.positions_m)
        .zip(&loads_n)
        .enumerate()
        .map(|(i, ((r, p), l))| AttachmentResponse {
            hinge: if i < n {
                format!("top {i}")
            } else {
                format!("bottom {}", i - n)
            },
            load_n: *l,
            reference_m: *r,
            position_m: *p,
            displacement_m: std::array::from_fn(|c| p[c] - r[c]),
        })
        .collect();
    let max_displacement_m = attachments
        .iter()
        .map(|a| a.displacement_m.iter().map(|d| d * d).sum::<f64>().sqrt())
        .fold(0.0, f64::max);
    Ok(SceneTrussResponse {
        model: truss.name().to_string(),
        loads_from,
        attachments,
        max_displacement_m,
        newton_iterations: response.newton_iterations,
        load_steps: response.load_steps,
        time_s: response.time_s,
    })
}
