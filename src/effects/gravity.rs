//! Gravity (DESIGN §8): the self weight of the cables, lumped half to each
//! end node as loads `p` of the force density method (paper eq. 3–4), and of
//! the truss's rods (half of each element to each of its nodes) and hinge
//! bodies, as dead loads of its model.
//!
//! With loads the uniformity problem is no longer homogeneous: its
//! pretension level is no longer free, and only solvers that take loads
//! (`bisection`) can solve it; the others say so. Along the reflector's axis
//! the weight is vertical, and the vertical ties absorb it: the plan problem
//! of the front net, hence its ratio, does not change. Across the axis it
//! enters plan equilibrium and changes the optimum.

use nalgebra::Vector3;

use super::{record, Effect, EffectKind};
use crate::mechanics::{ModelBuilder, NodalLoad, NodeId, Rod};
use crate::scene::Scene;

/// The self weight of a scene's cables.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CableSelfWeight {
    /// Weight per unit length, `ρ A g`, N/m, as a vector.
    pub weight_n_per_m: [f64; 3],
}

impl CableSelfWeight {
    /// The cables' self weight, when the scene asks for gravity.
    pub fn of(scene: &Scene) -> Option<Self> {
        let g = scene.effects.gravity.as_ref()?.vector_m_per_s2();
        record(EffectKind::CableSelfWeight);
        let c = &scene.cables;
        let mass_per_m = c.density_kg_per_m3 * c.area_m2();
        Some(CableSelfWeight {
            weight_n_per_m: g.map(|a| mass_per_m * a),
        })
    }

    /// Nodal loads, N (n_nodes × 3): each cable's weight at the geometry
    /// `nodes_m`, half at each end.
    pub fn nodal_loads(&self, nodes_m: &[[f64; 3]], edges: &[[usize; 2]]) -> Vec<[f64; 3]> {
        let mut loads = vec![[0.0; 3]; nodes_m.len()];
        for &[i, j] in edges {
            let (a, b) = (nodes_m[i], nodes_m[j]);
            let length =
                ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            for node in [i, j] {
                for (load, w) in loads[node].iter_mut().zip(self.weight_n_per_m) {
                    *load += 0.5 * length * w;
                }
            }
        }
        loads
    }
}

/// Gravity: the cables' weight on the nets, the rods' and hinges' weight on
/// the truss.
#[derive(Debug, Clone, PartialEq)]
pub struct Gravity {
    /// The cables' self weight.
    pub cables: CableSelfWeight,
    /// Weight per unit length of a truss tube, N/m.
    pub tube_weight_n_per_m: Vector3<f64>,
    /// Weight of one hinge body, N (none without a hinge mass).
    pub hinge_weight_n: Option<Vector3<f64>>,
}

impl Gravity {
    /// Gravity, when the scene asks for it.
    pub fn of(scene: &Scene) -> Option<Self> {
        let cables = CableSelfWeight::of(scene)?;
        let g = Vector3::from(scene.effects.gravity.as_ref()?.vector_m_per_s2());
        let t = &scene.truss;
        Some(Gravity {
            cables,
            tube_weight_n_per_m: t.density_kg_per_m3 * t.tube_area_m2() * g,
            hinge_weight_n: (t.hinge_mass_kg > 0.0).then(|| t.hinge_mass_kg * g),
        })
    }
}

impl Effect for Gravity {
    fn name(&self) -> &str {
        "gravity"
    }

    fn net_loads_n(&self, nodes_m: &[[f64; 3]], edges: &[[usize; 2]]) -> Option<Vec<[f64; 3]>> {
        Some(self.cables.nodal_loads(nodes_m, edges))
    }

    /// Each element of `rods` half at each of its nodes, each of `hinges`
    /// its weight.
    fn truss_dead_loads(
        &self,
        frame: &ModelBuilder,
        rods: &[Rod],
        hinges: &[NodeId],
    ) -> Vec<NodalLoad> {
        record(EffectKind::TrussSelfWeight);
        let position = |n: NodeId| frame.frame(n).map(|f| f.position_m);
        let mut loads = Vec::new();
        for rod in rods {
            for pair in rod.nodes.windows(2) {
                if let (Some(a), Some(b)) = (position(pair[0]), position(pair[1])) {
                    let half = 0.5 * (b - a).norm() * self.tube_weight_n_per_m;
                    for &node in pair {
                        loads.push(NodalLoad {
                            node,
                            force_n: half,
                            moment_nm: Vector3::zeros(),
                        });
                    }
                }
            }
        }
        if let Some(weight) = self.hinge_weight_n {
            loads.extend(hinges.iter().map(|&node| NodalLoad {
                node,
                force_n: weight,
                moment_nm: Vector3::zeros(),
            }));
        }
        loads
    }
}
