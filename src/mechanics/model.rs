//! A frame model: nodes (6-DOF frames or 3-DOF points), rods meshed into beam
//! elements, rigid bodies, joints, supports and dead loads, built once and
//! validated, then solved by [`super::statics`].
//!
//! A rigid body (paper §3.3) is a 6-DOF node with no element of its own: its
//! marker points (eq. 22) are the offsets at which joints and loads act.

use nalgebra::{UnitQuaternion, Vector3};

use super::beam::{BeamElement, ElementKind, Section};
use super::cable::Cable;
use super::circular_arc::{CircularArc, MAX_ELEMENT_ANGLE_RAD};
use super::joint::{Joint, JointKind};
use super::node::{Frame, NodeId};
use super::rotation::rod_frame;

/// A model that cannot be built; every variant names the item at fault.
#[derive(Debug, Clone, thiserror::Error)]
pub enum MechanicsError {
    /// An item of the model is invalid.
    #[error("{item}: {reason}")]
    Invalid {
        /// The item: `rod 3`, `joint 7`, `node 12`, `support 0`, `load 2`.
        item: String,
        /// What is wrong.
        reason: String,
    },
    /// The tangent of the reference configuration is singular: the frame is a
    /// mechanism (a rigid-body mode or a free joint rotation is not restrained).
    #[error("the frame is a mechanism: its stiffness matrix is singular ({detail})")]
    Mechanism {
        /// Where it was detected.
        detail: String,
    },
    /// Numbers beyond double precision: a modulus, a section or a load so
    /// large that the stiffness or the forces overflow.
    #[error(
        "the frame's numbers overflow double precision ({detail}): check the moduli, \
         sections and loads"
    )]
    NotFinite {
        /// Where it was detected.
        detail: String,
    },
    /// Loads below the force resolution of the model's stiffness.
    #[error(
        "the frame's stiffest members resolve forces only to about {floor:.1e} N, more than \
         half its loads ({loads:.1e} N): its stiffnesses span beyond double precision — \
         lower the stiffest section or raise the loads"
    )]
    Unresolvable {
        /// The force floor, N.
        floor: f64,
        /// The largest load component, N or N·m.
        loads: f64,
    },
    /// The stiffness could not be factored in the memory there is.
    #[error("out of memory factoring the frame's stiffness ({detail})")]
    OutOfMemory {
        /// Where it was detected.
        detail: String,
    },
}

impl MechanicsError {
    pub(crate) fn invalid(item: impl Into<String>, reason: impl Into<String>) -> Self {
        MechanicsError::Invalid {
            item: item.into(),
            reason: reason.into(),
        }
    }
}

/// A dead nodal load at the reference load factor 1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodalLoad {
    /// The node.
    pub node: NodeId,
    /// Force, N (spatial, fixed in direction).
    pub force_n: Vector3<f64>,
    /// Moment, N·m (spatial, fixed in direction).
    pub moment_nm: Vector3<f64>,
}

/// How a rod is meshed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RodSpec {
    /// Section stiffnesses.
    pub section: Section,
    /// Number of elements (≥ 1).
    pub elements: usize,
    /// Element type.
    pub kind: ElementKind,
}

/// The nodes of a meshed rod, start to end.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Rod {
    /// Node ids along the rod (elements + 1).
    pub nodes: Vec<NodeId>,
}

impl Rod {
    /// The start node.
    pub fn start(&self) -> NodeId {
        self.nodes[0]
    }
    /// The end node.
    pub fn end(&self) -> NodeId {
        *self.nodes.last().expect("a rod has at least two nodes")
    }
}

/// A built and validated frame model.
#[derive(Debug, Clone)]
pub struct Model {
    pub(crate) reference: Vec<Frame>,
    /// Degrees of freedom per node: 6 (frame) or 3 (point).
    pub(crate) node_dofs: Vec<usize>,
    pub(crate) elements: Vec<BeamElement>,
    pub(crate) cables: Vec<Cable>,
    pub(crate) joints: Vec<Joint>,
    /// Fixed components per node: translations x, y, z, rotations about x, y, z.
    pub(crate) fixed: Vec<[bool; 6]>,
    pub(crate) loads: Vec<NodalLoad>,
    /// The element each rod starts with, and the rods' node lists.
    pub(crate) rods: Vec<Rod>,
}

