//! Cable networks: nodes, cables, groups, the fixed/free split and the interchange
//! JSON format of DESIGN §10.
//!
//! A [`Network`] is plain data. [`Network::validate`] checks every invariant the
//! force density method relies on and names the offending entry when one fails,
//! so that kernels downstream may assume a consistent network.

use std::collections::VecDeque;
use std::fmt;
use std::path::Path;

use faer::sparse::{SparseColMat, Triplet};
use serde::{Deserialize, Serialize};

use crate::algebra::norm3;

/// The role of a cable in a reflector's mesh; its name is the group label of the
/// interchange format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CableGroup {
    /// Interior cables of the front (reflecting) net.
    Front,
    /// Scalloped boundary cables of the front net, between truss attachments.
    Boundary,
    /// Interior cables of the rear net.
    Rear,
    /// Boundary cables of the rear net.
    RearBoundary,
    /// Vertical tension ties joining front and rear nodes.
    Tie,
}

impl CableGroup {
    /// Every group, in the order summaries list them.
    pub const ALL: [CableGroup; 5] = [
        CableGroup::Front,
        CableGroup::Boundary,
        CableGroup::Rear,
        CableGroup::RearBoundary,
        CableGroup::Tie,
    ];

    /// The label used in files (`front`, `boundary`, `rear`, `rear_boundary`, `tie`).
    pub fn as_str(self) -> &'static str {
        match self {
            CableGroup::Front => "front",
            CableGroup::Boundary => "boundary",
            CableGroup::Rear => "rear",
            CableGroup::RearBoundary => "rear_boundary",
            CableGroup::Tie => "tie",
        }
    }
}

impl fmt::Display for CableGroup {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A pin-jointed cable network in the interchange format (DESIGN §10):
/// `{"nodes": [[x,y,z],…], "edges": [[i,j],…], "fixed": [i,…], "q": [...],
/// "loads": [[fx,fy,fz],…]?, "groups": ["front",…]?}`.
///
/// Positions of free nodes are a prescribed geometry (inverse problems) or a
/// starting guess that the forward solve ignores; positions of fixed nodes are
/// the supports.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Network {
    /// Node positions in metres: n_nodes × 3.
    pub nodes: Vec<[f64; 3]>,
    /// Cables as pairs of node indices: n_edges × 2.
    pub edges: Vec<[usize; 2]>,
    /// Indices of the fixed (supported) nodes; every other node is free.
    pub fixed: Vec<usize>,
    /// Force density of every cable in N/m: n_edges.
    pub q: Vec<f64>,
    /// External nodal loads in N: n_nodes × 3 (absent: no loads).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub loads: Option<Vec<[f64; 3]>>,
    /// Group label of every cable: n_edges (absent: one anonymous group).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub groups: Option<Vec<String>>,
}

