//! VTK XML unstructured grid (`.vtu`) of a cable network, for ParaView.
//!
//! Every array is ASCII. Group names travel as field data: a `String`
//! array `group_names` whose entry `k` names the cells of `group == k`. VTK
//! XML has no categorical type; its readers (`vtkXMLReader`, ParaView's)
//! read a `String` array in ASCII as the bytes of each string written as
//! integers, each string ended by a 0, and read one under `<FieldData>` into
//! the data set's field data (ParaView: *Information*, *Spreadsheet View*
//! with *Field Data*). Colouring needs a numeric array, so the cells keep
//! the integer `group` (ParaView: *Interpret Values As Categories*, the
//! names from `group_names`); a string array per cell would not colour.

use std::fmt::Write;

use crate::geometry::ReflectorMesh;
use crate::mechanics::Mode;
use crate::network::Network;
use crate::scene::Cables;
use crate::surface::PlacedParaboloid;
use crate::uniformity::Design;
use crate::verify::Verification;

/// The network as a `.vtu` document: points, one line cell per cable; point data
/// `fixed` (0/1); cell data `q_n_per_m`, `group` (index into the field data
/// `group_names`, the network's distinct group labels in order of first
/// appearance) and, when given, `force_n`.
///
/// `nodes` (n_nodes × 3) overrides the network's positions (an equilibrium
/// shape, say); `forces_n` is n_edges.
///
/// # Panics
/// If `nodes` or `forces_n` do not match the network's shape.
#[track_caller]
pub fn network_vtu(
    network: &Network,
    nodes: Option<&[[f64; 3]]>,
    forces_n: Option<&[f64]>,
) -> String {
    let fields = Fields {
        forces_n,
        ..Fields::default()
    };
    vtu_with_fields(network, nodes, &fields)
}

/// The optional arrays of a `.vtu` beyond positions, `fixed`, `q_n_per_m`
/// and `group`.
#[derive(Default)]
struct Fields<'a> {
    /// Cell data `force_n` (n_edges).
    forces_n: Option<&'a [f64]>,
    /// Named scalar point fields (n_nodes each).
    point_scalars: Vec<(&'static str, &'a [f64])>,
    /// A named vector point field (n_nodes × 3).
    point_vectors: Option<(&'static str, &'a [[f64; 3]])>,
    /// Named scalar cell fields (n_edges each).
    cell_scalars: Vec<(&'static str, &'a [f64])>,
}

/// One string of an ASCII `String` array of VTK XML: its bytes as integers,
/// then the 0 that ends it.
fn vtk_ascii_string(s: &str) -> String {
    let mut codes: Vec<String> = s.bytes().map(|b| b.to_string()).collect();
    codes.push("0".into());
    codes.join(" ")
}

/// A scalar `Float64` data array, one value a line.
fn push_scalars(s: &mut String, name: &str, values: &[f64]) {
    let _ = writeln!(
        s,
        "<DataArray type=\"Float64\" Name=\"{name}\" format=\"ascii\">"
    );
    for v in values {
        let _ = writeln!(s, "{v:e}");
    }
    s.push_str("</DataArray>\n");
}

