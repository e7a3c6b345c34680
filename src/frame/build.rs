//! Validating a parsed frame file and building it: every value checked with
//! the key at fault named, names and indices resolved to nodes, rods, bodies
//! and members, the [`Model`] built, and a rod or body that nothing holds
//! refused.

use std::collections::{BTreeMap, HashMap};

use nalgebra::Vector3;

use super::error::FrameFileError;
use super::file::{FrameFile, NodeOrigin};
use super::schema::{
    Component, RawArc, RawFile, RawJointKind, RawMember, RawOutput, RawPath, RawRecorded,
    RawSection, Ref, RodEnd,
};
use crate::mechanics::{
    CircularArc, JointKind, MechanicsError, Model, ModelBuilder, NodeId, PathSpec, PathTarget, Rod,
    RodSpec, Section, MAX_ELEMENT_ANGLE_RAD,
};

/// Most beam elements of one rod (a finer mesh buys nothing: 64 SE(3)
/// elements are exact to roundoff on the rolled-up cantilever).
pub const MAX_ROD_ELEMENTS: usize = 100_000;

/// Most beam elements of a whole frame: bounds the memory a file can ask for.
pub const MAX_FRAME_ELEMENTS: usize = 1_000_000;

fn vector(key: &str, v: [f64; 3]) -> Result<Vector3<f64>, FrameFileError> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(Vector3::from(v))
    } else {
        Err(FrameFileError::invalid(key, "a component is not finite"))
    }
}

fn nonzero(key: &str, v: [f64; 3]) -> Result<Vector3<f64>, FrameFileError> {
    let v = vector(key, v)?;
    if v.norm().is_normal() {
        Ok(v)
    } else if v.amax() > 0.0 {
        // A direction whose norm overflows (1e300) or underflows (1e-320):
        // scaled by its largest component.
        Ok(v / v.amax())
    } else {
        Err(FrameFileError::invalid(key, "must be a non-zero vector"))
    }
}