/// An invalid or inconsistent network; every variant names the entry at fault.
#[derive(Debug, thiserror::Error)]
pub enum NetworkError {
    /// Reading the file failed.
    #[error("reading {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// The file is not valid JSON of the interchange format.
    #[error("{path}: {source}")]
    Json {
        /// The file.
        path: String,
        /// The cause, with line and column.
        source: serde_json::Error,
    },
    /// A per-node or per-edge array has the wrong length.
    #[error("`{field}` has {found} entries but the network has {expected} {per}")]
    Length {
        /// The field.
        field: &'static str,
        /// Its length.
        found: usize,
        /// The expected length.
        expected: usize,
        /// "nodes" or "edges".
        per: &'static str,
    },
    /// A coordinate, load or force density is NaN or infinite.
    #[error("`{field}[{index}]` is not finite")]
    NotFinite {
        /// The field.
        field: &'static str,
        /// The entry.
        index: usize,
    },
    /// An edge refers to a node that does not exist.
    #[error("`edges[{edge}]` refers to node {node}, but the network has {n_nodes} nodes")]
    EdgeOutOfRange {
        /// The edge.
        edge: usize,
        /// The index found.
        node: usize,
        /// The number of nodes.
        n_nodes: usize,
    },
    /// An edge joins a node to itself.
    #[error("`edges[{edge}]` joins node {node} to itself (a zero-length cable)")]
    SelfLoop {
        /// The edge.
        edge: usize,
        /// The node.
        node: usize,
    },
    /// A fixed index refers to a node that does not exist.
    #[error("`fixed[{index}]` = {node}, but the network has {n_nodes} nodes")]
    FixedOutOfRange {
        /// Position in `fixed`.
        index: usize,
        /// The index found.
        node: usize,
        /// The number of nodes.
        n_nodes: usize,
    },
    /// A node is listed twice in `fixed`.
    #[error("`fixed` lists node {node} twice")]
    FixedTwice {
        /// The node.
        node: usize,
    },
    /// No node or no cable.
    #[error("the network is empty: {nodes} nodes, {edges} cables")]
    Empty {
        /// Its nodes.
        nodes: usize,
        /// Its cables.
        edges: usize,
    },
    /// Every node is fixed: nothing to solve for.
    #[error("all {nodes} nodes are fixed: the network has no free node to find")]
    NoFreeNode {
        /// Its nodes.
        nodes: usize,
    },
    /// Two cables join the same two nodes.
    #[error(
        "`edges[{first}]` and `edges[{second}]` both join nodes {i} and {j}{}: \
         one cable per pair of nodes",
        if *.reversed { " (the second reversed)" } else { "" }
    )]
    DuplicateEdge {
        /// The first cable.
        first: usize,
        /// The second.
        second: usize,
        /// Its nodes, as the first lists them.
        i: usize,
        /// The other.
        j: usize,
        /// The second lists them the other way round.
        reversed: bool,
    },
    /// Two nodes at the same position.
    #[error("fixed nodes {first} and {second} are at the same position {position:?} m")]
    CoincidentNodes {
        /// The first node.
        first: usize,
        /// The second.
        second: usize,
        /// Where.
        position: [f64; 3],
    },
    /// A force density too small to be a normal double.
    #[error(
        "`q[{edge}]` = {value:e} is subnormal: force densities must be at least \
         {:e} N/m (the smallest normal double), below which they carry no precision",
        f64::MIN_POSITIVE
    )]
    SubnormalQ {
        /// The edge.
        edge: usize,
        /// The value found.
        value: f64,
    },
    /// Force densities spread beyond what double precision can balance.
    #[error(
        "force densities span {ratio:.1e} (`q[{min_edge}]` = {min:e}, `q[{max_edge}]` = {max:e} \
         N/m), beyond the 1/ε = 4.5e15 of double precision: a cable's force vanishes in the \
         rounding of its neighbours'"
    )]
    QSpread {
        /// The cable with the smallest force density.
        min_edge: usize,
        /// Its force density.
        min: f64,
        /// The cable with the largest.
        max_edge: usize,
        /// Its force density.
        max: f64,
        /// `max/min`.
        ratio: f64,
    },
    /// A force density is zero or negative.
    #[error("`q[{edge}]` = {value}: force densities must be > 0")]
    NonPositiveQ {
        /// The edge.
        edge: usize,
        /// The value found.
        value: f64,
    },
    /// Free nodes with no path of cables to a fixed node: `D` would be singular.
    #[error(
        "free nodes {} are not connected to any fixed node ({count} in all): \
         their equilibrium is undetermined",
        list_some(.nodes)
    )]
    Unanchored {
        /// The first few such nodes.
        nodes: Vec<usize>,
        /// How many there are.
        count: usize,
    },
}

/// The first two of the nodes `among` at exactly the same position
/// (bitwise, with −0 as +0), in the order of `among`.
pub fn coincident_nodes(nodes: &[[f64; 3]], among: &[usize]) -> Option<(usize, usize)> {
    let key = |p: &[f64; 3]| p.map(|c| (c + 0.0).to_bits());
    let mut places = std::collections::HashMap::with_capacity(among.len());
    among
        .iter()
        .find_map(|&i| places.insert(key(&nodes[i]), i).map(|first| (first, i)))
}