impl Model {
    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.reference.len()
    }
    /// Number of beam elements.
    pub fn element_count(&self) -> usize {
        self.elements.len()
    }
    /// Number of joints.
    pub fn joint_count(&self) -> usize {
        self.joints.len()
    }
    /// The cables, in the order they were added.
    pub fn cables(&self) -> &[Cable] {
        &self.cables
    }
    /// The rods, in the order they were added.
    pub fn rods(&self) -> &[Rod] {
        &self.rods
    }
    /// The reference configuration of every node.
    pub fn reference(&self) -> &[Frame] {
        &self.reference
    }
    /// The dead loads at load factor 1.
    pub fn loads(&self) -> &[NodalLoad] {
        &self.loads
    }
    /// Replace the dead loads (the structure and its factorisation pattern stay).
    ///
    /// # Errors
    /// A load on a node that does not exist, a moment on a 3-DOF point, or a
    /// non-finite component.
    pub fn set_loads(&mut self, loads: Vec<NodalLoad>) -> Result<(), MechanicsError> {
        for (i, l) in loads.iter().enumerate() {
            check_load(i, l, &self.node_dofs)?;
        }
        self.loads = loads;
        Ok(())
    }
}

fn check_load(i: usize, l: &NodalLoad, node_dofs: &[usize]) -> Result<(), MechanicsError> {
    let item = format!("load {i}");
    let Some(&dofs) = node_dofs.get(l.node) else {
        return Err(MechanicsError::invalid(
            item,
            format!("node {} does not exist", l.node),
        ));
    };
    if !(l
        .force_n
        .iter()
        .chain(l.moment_nm.iter())
        .all(|v| v.is_finite()))
    {
        return Err(MechanicsError::invalid(item, "a component is not finite"));
    }
    if dofs == 3 && l.moment_nm != Vector3::zeros() {
        return Err(MechanicsError::invalid(
            item,
            format!(
                "node {} is a point (no rotation): it takes no moment",
                l.node
            ),
        ));
    }
    Ok(())
}

/// The two ends of a joint or cable: existing, distinct nodes.
fn check_ends(item: &str, [a, b]: [NodeId; 2], n_nodes: usize) -> Result<(), MechanicsError> {
    if let Some(n) = [a, b].into_iter().find(|&n| n >= n_nodes) {
        return Err(MechanicsError::invalid(
            item,
            format!("node {n} does not exist"),
        ));
    }
    if a == b {
        return Err(MechanicsError::invalid(
            item,
            format!("joins node {a} to itself"),
        ));
    }
    Ok(())
}

fn check_cable(k: usize, c: &Cable, reference: &[Frame]) -> Result<(), MechanicsError> {
    let item = format!("cable {k}");
    let [a, b] = c.nodes;
    check_ends(&item, [a, b], reference.len())?;
    if (reference[a].position_m - reference[b].position_m).norm() == 0.0 {
        return Err(MechanicsError::invalid(
            item,
            format!("nodes {a} and {b} coincide (zero length)"),
        ));
    }
    if !(c.axial_n.is_finite() && c.axial_n > 0.0) {
        return Err(MechanicsError::invalid(
            item,
            format!(
                "axial stiffness {} N must be finite and positive",
                c.axial_n
            ),
        ));
    }
    if let Some(l) = c
        .rest_lengths_m
        .iter()
        .find(|l| !(l.is_finite() && **l > 0.0))
    {
        return Err(MechanicsError::invalid(
            item,
            format!("unstressed length {l} m must be finite and positive"),
        ));
    }
    Ok(())
}

/// Builds a [`Model`] item by item; [`ModelBuilder::build`] validates it.
#[derive(Debug, Default, Clone)]
pub struct ModelBuilder {
    reference: Vec<Frame>,
    node_dofs: Vec<usize>,
    elements: Vec<BeamElement>,
    cables: Vec<Cable>,
    joints: Vec<(JointKind, NodeId, NodeId, Vector3<f64>)>,
    fixed: Vec<[bool; 6]>,
    loads: Vec<NodalLoad>,
    rods: Vec<Rod>,
    errors: Vec<MechanicsError>,
}

