//! `ringmesh frame`: the statics of a frame file, every node's position,
//! displacement and rotation, the reactions and the solver's statistics.

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::algebra::norm3;
use crate::frame::{FrameFile, FrameFileError, NodeOrigin};
use crate::mechanics::{rotation, MechanicsError, StaticSolver, StaticTermination, StepRecord};
use crate::report::write_json;
use crate::Error;

/// One node of `ringmesh frame`'s output.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameNodeOutput {
    /// Node id in the model.
    pub id: usize,
    /// The rod it belongs to (name, or `rods[i]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rod: Option<String>,
    /// Its place along the rod, 0 (start) … elements (end).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rod_node: Option<usize>,
    /// The rigid body it is (name, or `bodies[i]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub body: Option<String>,
    /// Deformed position, m.
    pub position_m: [f64; 3],
    /// Position minus reference position, m.
    pub displacement_m: [f64; 3],
    /// Rotation vector of `R R₀ᵀ` (spatial, relative to the reference), rad,
    /// angle in [0, π] (a full turn reads as zero).
    pub rotation_rad: [f64; 3],
}

/// A support reaction in `ringmesh frame`'s output.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameReaction {
    /// Node id.
    pub node: usize,
    /// What the node is (`rod beam node 0`, `body h0`).
    pub member: String,
    /// Force the support exerts, N (zero on free components).
    pub force_n: [f64; 3],
    /// Moment the support exerts, N·m (zero on free components).
    pub moment_nm: [f64; 3],
}

/// The output of `ringmesh frame`.
#[derive(Debug, Clone, Serialize)]
pub struct FrameOutput {
    /// The frame file.
    pub file: String,
    /// How the solve ended.
    pub termination: StaticTermination,
    /// The last converged load factor (1 when converged).
    pub load_factor: f64,
    /// Converged load steps.
    pub load_steps: usize,
    /// Newton iterations in all, rejected steps included.
    pub newton_iterations: usize,
    /// Load steps that were cut.
    pub rejected_steps: usize,
    /// Wall time of the solve, s.
    pub time_s: f64,
    /// Largest nodal displacement, m.
    pub max_displacement_m: f64,
    /// The node of the largest displacement.
    pub max_displacement_node: usize,
    /// Counts: nodes, rods, elements, bodies, joints.
    pub counts: FrameCounts,
    /// Every node, by id.
    pub nodes: Vec<FrameNodeOutput>,
    /// Every supported node's reaction, in the order of `[[supports]]`.
    pub reactions: Vec<FrameReaction>,
    /// Converged steps: load factor, Newton iterations, `‖F‖∞` per iteration.
    pub steps: Vec<StepRecord>,
}

/// The size of a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct FrameCounts {
    /// Nodes of the model (rods' nodes and bodies).
    pub nodes: usize,
    /// Rods.
    pub rods: usize,
    /// Beam elements.
    pub elements: usize,
    /// Rigid bodies.
    pub bodies: usize,
    /// Joints.
    pub joints: usize,
}

/// Where `ringmesh frame FILE` writes by default: `results/<file stem>/frame.json`.
pub fn default_frame_output(frame_path: &Path) -> PathBuf {
    let stem = frame_path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "frame".into());
    Path::new("results").join(stem).join("frame.json")
}

impl FrameOutput {
    /// Why the run ended before its target — the full load — or `None` when
    /// it reached it. The CLI exits 3 then, after writing what it found.
    pub fn ended_early(&self) -> Option<String> {
        match self.termination {
            StaticTermination::Converged => None,
            ref t => Some(t.to_string()),
        }
    }
}

/// `ringmesh frame`: reads a frame file, solves its statics and writes every
/// node's position, displacement and rotation, the reactions and the solver's
/// statistics as JSON (`output_path`, default [`default_frame_output`]).
/// Not converging is a termination status in the output, not an error.
pub fn frame(
    frame_path: &Path,
    output_path: Option<&Path>,
) -> Result<(FrameOutput, PathBuf), Error> {
    let file = FrameFile::read(frame_path)?;
    let output_path =
        output_path.map_or_else(|| default_frame_output(frame_path), Path::to_path_buf);
    let counts = FrameCounts {
        nodes: file.model.node_count(),
        rods: file.model.rods().len(),
        elements: file.model.element_count(),
        bodies: file.bodies.len(),
        joints: file.model.joint_count(),
    };
    crate::resources::check_memory(
        &format!("the frame's {} elements", counts.elements),
        "the factorised stiffness",
        crate::resources::frame_memory(counts.elements as u64),
    )?;
    let solver = StaticSolver::new(file.model.clone()).map_err(FrameFileError::from)?;
    let solution = solver.solve(&file.settings).map_err(FrameFileError::from)?;
    let reference = file.model.reference();
    let nodes: Vec<FrameNodeOutput> = solution
        .state
        .frames
        .iter()
        .zip(reference)
        .zip(&file.nodes_origins)
        .enumerate()
        .map(|(id, ((now, then), origin))| {
            let (rod, rod_node, body) = match origin {
                NodeOrigin::Rod { rod, index } => (Some(rod.clone()), Some(*index), None),
                NodeOrigin::Body { body } => (None, None, Some(body.clone())),
            };
            let rotation = rotation::log(&(now.rotation * then.rotation.inverse()));
            FrameNodeOutput {
                id,
                rod,
                rod_node,
                body,
                position_m: now.position_m.into(),
                displacement_m: (now.position_m - then.position_m).into(),
                rotation_rad: rotation.into(),
            }
        })
        .collect();
    let (max_displacement_node, max_displacement_m) = nodes
        .iter()
        .map(|n| (n.id, norm3(n.displacement_m)))
        .fold((0, 0.0), |best, d| if d.1 > best.1 { d } else { best });
    let reactions = file
        .supported_nodes
        .iter()
        .map(|&n| {
            let r = solution.reactions.get(n).copied().unwrap_or([0.0; 6]);
            FrameReaction {
                node: n,
                member: file.nodes_origins[n].to_string(),
                force_n: [r[0], r[1], r[2]],
                moment_nm: [r[3], r[4], r[5]],
            }
        })
        .collect();
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
    let bad_node = nodes
        .iter()
        .find(|n| !finite(&n.position_m) || !finite(&n.rotation_rad));
    let bad_reaction = solution.reactions.iter().position(|r| !finite(r));
    if let Some(what) = bad_node
        .map(|n| format!("position of node {}", n.id))
        .or(bad_reaction.map(|n| format!("reaction at node {n}")))
    {
        return Err(FrameFileError::from(MechanicsError::NotFinite {
            detail: format!("the solved {what} is not finite"),
        })
        .into());
    }
    let output = FrameOutput {
        file: frame_path.display().to_string(),
        termination: solution.termination,
        load_factor: solution.load_factor,
        load_steps: solution.steps.len(),
        newton_iterations: solution.newton_iterations,
        rejected_steps: solution.rejected_steps,
        time_s: solution.time_s,
        max_displacement_m,
        max_displacement_node,
        counts,
        nodes,
        reactions,
        steps: solution.steps,
    };
    write_json(&output_path, &output)?;
    Ok((output, output_path))
}
