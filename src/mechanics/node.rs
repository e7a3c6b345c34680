//! What a node of a model is, below everything that joins nodes: its id
//! ([`NodeId`], an index into the model's nodes) and its configuration
//! ([`Frame`], a position and a rotation). Beams, cables, joints, the model and
//! the assembly all speak of nodes in these terms.

use nalgebra::{UnitQuaternion, Vector3};

/// Index of a node in a [`Model`](super::Model).
pub type NodeId = usize;

/// A node's configuration: position and rotation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Position, m.
    pub position_m: Vector3<f64>,
    /// Rotation from the material to the spatial frame.
    pub rotation: UnitQuaternion<f64>,
}