impl ModelBuilder {
    /// An empty model.
    pub fn new() -> Self {
        Self::default()
    }

    /// A 6-DOF node (a rigid body, or a rod's node) at `position_m` with
    /// orientation `rotation`. Returns its id.
    pub fn add_frame(&mut self, position_m: Vector3<f64>, rotation: UnitQuaternion<f64>) -> NodeId {
        self.push_node(
            Frame {
                position_m,
                rotation,
            },
            6,
        )
    }

    /// A rigid body (paper §3.3) at `position_m`, axes along the global axes.
    pub fn add_body(&mut self, position_m: Vector3<f64>) -> NodeId {
        self.add_frame(position_m, UnitQuaternion::identity())
    }

    /// A 3-DOF point (a cable node): position only.
    pub fn add_point(&mut self, position_m: Vector3<f64>) -> NodeId {
        self.push_node(
            Frame {
                position_m,
                rotation: UnitQuaternion::identity(),
            },
            3,
        )
    }

    fn push_node(&mut self, frame: Frame, dofs: usize) -> NodeId {
        if !frame.position_m.iter().all(|v| v.is_finite()) {
            self.errors.push(MechanicsError::invalid(
                format!("node {}", self.reference.len()),
                "position is not finite",
            ));
        }
        self.reference.push(frame);
        self.node_dofs.push(dofs);
        self.fixed.push([false; 6]);
        self.reference.len() - 1
    }

    /// A straight rod from `start_m` to `end_m`, meshed into `spec.elements`
    /// elements with their own nodes (joints connect its end nodes to bodies).
    /// The material frame has its first axis along the rod and its second
    /// axis as close to `up` as possible (any vector not along the rod).
    pub fn add_rod(
        &mut self,
        start_m: Vector3<f64>,
        end_m: Vector3<f64>,
        up: Vector3<f64>,
        spec: &RodSpec,
    ) -> Rod {
        let item = format!("rod {}", self.rods.len());
        let axis = end_m - start_m;
        let length = axis.norm();
        self.check_spec(&item, spec);
        if !(length.is_finite() && length > 0.0) {
            self.errors.push(MechanicsError::invalid(
                &item,
                if length.is_finite() {
                    "start and end coincide (zero length)"
                } else {
                    "its length is not a finite number"
                },
            ));
            self.rods.push(Rod { nodes: vec![] });
            return self.rods.last().cloned().expect("just pushed");
        }
        let rotation = rod_frame(&axis, &up);
        let elements = spec.elements.max(1);
        let nodes: Vec<NodeId> = (0..=elements)
            .map(|i| {
                let s = i as f64 / elements as f64;
                self.add_frame(start_m + axis * s, rotation)
            })
            .collect();
        self.mesh(nodes, spec)
    }

    /// A rod along a circular arc from `start_m` to `end_m` ([`CircularArc`]:
    /// about a centre, or through a point), meshed into `spec.elements`
    /// elements with their own nodes, equally spaced in angle, each node's
    /// frame the start's turned about the arc's normal by its angle
    /// ([`frames`](super::ArcGeometry::frames)): every element has the same
    /// reference curvature `1/R`, exactly (the SE(3) element between two such
    /// frames is the arc), and its length is its arc length, not its chord.
    /// The material frame has its first axis along the tangent and, at the
    /// start, its second axis as close to `up` as possible; along the arc it
    /// turns with the tangent.
    ///
    /// An invalid arc, or too few elements to span it at
    /// [`MAX_ELEMENT_ANGLE_RAD`] each, is an error of [`ModelBuilder::build`]
    /// naming the rod.
    pub fn add_arc_rod(
        &mut self,
        start_m: Vector3<f64>,
        end_m: Vector3<f64>,
        arc: &CircularArc,
        up: Vector3<f64>,
        spec: &RodSpec,
    ) -> Rod {
        let item = format!("rod {}", self.rods.len());
        self.check_spec(&item, spec);
        let geometry = if start_m.iter().chain(end_m.iter()).all(|c| c.is_finite()) {
            arc.geometry(start_m, end_m).map_err(|e| format!("arc {e}"))
        } else {
            Err("its start or end is not finite".to_string())
        };
        let geometry = match geometry {
            Ok(g) => g,
            Err(reason) => {
                self.errors.push(MechanicsError::invalid(&item, reason));
                self.rods.push(Rod { nodes: vec![] });
                return self.rods.last().cloned().expect("just pushed");
            }
        };
        let fewest = geometry.fewest_elements();
        if (1..fewest).contains(&spec.elements) {
            self.errors.push(MechanicsError::invalid(
                &item,
                format!(
                    "its arc of {:.1}° needs at least {fewest} elements (at most {:.0}° each)",
                    geometry.angle_rad.to_degrees(),
                    MAX_ELEMENT_ANGLE_RAD.to_degrees()
                ),
            ));
        }
        let nodes: Vec<NodeId> = geometry
            .frames(&up, spec.elements.max(fewest))
            .into_iter()
            .map(|f| self.add_frame(f.position_m, f.rotation))
            .collect();
        self.mesh(nodes, spec)
    }