/// The first cable that joins the same two nodes as an earlier one (either
/// way round): `(first, second)`, `second` the smallest such index and
/// `first` the earliest cable of its pair. Each cable is filed under its
/// lower node (a counting sort), and each node's few cables sorted: linear
/// in the cables, with no hashing (a third of a 10⁵-node `fdm`'s validation
/// went into a hash map here). Every node must be below `n`.
fn duplicate_edge(edges: &[[usize; 2]], n: usize) -> Option<(usize, usize)> {
    let mut start = vec![0usize; n + 1];
    for &[i, j] in edges {
        start[i.min(j) + 1] += 1;
    }
    for k in 0..n {
        start[k + 1] += start[k];
    }
    let mut fill = start.clone();
    let mut under = vec![(0usize, 0usize); edges.len()];
    for (edge, &[i, j]) in edges.iter().enumerate() {
        let low = i.min(j);
        under[fill[low]] = (i.max(j), edge);
        fill[low] += 1;
    }
    let mut found: Option<(usize, usize)> = None;
    for k in 0..n {
        let cables = &mut under[start[k]..start[k + 1]];
        cables.sort_unstable();
        for pair in cables.windows(2) {
            if pair[0].0 == pair[1].0 && found.is_none_or(|(_, second)| pair[1].1 < second) {
                found = Some((pair[0].1, pair[1].1));
            }
        }
    }
    found
}

/// At most this many offending nodes are listed in an error.
const LISTED: usize = 10;

fn list_some(nodes: &[usize]) -> String {
    let shown: Vec<String> = nodes.iter().map(usize::to_string).collect();
    shown.join(", ")
}

impl Network {
    /// Reads and validates a network in the interchange format.
    pub fn read_json(path: &Path) -> Result<Network, NetworkError> {
        let shown = path.display().to_string();
        let text = crate::input::read_input(path).map_err(|source| NetworkError::Io {
            path: shown.clone(),
            source,
        })?;
        let network: Network =
            serde_json::from_str(&text).map_err(|source| NetworkError::Json {
                path: shown,
                source,
            })?;
        network.validate()?;
        Ok(network)
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.nodes.len()
    }

    /// Number of cables.
    pub fn n_edges(&self) -> usize {
        self.edges.len()
    }

    /// `true` for the fixed nodes: n_nodes.
    ///
    /// # Panics
    /// If a fixed index is out of range (see [`Network::validate`]).
    pub fn fixed_mask(&self) -> Vec<bool> {
        let mut mask = vec![false; self.n_nodes()];
        for &i in &self.fixed {
            mask[i] = true;
        }
        mask
    }

    /// The loads, or zeros when the network has none: n_nodes × 3.
    pub fn loads_or_zero(&self) -> Vec<[f64; 3]> {
        self.loads
            .clone()
            .unwrap_or_else(|| vec![[0.0; 3]; self.n_nodes()])
    }

