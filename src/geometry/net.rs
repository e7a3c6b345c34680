//! The net generator: front net, rear net and ties of a scene, as one [`Network`].
//!
//! The front net is the sector subdivision of the N-gon of top hinges (for
//! N = 6 the three-direction grid): sector `k` is the triangle (centre, `v_k`,
//! `v_{k+1}`) cut into `rings` rows; row `i` has points `j = 0..i`. Nodes are
//! numbered ring by ring (centre 0, then ring `i` by sector and `j`), as in the
//! reference data. The free boundary nodes between two truss attachments are
//! pulled inward, perpendicular to the bay chord, by
//! `sag · chord · 4s(1 − s)` with `s = j/i`, and that sag is scaled into the
//! inner rows by `i/rings` so the grid does not fold: a straight boundary has
//! no strictly positive self-stress (DESIGN §4).
//!
//! The rear net has the same plan grid, on the paraboloid through the bottom
//! hinges that opens towards the front net; vertical ties join every free front
//! node to the rear node below it.

use super::{Aperture, Paraboloid, RingTrussLayout};
use crate::algebra::norm3;
use crate::network::{edges_vectors, CableGroup, Network};
use crate::scene::{Scene, SceneError};

/// Largest number of net nodes (front + rear) a scene may generate.
pub const MAX_NODES: usize = 4_000_000;

/// Shortest cable allowed, as a fraction of the aperture diameter: a mesh density
/// that produces shorter cables is rejected as degenerate.
pub const MIN_CABLE_LENGTH_RATIO: f64 = 1e-4;

/// A scene's cable network with its design geometry and its truss layout.
#[derive(Debug, Clone)]
pub struct ReflectorMesh {
    /// Front net, rear net and ties; nodes at the design positions (front net on
    /// the paraboloid), `q` a uniform initial guess per group (see [`build_mesh`]).
    pub network: Network,
    /// Group of every cable: n_edges.
    pub groups: Vec<CableGroup>,
    /// Front-net nodes are `0..n_front_nodes`; rear node `n_front_nodes + i` lies
    /// below front node `i`.
    pub n_front_nodes: usize,
    /// Front-net node attached to top hinge `k`: N.
    pub front_attachments: Vec<usize>,
    /// Rear-net node attached to bottom hinge `k`: N.
    pub rear_attachments: Vec<usize>,
    /// The reflecting paraboloid.
    pub paraboloid: Paraboloid,
    /// The aperture.
    pub aperture: Aperture,
    /// The ring-truss hinge points.
    pub truss: RingTrussLayout,
    /// Rings of the sector subdivision.
    pub rings: usize,
    /// The front net's facets: triangles of front-net nodes, counter-clockwise
    /// in plan.
    pub front_triangles: Vec<[usize; 3]>,
    /// Inward sag of the free boundary, as a fraction of the bay chord.
    pub boundary_sag_ratio: f64,
    /// The rear net's target mean tension over its interior cables, N
    /// (`rear_net.mean_tension_n`): the design holds it.
    pub rear_mean_tension_n: f64,
}

impl ReflectorMesh {
    /// The front net's plan grid rebuilt, by the same construction, on top
    /// hinges at `top_m` (their plan positions; the centre stays): the design
    /// geometry for a deformed truss, whose nodes move with the hinges.
    ///
    /// # Panics
    /// If `top_m` does not hold one point per bay.
    #[track_caller]
    pub fn front_plan(&self, top_m: &[[f64; 3]]) -> Vec<[f64; 2]> {
        assert_eq!(top_m.len(), self.truss.bays(), "one top hinge per bay");
        let vertex: Vec<[f64; 2]> = top_m.iter().map(|p| [p[0], p[1]]).collect();
        grid_points(
            self.aperture.centre(),
            &vertex,
            self.rings,
            self.boundary_sag_ratio,
        )
    }
}

/// Plan grid of the sector subdivision: positions and cables of one net.
struct PlanGrid {
    points: Vec<[f64; 2]>,
    /// (i, j, is_boundary)
    edges: Vec<([usize; 2], bool)>,
    /// Node of vertex `k` of the N-gon.
    vertices: Vec<usize>,
    /// Counter-clockwise triangles, for the fold check.
    triangles: Vec<[usize; 3]>,
}

/// Node index of grid point (ring `i`, sector `k`, position `j ≤ i`).
fn node_index(bays: usize, i: usize, k: usize, j: usize) -> usize {
    if i == 0 {
        0
    } else {
        1 + bays * i * (i - 1) / 2 + (k * i + j) % (bays * i)
    }
}

