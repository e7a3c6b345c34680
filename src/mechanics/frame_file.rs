//! The frame file (TOML): any structure of rods, rigid bodies, joints,
//! supports and dead loads, read, validated with the key at fault named, and
//! built into a [`Model`] (DESIGN §5: "a generic frame input runs on the same
//! engine").
//!
//! # Format
//!
//! SI units in key names; unknown keys are rejected. Items of a list are named
//! in errors by their index (`rods[2].elements: must be at least 1`).
//!
//! * `[[nodes]]` — points of the geometry: `position_m`, optional `name`.
//!   Referenced by name (`"tip"`) or by index (`3`). A node is only a place:
//!   rods, bodies and joints are located at nodes, and what is attached there is
//!   decided by joints.
//! * `[sections.NAME]` — a named section, reused by rods with `section = "NAME"`.
//!   Either `tube = { outer_diameter_m, inner_diameter_m, youngs_modulus_pa,
//!   shear_modulus_pa }` (a circular tube, [`Section::tube`]) or the four
//!   stiffnesses directly: `axial_n` (EA), `shear_n = [GA₂, GA₃]`,
//!   `torsion_nm2` (GJ), `bending_nm2 = [EI₂, EI₃]`.
//! * `[[rods]]` — straight rods from node `start` to node `end`; the section is
//!   either `section = "NAME"`, or `tube = { … }`, or the four stiffnesses
//!   written on the rod. `elements` (default 1), `element = "se3"` (default) or
//!   `"crisfield-jelenic"`, optional `up` (the second axis of the section is the
//!   one closest to `up`; default `[0, 0, 1]`), optional `name`. Every rod is
//!   meshed with nodes of its own: its ends are connected to anything else only
//!   by joints.
//! * `[[bodies]]` — rigid bodies (hinges, paper §3.3) at a node (`at = "h0"`) or
//!   a point (`at_m = [x, y, z]`), optional `name`.
//! * Members: the things joints, supports and loads act on, written
//!   `{ rod = "beam", end = "start" | "end" }`, `{ body = "h0" }`, or
//!   `{ node = "tip" }` — the one rod end or body located at that node (an error
//!   when several are there: say which).
//! * `[[joints]]` — `kind = "fixed" | "revolute" | "spherical"` between members
//!   `a` and `b`; `axis = [x, y, z]` for a revolute joint (global, reference
//!   configuration); the joint's point is `at = NODE` or `at_m = [x, y, z]`,
//!   by default the reference position of `a`.
//! * `[[supports]]` — `on = MEMBER`, `fixed = ["x", "y", "z", "rx", "ry", "rz"]`
//!   (global components; `"all"` for the six).
//! * `[[loads]]` — dead loads at load factor 1: `on = MEMBER`, `force_n`,
//!   `moment_nm` (global, fixed in direction; each defaults to zero).
//! * `[solver]` — [`StaticSettings`]: `tolerance`, `max_iterations`,
//!   `initial_step`, `min_step`, `max_steps`, `path = "load" | "arc_length"`.
//!
//! # Example
//!
//! A portal: two clamped columns, a beam pinned to a rigid knee at each top,
//! a lateral force and a moment.
//!
//! ```toml
//! [[nodes]]
//! name = "a"
//! position_m = [0.0, 0.0, 0.0]
//! [[nodes]]
//! name = "b"
//! position_m = [0.0, 0.0, 3.0]
//! [[nodes]]
//! name = "c"
//! position_m = [4.0, 0.0, 3.0]
//! [[nodes]]
//! name = "d"
//! position_m = [4.0, 0.0, 0.0]
//!
//! [sections.steel]
//! tube = { outer_diameter_m = 0.1, inner_diameter_m = 0.09, youngs_modulus_pa = 2.1e11, shear_modulus_pa = 8.1e10 }
//!
//! [[rods]]
//! name = "left"
//! start = "a"
//! end = "b"
//! section = "steel"
//! elements = 4
//! up = [1.0, 0.0, 0.0]
//!
//! [[rods]]
//! name = "beam"
//! start = "b"
//! end = "c"
//! axial_n = 1e8
//! shear_n = [4e7, 4e7]
//! torsion_nm2 = 2e5
//! bending_nm2 = [1.5e5, 1.5e5]
//! elements = 6
//! element = "crisfield-jelenic"
//!
//! [[rods]]
//! name = "right"
//! start = 3
//! end = 2
//! tube = { outer_diameter_m = 0.1, inner_diameter_m = 0.09, youngs_modulus_pa = 2.1e11, shear_modulus_pa = 8.1e10 }
//! elements = 4
//!
//! [[bodies]]
//! name = "knee-left"
//! at = "b"
//! [[bodies]]
//! name = "knee-right"
//! at_m = [4.0, 0.0, 3.0]
//!
//! [[joints]]
//! kind = "fixed"
//! a = { rod = "left", end = "end" }
//! b = { body = "knee-left" }
//! [[joints]]
//! kind = "revolute"
//! axis = [0.0, 1.0, 0.0]
//! a = { rod = "beam", end = "start" }
//! b = { body = "knee-left" }
//! at = "b"
//! [[joints]]
//! kind = "revolute"
//! axis = [0.0, 1.0, 0.0]
//! a = { rod = "beam", end = "end" }
//! b = { body = "knee-right" }
//! [[joints]]
//! kind = "fixed"
//! a = { rod = "right", end = "end" }
//! b = { body = "knee-right" }
//!
//! [[supports]]
//! on = { node = "a" }
//! fixed = ["all"]
//! [[supports]]
//! on = { rod = "right", end = "start" }
//! fixed = ["x", "y", "z", "rx", "ry", "rz"]
//!
//! [[loads]]
//! on = { body = "knee-left" }
//! force_n = [1000.0, 0.0, 0.0]
//! [[loads]]
//! on = { rod = "beam", end = "end" }
//! moment_nm = [0.0, 500.0, 0.0]
//!
//! [solver]
//! tolerance = 1e-10
//! path = "load"
//! ```