    /// Checks every invariant the force density method relies on: array lengths,
    /// finite values, indices in range, no self-loops, `q > 0`, and a cable path from
    /// every free node to a fixed node (which makes `D = C_fᵀ Q C_f` positive
    /// definite, DESIGN §3).
    pub fn validate(&self) -> Result<(), NetworkError> {
        let n = self.n_nodes();
        let m = self.n_edges();
        let lengths = [
            ("q", self.q.len(), m, "edges"),
            ("loads", self.loads.as_ref().map_or(n, Vec::len), n, "nodes"),
            (
                "groups",
                self.groups.as_ref().map_or(m, Vec::len),
                m,
                "edges",
            ),
        ];
        for (field, found, expected, per) in lengths {
            if found != expected {
                return Err(NetworkError::Length {
                    field,
                    found,
                    expected,
                    per,
                });
            }
        }
        if n == 0 || m == 0 {
            return Err(NetworkError::Empty { nodes: n, edges: m });
        }
        let not_finite = |v: &[f64; 3]| v.iter().any(|c| !c.is_finite());
        if let Some(index) = self.nodes.iter().position(not_finite) {
            return Err(NetworkError::NotFinite {
                field: "nodes",
                index,
            });
        }
        if let Some(index) = self.loads.iter().flatten().position(not_finite) {
            return Err(NetworkError::NotFinite {
                field: "loads",
                index,
            });
        }
        for (edge, &[i, j]) in self.edges.iter().enumerate() {
            for node in [i, j] {
                if node >= n {
                    return Err(NetworkError::EdgeOutOfRange {
                        edge,
                        node,
                        n_nodes: n,
                    });
                }
            }
            if i == j {
                return Err(NetworkError::SelfLoop { edge, node: i });
            }
        }
        let mut seen = vec![false; n];
        for (index, &node) in self.fixed.iter().enumerate() {
            if node >= n {
                return Err(NetworkError::FixedOutOfRange {
                    index,
                    node,
                    n_nodes: n,
                });
            }
            if std::mem::replace(&mut seen[node], true) {
                return Err(NetworkError::FixedTwice { node });
            }
        }
        if self.fixed.len() == n {
            return Err(NetworkError::NoFreeNode { nodes: n });
        }
        if let Some((first, second)) = duplicate_edge(&self.edges, n) {
            let [a, b] = self.edges[first];
            return Err(NetworkError::DuplicateEdge {
                first,
                second,
                i: a,
                j: b,
                reversed: a != self.edges[second][0],
            });
        }
        // Two supports at one point (the free nodes' positions are only a
        // start for the forward solve; a prescribed geometry checks them all:
        // `coincident_nodes`).
        if let Some((first, second)) = coincident_nodes(&self.nodes, &self.fixed) {
            return Err(NetworkError::CoincidentNodes {
                first,
                second,
                position: self.nodes[first],
            });
        }
        for (edge, &value) in self.q.iter().enumerate() {
            if !value.is_finite() {
                return Err(NetworkError::NotFinite {
                    field: "q",
                    index: edge,
                });
            }
            if value <= 0.0 {
                return Err(NetworkError::NonPositiveQ { edge, value });
            }
            if value < f64::MIN_POSITIVE {
                return Err(NetworkError::SubnormalQ { edge, value });
            }
        }
        let by_q = |a: &(usize, &f64), b: &(usize, &f64)| a.1.total_cmp(b.1);
        if let (Some((min_edge, &min)), Some((max_edge, &max))) = (
            self.q.iter().enumerate().min_by(by_q),
            self.q.iter().enumerate().max_by(by_q),
        ) {
            if max / min > 1.0 / f64::EPSILON {
                return Err(NetworkError::QSpread {
                    min_edge,
                    min,
                    max_edge,
                    max,
                    ratio: max / min,
                });
            }
        }
        let unanchored = self.unanchored_nodes();
        if !unanchored.is_empty() {
            return Err(NetworkError::Unanchored {
                count: unanchored.len(),
                nodes: unanchored.into_iter().take(LISTED).collect(),
            });
        }
        Ok(())
    }

    /// Free nodes from which no chain of cables reaches a fixed node, ascending.
    fn unanchored_nodes(&self) -> Vec<usize> {
        let n = self.n_nodes();
        let mut adjacency_start = vec![0usize; n + 1];
        for &[i, j] in &self.edges {
            adjacency_start[i + 1] += 1;
            adjacency_start[j + 1] += 1;
        }
        for k in 0..n {
            adjacency_start[k + 1] += adjacency_start[k];
        }
        let mut fill = adjacency_start.clone();
        let mut adjacency = vec![0usize; 2 * self.n_edges()];
        for &[i, j] in &self.edges {
            adjacency[fill[i]] = j;
            fill[i] += 1;
            adjacency[fill[j]] = i;
            fill[j] += 1;
        }
        let mut reached = self.fixed_mask();
        let mut queue: VecDeque<usize> = self.fixed.iter().copied().collect();
        while let Some(i) = queue.pop_front() {
            for &j in &adjacency[adjacency_start[i]..adjacency_start[i + 1]] {
                if !std::mem::replace(&mut reached[j], true) {
                    queue.push_back(j);
                }
            }
        }
        (0..n).filter(|&i| !reached[i]).collect()
    }

    /// The branch–node matrix `C` (n_edges × n_nodes): `C[k, i] = +1`,
    /// `C[k, j] = −1` for cable `k = (i, j)` (paper eq. 1). Edge vectors are
    /// `u = C x` per coordinate.
    pub fn branch_node_matrix(&self) -> SparseColMat<usize, f64> {
        let triplets: Vec<Triplet<usize, usize, f64>> = self
            .edges
            .iter()
            .enumerate()
            .flat_map(|(k, &[i, j])| [Triplet::new(k, i, 1.0), Triplet::new(k, j, -1.0)])
            .collect();
        SparseColMat::try_new_from_triplets(self.n_edges(), self.n_nodes(), &triplets)
            .expect("valid edges give a valid branch-node matrix")
    }

