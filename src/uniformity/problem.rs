//! The tension-uniformity problem (paper eq. 5, DESIGN §4), formulated once for
//! every solver: a prescribed geometry, uniformity sets, bounds, loads, and the
//! surface whose accuracy a design is judged by.

use crate::algebra::norm3;
use crate::fdm::{Equilibrium, FdmStructure};
use crate::geometry::{Paraboloid, ReflectorMesh};
use crate::network::Network;

use super::UniformityError;

/// Cables whose tensions should be uniform, with their target mean tension.
#[derive(Debug, Clone, PartialEq)]
pub struct UniformitySet {
    /// Name shown in reports: a group label, or labels joined with `+`.
    pub name: String,
    /// The cables, ascending.
    pub edges: Vec<usize>,
    /// Target mean tension, N. The first set's target fixes the pretension level
    /// of a homogeneous problem; the other sets' levels follow from equilibrium.
    pub mean_tension_n: f64,
}

impl UniformitySet {
    /// `Tmax/Tmin` of `tensions_n` (all cables) over the set's cables:
    /// infinite when one of them is slack (`T ≤ 0`).
    pub fn ratio(&self, tensions_n: &[f64]) -> f64 {
        ratio_over(&self.edges, |k| tensions_n[k])
    }
}

/// `Tmax/Tmin` over `cables` of the tensions `tension(k)`: infinite when
/// one of them is slack (`T ≤ 0`).
pub(crate) fn ratio_over(cables: &[usize], tension: impl Fn(usize) -> f64) -> f64 {
    let (lo, hi) = cables
        .iter()
        .map(|&k| tension(k))
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), t| {
            (lo.min(t), hi.max(t))
        });
    if lo > 0.0 {
        hi / lo
    } else {
        f64::INFINITY
    }
}

/// What the surface accuracy of a design is measured against.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SurfaceTarget {
    /// Vertical distance to the paraboloid (the reflector's surface error).
    Paraboloid(Paraboloid),
    /// Distance to the prescribed node positions.
    Prescribed,
}

/// The uniformity problem: find `q` with `A(x) q = p` for the prescribed
/// geometry `x`, `0 < q ≤ [q]`, minimising `Tmax/Tmin` over each uniformity set.
#[derive(Debug, Clone)]
pub struct UniformityProblem {
    network: Network,
    structure: FdmStructure,
    lengths_m: Vec<f64>,
    sets: Vec<UniformitySet>,
    surface_nodes: Vec<usize>,
    surface: SurfaceTarget,
    /// Upper bound `[q]` on every force density, N/m (paper eq. 5); may be infinite.
    pub max_force_density_n_per_m: f64,
    /// Cables outside every uniformity set keep a tension of at least this
    /// fraction of the first set's mean tension, so that `q > 0` strictly.
    pub min_tension_fraction: f64,
}

impl UniformityProblem {
    /// The problem on a network whose node positions are the prescribed geometry.
    ///
    /// `sets`: (name, cables, target mean tension) per uniformity set; every set
    /// non-empty. `surface_nodes`: the nodes whose accuracy is reported (free).
    pub fn new(
        network: Network,
        sets: Vec<UniformitySet>,
        surface_nodes: Vec<usize>,
        surface: SurfaceTarget,
        max_force_density_n_per_m: f64,
    ) -> Result<Self, UniformityError> {
        let structure = FdmStructure::new(&network)?;
        if sets.is_empty() {
            return Err(UniformityError::invalid("uniformity sets", "none given"));
        }
        for set in &sets {
            if set.edges.is_empty() {
                return Err(UniformityError::invalid(
                    format!("uniformity set `{}`", set.name),
                    "no cable",
                ));
            }
            if let Some(&k) = set.edges.iter().find(|&&k| k >= network.n_edges()) {
                return Err(UniformityError::invalid(
                    format!("uniformity set `{}`", set.name),
                    format!(
                        "names cable {k}, but the network has {} cables",
                        network.n_edges()
                    ),
                ));
            }
            if !(set.mean_tension_n.is_finite() && set.mean_tension_n > 0.0) {
                return Err(UniformityError::invalid(
                    format!("uniformity set `{}`", set.name),
                    format!("mean tension {} N must be > 0", set.mean_tension_n),
                ));
            }
        }
        if max_force_density_n_per_m.is_nan() || max_force_density_n_per_m <= 0.0 {
            return Err(UniformityError::invalid(
                "maximum force density [q]",
                format!("{max_force_density_n_per_m} N/m must be > 0"),
            ));
        }
        let lengths_m: Vec<f64> = network.edges_vectors().into_iter().map(norm3).collect();
        if let Some(k) = lengths_m.iter().position(|&l| l.is_nan() || l <= 0.0) {
            return Err(UniformityError::invalid(
                format!("cable {k} (nodes {:?})", network.edges[k]),
                "zero length in the prescribed geometry",
            ));
        }
        let every: Vec<usize> = (0..network.n_nodes()).collect();
        if let Some((a, b)) = crate::network::coincident_nodes(&network.nodes, &every) {
            return Err(UniformityError::invalid(
                format!("nodes {a} and {b}"),
                format!(
                    "both at {:?} m in the prescribed geometry",
                    network.nodes[a]
                ),
            ));
        }
        if let Some(&i) = surface_nodes
            .iter()
            .find(|&&i| structure.free_index(i).is_none())
        {
            return Err(UniformityError::invalid(
                format!("surface node {i}"),
                "not free",
            ));
        }
        Ok(UniformityProblem {
            network,
            structure,
            lengths_m,
            sets,
            surface_nodes,
            surface,
            max_force_density_n_per_m,
            min_tension_fraction: 1e-3,
        })
    }