fn plan_grid(aperture: &Aperture, bays: usize, rings: usize, sag_ratio: f64) -> PlanGrid {
    let angle = |k: usize| std::f64::consts::TAU * (k % bays) as f64 / bays as f64;
    let vertex: Vec<[f64; 2]> = (0..bays).map(|k| aperture.rim_point(angle(k))).collect();
    let points = grid_points(aperture.centre(), &vertex, rings, sag_ratio);
    let mut edges = Vec::new();
    let mut triangles = Vec::new();
    for k in 0..bays {
        let at = |i: usize, j: usize| node_index(bays, i, k, j);
        for i in 0..rings {
            for j in 0..=i {
                edges.push(([at(i, j), at(i + 1, j)], false));
                triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                if j < i {
                    edges.push(([at(i, j), at(i + 1, j + 1)], false));
                    triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
                }
            }
        }
        for i in 1..=rings {
            for j in 0..i {
                edges.push(([at(i, j), at(i, j + 1)], i == rings));
            }
        }
    }
    let vertices = (0..bays).map(|k| node_index(bays, rings, k, 0)).collect();
    PlanGrid {
        points,
        edges,
        vertices,
        triangles,
    }
}

/// Plan points of the sector subdivision of the polygon `vertex` about the
/// centre `c` (node numbering of [`node_index`]).
fn grid_points(c: [f64; 2], vertex: &[[f64; 2]], rings: usize, sag_ratio: f64) -> Vec<[f64; 2]> {
    let bays = vertex.len();
    let n_points = 1 + bays * rings * (rings + 1) / 2;
    let mut points = vec![c; n_points];
    let n = rings as f64;
    for i in 1..=rings {
        for k in 0..bays {
            let (a, b) = (vertex[k], vertex[(k + 1) % bays]);
            let chord = [b[0] - a[0], b[1] - a[1]];
            let chord_length = chord[0].hypot(chord[1]);
            // Unit normal to the chord, pointing to the centre.
            let inward = [chord[1] / chord_length, -chord[0] / chord_length];
            let inward = if (c[0] - a[0]) * inward[0] + (c[1] - a[1]) * inward[1] >= 0.0 {
                inward
            } else {
                [-inward[0], -inward[1]]
            };
            for j in 0..i {
                let (fi, fj) = (i as f64 / n, j as f64 / n);
                let s = j as f64 / i as f64;
                let sag = sag_ratio * chord_length * (i as f64 / n) * 4.0 * s * (1.0 - s);
                points[node_index(bays, i, k, j)] = std::array::from_fn(|d| {
                    c[d] + fi * (a[d] - c[d]) + fj * (b[d] - a[d]) + sag * inward[d]
                });
            }
        }
    }
    points
}