/// A rod's `up` (its section's second axis) must leave the rod's axis: one
/// along it orients no section. Given, it is refused; defaulted (`z`) on a
/// rod along `z`, it is refused when the section's two bending stiffnesses
/// differ (with equal ones the section's orientation changes nothing).
fn check_up(
    key: &str,
    label: &str,
    axis: Vector3<f64>,
    up: Vector3<f64>,
    given: bool,
    section: &Section,
) -> Result<(), FrameFileError> {
    let (a, u) = (axis / axis.amax(), up / up.amax());
    let along = a.cross(&u).norm() <= 1e-8 * a.norm() * u.norm();
    if !along || (!given && section.bending_nm2[0] == section.bending_nm2[1]) {
        return Ok(());
    }
    Err(FrameFileError::invalid(
        format!("{key}.up"),
        if given {
            format!(
                "[{}, {}, {}] is along rod \"{label}\": `up` orients the section's second axis \
                 and must leave the rod's axis",
                up[0], up[1], up[2]
            )
        } else {
            format!(
                "missing: rod \"{label}\" runs along z, the default `up`, and its bending \
                 stiffnesses differ: give the direction of the section's second axis"
            )
        },
    ))
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

/// Largest elastic modulus a frame file may give, Pa (diamond: 1.2e12).
const MAX_MODULUS_PA: f64 = 1e13;

/// Largest section stiffness (EA, GA in N; GJ, EI in N·m²): a 1 m² steel
/// section has EA = 2e11 N. Beyond it the stiffness's roundoff, `ε·EA`,
/// exceeds any load (a cantilever with EA = 1e300 'converged' undeformed).
const MAX_STIFFNESS: f64 = 1e16;

/// A positive value at most `max`.
fn bounded(key: &str, v: f64, max: f64, what: &str) -> Result<(), FrameFileError> {
    positive(key, v)?;
    if v > max {
        return Err(FrameFileError::invalid(
            key,
            format!("{v:e} is stiffer than any {what} (at most {max:e})"),
        ));
    }
    Ok(())
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
                for (name, v) in [
                    ("youngs_modulus_pa", t.youngs_modulus_pa),
                    ("shear_modulus_pa", t.shear_modulus_pa),
                ] {
                    bounded(&format!("{key}.tube.{name}"), v, MAX_MODULUS_PA, "material")?;
                }
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
                bounded(&format!("{key}.axial_n"), axial, MAX_STIFFNESS, "section")?;
                for (i, v) in shear.iter().enumerate() {
                    bounded(&format!("{key}.shear_n[{i}]"), *v, MAX_STIFFNESS, "section")?;
                }
                bounded(&format!("{key}.torsion_nm2"), torsion, MAX_STIFFNESS, "section")?;
                for (i, v) in bending.iter().enumerate() {
                    bounded(&format!("{key}.bending_nm2[{i}]"), *v, MAX_STIFFNESS, "section")?;
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

/// The circular arc of rod `key` (`rods[i]`) from `p` to `q`, checked with
/// the key at fault named: `centre_m` (with an optional `normal`) or
/// `through_m`, the ends on one circle, the normal across its plane, and
/// enough `elements` to span it at [`MAX_ELEMENT_ANGLE_RAD`] each.
fn arc(
    key: &str,
    raw: &RawArc,
    p: Vector3<f64>,
    q: Vector3<f64>,
    elements: usize,
) -> Result<CircularArc, FrameFileError> {
    let arc_key = format!("{key}.arc");
    let arc = match (raw.centre_m, raw.through_m) {
        (Some(centre), None) => CircularArc::Centre {
            centre_m: vector(&format!("{arc_key}.centre_m"), centre)?,
            normal: match raw.normal {
                Some(n) => Some(nonzero(&format!("{arc_key}.normal"), n)?),
                None => None,
            },
        },
        (None, Some(through)) => {
            if raw.normal.is_some() {
                return Err(FrameFileError::invalid(
                    format!("{arc_key}.normal"),
                    "the circle through the start, `through_m` and the end has its own \
                     normal: give `normal` only with `centre_m`",
                ));
            }
            CircularArc::Through {
                through_m: vector(&format!("{arc_key}.through_m"), through)?,
            }
        }
        (Some(_), Some(_)) => {
            return Err(FrameFileError::invalid(
                arc_key,
                "give either `centre_m` (with an optional `normal`) or `through_m`, not both",
            ))
        }
        (None, None) => {
            return Err(FrameFileError::invalid(
                arc_key,
                "missing: `centre_m` (with an optional `normal`) or `through_m`",
            ))
        }
    };
    let geometry = arc
        .geometry(p, q)
        .map_err(|e| FrameFileError::invalid(format!("{arc_key}.{}", e.input.name()), e.reason))?;
    let fewest = geometry.fewest_elements();
    if elements < fewest {
        return Err(FrameFileError::invalid(
            format!("{key}.elements"),
            format!(
                "{elements} is too few for an arc of {:.1}°: at least {fewest} (at most {:.0}° \
                 an element)",
                geometry.angle_rad.to_degrees(),
                MAX_ELEMENT_ANGLE_RAD.to_degrees()
            ),
        ));
    }
    Ok(arc)
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

/// Validates `raw` and builds it into a frame file.
pub(super) fn build(raw: RawFile) -> Result<FrameFile, FrameFileError> {
    raw.solver.validate().map_err(|e| match e {
        MechanicsError::Invalid { item, reason } => FrameFileError::invalid(item, reason),
        other => other.into(),
    })?;
    let nodes = Names::new("node", "nodes", raw.nodes.iter().map(|n| n.name.as_ref()))?;
    let nodes_positions = raw
        .nodes
        .iter()
        .enumerate()
        .map(|(i, n)| vector(&format!("nodes[{i}].position_m"), n.position_m))
        .collect::<Result<Vec<_>, _>>()?;
    let mut sections = BTreeMap::new();
    for (name, s) in &raw.sections {
        sections.insert(name.clone(), s.resolve(&format!("sections.{name}"))?);
    }

    let mut builder = ModelBuilder::new();
    let mut origins = Vec::new();
    let rods_names = Names::new("rod", "rods", raw.rods.iter().map(|r| r.name.as_ref()))?;
    let mut rods_built = Vec::with_capacity(raw.rods.len());
    let mut rods_labels = Vec::with_capacity(raw.rods.len());
    let mut located = Vec::new();
    let mut total_elements = 0usize;
    for (i, r) in raw.rods.iter().enumerate() {
        let key = format!("rods[{i}]");
        let label = r.name.clone().unwrap_or_else(|| key.clone());
        let start = nodes.resolve(&format!("{key}.start"), &r.start)?;
        let end = nodes.resolve(&format!("{key}.end"), &r.end)?;
        let (p, q) = (nodes_positions[start], nodes_positions[end]);
        if p == q {
            return Err(FrameFileError::invalid(
                format!("{key}.end"),
                format!(
                    "node {} is where the rod starts (node {}): zero length{}",
                    r.end,
                    r.start,
                    if r.arc.is_some() {
                        " (a closed circle is two arcs, joined)"
                    } else {
                        ""
                    }
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
        let arc = match &r.arc {
            Some(raw) => Some(arc(&key, raw, p, q, r.elements)?),
            None => None,
        };
        // The rod's axis at its start: along the chord, or the arc's
        // tangent (an invalid arc is the builder's error, naming it).
        let axis = match &arc {
            Some(a) => a
                .geometry(p, q)
                .ok()
                .map(|g| g.axis.cross(&(p - g.centre_m))),
            None => Some(q - p),
        };
        if let Some(axis) = axis {
            check_up(&key, &label, axis, up, r.up.is_some(), &section)?;
        }
        let rod = match &arc {
            Some(arc) => builder.add_arc_rod(p, q, arc, up, &spec),
            None => builder.add_rod(p, q, up, &spec),
        };
        origins.extend((0..rod.nodes.len()).map(|index| NodeOrigin::Rod {
            rod: label.clone(),
            index,
        }));
        located.push((format!("rod {label} start"), rod.start(), p));
        located.push((format!("rod {label} end"), rod.end(), q));
        rods_built.push(rod);
        rods_labels.push(label);
    }

    if raw.rods.is_empty() && raw.bodies.is_empty() {
        return Err(FrameFileError::invalid(
            "rods",
            "the frame has no rod and no body: nothing to solve",
        ));
    }
    let bodies_names = Names::new("body", "bodies", raw.bodies.iter().map(|b| b.name.as_ref()))?;
    let mut members = Members {
        nodes,
        nodes_positions,
        rods: rods_names,
        rods_built,
        rods_labels,
        bodies: bodies_names,
        bodies_nodes: Vec::with_capacity(raw.bodies.len()),
        bodies_labels: Vec::with_capacity(raw.bodies.len()),
        located,
    };
    for (i, b) in raw.bodies.iter().enumerate() {
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

    let mut joined = Vec::with_capacity(raw.joints.len());
    for (i, j) in raw.joints.iter().enumerate() {
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
    for (i, s) in raw.supports.iter().enumerate() {
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

    for (i, l) in raw.loads.iter().enumerate() {
        let key = format!("loads[{i}]");
        let node = members.resolve(&format!("{key}.on"), &l.on)?;
        let force = vector(&format!("{key}.force_n"), l.force_n)?;
        let moment = vector(&format!("{key}.moment_nm"), l.moment_nm)?;
        builder.add_load(node, force, moment);
    }

    let (path, recorded_labels) = path_spec(&raw.path, &raw.output, &members)?;
    let model = builder.build()?;
    unsupported_member(&model, &joined, &supported_nodes, &members)?;
    let bodies = members
        .bodies_labels
        .into_iter()
        .zip(members.bodies_nodes)
        .collect();
    Ok(FrameFile {
        model,
        settings: raw.solver,
        nodes_origins: origins,
        rods_labels: members.rods_labels,
        bodies,
        supported_nodes,
        path,
        recorded_labels,
    })
}

/// A member's label: the node's or body's name, `ROD.start`, `ROD.end`.
fn member_label(m: &RawMember) -> String {
    let label = match (&m.node, &m.rod, m.end, &m.body) {
        (Some(n), ..) => n.to_string(),
        (_, Some(r), Some(RodEnd::Start), _) => format!("{r}.start"),
        (_, Some(r), _, _) => format!("{r}.end"),
        (.., Some(b)) => b.to_string(),
        _ => "member".into(),
    };
    label.replace('"', "")
}

/// `[path]` and `[output]`: the target (default: the full load), the
/// controlled translation, the recorded nodes — each node a `[[nodes]]`
/// reference resolved to the one rod end or body there.
fn path_spec(
    raw: &RawPath,
    output: &RawOutput,
    members: &Members,
) -> Result<(PathSpec, Vec<String>), FrameFileError> {
    let node_ref = |r: &Ref| RawMember {
        node: Some(r.clone()),
        rod: None,
        end: None,
        body: None,
    };
    let target = match &raw.target {
        None => PathTarget::LoadFactor(1.0),
        Some(t) => {
            let key = "path.target";
            let given = [
                t.load_factor.is_some(),
                t.on.is_some() || t.component.is_some() || t.displacement_m.is_some(),
                t.steps.is_some(),
            ];
            if given.iter().filter(|&&g| g).count() != 1 {
                return Err(FrameFileError::invalid(
                    key,
                    "give exactly one of `load_factor`, `node` with `component` and \
                     `displacement_m`, or `steps`",
                ));
            }
            if let Some(l) = t.load_factor {
                if !(l.is_finite() && l != 0.0) {
                    return Err(FrameFileError::invalid(
                        format!("{key}.load_factor"),
                        "must be a finite number other than 0 (the start)",
                    ));
                }
                PathTarget::LoadFactor(l)
            } else if let Some(n) = t.steps {
                if n == 0 {
                    return Err(FrameFileError::invalid(
                        format!("{key}.steps"),
                        "must be at least 1",
                    ));
                }
                PathTarget::Steps(n)
            } else {
                let (Some(on), Some(component), Some(value_m)) =
                    (&t.on, t.component, t.displacement_m)
                else {
                    return Err(FrameFileError::invalid(
                        key,
                        "a displacement target needs `on`, `component` and `displacement_m`",
                    ));
                };
                if !(value_m.is_finite() && value_m != 0.0) {
                    return Err(FrameFileError::invalid(
                        format!("{key}.displacement_m"),
                        "must be a finite number other than 0 (the start)",
                    ));
                }
                PathTarget::Displacement {
                    node: members.resolve(&format!("{key}.on"), on)?,
                    component: component as usize,
                    value_m,
                }
            }
        }
    };
    let control = match &raw.control {
        None => None,
        Some(c) => Some((
            members.resolve("path.control.on", &c.on)?,
            c.component as usize,
        )),
    };
    let mut record = Vec::with_capacity(output.nodes.len());
    let mut labels = Vec::with_capacity(output.nodes.len());
    for (i, r) in output.nodes.iter().enumerate() {
        let key = format!("output.nodes[{i}]");
        let (member, label) = match r {
            RawRecorded::Node(Ref::Name(n)) => (node_ref(&Ref::Name(n.clone())), n.clone()),
            RawRecorded::Node(Ref::Index(n)) => (node_ref(&Ref::Index(*n)), format!("nodes[{n}]")),
            RawRecorded::Member(m) => (m.clone(), member_label(m)),
        };
        record.push(members.resolve(&key, &member)?);
        labels.push(label);
    }
    Ok((
        PathSpec {
            target,
            control,
            record,
        },
        labels,
    ))
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