use std::collections::{BTreeMap, HashMap};
use std::fmt;
use std::path::Path;

use nalgebra::Vector3;
use serde::Deserialize;

use super::beam::{ElementKind, Section};
use super::joint::JointKind;
use super::model::{MechanicsError, Model, ModelBuilder, NodeId, Rod, RodSpec};
use super::statics::StaticSettings;

/// Most beam elements of one rod (a finer mesh buys nothing: 64 SE(3)
/// elements are exact to roundoff on the rolled-up cantilever).
pub const MAX_ROD_ELEMENTS: usize = 100_000;

/// Most beam elements of a whole frame: bounds the memory a file can ask for.
pub const MAX_FRAME_ELEMENTS: usize = 1_000_000;

/// An invalid frame file: every variant names the file or the key.
#[derive(Debug, thiserror::Error)]
pub enum FrameFileError {
    /// Reading the file failed.
    #[error("reading {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// Not TOML of the frame format (unknown or missing key, wrong type); the
    /// parser's message names the key and the line.
    #[error("{path}: {message}")]
    Parse {
        /// The file.
        path: String,
        /// The parser's message.
        message: String,
    },
    /// A value is invalid.
    #[error("{key}: {reason}")]
    Invalid {
        /// The key, e.g. `rods[2].elements` or `joints[0].a`.
        key: String,
        /// Why it is rejected.
        reason: String,
    },
    /// The model could not be built or analysed (a mechanism, say).
    #[error(transparent)]
    Model(#[from] MechanicsError),
}

impl FrameFileError {
    /// The key at fault, when the error is about one value.
    pub fn key(&self) -> Option<&str> {
        match self {
            FrameFileError::Invalid { key, .. } => Some(key),
            _ => None,
        }
    }

    /// Every frame-file error is the input's fault (exit code 2).
    pub fn is_bad_input(&self) -> bool {
        true
    }

    fn invalid(key: impl Into<String>, reason: impl Into<String>) -> Self {
        FrameFileError::Invalid {
            key: key.into(),
            reason: reason.into(),
        }
    }
}

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
}

