//! The points a surface measurement visits, with their weights: the nodes
//! (one each), or the facets' quadrature points (plan area × rule weight).
//! Validated once; then streamed, so a net of 10⁵ facets costs no memory.

use super::quadrature::TriangleRule;
use super::SurfaceError;

/// Gauss–Legendre points per direction of the facet rule: 6 × 6 = 36 points,
/// exact to degree 10. The axial deviation's square has degree 4; the normal
/// and half-path ones carry the smooth weights cos² α and cos⁴ α, which 25
/// points integrate to 6e-8 relative on facets of 0.8 F and 36 points to
/// 1e-9 (the brute-force test's own accuracy).
pub(crate) const FACET_RULE_POINTS_PER_DIRECTION: usize = 6;

/// Nodes, or flat triangular facets between nodes, checked.
#[derive(Debug, Clone)]
pub(crate) enum Samples<'a> {
    /// Every node counts once.
    Nodes(&'a [[f64; 3]]),
    /// Every facet counts by its plan area (its projection on the design
    /// aperture plane, z = const).
    Facets {
        nodes_m: &'a [[f64; 3]],
        triangles: &'a [[usize; 3]],
        rule: TriangleRule,
    },
}

/// Rejects a node with a NaN or infinite coordinate.
fn check_finite(node: usize, xyz_m: [f64; 3]) -> Result<(), SurfaceError> {
    if xyz_m.iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(SurfaceError::NonFiniteNode { node, xyz_m })
    }
}

/// Plan area of the triangle `p q r`, m².
pub(crate) fn plan_area_m2(p: [f64; 3], q: [f64; 3], r: [f64; 3]) -> f64 {
    0.5 * ((q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])).abs()
}

impl<'a> Samples<'a> {
    /// The nodes, checked: at least one, all finite.
    pub(crate) fn nodes(nodes_m: &'a [[f64; 3]]) -> Result<Samples<'a>, SurfaceError> {
        if nodes_m.is_empty() {
            return Err(SurfaceError::NoNodes);
        }
        for (i, &p) in nodes_m.iter().enumerate() {
            check_finite(i, p)?;
        }
        Ok(Samples::Nodes(nodes_m))
    }

    /// The facets, checked: at least one, every corner an existing finite
    /// node, some plan area in all.
    pub(crate) fn facets(
        nodes_m: &'a [[f64; 3]],
        triangles: &'a [[usize; 3]],
    ) -> Result<Samples<'a>, SurfaceError> {
        if triangles.is_empty() {
            return Err(SurfaceError::NoFacets);
        }
        let mut area = 0.0;
        for (facet, t) in triangles.iter().enumerate() {
            for &node in t {
                let p = *nodes_m.get(node).ok_or(SurfaceError::FacetNode {
                    facet,
                    node,
                    n_nodes: nodes_m.len(),
                })?;
                check_finite(node, p)?;
            }
            area += plan_area_m2(nodes_m[t[0]], nodes_m[t[1]], nodes_m[t[2]]);
        }
        // A sum of non-negative terms: zero only if every facet is flat in plan.
        if area <= 0.0 {
            return Err(SurfaceError::NoPlanArea {
                n_facets: triangles.len(),
            });
        }
        Ok(Samples::Facets {
            nodes_m,
            triangles,
            rule: TriangleRule::collapsed_gauss(FACET_RULE_POINTS_PER_DIRECTION),
        })
    }

    /// Number of points visited.
    pub(crate) fn len(&self) -> usize {
        match self {
            Samples::Nodes(nodes) => nodes.len(),
            Samples::Facets {
                triangles, rule, ..
            } => triangles.len() * rule.points.len(),
        }
    }

    /// Largest coordinate magnitude, m: the scale of rounding errors.
    pub(crate) fn scale_m(&self) -> f64 {
        let nodes = match self {
            Samples::Nodes(nodes) => nodes,
            Samples::Facets { nodes_m, .. } => nodes_m,
        };
        nodes
            .iter()
            .flat_map(|p| p.iter())
            .fold(0.0, |m: f64, c| m.max(c.abs()))
    }

    /// Calls `f(point, weight)` for every point; the weights sum to the number
    /// of nodes, or to the facets' plan area.
    pub(crate) fn for_each(&self, mut f: impl FnMut([f64; 3], f64)) {
        match self {
            Samples::Nodes(nodes) => nodes.iter().for_each(|&p| f(p, 1.0)),
            Samples::Facets {
                nodes_m,
                triangles,
                rule,
            } => {
                for t in *triangles {
                    let [p, q, r] = t.map(|i| nodes_m[i]);
                    let area = plan_area_m2(p, q, r);
                    for (l, w) in &rule.points {
                        let x = std::array::from_fn(|d| l[0] * p[d] + l[1] * q[d] + l[2] * r[d]);
                        f(x, area * w);
                    }
                }
            }
        }
    }
}
