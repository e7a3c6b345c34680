//! An independent generator of reflector nets, *different from ours* in
//! everything the plan reduction of `lp` must not rely on: a hexagonal
//! six-sector three-direction grid of `rings` rings (the kind of
//! `tests/data/hex5-lp.json`), its six corners the only fixed net nodes, every
//! ring's sector chord sagged inward by `sag` of its length (a parabola in
//! plan), net nodes on `z = (x² + y²)/(4F)`, every free net node hung on a
//! vertical tie (`tie_m` down) to its own fixed anchor; node order, cable
//! order and the ends of each cable shuffled with a fixed seed; groups
//! `surface` (interior), `rim` (the outer ring), `hangers` (ties).
//!
//! Self-contained (only `ringmesh`) so that a bench can include it with
//! `#[path = "../tests/common/hexnet.rs"] mod hexnet;`.
#![allow(dead_code)]

use std::collections::HashMap;

use ringmesh::network::Network;
use ringmesh::uniformity::{SurfaceTarget, UniformityProblem, UniformitySet};

/// The `lp` problem of a tied net: one set of every cable but those of the
/// group `ties` at `mean_tension_n`, every free node on the surface, the
/// bound `[q]` at `max_q`.
pub fn tied_net_problem(
    network: Network,
    ties: &str,
    mean_tension_n: f64,
    max_q: f64,
) -> UniformityProblem {
    let edges = (0..network.n_edges())
        .filter(|&k| network.group_of(k) != ties)
        .collect();
    let fixed = network.fixed_mask();
    let surface = (0..network.n_nodes()).filter(|&i| !fixed[i]).collect();
    let set = UniformitySet {
        name: format!("all but {ties}"),
        edges,
        mean_tension_n,
    };
    UniformityProblem::new(
        network,
        vec![set],
        surface,
        SurfaceTarget::Prescribed,
        max_q,
    )
    .expect("a tied net's problem")
}

/// The parameters of one generated net.
#[derive(Debug, Clone, Copy)]
pub struct HexNet {
    /// Rings of the grid (ring r has 6r nodes): 3R(R+1) + 1 net nodes.
    pub rings: usize,
    /// Aperture (corner to corner), m.
    pub diameter_m: f64,
    /// Focal length, m.
    pub focal_m: f64,
    /// Sag of every ring's sector chord at its middle, per unit chord.
    pub sag: f64,
    /// Tie length, m.
    pub tie_m: f64,
    /// Tilt of every tie from the vertical (its anchor moved radially out), degrees.
    pub tilt_deg: f64,
    /// Seed of the shuffles.
    pub seed: u64,
    /// Whether to shuffle nodes, cables and cable ends (else: ring by ring).
    pub shuffle: bool,
}

impl HexNet {
    /// `hex5-lp.json`'s kind of net at `rings` rings: D = 26 m, F = 4 m, sag 5 %,
    /// ties 1 m.
    pub fn like_hex5(rings: usize) -> Self {
        HexNet {
            rings,
            diameter_m: 26.0,
            focal_m: 4.0,
            sag: 0.05,
            tie_m: 1.0,
            tilt_deg: 0.0,
            seed: 0x5eed,
            shuffle: true,
        }
    }

    /// A net of about `free` free net nodes on a `diameter_m` aperture with
    /// F/D = 0.4.
    pub fn with_free_nodes(free: usize, diameter_m: f64) -> Self {
        // 3R(R+1) + 1 − 6 ≈ free.
        let rings = ((free as f64 / 3.0).sqrt()).round().max(1.0) as usize;
        HexNet {
            rings,
            diameter_m,
            focal_m: 0.4 * diameter_m,
            ..HexNet::like_hex5(rings)
        }
    }

    /// Number of free net nodes (one tie each).
    pub fn free_nodes(&self) -> usize {
        3 * self.rings * (self.rings + 1) + 1 - 6
    }