    /// Edge vectors `u_k = x_i − x_j` of the current node positions: n_edges × 3.
    pub fn edges_vectors(&self) -> Vec<[f64; 3]> {
        edges_vectors(&self.edges, &self.nodes)
    }
}

/// What a network holds, for a person to read: node and cable counts, cables per
/// group, the shortest and longest cable.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NetworkSummary {
    /// Number of free nodes.
    pub free_nodes: usize,
    /// Number of fixed nodes.
    pub fixed_nodes: usize,
    /// Cables per group label, in order of first appearance (`all` without groups).
    pub cables_per_group: Vec<(String, usize)>,
    /// Shortest cable: (edge, group, length in m).
    pub shortest: Option<(usize, String, f64)>,
    /// Longest cable: (edge, group, length in m).
    pub longest: Option<(usize, String, f64)>,
}

impl Network {
    /// The group label of cable `edge` (`all` when the network has no groups).
    pub fn group_of(&self, edge: usize) -> &str {
        self.groups.as_ref().map_or("all", |g| g[edge].as_str())
    }

    /// Counts and extreme cable lengths of the network at its node positions.
    pub fn summary(&self) -> NetworkSummary {
        let mut cables_per_group: Vec<(String, usize)> = Vec::new();
        for k in 0..self.n_edges() {
            let group = self.group_of(k);
            match cables_per_group.iter_mut().find(|(g, _)| g == group) {
                Some((_, count)) => *count += 1,
                None => cables_per_group.push((group.to_string(), 1)),
            }
        }
        let lengths: Vec<f64> = self.edges_vectors().into_iter().map(norm3).collect();
        let pick = |better: fn(f64, f64) -> bool| {
            let mut best: Option<usize> = None;
            for (k, &l) in lengths.iter().enumerate() {
                if best.is_none_or(|b| better(l, lengths[b])) {
                    best = Some(k);
                }
            }
            best.map(|k| (k, self.group_of(k).to_string(), lengths[k]))
        };
        NetworkSummary {
            free_nodes: self.n_nodes() - self.fixed.len(),
            fixed_nodes: self.fixed.len(),
            cables_per_group,
            shortest: pick(|a, b| a < b),
            longest: pick(|a, b| a > b),
        }
    }
}

impl fmt::Display for NetworkSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "nodes: {} ({} free, {} fixed)",
            self.free_nodes + self.fixed_nodes,
            self.free_nodes,
            self.fixed_nodes
        )?;
        let total: usize = self.cables_per_group.iter().map(|(_, c)| c).sum();
        let per: Vec<String> = self
            .cables_per_group
            .iter()
            .map(|(g, c)| format!("{g} {c}"))
            .collect();
        writeln!(f, "cables: {total} ({})", per.join(", "))?;
        for (name, extreme) in [("shortest", &self.shortest), ("longest", &self.longest)] {
            if let Some((k, group, length)) = extreme {
                writeln!(f, "{name} cable: {length:.6} m (cable {k}, {group})")?;
            }
        }
        Ok(())
    }
}