/// Builds the nets of a scene (validated by [`Scene::read`]) and checks what
/// only the generated geometry shows: positive tie lengths, an unfolded plan
/// grid, no cable shorter than [`MIN_CABLE_LENGTH_RATIO`] × aperture, at most
/// [`MAX_NODES`] nodes.
///
/// The initial `q` is uniform per group, from the scene's mean tensions and the
/// mean design length `ℓ̄_g` of each group: `q = T/ℓ̄` for the interior cables;
/// `T·rings/(8·sag)/ℓ̄` for boundary cables (a scalloped cable carrying the
/// inner net's pull); for ties, the mean vertical pull of the front net at its
/// free nodes divided by `ℓ̄_tie`.
pub fn build_mesh(scene: &Scene) -> Result<ReflectorMesh, SceneError> {
    let bays = scene.truss.bays;
    let rings = scene.front_net.rings;
    let n_front = bays
        .checked_mul(rings)
        .and_then(|v| v.checked_mul(rings + 1))
        .map(|v| 1 + v / 2)
        .filter(|&v| v <= MAX_NODES / 2)
        .ok_or_else(|| {
            SceneError::invalid(
                "front_net.rings",
                format!(
                    "{rings} rings × {bays} bays make more than the {MAX_NODES} net nodes \
                     supported"
                ),
            )
        })?;
    // The shortest cable of the sector grid is the first ring's, chord/rings in
    // plan: reject a degenerate density before allocating the net.
    let diameter = scene.reflector.aperture_diameter_m;
    let chord = diameter * (std::f64::consts::PI / bays as f64).sin();
    let first_ring_cable = chord / rings as f64;
    if first_ring_cable < MIN_CABLE_LENGTH_RATIO * diameter {
        return Err(SceneError::invalid(
            "front_net.rings",
            format!(
                "{rings} rings on {bays} bays make degenerate cables: the first ring's cables are \
                 {first_ring_cable:.3e} m long, below {MIN_CABLE_LENGTH_RATIO:e} × aperture"
            ),
        ));
    }
    let paraboloid = Paraboloid {
        focal_length_m: scene.reflector.focal_length_m,
    };
    let aperture = Aperture {
        radius_m: scene.aperture_radius_m(),
        offset_m: scene.reflector.offset_m,
    };
    let truss = RingTrussLayout::new(&paraboloid, &aperture, bays, scene.truss.height_m);
    let grid = plan_grid(&aperture, bays, rings, scene.front_net.boundary_sag_ratio);
    debug_assert_eq!(grid.points.len(), n_front);
    check_unfolded(&grid)?;

    let r2 = aperture.radius_m * aperture.radius_m;
    let rear_focal = scene.rear_net.focal_length_m;
    let mut nodes: Vec<[f64; 3]> = grid
        .points
        .iter()
        .map(|&[x, y]| [x, y, paraboloid.z(x, y)])
        .collect();
    nodes.extend(grid.points.iter().map(|&[x, y]| {
        let rise = (r2 - aperture.rho_squared(x, y)) / (4.0 * rear_focal);
        [
            x,
            y,
            aperture.rim_plane_z(&paraboloid, x) - scene.truss.height_m + rise,
        ]
    }));
    // The grid's vertices must coincide with the hinges (same construction).
    debug_assert!(grid.vertices.iter().zip(&truss.top_m).all(|(&v, t)| {
        (0..3).all(|d| (nodes[v][d] - t[d]).abs() <= 1e-9 * aperture.radius_m.max(1.0))
    }));

    let mut fixed_mask = vec![false; 2 * n_front];
    let front_attachments = grid.vertices.clone();
    let rear_attachments: Vec<usize> = grid.vertices.iter().map(|&v| v + n_front).collect();
    for &v in front_attachments.iter().chain(&rear_attachments) {
        fixed_mask[v] = true;
    }

    let mut edges = Vec::with_capacity(2 * grid.edges.len() + n_front);
    let mut groups = Vec::with_capacity(edges.capacity());
    for (net_offset, interior, boundary) in [
        (0, CableGroup::Front, CableGroup::Boundary),
        (n_front, CableGroup::Rear, CableGroup::RearBoundary),
    ] {
        for &([a, b], is_boundary) in &grid.edges {
            edges.push([a + net_offset, b + net_offset]);
            groups.push(if is_boundary { boundary } else { interior });
        }
    }
    let tied: Vec<usize> = (0..n_front).filter(|&i| !fixed_mask[i]).collect();
    let mut shortest_tie = f64::INFINITY;
    for &i in &tied {
        shortest_tie = shortest_tie.min(nodes[i][2] - nodes[i + n_front][2]);
        edges.push([i, i + n_front]);
        groups.push(CableGroup::Tie);
    }
    if shortest_tie <= MIN_CABLE_LENGTH_RATIO * diameter {
        let needed = r2 * (1.0 / paraboloid.focal_length_m + 1.0 / rear_focal) / 4.0;
        return Err(SceneError::invalid(
            "truss.height_m",
            format!(
                "{} m: the rear net touches or crosses the front net (shortest tie {:.4} m); \
                 with these focal lengths the truss must be taller than {:.4} m, or \
                 rear_net.focal_length_m larger",
                scene.truss.height_m, shortest_tie, needed
            ),
        ));
    }

    let lengths: Vec<f64> = edges_vectors(&edges, &nodes)
        .into_iter()
        .map(norm3)
        .collect();
    let (shortest_edge, shortest) =
        lengths
            .iter()
            .copied()
            .enumerate()
            .fold(
                (0, f64::INFINITY),
                |best, (k, l)| if l < best.1 { (k, l) } else { best },
            );
    if shortest < MIN_CABLE_LENGTH_RATIO * diameter {
        return Err(SceneError::invalid(
            "front_net.rings",
            format!(
                "{rings} rings make degenerate cables: cable {shortest_edge} ({}) is {shortest:.3e} m \
                 long, below {MIN_CABLE_LENGTH_RATIO:e} × aperture",
                groups[shortest_edge]
            ),
        ));
    }

    let q = initial_force_densities(scene, &nodes, &edges, &groups, &lengths);
    let network = Network {
        nodes,
        edges,
        fixed: front_attachments
            .iter()
            .chain(&rear_attachments)
            .copied()
            .collect(),
        q,
        loads: None,
        groups: Some(groups.iter().map(|g| g.as_str().to_string()).collect()),
    };
    // A mesh no force density solve takes is the scene's fault: say so
    // here, naming the scene, not later naming a cable.
    network.validate().map_err(|e| {
        SceneError::invalid(
            "scene",
            format!("its mesh is not a valid cable network ({e}); check the truss height, aperture and rings"),
        )
    })?;
    Ok(ReflectorMesh {
        network,
        groups,
        n_front_nodes: n_front,
        front_attachments,
        rear_attachments,
        paraboloid,
        aperture,
        truss,
        rings,
        front_triangles: grid.triangles,
        boundary_sag_ratio: scene.front_net.boundary_sag_ratio,
        rear_mean_tension_n: scene.rear_net.mean_tension_n,
    })
}

