//! What a frame file is once read and built: the engine's [`Model`] and
//! solver settings, and the labels that map the model's nodes, rods and
//! bodies back to the file ([`NodeOrigin`]).

use std::fmt;

use crate::mechanics::{Model, NodeId, PathSpec, Rod, StaticSettings};

/// What a node of the model is: a rod's node or a rigid body.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum NodeOrigin {
    /// Node `index` (0 = start) of the rod labelled `rod`.
    Rod {
        /// The rod's name, or `rods[i]`.
        rod: String,
        /// Position along the rod, 0 … elements.
        index: usize,
    },
    /// The rigid body labelled `body`.
    Body {
        /// The body's name, or `bodies[i]`.
        body: String,
    },
}

impl fmt::Display for NodeOrigin {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            NodeOrigin::Rod { rod, index } => write!(f, "{rod} node {index}"),
            NodeOrigin::Body { body } => write!(f, "body {body}"),
        }
    }
}

/// A frame file, read and built.
#[derive(Debug, Clone)]
pub struct FrameFile {
    /// The model.
    pub model: Model,
    /// The solver settings of `[solver]`.
    pub settings: StaticSettings,
    /// What each node of the model is: `model.node_count()` entries.
    pub nodes_origins: Vec<NodeOrigin>,
    /// Rod labels (name, or `rods[i]`), in file order, as `model.rods()`.
    pub rods_labels: Vec<String>,
    /// Body labels (name, or `bodies[i]`) and their nodes, in file order.
    pub bodies: Vec<(String, NodeId)>,
    /// Nodes with a support, in the order of `[[supports]]` (each once).
    pub supported_nodes: Vec<NodeId>,
    /// The path to follow (`[path]`, `[output]`): its target, controlled
    /// translation and recorded nodes.
    pub path: PathSpec,
    /// The recorded nodes' labels (as written in `[output] nodes`), in the
    /// order of `path.record`.
    pub recorded_labels: Vec<String>,
}

impl FrameFile {
    /// The rod labelled `label` (its name, or `rods[i]`).
    pub fn rod(&self, label: &str) -> Option<&Rod> {
        let i = self.rods_labels.iter().position(|l| l == label)?;
        self.model.rods().get(i)
    }

    /// The node of the body labelled `label` (its name, or `bodies[i]`).
    pub fn body(&self, label: &str) -> Option<NodeId> {
        self.bodies
            .iter()
            .find(|(l, _)| l == label)
            .map(|&(_, n)| n)
    }
}
