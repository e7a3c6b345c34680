//! The TOML syntax of a frame file, as serde reads it: one struct per table,
//! unknown keys rejected. Nothing here is validated; [`super::build`] does
//! that, naming the key at fault.

use std::collections::BTreeMap;
use std::fmt;

use serde::Deserialize;

use crate::mechanics::{ElementKind, StaticSettings};

/// A reference to a node, rod or body: its name or its index.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(untagged)]
pub(super) enum Ref {
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
pub(super) struct RawFile {
    #[serde(default)]
    pub(super) nodes: Vec<RawNode>,
    #[serde(default)]
    pub(super) sections: BTreeMap<String, RawSection>,
    #[serde(default)]
    pub(super) rods: Vec<RawRod>,
    #[serde(default)]
    pub(super) bodies: Vec<RawBody>,
    #[serde(default)]
    pub(super) joints: Vec<RawJoint>,
    #[serde(default)]
    pub(super) supports: Vec<RawSupport>,
    #[serde(default)]
    pub(super) loads: Vec<RawLoad>,
    #[serde(default)]
    pub(super) solver: StaticSettings,
    #[serde(default)]
    pub(super) path: RawPath,
    #[serde(default)]
    pub(super) output: RawOutput,
}

/// A translation component.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub(super) enum Axis {
    X,
    Y,
    Z,
}

/// `[path]`: where the path ends and what drives displacement control.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawPath {
    pub(super) target: Option<RawTarget>,
    pub(super) control: Option<RawControl>,
}

/// `target = { load_factor = … }`, `{ on = MEMBER, component = …,
/// displacement_m = … }` or `{ steps = … }`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawTarget {
    pub(super) load_factor: Option<f64>,
    pub(super) on: Option<RawMember>,
    pub(super) component: Option<Axis>,
    pub(super) displacement_m: Option<f64>,
    pub(super) steps: Option<usize>,
}

/// `control = { on = MEMBER, component = … }`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawControl {
    pub(super) on: RawMember,
    pub(super) component: Axis,
}

/// A recorded node: a `[[nodes]]` reference (the one member there) or a
/// member.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
pub(super) enum RawRecorded {
    Node(Ref),
    Member(RawMember),
}

/// `[output]`: the nodes whose displacements the path records.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawOutput {
    #[serde(default)]
    pub(super) nodes: Vec<RawRecorded>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawNode {
    pub(super) name: Option<String>,
    pub(super) position_m: [f64; 3],
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Tube {
    pub(super) outer_diameter_m: f64,
    pub(super) inner_diameter_m: f64,
    pub(super) youngs_modulus_pa: f64,
    pub(super) shear_modulus_pa: f64,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSection {
    pub(super) tube: Option<Tube>,
    pub(super) axial_n: Option<f64>,
    pub(super) shear_n: Option<[f64; 2]>,
    pub(super) torsion_nm2: Option<f64>,
    pub(super) bending_nm2: Option<[f64; 2]>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRod {
    pub(super) name: Option<String>,
    pub(super) start: Ref,
    pub(super) end: Ref,
    pub(super) section: Option<String>,
    pub(super) tube: Option<Tube>,
    pub(super) axial_n: Option<f64>,
    pub(super) shear_n: Option<[f64; 2]>,
    pub(super) torsion_nm2: Option<f64>,
    pub(super) bending_nm2: Option<[f64; 2]>,
    #[serde(default = "one")]
    pub(super) elements: usize,
    #[serde(default)]
    pub(super) element: ElementKind,
    pub(super) up: Option<[f64; 3]>,
    pub(super) arc: Option<RawArc>,
}

/// A rod's circular arc: `centre_m` (with an optional `normal`) or `through_m`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawArc {
    pub(super) centre_m: Option<[f64; 3]>,
    pub(super) normal: Option<[f64; 3]>,
    pub(super) through_m: Option<[f64; 3]>,
}

fn one() -> usize {
    1
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBody {
    pub(super) name: Option<String>,
    pub(super) at: Option<Ref>,
    pub(super) at_m: Option<[f64; 3]>,
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub(super) enum RodEnd {
    Start,
    End,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawMember {
    pub(super) node: Option<Ref>,
    pub(super) rod: Option<Ref>,
    pub(super) end: Option<RodEnd>,
    pub(super) body: Option<Ref>,
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(super) enum RawJointKind {
    Fixed,
    Revolute,
    Spherical,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawJoint {
    pub(super) kind: RawJointKind,
    pub(super) a: RawMember,
    pub(super) b: RawMember,
    pub(super) axis: Option<[f64; 3]>,
    pub(super) at: Option<Ref>,
    pub(super) at_m: Option<[f64; 3]>,
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(super) enum Component {
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
pub(super) struct RawSupport {
    pub(super) on: RawMember,
    pub(super) fixed: Vec<Component>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawLoad {
    pub(super) on: RawMember,
    #[serde(default)]
    pub(super) force_n: [f64; 3],
    #[serde(default)]
    pub(super) moment_nm: [f64; 3],
}
