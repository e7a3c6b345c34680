//! VTK XML unstructured grid (`.vtu`) of a cable network, for ParaView.

use std::fmt::Write;

use crate::mechanics::Mode;
use crate::network::Network;
use crate::verify::Verification;

/// The network as a `.vtu` document: points, one line cell per cable; point data
/// `fixed` (0/1); cell data `q_n_per_m`, `group` (index into the network's
/// distinct group labels, listed in a field-data comment) and, when given,
/// `force_n`.
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
    vtu_with_vectors(network, nodes, forces_n, None)
}

/// [`network_vtu`] with a named vector point field (n_nodes × 3).
#[track_caller]
fn vtu_with_vectors(
    network: &Network,
    nodes: Option<&[[f64; 3]]>,
    forces_n: Option<&[f64]>,
    point_vectors: Option<(&str, &[[f64; 3]])>,
) -> String {
    let nodes = nodes.unwrap_or(&network.nodes);
    assert_eq!(nodes.len(), network.n_nodes(), "nodes: one row per node");
    if let Some(f) = forces_n {
        assert_eq!(f.len(), network.n_edges(), "forces_n: one entry per edge");
    }
    let (n, m) = (network.n_nodes(), network.n_edges());
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
    let fixed = network.fixed_mask();

    let mut s = String::with_capacity(64 * (n + m) + 1024);
    s.push_str("<?xml version=\"1.0\"?>\n");
    s.push_str("<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\">\n");
    let _ = writeln!(s, "<!-- groups: {} -->", labels.join(", "));
    s.push_str("<UnstructuredGrid>\n");
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
    if let Some((name, vectors)) = point_vectors {
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
    s.push_str("<DataArray type=\"Float64\" Name=\"q_n_per_m\" format=\"ascii\">\n");
    for q in &network.q {
        let _ = writeln!(s, "{q:e}");
    }
    s.push_str("</DataArray>\n<DataArray type=\"Int32\" Name=\"group\" format=\"ascii\">\n");
    for g in group_ids {
        let _ = writeln!(s, "{g}");
    }
    s.push_str("</DataArray>\n");
    if let Some(forces) = forces_n {
        s.push_str("<DataArray type=\"Float64\" Name=\"force_n\" format=\"ascii\">\n");
        for f in forces {
            let _ = writeln!(s, "{f:e}");
        }
        s.push_str("</DataArray>\n");
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
/// # Panics
/// If `mode` does not cover the truss's nodes.
pub fn assembly_vtu(
    network: &Network,
    q: &[f64],
    verification: &Verification,
    mode: Option<&Mode>,
) -> String {
    let mut combined = network.clone();
    combined.nodes = verification.nodes_xyz_m.clone();
    combined.q = q.to_vec();
    let mut groups: Vec<String> = (0..network.n_edges())
        .map(|k| network.group_of(k).to_string())
        .collect();
    let mut forces = verification.tensions_n.clone();
    for [a, b] in &verification.truss_segments_m {
        let i = combined.nodes.len();
        combined.nodes.extend([*a, *b]);
        combined.edges.push([i, i + 1]);
        combined.q.push(0.0);
        groups.push("truss".into());
        forces.push(0.0);
    }
    combined.groups = Some(groups);
    combined.loads = None;
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
    vtu_with_vectors(
        &combined,
        None,
        Some(&forces),
        mode.as_deref().map(|m| ("buckling_mode", m)),
    )
}
