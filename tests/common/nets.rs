//! The three families of tied reflector nets the plan interior point is
//! measured on (issue 38), generated in code:
//!
//! * `hex` — the hexagonal generator of `hexnet.rs` (shuffled, `100m` kind:
//!   D = 100 m, F/D = 0.4);
//! * `sector` — a six-sector three-direction grid written independently of
//!   `hexnet.rs`, nodes numbered sector by sector and row by row, every row of
//!   each sector sagged toward the centre like the boundary (5 % of its chord,
//!   a parabola in plan), ties vertical to fixed anchors: the kind of
//!   `tests/data/hex5-lp.json` (D = 26 m, F = 4 m) at issue 38's sizes
//!   (R = 18, 57, 182 rows: 1 021, 9 913, 99 913 free nodes);
//! * `jitter` — the same grid graded radially (rows denser toward the
//!   centre, radius ∝ (row/R)^1.3, so no two rows are equally spaced) and every
//!   interior node moved in plan by a seeded random ±10 % of its shortest cable
//!   in x and y.
//!
//! Every free net node hangs on a vertical tie (1 m) to its own fixed anchor;
//! the six corners are the fixed net nodes. Groups: `net` (interior), `rim`,
//! `ties`. Needs only `ringmesh` and a sibling module `hexnet`, so that a bench
//! can include both with `#[path]`.
#![allow(dead_code)]

use ringmesh::network::Network;
use ringmesh::uniformity::UniformityProblem;

// `hexnet.rs`, a sibling module wherever this file is included.
use super::hexnet;

/// A net family of issue 38.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Family {
    /// `hexnet.rs`'s `100m` kind.
    Hex,
    /// The six-sector grid, every row sagged (`hex5-lp.json`'s kind).
    Sector,
    /// The sector grid graded and jittered ±10 %.
    Jitter,
}

impl Family {
    /// All three, in the order of the tables.
    pub const ALL: [Family; 3] = [Family::Hex, Family::Sector, Family::Jitter];

    /// The name in bench ids and tables.
    pub fn name(self) -> &'static str {
        match self {
            Family::Hex => "hex",
            Family::Sector => "sector",
            Family::Jitter => "jitter",
        }
    }

    /// The family's net of `rings` rows (3R(R+1) − 5 free net nodes).
    pub fn network(self, rings: usize) -> Network {
        match self {
            Family::Hex => hexnet::HexNet {
                rings,
                ..hexnet::HexNet::with_free_nodes(3 * rings * (rings + 1), 100.0)
            }
            .build(),
            Family::Sector => SectorGrid::like_hex5(rings).build(),
            Family::Jitter => SectorGrid {
                grading: 1.3,
                jitter: 0.1,
                ..SectorGrid::like_hex5(rings)
            }
            .build(),
        }
    }

    /// The `lp` problem of [`Self::network`]: one set of every cable but the
    /// ties, mean tension 50 N, no active bound.
    pub fn problem(self, rings: usize) -> UniformityProblem {
        let ties = if self == Family::Hex {
            "hangers"
        } else {
            "ties"
        };
        hexnet::tied_net_problem(self.network(rings), ties, 50.0, 1e9)
    }
}

/// Rows of a net of about `free` free net nodes (3R(R+1) − 5 ≈ free).
pub fn rings_for(free: usize) -> usize {
    ((free as f64 / 3.0).sqrt()).floor().max(1.0) as usize
}

/// A six-sector three-direction grid of `rings` rows.
#[derive(Debug, Clone, Copy)]
pub struct SectorGrid {
    /// Rows per sector.
    pub rings: usize,
    /// Aperture, corner to corner, m.
    pub diameter_m: f64,
    /// Focal length, m.
    pub focal_m: f64,
    /// Sag of every row at its middle, per unit chord.
    pub sag: f64,
    /// Radial grading: a row's radius ∝ (row/R)^grading.
    pub grading: f64,
    /// Plan jitter of interior nodes, per unit shortest cable.
    pub jitter: f64,
    /// Tie length, m.
    pub tie_m: f64,
    /// Seed of the jitter.
    pub seed: u64,
}

impl SectorGrid {
    /// `hex5-lp.json`'s kind: D = 26 m, F = 4 m, sag 5 %, ties 1 m, regular.
    pub fn like_hex5(rings: usize) -> Self {
        SectorGrid {
            rings,
            diameter_m: 26.0,
            focal_m: 4.0,
            sag: 0.05,
            grading: 1.0,
            jitter: 0.0,
            tie_m: 1.0,
            seed: 0x0038,
        }
    }