/// [`network_vtu`] with the optional arrays `fields`.
#[track_caller]
fn vtu_with_fields(network: &Network, nodes: Option<&[[f64; 3]]>, fields: &Fields<'_>) -> String {
    let nodes = nodes.unwrap_or(&network.nodes);
    assert_eq!(nodes.len(), network.n_nodes(), "nodes: one row per node");
    let (n, m) = (network.n_nodes(), network.n_edges());
    if let Some(f) = fields.forces_n {
        assert_eq!(f.len(), m, "forces_n: one entry per edge");
    }
    for (name, values) in &fields.point_scalars {
        assert_eq!(values.len(), n, "{name}: one entry per node");
    }
    for (name, values) in &fields.cell_scalars {
        assert_eq!(values.len(), m, "{name}: one entry per edge");
    }
    let mut labels: Vec<&str> = Vec::new();
    let group_ids: Vec<usize> = match &network.groups {
        Some(groups) => groups
            .iter()
            .map(|g| match labels.iter().position(|l| l == g) {
                Some(i) => i,
                None => {
                    labels.push(g);
                    labels.len() - 1
                }
            })
            .collect(),
        None => vec![0; m],
    };
    if network.groups.is_none() {
        labels.push(network.group_of(0));
    }
    let fixed = network.fixed_mask();

    let mut s = String::with_capacity(64 * (n + m) + 1024);
    s.push_str("<?xml version=\"1.0\"?>\n");
    s.push_str("<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\">\n");
    let _ = writeln!(s, "<!-- groups: {} -->", labels.join(", "));
    s.push_str("<UnstructuredGrid>\n<FieldData>\n");
    let _ = writeln!(
        s,
        "<DataArray type=\"String\" Name=\"group_names\" NumberOfTuples=\"{}\" format=\"ascii\">",
        labels.len()
    );
    for label in &labels {
        let _ = writeln!(s, "{}", vtk_ascii_string(label));
    }
    s.push_str("</DataArray>\n</FieldData>\n");
    let _ = writeln!(s, "<Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{m}\">");
    s.push_str(
        "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n",
    );
    for p in nodes {
        let _ = writeln!(s, "{:e} {:e} {:e}", p[0], p[1], p[2]);
    }
    s.push_str("</DataArray>\n</Points>\n<Cells>\n");
    s.push_str("<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for [i, j] in &network.edges {
        let _ = writeln!(s, "{i} {j}");
    }
    s.push_str("</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for k in 1..=m {
        let _ = writeln!(s, "{}", 2 * k);
    }
    s.push_str("</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    for _ in 0..m {
        s.push_str("3\n");
    }
    s.push_str("</DataArray>\n</Cells>\n<PointData>\n");
    s.push_str("<DataArray type=\"UInt8\" Name=\"fixed\" format=\"ascii\">\n");
    for f in fixed {
        s.push_str(if f { "1\n" } else { "0\n" });
    }
    s.push_str("</DataArray>\n");
    for (name, values) in &fields.point_scalars {
        push_scalars(&mut s, name, values);
    }
    if let Some((name, vectors)) = fields.point_vectors {
        assert_eq!(vectors.len(), n, "{name}: one row per node");
        let _ = writeln!(
            s,
            "<DataArray type=\"Float64\" Name=\"{name}\" NumberOfComponents=\"3\" format=\"ascii\">"
        );
        for v in vectors {
            let _ = writeln!(s, "{:e} {:e} {:e}", v[0], v[1], v[2]);
        }
        s.push_str("</DataArray>\n");
    }
    s.push_str("</PointData>\n<CellData>\n");
    push_scalars(&mut s, "q_n_per_m", &network.q);
    s.push_str("<DataArray type=\"Int32\" Name=\"group\" format=\"ascii\">\n");
    for g in group_ids {
        let _ = writeln!(s, "{g}");
    }
    s.push_str("</DataArray>\n");
    if let Some(forces) = fields.forces_n {
        push_scalars(&mut s, "force_n", forces);
    }
    for (name, values) in &fields.cell_scalars {
        push_scalars(&mut s, name, values);
    }
    s.push_str("</CellData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    s
}

/// The assembled model as one `.vtu`: the net at its assembled positions (its
/// cables carry `q_n_per_m` and the assembled `force_n`) and the deformed
/// truss as line cells of group `truss` (q and force 0). With the truss's
/// buckling `mode` (its model's nodes, [`crate::mechanics::LimitSearch::mode`]),
/// the point field `buckling_mode` holds it on the truss (zero on the net):
/// ParaView's *Warp By Vector* shows it.
///
/// Two fields to colour by:
/// * point data `deviation_mm`: the axial deviation δz of each front-net
///   node as built from the design paraboloid, mm, positive towards the
///   focus ([`PlacedParaboloid::deviation`], the deviation the design's
///   node RMS `rms_mm` is of); 0 on the rear net's nodes and the truss's,
///   which are not meant to lie on the paraboloid;
/// * cell data `cut_length_m`: each cable's unstressed length to cut,
///   `L0 = ℓ/(1 + T/EA)` of `design`'s length and tension, as in
///   `cables.csv`; 0 on the truss's cells, which are no cables.
///
/// `design` is the net's design (`q`, lengths, tensions: n_edges),
/// `verification` its assembly on the truss.
///
/// # Panics
/// If `design` is not of `network`, or `mode` does not cover the truss's
/// nodes.
#[track_caller]
pub fn assembly_vtu(
    network: &Network,
    mesh: &ReflectorMesh,
    design: &Design,
    cables: &Cables,
    verification: &Verification,
    mode: Option<&Mode>,
) -> String {
    let m = network.n_edges();
    assert_eq!(design.q.len(), m, "design of another network");
    let mut combined = network.clone();
    combined.nodes = verification.nodes_xyz_m.clone();
    combined.q = design.q.clone();
    let mut groups: Vec<String> = (0..m).map(|k| network.group_of(k).to_string()).collect();
    let mut forces = verification.tensions_n.clone();
    let mut cut_lengths_m: Vec<f64> = design
        .lengths_m
        .iter()
        .zip(&design.tensions_n)
        .map(|(&l, &t)| cables.cut_length_m(l, t))
        .collect();
    for [a, b] in &verification.truss_segments_m {
        let i = combined.nodes.len();
        combined.nodes.extend([*a, *b]);
        combined.edges.push([i, i + 1]);
        combined.q.push(0.0);
        groups.push("truss".into());
        forces.push(0.0);
        cut_lengths_m.push(0.0);
    }
    combined.groups = Some(groups);
    combined.loads = None;
    let surface = PlacedParaboloid::design(&mesh.paraboloid);
    let deviation_mm: Vec<f64> = combined
        .nodes
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            if i < mesh.n_front_nodes {
                1e3 * surface.deviation(p).axial_m
            } else {
                0.0
            }
        })
        .collect();
    let mode = mode.map(|mode| {
        let shape = mode.translations_m();
        let mut field = vec![[0.0; 3]; network.n_nodes()];
        field.extend(
            verification
                .truss_segment_nodes
                .iter()
                .flat_map(|&[a, b]| [shape[a], shape[b]]),
        );
        field
    });
    let fields = Fields {
        forces_n: Some(&forces),
        point_scalars: vec![("deviation_mm", &deviation_mm)],
        point_vectors: mode.as_deref().map(|m| ("buckling_mode", m)),
        cell_scalars: vec![("cut_length_m", &cut_lengths_m)],
    };
    vtu_with_fields(&combined, None, &fields)
}