/// Rejects a sag that folds the plan grid: every triangle must keep its
/// counter-clockwise orientation.
fn check_unfolded(grid: &PlanGrid) -> Result<(), SceneError> {
    let area = |[a, b, c]: [usize; 3]| {
        let (p, q, r) = (grid.points[a], grid.points[b], grid.points[c]);
        0.5 * ((q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]))
    };
    let reference = grid
        .triangles
        .iter()
        .map(|&t| area(t).abs())
        .fold(0.0, f64::max);
    if let Some(&t) = grid
        .triangles
        .iter()
        .find(|&&t| area(t) <= 1e-9 * reference)
    {
        return Err(SceneError::invalid(
            "front_net.boundary_sag_ratio",
            format!(
                "the boundary sag folds the net: the triangle of nodes {t:?} is inverted or flat \
                 in plan; choose a smaller sag or more bays"
            ),
        ));
    }
    Ok(())
}

fn initial_force_densities(
    scene: &Scene,
    nodes: &[[f64; 3]],
    edges: &[[usize; 2]],
    groups: &[CableGroup],
    lengths: &[f64],
) -> Vec<f64> {
    let mean_length = |group: CableGroup| {
        let (sum, count) = groups
            .iter()
            .zip(lengths)
            .filter(|(g, _)| **g == group)
            .fold((0.0, 0usize), |(s, c), (_, l)| (s + l, c + 1));
        sum / count.max(1) as f64
    };
    let scallop = scene.front_net.rings as f64 / (8.0 * scene.front_net.boundary_sag_ratio);
    let (front, rear) = (
        scene.front_net.mean_tension_n,
        scene.rear_net.mean_tension_n,
    );
    let per_group = |group: CableGroup| match group {
        CableGroup::Front => front / mean_length(group),
        CableGroup::Boundary => front * scallop / mean_length(group),
        CableGroup::Rear => rear / mean_length(group),
        CableGroup::RearBoundary => rear * scallop / mean_length(group),
        CableGroup::Tie => 0.0,
    };
    let q_of: Vec<f64> = CableGroup::ALL.iter().map(|&g| per_group(g)).collect();
    let index = |g: CableGroup| CableGroup::ALL.iter().position(|&h| h == g).unwrap();
    let mut q: Vec<f64> = groups.iter().map(|&g| q_of[index(g)]).collect();

    // Ties: the front net's mean vertical pull at the tied nodes, Σ_j q_ij (z_j − z_i).
    let mut pull = vec![0.0; nodes.len()];
    for ((&[i, j], &g), &qk) in edges.iter().zip(groups).zip(&q) {
        if matches!(g, CableGroup::Front | CableGroup::Boundary) {
            let dz = nodes[j][2] - nodes[i][2];
            pull[i] += qk * dz;
            pull[j] -= qk * dz;
        }
    }
    let tie_edges: Vec<usize> = (0..edges.len())
        .filter(|&k| groups[k] == CableGroup::Tie)
        .collect();
    let mean_pull = tie_edges
        .iter()
        .map(|&k| pull[edges[k][0]].abs())
        .sum::<f64>()
        / tie_edges.len().max(1) as f64;
    let fallback = front / mean_length(CableGroup::Front);
    let q_tie = if mean_pull > 0.0 {
        mean_pull / mean_length(CableGroup::Tie)
    } else {
        fallback
    };
    for k in tie_edges {
        q[k] = q_tie;
    }
    q
}