    /// The front-net problem of a scene's mesh: uniformity over each named group
    /// (its own level; the first group's level is its scene target), the front
    /// net's free nodes judged against the paraboloid.
    pub fn from_mesh(
        mesh: &ReflectorMesh,
        groups: &[(crate::CableGroup, f64)],
        max_force_density_n_per_m: f64,
    ) -> Result<Self, UniformityError> {
        let sets = groups
            .iter()
            .map(|&(group, mean_tension_n)| UniformitySet {
                name: group.as_str().to_string(),
                edges: (0..mesh.groups.len())
                    .filter(|&k| mesh.groups[k] == group)
                    .collect(),
                mean_tension_n,
            })
            .collect();
        let fixed = mesh.network.fixed_mask();
        let surface_nodes = (0..mesh.n_front_nodes).filter(|&i| !fixed[i]).collect();
        Self::new(
            mesh.network.clone(),
            sets,
            surface_nodes,
            SurfaceTarget::Paraboloid(mesh.paraboloid),
            max_force_density_n_per_m,
        )
    }

    /// The same problem on new prescribed positions of every node (n_nodes × 3);
    /// the factorisation structure is reused.
    ///
    /// # Errors
    /// A count that does not match, a non-finite position, or a zero-length
    /// cable (named).
    pub fn with_positions(&self, nodes_m: Vec<[f64; 3]>) -> Result<Self, UniformityError> {
        if nodes_m.len() != self.network.n_nodes() {
            return Err(UniformityError::invalid(
                "positions",
                format!(
                    "{} given for {} nodes",
                    nodes_m.len(),
                    self.network.n_nodes()
                ),
            ));
        }
        if let Some(i) = nodes_m
            .iter()
            .position(|p| !p.iter().all(|v| v.is_finite()))
        {
            return Err(UniformityError::invalid(
                format!("node {i}"),
                "its position is not finite",
            ));
        }
        let mut moved = self.clone();
        moved.network.nodes = nodes_m;
        moved.lengths_m = moved
            .network
            .edges_vectors()
            .into_iter()
            .map(norm3)
            .collect();
        if let Some(k) = moved.lengths_m.iter().position(|&l| l.is_nan() || l <= 0.0) {
            return Err(UniformityError::invalid(
                format!("cable {k} (nodes {:?})", moved.network.edges[k]),
                "zero length in the prescribed geometry",
            ));
        }
        Ok(moved)
    }

