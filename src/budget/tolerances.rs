//! Manufacturing tolerances as perturbations: one Monte Carlo sample is a
//! draw of every item's error (`[tolerances]`: independent zero-mean normal
//! errors of the cut length of each cable and tie, the length of each rod,
//! each cable's EA, each hinge's position).
//!
//! **Reproducible and shardable.** Sample `k` of seed `S` draws from its own
//! ChaCha8 stream (`seed_from_u64(S)`, stream `k`): it does not depend on
//! which other samples a run draws, so a shard reproduces the unsharded
//! run's samples bit for bit, on any machine (ChaCha and `rand_distr`'s
//! normal are portable; `Cargo.lock` pins their versions). Every item is
//! drawn whatever its σ, in a fixed order (cables, EA, rods, hinges), so a
//! zero σ leaves the other sources' draws unchanged.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::geometry::ReflectorMesh;
use crate::network::{CableGroup, Network};
use crate::scene::{Cables, Tolerances};
use crate::uniformity::Design;
use crate::verify::Perturbation;

/// What a sample perturbs: the design's cut lengths and the rods' lengths.
#[derive(Debug, Clone)]
pub struct ToleranceModel {
    /// The standard deviations.
    pub tolerances: Tolerances,
    /// Each cable's cut length, m, and whether it is a tie.
    cables: Vec<(f64, bool)>,
    /// Each rod's length, m (frame build order).
    rods_m: Vec<f64>,
    /// Hinges (top then bottom).
    hinges: usize,
}

impl ToleranceModel {
    /// The model of `tolerances` on `design` (made on `network` of `mesh`,
    /// cables of `cables`).
    pub fn new(
        tolerances: &Tolerances,
        mesh: &ReflectorMesh,
        network: &Network,
        design: &Design,
        cables: &Cables,
    ) -> Self {
        let cut = (0..network.n_edges())
            .map(|k| {
                (
                    cables.cut_length_m(design.lengths_m[k], design.tensions_n[k]),
                    mesh.groups[k] == CableGroup::Tie,
                )
            })
            .collect();
        let layout = &mesh.truss;
        let n = layout.bays();
        let dist = |a: [f64; 3], b: [f64; 3]| {
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        };
        let rods_m = (0..n)
            .flat_map(|k| {
                let next = (k + 1) % n;
                let (t, b) = (layout.top_m[k], layout.bottom_m[k]);
                let diagonal = dist(b, layout.top_m[next]);
                [
                    dist(b, t),
                    dist(t, layout.top_m[next]),
                    dist(b, layout.bottom_m[next]),
                    0.5 * diagonal,
                    0.5 * diagonal,
                ]
            })
            .collect();
        ToleranceModel {
            tolerances: tolerances.clone(),
            cables: cut,
            rods_m,
            hinges: 2 * n,
        }
    }

    /// Sample `k` of seed `seed` ([module docs](self)).
    pub fn sample(&self, seed: u64, k: usize) -> Perturbation {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(k as u64);
        let mut normal = || -> f64 { StandardNormal.sample(&mut rng) };
        let t = &self.tolerances;
        let lengths = self
            .cables
            .iter()
            .map(|&(cut, tie)| {
                let sigma = if tie {
                    t.tie_length_sigma_m
                } else {
                    t.cable_length_sigma_m
                };
                1.0 + sigma * normal() / cut
            })
            .collect();
        let stiffness = self
            .cables
            .iter()
            .map(|_| 1.0 + t.cable_stiffness_sigma * normal())
            .collect();
        let rods = self
            .rods_m
            .iter()
            .map(|l| [1.0 + t.rod_length_sigma_m * normal() / l, 1.0])
            .collect();
        let hinges = (0..self.hinges)
            .map(|_| std::array::from_fn(|_| t.hinge_position_sigma_m * normal()))
            .collect();
        Perturbation {
            cable_length_factors: Some(lengths),
            cable_stiffness_factors: Some(stiffness),
            rod_stretch: Some(rods),
            hinge_offsets_m: Some(hinges),
        }
    }
}