impl FrameFile {
    /// Reads, parses, validates and builds a frame file.
    ///
    /// # Errors
    /// The file cannot be read, is not of the format, or a value is invalid
    /// (the key is named).
    pub fn read(path: &Path) -> Result<FrameFile, FrameFileError> {
        let shown = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| FrameFileError::Io {
            path: shown.clone(),
            source,
        })?;
        FrameFile::from_toml(&text).map_err(|e| match e {
            FrameFileError::Parse { message, .. } => FrameFileError::Parse {
                path: shown,
                message,
            },
            other => other,
        })
    }

    /// Parses, validates and builds frame-file text.
    ///
    /// # Errors
    /// As [`FrameFile::read`].
    pub fn from_toml(text: &str) -> Result<FrameFile, FrameFileError> {
        let raw: RawFile = toml::from_str(text).map_err(|e| FrameFileError::Parse {
            path: "<frame>".into(),
            message: e.to_string(),
        })?;
        raw.build()
    }

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

/// A reference to a node, rod or body: its name or its index.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(untagged)]
enum Ref {
    Index(usize),
    Name(String),
}

impl fmt::Display for Ref {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Ref::Index(i) => write!(f, "{i}"),
            Ref::Name(n) => write!(f, "\"{n}\""),
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFile {
    #[serde(default)]
    nodes: Vec<RawNode>,
    #[serde(default)]
    sections: BTreeMap<String, RawSection>,
    #[serde(default)]
    rods: Vec<RawRod>,
    #[serde(default)]
    bodies: Vec<RawBody>,
    #[serde(default)]
    joints: Vec<RawJoint>,
    #[serde(default)]
    supports: Vec<RawSupport>,
    #[serde(default)]
    loads: Vec<RawLoad>,
    #[serde(default)]
    solver: StaticSettings,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawNode {
    name: Option<String>,
    position_m: [f64; 3],
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
struct Tube {
    outer_diameter_m: f64,
    inner_diameter_m: f64,
    youngs_modulus_pa: f64,
    shear_modulus_pa: f64,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSection {
    tube: Option<Tube>,
    axial_n: Option<f64>,
    shear_n: Option<[f64; 2]>,
    torsion_nm2: Option<f64>,
    bending_nm2: Option<[f64; 2]>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRod {
    name: Option<String>,
    start: Ref,
    end: Ref,
    section: Option<String>,
    tube: Option<Tube>,
    axial_n: Option<f64>,
    shear_n: Option<[f64; 2]>,
    torsion_nm2: Option<f64>,
    bending_nm2: Option<[f64; 2]>,
    #[serde(default = "one")]
    elements: usize,
    #[serde(default)]
    element: ElementKind,
    up: Option<[f64; 3]>,
}

fn one() -> usize {
    1
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBody {
    name: Option<String>,
    at: Option<Ref>,
    at_m: Option<[f64; 3]>,
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
enum RodEnd {
    Start,
    End,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMember {
    node: Option<Ref>,
    rod: Option<Ref>,
    end: Option<RodEnd>,
    body: Option<Ref>,
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(rename_all = "lowercase")]
enum RawJointKind {
    Fixed,
    Revolute,
    Spherical,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawJoint {
    kind: RawJointKind,
    a: RawMember,
    b: RawMember,
    axis: Option<[f64; 3]>,
    at: Option<Ref>,
    at_m: Option<[f64; 3]>,
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(rename_all = "lowercase")]
enum Component {
    X,
    Y,
    Z,
    Rx,
    Ry,
    Rz,
    All,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSupport {
    on: RawMember,
    fixed: Vec<Component>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLoad {
    on: RawMember,
    #[serde(default)]
    force_n: [f64; 3],
    #[serde(default)]
    moment_nm: [f64; 3],
}

fn vector(key: &str, v: [f64; 3]) -> Result<Vector3<f64>, FrameFileError> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(Vector3::from(v))
    } else {
        Err(FrameFileError::invalid(key, "a component is not finite"))
    }
}

fn nonzero(key: &str, v: [f64; 3]) -> Result<Vector3<f64>, FrameFileError> {
    let v = vector(key, v)?;
    if v.norm() > 0.0 {
        Ok(v)
    } else {
        Err(FrameFileError::invalid(key, "must be a non-zero vector"))
    }
}

fn positive(key: &str, v: f64) -> Result<(), FrameFileError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(FrameFileError::invalid(
            key,
            format!("{v} must be finite and positive"),
        ))
    }
}

impl RawSection {
    /// The section, `key` naming where it was written (`rods[2]`, `sections.steel`).
    fn resolve(&self, key: &str) -> Result<Section, FrameFileError> {
        let direct = [
            self.axial_n.is_some(),
            self.shear_n.is_some(),
            self.torsion_nm2.is_some(),
            self.bending_nm2.is_some(),
        ];
        match (self.tube, direct.iter().any(|&d| d)) {
            (Some(_), true) => Err(FrameFileError::invalid(
                key,
                "give either `tube` or the stiffnesses (axial_n, shear_n, torsion_nm2, bending_nm2), not both",
            )),
            (None, false) => Err(FrameFileError::invalid(
                key,
                "no section: give `section`, `tube`, or axial_n, shear_n, torsion_nm2, bending_nm2",
            )),
            (Some(t), false) => {
                positive(&format!("{key}.tube.outer_diameter_m"), t.outer_diameter_m)?;
                let inner = format!("{key}.tube.inner_diameter_m");
                if !(t.inner_diameter_m.is_finite() && t.inner_diameter_m >= 0.0) {
                    return Err(FrameFileError::invalid(
                        inner,
                        format!("{} must be finite and non-negative", t.inner_diameter_m),
                    ));
                }
                if t.inner_diameter_m >= t.outer_diameter_m {
                    return Err(FrameFileError::invalid(
                        inner,
                        format!(
                            "{} must be less than outer_diameter_m = {}",
                            t.inner_diameter_m, t.outer_diameter_m
                        ),
                    ));
                }
                positive(&format!("{key}.tube.youngs_modulus_pa"), t.youngs_modulus_pa)?;
                positive(&format!("{key}.tube.shear_modulus_pa"), t.shear_modulus_pa)?;
                Ok(Section::tube(
                    t.outer_diameter_m,
                    t.inner_diameter_m,
                    t.youngs_modulus_pa,
                    t.shear_modulus_pa,
                ))
            }
            (None, true) => {
                let missing = |name: &str| {
                    FrameFileError::invalid(
                        format!("{key}.{name}"),
                        "missing: a section given by stiffnesses needs axial_n, shear_n, torsion_nm2 and bending_nm2",
                    )
                };
                let axial = self.axial_n.ok_or_else(|| missing("axial_n"))?;
                let shear = self.shear_n.ok_or_else(|| missing("shear_n"))?;
                let torsion = self.torsion_nm2.ok_or_else(|| missing("torsion_nm2"))?;
                let bending = self.bending_nm2.ok_or_else(|| missing("bending_nm2"))?;
                positive(&format!("{key}.axial_n"), axial)?;
                for (i, v) in shear.iter().enumerate() {
                    positive(&format!("{key}.shear_n[{i}]"), *v)?;
                }
                positive(&format!("{key}.torsion_nm2"), torsion)?;
                for (i, v) in bending.iter().enumerate() {
                    positive(&format!("{key}.bending_nm2[{i}]"), *v)?;
                }
                Ok(Section {
                    axial_n: axial,
                    shear_n: shear,
                    torsion_nm2: torsion,
                    bending_nm2: bending,
                })
            }
        }
    }
}

/// A named list (nodes, rods, bodies): names to indices, checked unique.
struct Names {
    what: &'static str,
    count: usize,
    index: HashMap<String, usize>,
}

impl Names {
    fn new<'a>(
        what: &'static str,
        list: &'static str,
        names: impl Iterator<Item = Option<&'a String>>,
    ) -> Result<Names, FrameFileError> {
        let mut index = HashMap::new();
        let mut count = 0;
        for (i, name) in names.enumerate() {
            count += 1;
            if let Some(name) = name {
                if name.is_empty() {
                    return Err(FrameFileError::invalid(
                        format!("{list}[{i}].name"),
                        "must not be empty",
                    ));
                }
                if let Some(first) = index.insert(name.clone(), i) {
                    return Err(FrameFileError::invalid(
                        format!("{list}[{i}].name"),
                        format!("{what} \"{name}\" is already {list}[{first}]"),
                    ));
                }
            }
        }
        Ok(Names { what, count, index })
    }

    fn resolve(&self, key: &str, r: &Ref) -> Result<usize, FrameFileError> {
        match r {
            Ref::Name(n) => self.index.get(n).copied().ok_or_else(|| {
                FrameFileError::invalid(key, format!("unknown {} \"{n}\"", self.what))
            }),
            Ref::Index(i) if *i < self.count => Ok(*i),
            Ref::Index(i) => Err(FrameFileError::invalid(
                key,
                format!(
                    "{} {i} does not exist ({} in the file)",
                    self.what, self.count
                ),
            )),
        }
    }
}

/// Where rods and bodies are, to resolve members.
struct Members {
    nodes: Names,
    nodes_positions: Vec<Vector3<f64>>,
    rods: Names,
    rods_built: Vec<Rod>,
    rods_labels: Vec<String>,
    bodies: Names,
    bodies_nodes: Vec<NodeId>,
    bodies_labels: Vec<String>,
    /// Every member's node and reference position, with its label.
    located: Vec<(String, NodeId, Vector3<f64>)>,
}

impl Members {
    fn resolve(&self, key: &str, m: &RawMember) -> Result<NodeId, FrameFileError> {
        let given = [m.node.is_some(), m.rod.is_some(), m.body.is_some()];
        if given.iter().filter(|&&g| g).count() != 1 {
            return Err(FrameFileError::invalid(
                key,
                "name exactly one of `node`, `rod` (with `end`) or `body`",
            ));
        }
        if m.rod.is_none() && m.end.is_some() {
            return Err(FrameFileError::invalid(
                format!("{key}.end"),
                "only a rod has ends",
            ));
        }
        if let Some(r) = &m.rod {
            let i = self.rods.resolve(&format!("{key}.rod"), r)?;
            let rod = &self.rods_built[i];
            return match m.end {
                Some(RodEnd::Start) => Ok(rod.start()),
                Some(RodEnd::End) => Ok(rod.end()),
                None => Err(FrameFileError::invalid(
                    format!("{key}.end"),
                    format!(
                        "missing: which end of rod {}, \"start\" or \"end\"",
                        self.rods_labels[i]
                    ),
                )),
            };
        }
        if let Some(b) = &m.body {
            let i = self.bodies.resolve(&format!("{key}.body"), b)?;
            return Ok(self.bodies_nodes[i]);
        }
        let r = m.node.as_ref().expect("one of three");
        let n = self.nodes.resolve(&format!("{key}.node"), r)?;
        let at = self.nodes_positions[n];
        let here: Vec<&(String, NodeId, Vector3<f64>)> =
            self.located.iter().filter(|(_, _, p)| *p == at).collect();
        match here.as_slice() {
            [(_, node, _)] => Ok(*node),
            [] => Err(FrameFileError::invalid(
                format!("{key}.node"),
                format!("no rod end or body is at node {r}"),
            )),
            many => Err(FrameFileError::invalid(
                format!("{key}.node"),
                format!(
                    "{} members are at node {r} ({}): name one with {{ rod = …, end = … }} or {{ body = … }}",
                    many.len(),
                    many.iter().map(|(l, _, _)| l.as_str()).collect::<Vec<_>>().join(", ")
                ),
            )),
        }
    }

    /// A point given as `at` (a node) or `at_m`, or `default`.
    fn point(
        &self,
        key: &str,
        at: &Option<Ref>,
        at_m: Option<[f64; 3]>,
        default: Option<Vector3<f64>>,
    ) -> Result<Vector3<f64>, FrameFileError> {
        match (at, at_m, default) {
            (Some(_), Some(_), _) => Err(FrameFileError::invalid(
                key,
                "give either `at` (a node) or `at_m` (a point), not both",
            )),
            (Some(r), None, _) => {
                Ok(self.nodes_positions[self.nodes.resolve(&format!("{key}.at"), r)?])
            }
            (None, Some(p), _) => vector(&format!("{key}.at_m"), p),
            (None, None, Some(d)) => Ok(d),
            (None, None, None) => Err(FrameFileError::invalid(
                key,
                "missing: `at` (a node) or `at_m` (a point)",
            )),
        }
    }
}

impl RawFile {
    fn build(self) -> Result<FrameFile, FrameFileError> {
        self.solver.validate().map_err(|e| match e {
            MechanicsError::Invalid { item, reason } => FrameFileError::invalid(item, reason),
            other => other.into(),
        })?;
        let nodes = Names::new("node", "nodes", self.nodes.iter().map(|n| n.name.as_ref()))?;
        let nodes_positions = self
            .nodes
            .iter()
            .enumerate()
            .map(|(i, n)| vector(&format!("nodes[{i}].position_m"), n.position_m))
            .collect::<Result<Vec<_>, _>>()?;
        let mut sections = BTreeMap::new();
        for (name, s) in &self.sections {
            sections.insert(name.clone(), s.resolve(&format!("sections.{name}"))?);
        }

        let mut builder = ModelBuilder::new();
        let mut origins = Vec::new();
        let rods_names = Names::new("rod", "rods", self.rods.iter().map(|r| r.name.as_ref()))?;
        let mut rods_built = Vec::with_capacity(self.rods.len());
        let mut rods_labels = Vec::with_capacity(self.rods.len());
        let mut located = Vec::new();
        let mut total_elements = 0usize;
        for (i, r) in self.rods.iter().enumerate() {
            let key = format!("rods[{i}]");
            let label = r.name.clone().unwrap_or_else(|| key.clone());
            let start = nodes.resolve(&format!("{key}.start"), &r.start)?;
            let end = nodes.resolve(&format!("{key}.end"), &r.end)?;
            let (p, q) = (nodes_positions[start], nodes_positions[end]);
            if p == q {
                return Err(FrameFileError::invalid(
                    format!("{key}.end"),
                    format!(
                        "node {} is where the rod starts (node {}): zero length",
                        r.end, r.start
                    ),
                ));
            }
            if !(q - p).norm().is_finite() {
                return Err(FrameFileError::invalid(
                    format!("{key}.end"),
                    format!(
                        "the rod from node {} to node {} is longer than a number can hold",
                        r.start, r.end
                    ),
                ));
            }
            let inline = RawSection {
                tube: r.tube,
                axial_n: r.axial_n,
                shear_n: r.shear_n,
                torsion_nm2: r.torsion_nm2,
                bending_nm2: r.bending_nm2,
            };
            let section = match &r.section {
                Some(name) => {
                    if inline.tube.is_some()
                        || inline.axial_n.is_some()
                        || inline.shear_n.is_some()
                        || inline.torsion_nm2.is_some()
                        || inline.bending_nm2.is_some()
                    {
                        return Err(FrameFileError::invalid(
                            format!("{key}.section"),
                            "a named section and a section written on the rod: give one",
                        ));
                    }
                    *sections.get(name).ok_or_else(|| {
                        FrameFileError::invalid(
                            format!("{key}.section"),
                            format!("unknown section \"{name}\" (no [sections.{name}])"),
                        )
                    })?
                }
                None => inline.resolve(&key)?,
            };
            if r.elements == 0 {
                return Err(FrameFileError::invalid(
                    format!("{key}.elements"),
                    "must be at least 1",
                ));
            }
            if r.elements > MAX_ROD_ELEMENTS {
                return Err(FrameFileError::invalid(
                    format!("{key}.elements"),
                    format!(
                        "{} is more than the {MAX_ROD_ELEMENTS} supported",
                        r.elements
                    ),
                ));
            }
            total_elements += r.elements;
            if total_elements > MAX_FRAME_ELEMENTS {
                return Err(FrameFileError::invalid(
                    format!("{key}.elements"),
                    format!(
                        "the rods up to this one have {total_elements} elements in all, more than \
                         the {MAX_FRAME_ELEMENTS} supported"
                    ),
                ));
            }
            let up = match r.up {
                Some(u) => nonzero(&format!("{key}.up"), u)?,
                None => Vector3::z(),
            };
            let spec = RodSpec {
                section,
                elements: r.elements,
                kind: r.element,
            };
            let rod = builder.add_rod(p, q, up, &spec);
            origins.extend((0..rod.nodes.len()).map(|index| NodeOrigin::Rod {
                rod: label.clone(),
                index,
            }));
            located.push((format!("rod {label} start"), rod.start(), p));
            located.push((format!("rod {label} end"), rod.end(), q));
            rods_built.push(rod);
            rods_labels.push(label);
        }

        if self.rods.is_empty() && self.bodies.is_empty() {
            return Err(FrameFileError::invalid(
                "rods",
                "the frame has no rod and no body: nothing to solve",
            ));
        }
        let bodies_names = Names::new(
            "body",
            "bodies",
            self.bodies.iter().map(|b| b.name.as_ref()),
        )?;
        let mut members = Members {
            nodes,
            nodes_positions,
            rods: rods_names,
            rods_built,
            rods_labels,
            bodies: bodies_names,
            bodies_nodes: Vec::with_capacity(self.bodies.len()),
            bodies_labels: Vec::with_capacity(self.bodies.len()),
            located,
        };
        for (i, b) in self.bodies.iter().enumerate() {
            let key = format!("bodies[{i}]");
            let at = members.point(&key, &b.at, b.at_m, None)?;
            let label = b.name.clone().unwrap_or_else(|| key.clone());
            let node = builder.add_body(at);
            origins.push(NodeOrigin::Body {
                body: label.clone(),
            });
            members.located.push((format!("body {label}"), node, at));
            members.bodies_nodes.push(node);
            members.bodies_labels.push(label);
        }

        let mut joined = Vec::with_capacity(self.joints.len());
        for (i, j) in self.joints.iter().enumerate() {
            let key = format!("joints[{i}]");
            let a = members.resolve(&format!("{key}.a"), &j.a)?;
            let b = members.resolve(&format!("{key}.b"), &j.b)?;
            if a == b {
                return Err(FrameFileError::invalid(
                    format!("{key}.b"),
                    format!("is the same member as {key}.a"),
                ));
            }
            let kind = match (j.kind, j.axis) {
                (RawJointKind::Revolute, Some(axis)) => JointKind::Revolute {
                    axis: nonzero(&format!("{key}.axis"), axis)?,
                },
                (RawJointKind::Revolute, None) => {
                    return Err(FrameFileError::invalid(
                        format!("{key}.axis"),
                        "missing: a revolute joint needs its axis",
                    ))
                }
                (_, Some(_)) => {
                    return Err(FrameFileError::invalid(
                        format!("{key}.axis"),
                        "only a revolute joint has an axis",
                    ))
                }
                (RawJointKind::Fixed, None) => JointKind::Fixed,
                (RawJointKind::Spherical, None) => JointKind::Spherical,
            };
            let default = builder.frame(a).map(|f| f.position_m);
            let at = members.point(&key, &j.at, j.at_m, default)?;
            builder.add_joint(kind, a, b, at);
            joined.push([a, b]);
        }

        let mut supported_nodes = Vec::new();
        for (i, s) in self.supports.iter().enumerate() {
            let key = format!("supports[{i}]");
            let node = members.resolve(&format!("{key}.on"), &s.on)?;
            if s.fixed.is_empty() {
                return Err(FrameFileError::invalid(
                    format!("{key}.fixed"),
                    "names no component (x, y, z, rx, ry, rz or all)",
                ));
            }
            let mut components = [false; 6];
            for c in &s.fixed {
                match c {
                    Component::All => components = [true; 6],
                    other => components[*other as usize] = true,
                }
            }
            builder.fix(node, components);
            if !supported_nodes.contains(&node) {
                supported_nodes.push(node);
            }
        }

        for (i, l) in self.loads.iter().enumerate() {
            let key = format!("loads[{i}]");
            let node = members.resolve(&format!("{key}.on"), &l.on)?;
            let force = vector(&format!("{key}.force_n"), l.force_n)?;
            let moment = vector(&format!("{key}.moment_nm"), l.moment_nm)?;
            builder.add_load(node, force, moment);
        }

        let model = builder.build()?;
        unsupported_member(&model, &joined, &supported_nodes, &members)?;
        let bodies = members
            .bodies_labels
            .into_iter()
            .zip(members.bodies_nodes)
            .collect();
        Ok(FrameFile {
            model,
            settings: self.solver,
            nodes_origins: origins,
            rods_labels: members.rods_labels,
            bodies,
            supported_nodes,
        })
    }
}

/// Refuses a frame with a rod or body that no chain of elements and joints
/// connects to a support: it could move freely, so no load has an
/// equilibrium (its stiffness is singular). Names the first such rod, or
/// body, with everything connected to it.
fn unsupported_member(
    model: &Model,
    joined: &[[NodeId; 2]],
    supported: &[NodeId],
    members: &Members,
) -> Result<(), FrameFileError> {
    let n = model.node_count();
    let mut parent: Vec<NodeId> = (0..n).collect();
    fn root(parent: &mut [NodeId], mut i: NodeId) -> NodeId {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let pairs = model
        .rods()
        .iter()
        .flat_map(|rod| rod.nodes.windows(2).map(|w| [w[0], w[1]]))
        .chain(joined.iter().copied());
    for [a, b] in pairs {
        let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
        parent[ra] = rb;
    }
    let mut held = vec![false; n];
    for &s in supported {
        let r = root(&mut parent, s);
        held[r] = true;
    }
    let loose = |node: NodeId, parent: &mut [NodeId]| !held[root(parent, node)];
    let rods = model.rods().iter().enumerate().map(|(i, rod)| {
        (
            format!("rods[{i}]"),
            format!("rod {}", members.rods_labels[i]),
            rod.start(),
        )
    });
    let bodies = members.bodies_nodes.iter().enumerate().map(|(i, &node)| {
        (
            format!("bodies[{i}]"),
            format!("body {}", members.bodies_labels[i]),
            node,
        )
    });
    for (key, label, node) in rods.chain(bodies) {
        if loose(node, &mut parent) {
            return Err(FrameFileError::invalid(
                key,
                format!(
                    "{label} is not connected to any support through rods and joints: it \
                     could move freely (add a [[supports]] or a joint to a supported member)"
                ),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The example of the module documentation, as written there.
    fn doc_example() -> String {
        let source = include_str!("frame_file.rs");
        let start = source
            .find("//! ```toml\n")
            .expect("the docs have an example");
        let end = start + source[start..].find("//! ```\n").expect("closed");
        source[start..end]
            .lines()
            .skip(1)
            .map(|l| l.strip_prefix("//!").unwrap_or(l).trim_start())
            .collect::<Vec<_>>()
            .join("\n")
    }

    #[test]
    fn documented_example_builds() {
        let file = FrameFile::from_toml(&doc_example()).unwrap();
        assert_eq!(file.rods_labels, ["left", "beam", "right"]);
        assert_eq!(file.model.element_count(), 14);
        assert_eq!(file.model.node_count(), 5 + 7 + 5 + 2);
        assert_eq!(file.model.joint_count(), 4);
        assert_eq!(file.supported_nodes.len(), 2);
        assert_eq!(file.nodes_origins.len(), file.model.node_count());
        assert_eq!(file.body("knee-right"), Some(18));
    }

    #[test]
    fn ambiguous_node_member_lists_what_is_there() {
        let text = doc_example().replace("on = { node = \"a\" }", "on = { node = \"b\" }");
        let err = FrameFile::from_toml(&text).unwrap_err();
        assert_eq!(err.key(), Some("supports[0].on.node"));
        let message = err.to_string();
        assert!(
            message.contains("rod left end") && message.contains("body knee-left"),
            "{message}"
        );
    }
}