    /// The same problem under nodal loads `loads_n` (n_nodes × 3, N; `None`:
    /// unloaded). Loads on fixed nodes only change the reactions.
    ///
    /// # Errors
    /// A count that does not match, or a non-finite load (named).
    pub fn with_loads(mut self, loads_n: Option<Vec<[f64; 3]>>) -> Result<Self, UniformityError> {
        if let Some(loads) = &loads_n {
            if loads.len() != self.network.n_nodes() {
                return Err(UniformityError::invalid(
                    "loads",
                    format!("{} given for {} nodes", loads.len(), self.network.n_nodes()),
                ));
            }
            if let Some(i) = loads.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
                return Err(UniformityError::invalid(
                    format!("node {i}"),
                    "its load is not finite",
                ));
            }
        }
        self.network.loads = loads_n;
        Ok(self)
    }

    /// The network: prescribed positions, cables, supports, loads, groups.
    pub fn network(&self) -> &Network {
        &self.network
    }

    /// The force density structure (factor once, refactor per `q`).
    pub fn structure(&self) -> &FdmStructure {
        &self.structure
    }

    /// Cable lengths of the prescribed geometry, m.
    pub fn lengths_m(&self) -> &[f64] {
        &self.lengths_m
    }

    /// The uniformity sets.
    pub fn sets(&self) -> &[UniformitySet] {
        &self.sets
    }

    /// Nodes whose accuracy is reported.
    pub fn surface_nodes(&self) -> &[usize] {
        &self.surface_nodes
    }

    /// What accuracy is measured against.
    pub fn surface(&self) -> SurfaceTarget {
        self.surface
    }

    /// True when the network carries a non-zero load (then the problem is not
    /// scale-free and its pretension level follows from the loads).
    pub fn has_loads(&self) -> bool {
        self.network
            .loads
            .iter()
            .flatten()
            .any(|p| p.iter().any(|&v| v != 0.0))
    }

    /// Loads at the free nodes, stacked `3f + c`: the right-hand side `p` of
    /// `A q = p`.
    pub fn free_loads(&self) -> Vec<f64> {
        let mut p = vec![0.0; 3 * self.structure.free_nodes().len()];
        if let Some(loads) = &self.network.loads {
            for (f, &i) in self.structure.free_nodes().iter().enumerate() {
                p[3 * f..3 * f + 3].copy_from_slice(&loads[i]);
            }
        }
        p
    }

    /// Cables in no uniformity set.
    pub fn other_edges(&self) -> Vec<usize> {
        let mut in_set = vec![false; self.network.n_edges()];
        for set in &self.sets {
            for &k in &set.edges {
                in_set[k] = true;
            }
        }
        (0..in_set.len()).filter(|&k| !in_set[k]).collect()
    }

    /// Smallest tension a cable outside the sets may carry, N.
    pub fn min_other_tension_n(&self) -> f64 {
        self.min_tension_fraction * self.sets[0].mean_tension_n
    }

    /// Largest out-of-balance force of `q` on the prescribed geometry,
    /// `max_i |(A q − p)_i|` over free nodes (Euclidean per node), N.
    pub fn prescribed_residual_n(&self, q: &[f64]) -> f64 {
        let x = &self.network.nodes;
        let mut r = vec![[0.0; 3]; self.network.n_nodes()];
        for (&[i, j], &qk) in self.network.edges.iter().zip(q) {
            for c in 0..3 {
                let f = qk * (x[i][c] - x[j][c]);
                r[i][c] += f;
                r[j][c] -= f;
            }
        }
        let loads = self.network.loads.as_deref();
        self.structure
            .free_nodes()
            .iter()
            .map(|&i| {
                let p = loads.map_or([0.0; 3], |l| l[i]);
                norm3([r[i][0] - p[0], r[i][1] - p[1], r[i][2] - p[2]])
            })
            .fold(0.0, f64::max)
    }

    /// Forward equilibrium for `q` from the prescribed supports and loads.
    pub fn forward(&self, q: &[f64]) -> Result<Equilibrium, UniformityError> {
        Ok(self
            .structure
            .solve(q, &self.network.nodes, self.network.loads.as_deref())?)
    }

    /// Signed surface error of every surface node of `nodes` (n_nodes × 3), m:
    /// vertical distance to the paraboloid, or distance to the prescribed
    /// position.
    pub fn surface_errors_m(&self, nodes: &[[f64; 3]]) -> Vec<f64> {
        self.surface_nodes
            .iter()
            .map(|&i| match self.surface {
                SurfaceTarget::Paraboloid(p) => p.axial_deviation(nodes[i]),
                SurfaceTarget::Prescribed => {
                    let t = self.network.nodes[i];
                    norm3([nodes[i][0] - t[0], nodes[i][1] - t[1], nodes[i][2] - t[2]])
                }
            })
            .collect()
    }

    /// RMS of [`Self::surface_errors_m`], m.
    pub fn surface_rms_m(&self, nodes: &[[f64; 3]]) -> f64 {
        let e = self.surface_errors_m(nodes);
        (e.iter().map(|v| v * v).sum::<f64>() / e.len().max(1) as f64).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::UniformitySet;

    #[test]
    fn a_set_with_a_slack_cable_has_no_finite_ratio() {
        let set = UniformitySet {
            name: "front".into(),
            edges: vec![0, 2],
            mean_tension_n: 1.0,
        };
        assert_eq!(set.ratio(&[2.0, 100.0, 5.0]), 2.5);
        // A slack cable's tension: zero, or a roundoff below it.
        assert_eq!(set.ratio(&[-2e-9, 100.0, 5.0]), f64::INFINITY);
        assert_eq!(set.ratio(&[0.0, 100.0, 5.0]), f64::INFINITY);
    }
}