    /// The errors of a rod's mesh and section.
    fn check_spec(&mut self, item: &str, spec: &RodSpec) {
        if spec.elements == 0 {
            self.errors
                .push(MechanicsError::invalid(item, "needs at least one element"));
        }
        if let Some(field) = spec.section.invalid_field() {
            self.errors.push(MechanicsError::invalid(
                item,
                format!("section stiffness {field} must be finite and positive"),
            ));
        }
    }

    /// The elements between consecutive `nodes` of a rod, and the rod.
    fn mesh(&mut self, nodes: Vec<NodeId>, spec: &RodSpec) -> Rod {
        for w in nodes.windows(2) {
            let (a, b) = (w[0], w[1]);
            let element = BeamElement::new(
                spec.kind,
                [a, b],
                [&self.reference[a], &self.reference[b]],
                &spec.section,
            );
            self.elements.push(element);
        }
        let rod = Rod { nodes };
        self.rods.push(rod.clone());
        rod
    }

    /// A joint between nodes `a` and `b` at the point `at_m` of the reference
    /// configuration: [`JointKind::Fixed`] (6 equations, eq. 24) or
    /// [`JointKind::Revolute`] about a global reference axis (5 equations, eq. 25),
    /// or [`JointKind::Spherical`] (3 equations: the point only).
    pub fn add_joint(&mut self, kind: JointKind, a: NodeId, b: NodeId, at_m: Vector3<f64>) {
        self.joints.push((kind, a, b, at_m));
    }

    /// A tension-only cable between the positions of nodes `a` and `b` with
    /// axial stiffness `axial_n` (EA, N) and unstressed length ramped from
    /// `rest_lengths_m[0]` at load factor 0 to `rest_lengths_m[1]` at 1
    /// (see [`Cable`]). Returns its index.
    pub fn add_cable(
        &mut self,
        a: NodeId,
        b: NodeId,
        axial_n: f64,
        rest_lengths_m: [f64; 2],
    ) -> usize {
        self.cables.push(Cable {
            nodes: [a, b],
            axial_n,
            rest_lengths_m,
        });
        self.cables.len() - 1
    }

    /// Fix components of node `node`: `[x, y, z, θx, θy, θz]` (global axes).
    pub fn fix(&mut self, node: NodeId, components: [bool; 6]) {
        match self.fixed.get_mut(node) {
            Some(f) => {
                for (slot, c) in f.iter_mut().zip(components) {
                    *slot |= c;
                }
            }
            None => self.errors.push(MechanicsError::invalid(
                format!("support on node {node}"),
                "the node does not exist",
            )),
        }
    }

    /// A dead load at node `node` (scaled by the load factor).
    pub fn add_load(&mut self, node: NodeId, force_n: Vector3<f64>, moment_nm: Vector3<f64>) {
        self.loads.push(NodalLoad {
            node,
            force_n,
            moment_nm,
        });
    }