    /// The net.
    pub fn build(&self) -> Network {
        let big_r = self.rings;
        let radius = 0.5 * self.diameter_m;
        let corner = |s: usize| {
            let a = std::f64::consts::FRAC_PI_3 * s as f64;
            [radius * a.cos(), radius * a.sin()]
        };
        // Node (s, r, j): sector s, row r ≥ 1, j in 0..r (j = r is the next
        // sector's j = 0); the centre is node 0.
        let id = |s: usize, r: usize, j: usize| -> usize {
            if r == 0 {
                return 0;
            }
            let (s, j) = if j == r { ((s + 1) % 6, 0) } else { (s, j) };
            1 + s * big_r * (big_r + 1) / 2 + (r - 1) * r / 2 + j
        };
        let n_net = 1 + 3 * big_r * (big_r + 1);
        let mut plan = vec![[0.0; 2]; n_net];
        for s in 0..6 {
            let (a, b) = (corner(s), corner(s + 1));
            let mid = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
            let mid_norm = mid[0].hypot(mid[1]);
            for r in 1..=big_r {
                let scale = (r as f64 / big_r as f64).powf(self.grading);
                let chord = scale * radius;
                for j in 0..r {
                    let t = j as f64 / r as f64;
                    let depth = self.sag * chord * 4.0 * t * (1.0 - t);
                    plan[id(s, r, j)] = [
                        scale * (a[0] + t * (b[0] - a[0])) - depth * mid[0] / mid_norm,
                        scale * (a[1] + t * (b[1] - a[1])) - depth * mid[1] / mid_norm,
                    ];
                }
            }
        }
        // Cables: along the rows, and from row r to row r + 1 (two each).
        let mut edges: Vec<[usize; 2]> = Vec::new();
        let mut groups: Vec<&str> = Vec::new();
        for s in 0..6 {
            for r in 0..=big_r {
                for j in 0..r.max(1) {
                    if r == 0 && s > 0 {
                        break;
                    }
                    let i = id(s, r, j);
                    if r > 0 {
                        edges.push([i, id(s, r, j + 1)]);
                        groups.push(if r == big_r { "rim" } else { "net" });
                    }
                    if r < big_r {
                        if r == 0 {
                            for t in 0..6 {
                                edges.push([0, id(t, 1, 0)]);
                                groups.push("net");
                            }
                        } else {
                            edges.push([i, id(s, r + 1, j)]);
                            edges.push([i, id(s, r + 1, j + 1)]);
                            groups.push("net");
                            groups.push("net");
                            if j == 0 {
                                // A corner's third cable out, into the
                                // previous sector.
                                edges.push([i, id((s + 5) % 6, r + 1, r)]);
                                groups.push("net");
                            }
                        }
                    }
                }
            }
        }
        let corners: Vec<usize> = (0..6).map(|s| id(s, big_r, 0)).collect();
        // Jitter: interior nodes only (the rim keeps its sag, so it stays in
        // tension), by a fraction of each node's shortest cable.
        if self.jitter > 0.0 {
            let mut shortest = vec![f64::INFINITY; n_net];
            for &[i, j] in &edges {
                let d = (plan[i][0] - plan[j][0]).hypot(plan[i][1] - plan[j][1]);
                shortest[i] = shortest[i].min(d);
                shortest[j] = shortest[j].min(d);
            }
            let mut rng = self.seed;
            let mut next = move || {
                rng = rng.wrapping_add(0x9e37_79b9_7f4a_7c15);
                let mut z = rng;
                z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
                z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
                z ^= z >> 31;
                2.0 * ((z >> 11) as f64 / (1u64 << 53) as f64) - 1.0
            };
            for s in 0..6 {
                for r in 1..big_r {
                    for j in 0..r {
                        let i = id(s, r, j);
                        let amplitude = self.jitter * shortest[i];
                        plan[i][0] += amplitude * next();
                        plan[i][1] += amplitude * next();
                    }
                }
            }
            let amplitude = self.jitter * shortest[0];
            plan[0][0] += amplitude * next();
            plan[0][1] += amplitude * next();
        }
        let z = |p: [f64; 2]| (p[0] * p[0] + p[1] * p[1]) / (4.0 * self.focal_m);
        let mut nodes: Vec<[f64; 3]> = plan.iter().map(|&p| [p[0], p[1], z(p)]).collect();
        let mut fixed = corners.clone();
        for i in 0..n_net {
            if corners.contains(&i) {
                continue;
            }
            let [x, y, zi] = nodes[i];
            fixed.push(nodes.len());
            edges.push([i, nodes.len()]);
            groups.push("ties");
            nodes.push([x, y, zi - self.tie_m]);
        }
        fixed.sort_unstable();
        Network {
            nodes,
            q: vec![1.0; edges.len()],
            edges,
            fixed,
            loads: None,
            groups: Some(groups.iter().map(|g| g.to_string()).collect()),
        }
    }
}