    /// The net.
    pub fn build(&self) -> Network {
        let r_max = self.rings as i64;
        let spacing = 0.5 * self.diameter_m / r_max as f64;
        // Corners in axial lattice coordinates (u, v), point u e1 + v e2.
        let corners: [(i64, i64); 6] = [(1, 0), (0, 1), (-1, 1), (-1, 0), (0, -1), (1, -1)];
        let plan = |u: f64, v: f64| [spacing * (u + 0.5 * v), spacing * v * 3f64.sqrt() / 2.0];
        let mut index: HashMap<(i64, i64), usize> = HashMap::new();
        let mut nodes: Vec<[f64; 3]> = Vec::new();
        let mut ring_of: Vec<i64> = Vec::new();
        let mut lattice: Vec<(i64, i64)> = vec![(0, 0)];
        let mut corner = Vec::new();
        let z = |x: f64, y: f64| (x * x + y * y) / (4.0 * self.focal_m);
        index.insert((0, 0), 0);
        nodes.push([0.0, 0.0, 0.0]);
        ring_of.push(0);
        for r in 1..=r_max {
            for s in 0..6 {
                let (a, b) = (corners[s], corners[(s + 1) % 6]);
                for j in 0..r {
                    let (u, v) = (r * a.0 + j * (b.0 - a.0), r * a.1 + j * (b.1 - a.1));
                    let [mut x, mut y] = plan(u as f64, v as f64);
                    // Sag toward the centre, across the chord.
                    let t = j as f64 / r as f64;
                    let [ma, mb] = [plan(a.0 as f64, a.1 as f64), plan(b.0 as f64, b.1 as f64)];
                    let (nx, ny) = (ma[0] + mb[0], ma[1] + mb[1]);
                    let norm = nx.hypot(ny);
                    let chord = spacing * r as f64;
                    let depth = self.sag * chord * 4.0 * t * (1.0 - t);
                    x -= depth * nx / norm;
                    y -= depth * ny / norm;
                    index.insert((u, v), nodes.len());
                    lattice.push((u, v));
                    if r == r_max && j == 0 {
                        corner.push(nodes.len());
                    }
                    nodes.push([x, y, z(x, y)]);
                    ring_of.push(r);
                }
            }
        }
        let n_net = nodes.len();
        let mut edges: Vec<[usize; 2]> = Vec::new();
        let mut groups: Vec<&str> = Vec::new();
        for (i, &(u, v)) in lattice.iter().enumerate() {
            for (du, dv) in [(1, 0), (0, 1), (-1, 1)] {
                if let Some(&j) = index.get(&(u + du, v + dv)) {
                    edges.push([i, j]);
                    let rim = ring_of[i] == r_max && ring_of[j] == r_max;
                    groups.push(if rim { "rim" } else { "surface" });
                }
            }
        }
        let mut fixed = corner.clone();
        let (sin, cos) = self.tilt_deg.to_radians().sin_cos();
        for i in 0..n_net {
            if corner.contains(&i) {
                continue;
            }
            let [x, y, zi] = nodes[i];
            let rho = x.hypot(y);
            let (ex, ey) = if rho > 0.0 {
                (x / rho, y / rho)
            } else {
                (1.0, 0.0)
            };
            let out = self.tie_m * sin;
            let anchor = [x + out * ex, y + out * ey, zi - self.tie_m * cos];
            fixed.push(nodes.len());
            edges.push([i, nodes.len()]);
            groups.push("hangers");
            nodes.push(anchor);
        }
        // Shuffle nodes, cables and the ends of every cable.
        let mut rng = self.seed;
        let mut next = move || {
            rng = rng.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = rng;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        };
        let shuffle = self.shuffle;
        let mut order: Vec<usize> = (0..nodes.len()).collect();
        for i in (1..order.len()).rev().filter(|_| shuffle) {
            order.swap(i, (next() % (i as u64 + 1)) as usize);
        }
        let mut new_of = vec![0; nodes.len()];
        for (new, &old) in order.iter().enumerate() {
            new_of[old] = new;
        }
        let mut cables: Vec<usize> = (0..edges.len()).collect();
        for i in (1..cables.len()).rev().filter(|_| shuffle) {
            cables.swap(i, (next() % (i as u64 + 1)) as usize);
        }
        let mut flip = || shuffle && next() % 2 == 1;
        let mut fixed: Vec<usize> = fixed.iter().map(|&i| new_of[i]).collect();
        fixed.sort_unstable();
        Network {
            nodes: order.iter().map(|&i| nodes[i]).collect(),
            edges: cables
                .iter()
                .map(|&k| {
                    let [a, b] = edges[k].map(|i| new_of[i]);
                    if flip() {
                        [b, a]
                    } else {
                        [a, b]
                    }
                })
                .collect(),
            fixed,
            q: vec![1.0; cables.len()],
            loads: None,
            groups: Some(cables.iter().map(|&k| groups[k].to_string()).collect()),
        }
    }
}