/// Edge vectors `u_k = x_i − x_j` for cables `k = (i, j)`: n_edges × 3.
pub(crate) fn edges_vectors(edges: &[[usize; 2]], nodes: &[[f64; 3]]) -> Vec<[f64; 3]> {
    edges
        .iter()
        .map(|&[i, j]| {
            let (a, b) = (nodes[i], nodes[j]);
            [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangle() -> Network {
        Network {
            nodes: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            edges: vec![[0, 1], [1, 2], [2, 0]],
            fixed: vec![0, 1],
            q: vec![1.0; 3],
            loads: None,
            groups: None,
        }
    }

    #[test]
    fn valid_network_passes() {
        triangle().validate().unwrap();
    }

    #[test]
    fn edge_out_of_range_is_named() {
        let mut net = triangle();
        net.edges[1] = [1, 7];
        let err = net.validate().unwrap_err().to_string();
        assert!(err.contains("edges[1]") && err.contains('7'), "{err}");
    }

    #[test]
    fn non_positive_q_is_named() {
        let mut net = triangle();
        net.q[2] = 0.0;
        let err = net.validate().unwrap_err().to_string();
        assert!(err.contains("q[2]"), "{err}");
    }

    /// The sorted search finds the pair a scan in cable order with a hash
    /// map finds: the earliest cable that repeats a pair, with the pair's
    /// first cable (triples, both orientations, several pairs).
    #[test]
    fn duplicate_edge_is_the_first_repeat_in_cable_order() {
        let by_scan = |edges: &[[usize; 2]]| {
            let mut seen = std::collections::HashMap::new();
            edges.iter().enumerate().find_map(|(k, &[i, j])| {
                let key = (i.min(j), i.max(j));
                match seen.get(&key) {
                    Some(&first) => Some((first, k)),
                    None => {
                        seen.insert(key, k);
                        None
                    }
                }
            })
        };
        let mut state = 12345u64;
        let mut next = |m: usize| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) as usize % m
        };
        for _ in 0..200 {
            let n = 3 + next(12);
            let edges: Vec<[usize; 2]> = (0..1 + next(30))
                .map(|_| {
                    let i = next(n);
                    [i, (i + 1 + next(n - 1)) % n]
                })
                .collect();
            assert_eq!(duplicate_edge(&edges, n), by_scan(&edges), "{edges:?}");
        }
        assert_eq!(duplicate_edge(&[[0, 1], [1, 2]], 3), None);
        assert_eq!(
            duplicate_edge(&[[2, 3], [0, 1], [1, 0], [3, 2], [0, 1]], 4),
            Some((1, 2))
        );
    }

    /// Issue 19, item 8 and the honest-number items: each refused, naming
    /// what is at fault.
    #[test]
    fn degenerate_networks_are_refused_naming_the_culprits() {
        let refused = |net: Network| net.validate().unwrap_err();
        let mut dup = triangle();
        dup.edges.push([1, 0]);
        dup.q.push(1.0);
        assert!(matches!(
            refused(dup),
            NetworkError::DuplicateEdge {
                first: 0,
                second: 3,
                i: 0,
                j: 1,
                reversed: true
            }
        ));
        let mut same = triangle();
        same.nodes[1] = [0.0, -0.0, 0.0];
        assert!(matches!(
            refused(same),
            NetworkError::CoincidentNodes {
                first: 0,
                second: 1,
                ..
            }
        ));
        // A free node's position is only the forward solve's start.
        let mut start = triangle();
        start.nodes[2] = start.nodes[0];
        start.validate().unwrap();
        let mut all = triangle();
        all.fixed = vec![0, 1, 2];
        assert!(matches!(
            refused(all),
            NetworkError::NoFreeNode { nodes: 3 }
        ));
        let empty = Network {
            nodes: vec![],
            edges: vec![],
            fixed: vec![],
            q: vec![],
            loads: None,
            groups: None,
        };
        assert!(matches!(refused(empty), NetworkError::Empty { .. }));
        let mut tiny = triangle();
        tiny.q[1] = 5e-324;
        assert!(matches!(
            refused(tiny),
            NetworkError::SubnormalQ { edge: 1, .. }
        ));
        let mut spread = triangle();
        spread.q[2] = 1e16;
        let e = refused(spread);
        assert!(
            matches!(
                e,
                NetworkError::QSpread {
                    min_edge: 0,
                    max_edge: 2,
                    ..
                }
            ),
            "{e}"
        );
        // Within double precision's reach: accepted.
        let mut wide = triangle();
        wide.q[2] = 1e15;
        wide.validate().unwrap();
    }

    #[test]
    fn unanchored_free_node_is_named() {
        let mut net = triangle();
        net.nodes.push([5.0, 5.0, 0.0]);
        net.nodes.push([6.0, 5.0, 0.0]);
        net.edges.push([3, 4]);
        net.q.push(1.0);
        match net.validate().unwrap_err() {
            NetworkError::Unanchored { nodes, count } => {
                assert_eq!((nodes, count), (vec![3, 4], 2));
            }
            other => panic!("unexpected {other}"),
        }
    }

    #[test]
    fn branch_node_matrix_gives_edge_vectors() {
        let net = triangle();
        let c = net.branch_node_matrix();
        let x = faer::Col::<f64>::from_fn(3, |i| net.nodes[i][0]);
        let u = &c * &x;
        for (k, v) in net.edges_vectors().iter().enumerate() {
            assert_eq!(u[k], v[0]);
        }
    }
}