    /// A free stretch of every rod, in the order they were added:
    /// `factors[r] = [length, section]`, each element of rod `r` made
    /// [`BeamElement::stretched`] (its stress-free length × `length`, its
    /// section's dimensions × `section`). The structure stays: the same
    /// nodes, elements and joints.
    ///
    /// # Panics
    /// If `factors` does not hold one pair per rod.
    #[track_caller]
    pub fn stretch_rods(&mut self, factors: &[[f64; 2]]) {
        assert_eq!(factors.len(), self.rods.len(), "one stretch per rod");
        // Elements are meshed rod by rod: rod r's are the next
        // `nodes − 1` of the list.
        let mut first = 0;
        for (rod, &[length, section]) in self.rods.iter().zip(factors) {
            let n = rod.nodes.len().saturating_sub(1);
            for e in &mut self.elements[first..first + n] {
                *e = e.stretched(length, section);
            }
            first += n;
        }
    }

    /// Move node `node`'s reference position by `by_m`, the joints on it
    /// staying where they were added: a rigid body (a hinge) built off its
    /// place by `by_m`, what it carries (cables on its position) moved with
    /// it.
    pub fn displace_node(&mut self, node: NodeId, by_m: Vector3<f64>) {
        match self.reference.get_mut(node) {
            Some(f) if by_m.iter().all(|c| c.is_finite()) => f.position_m += by_m,
            _ => self.errors.push(MechanicsError::invalid(
                format!("node {node}"),
                "a displacement of a missing node, or not finite",
            )),
        }
    }

    /// Nodes added so far.
    pub fn node_count(&self) -> usize {
        self.reference.len()
    }

    /// Rods added so far.
    pub fn rod_count(&self) -> usize {
        self.rods.len()
    }

    /// The reference configuration of a node added so far.
    pub fn frame(&self, node: NodeId) -> Option<&Frame> {
        self.reference.get(node)
    }

    /// Validate and build.
    ///
    /// # Errors
    /// The first invalid item, named: a zero-length rod, an arc whose ends
    /// are not on one circle (or too few elements for it), a joint on a missing
    /// node or between a node and itself, a rotational joint on a point, a
    /// load on a missing node.
    pub fn build(mut self) -> Result<Model, MechanicsError> {
        if let Some(e) = self.errors.drain(..).next() {
            return Err(e);
        }
        let mut joints = Vec::with_capacity(self.joints.len());
        for (j, &(kind, a, b, at)) in self.joints.iter().enumerate() {
            let item = format!("joint {j}");
            check_ends(&item, [a, b], self.reference.len())?;
            if !at.iter().all(|v| v.is_finite()) {
                return Err(MechanicsError::invalid(item, "its point is not finite"));
            }
            let rotational = !matches!(kind, JointKind::Spherical);
            for n in [a, b] {
                if self.node_dofs[n] == 3 && rotational {
                    return Err(MechanicsError::invalid(
                        item,
                        format!("node {n} is a point: it has no rotation to join"),
                    ));
                }
                if self.node_dofs[n] == 3 && (self.reference[n].position_m - at).norm() > 0.0 {
                    return Err(MechanicsError::invalid(
                        item,
                        format!("node {n} is a point: the joint must be at its position"),
                    ));
                }
            }
            if let JointKind::Revolute { axis } = kind {
                if !(axis.norm().is_finite() && axis.norm() > 0.0) {
                    return Err(MechanicsError::invalid(
                        item,
                        "revolute axis must be a non-zero vector",
                    ));
                }
            }
            joints.push(Joint::new(
                kind,
                [a, b],
                [&self.reference[a], &self.reference[b]],
                at,
            ));
        }
        for (k, c) in self.cables.iter().enumerate() {
            check_cable(k, c, &self.reference)?;
        }
        for (n, f) in self.fixed.iter_mut().enumerate() {
            if self.node_dofs[n] == 3 {
                f[3..].iter_mut().for_each(|c| *c = true);
            }
        }
        for (i, l) in self.loads.iter().enumerate() {
            check_load(i, l, &self.node_dofs)?;
        }
        Ok(Model {
            reference: self.reference,
            node_dofs: self.node_dofs,
            elements: self.elements,
            cables: self.cables,
            joints,
            fixed: self.fixed,
            loads: self.loads,
            rods: self.rods,
        })
    }
}
