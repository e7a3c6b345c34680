//! Joints as algebraic constraints between two nodes (paper eq. 22–25),
//! enforced with Lagrange multipliers.
//!
//! Marker points `p = x + R ρ` (eq. 22) with `ρ` fixed in the node's material
//! frame. A joint's equations:
//!
//! * position: `p_a − p_b = 0` (3 equations, every joint);
//! * orientation, by directors `e = R E` fixed in each node's material frame:
//!   fixed joint (eq. 24) `e₁ᵃ·e₂ᵇ = e₂ᵃ·e₃ᵇ = e₃ᵃ·e₁ᵇ = 0`; revolute joint
//!   about `h` (eq. 25) `hᵃ·uᵇ = hᵃ·vᵇ = 0` with `u, v ⟂ h`.
//!
//! Each equation returns its value, its gradient along the spatial increments
//! `(δx, δθ)` of both nodes, and the derivative of `μ ∇g` (the multiplier's
//! contribution to the residual) that the consistent tangent needs.

use nalgebra::{Matrix3, Vector3};

use super::node::Frame;
use super::rotation::{rod_frame, skew};

/// The kinds of joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum JointKind {
    /// All six relative motions locked (eq. 24).
    Fixed,
    /// Relative rotation about `axis` (global, reference configuration) free (eq. 25).
    Revolute {
        /// The hinge axis in the reference configuration.
        axis: Vector3<f64>,
    },
    /// Only the point is shared: all relative rotations free.
    Spherical,
}

/// A built joint: local markers and directors of each node.
#[derive(Debug, Clone)]
pub(crate) struct Joint {
    pub nodes: [usize; 2],
    /// Marker offsets in each node's material frame.
    markers: [Vector3<f64>; 2],
    /// Director pairs `(Eᵃ, Eᵇ)` in the material frames, one per equation.
    directors: Vec<[Vector3<f64>; 2]>,
}

/// One scalar equation of a joint at the current configuration.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ConstraintRow {
    /// `g`, m (position) or 1 (directors).
    pub value: f64,
    /// `∂g/∂(δx_a, δθ_a, δx_b, δθ_b)`.
    pub gradient: [f64; 12],
    /// `∂(∇g)/∂(δθ_a, δθ_b)` on the rotation dofs: blocks `[aa, ab, ba, bb]`.
    pub curvature: [[Matrix3<f64>; 2]; 2],
}

impl Joint {
    pub fn new(
        kind: JointKind,
        nodes: [usize; 2],
        frames: [&Frame; 2],
        at_m: Vector3<f64>,
    ) -> Self {
        let markers = frames.map(|f| f.rotation.inverse() * (at_m - f.position_m));
        let local = |v: Vector3<f64>| frames.map(|f| f.rotation.inverse() * v);
        let directors = match kind {
            JointKind::Fixed => {
                let e = [Vector3::x(), Vector3::y(), Vector3::z()];
                (0..3)
                    .map(|i| {
                        let a = local(e[i])[0];
                        let b = local(e[(i + 1) % 3])[1];
                        [a, b]
                    })
                    .collect()
            }
            JointKind::Revolute { axis } => {
                let h = axis.normalize();
                let u = rod_frame(&h, &Vector3::z()) * Vector3::y();
                let v = h.cross(&u);
                vec![[local(h)[0], local(u)[1]], [local(h)[0], local(v)[1]]]
            }
            JointKind::Spherical => vec![],
        };
        Joint {
            nodes,
            markers,
            directors,
        }
    }

    /// Number of equations.
    pub fn rows(&self) -> usize {
        3 + self.directors.len()
    }

    /// Every equation at `frames`.
    pub fn evaluate(&self, frames: [&Frame; 2], out: &mut Vec<ConstraintRow>) {
        out.clear();
        let arm = [
            frames[0].rotation * self.markers[0],
            frames[1].rotation * self.markers[1],
        ];
        let gap = frames[0].position_m + arm[0] - frames[1].position_m - arm[1];
        let zero = Matrix3::zeros();
        for c in 0..3 {
            let mut e = Vector3::zeros();
            e[c] = 1.0;
            let mut gradient = [0.0; 12];
            gradient[c] = 1.0;
            gradient[6 + c] = -1.0;
            // δ(e·R ρ) = δθ·(Rρ × e).
            let ta = arm[0].cross(&e);
            let tb = -arm[1].cross(&e);
            gradient[3..6].copy_from_slice(ta.as_slice());
            gradient[9..12].copy_from_slice(tb.as_slice());
            // d/dθ (Rρ × e) = ẽ (Rρ)~ (the derivative of (δθ × a) × e).
            let ee = skew(&e);
            out.push(ConstraintRow {
                value: gap[c],
                gradient,
                curvature: [[ee * skew(&arm[0]), zero], [zero, -(ee * skew(&arm[1]))]],
            });
        }
        for [da, db] in &self.directors {
            let ea = frames[0].rotation * da;
            let eb = frames[1].rotation * db;
            let n = ea.cross(&eb);
            let mut gradient = [0.0; 12];
            gradient[3..6].copy_from_slice(n.as_slice());
            gradient[9..12].copy_from_slice((-n).as_slice());
            let (sa, sb) = (skew(&ea), skew(&eb));
            out.push(ConstraintRow {
                value: ea.dot(&eb),
                gradient,
                curvature: [[sb * sa, -(sa * sb)], [-(sb * sa), sa * sb]],
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::rotation::exp;
    use nalgebra::UnitQuaternion;

    fn frames() -> [Frame; 2] {
        [
            Frame {
                position_m: Vector3::new(0.1, 0.2, -0.3),
                rotation: exp(&Vector3::new(0.4, -0.1, 0.9)),
            },
            Frame {
                position_m: Vector3::new(0.5, -0.2, 0.1),
                rotation: exp(&Vector3::new(-0.7, 0.3, 0.2)),
            },
        ]
    }

    fn perturb(f: &[Frame; 2], i: usize, h: f64) -> [Frame; 2] {
        let mut f = *f;
        let (n, c) = (i / 6, i % 6);
        if c < 3 {
            f[n].position_m[c] += h;
        } else {
            let mut t = Vector3::zeros();
            t[c - 3] = h;
            f[n].rotation = exp(&t) * f[n].rotation;
        }
        f
    }

    #[test]
    fn gradients_and_curvatures_match_differences() {
        let reference = [
            Frame {
                position_m: Vector3::zeros(),
                rotation: UnitQuaternion::identity(),
            },
            Frame {
                position_m: Vector3::new(1.0, 0.0, 0.0),
                rotation: exp(&Vector3::new(0.0, 0.0, 0.5)),
            },
        ];
        for kind in [
            JointKind::Fixed,
            JointKind::Revolute {
                axis: Vector3::new(0.3, 1.0, 0.2),
            },
            JointKind::Spherical,
        ] {
            let joint = Joint::new(
                kind,
                [0, 1],
                [&reference[0], &reference[1]],
                Vector3::new(0.4, 0.3, 0.0),
            );
            let f = frames();
            let mut rows = vec![];
            joint.evaluate([&f[0], &f[1]], &mut rows);
            assert_eq!(rows.len(), joint.rows());
            let h = 1e-6;
            for j in 0..12 {
                let (p, m) = (perturb(&f, j, h), perturb(&f, j, -h));
                let (mut rp, mut rm) = (vec![], vec![]);
                joint.evaluate([&p[0], &p[1]], &mut rp);
                joint.evaluate([&m[0], &m[1]], &mut rm);
                for (k, row) in rows.iter().enumerate() {
                    let fd = (rp[k].value - rm[k].value) / (2.0 * h);
                    assert!(
                        (fd - row.gradient[j]).abs() < 1e-8,
                        "{kind:?} row {k} dof {j}"
                    );
                    // Derivative of the rotational gradient along rotation dof j.
                    if j % 6 >= 3 {
                        let (nb, cj) = (j / 6, j % 6 - 3);
                        for na in 0..2 {
                            for ci in 0..3 {
                                let i = 6 * na + 3 + ci;
                                let fd = (rp[k].gradient[i] - rm[k].gradient[i]) / (2.0 * h);
                                let an = row.curvature[na][nb][(ci, cj)];
                                assert!(
                                    (fd - an).abs() < 1e-7,
                                    "{kind:?} row {k} ∂g[{i}]/∂θ[{j}]: {fd} vs {an}"
                                );
                            }
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn reference_configuration_satisfies_every_joint() {
        let reference = [
            Frame {
                position_m: Vector3::zeros(),
                rotation: exp(&Vector3::new(0.2, 0.1, 0.0)),
            },
            Frame {
                position_m: Vector3::new(1.0, 2.0, 0.0),
                rotation: exp(&Vector3::new(0.0, 0.0, 0.5)),
            },
        ];
        for kind in [JointKind::Fixed, JointKind::Revolute { axis: Vector3::z() }] {
            let joint = Joint::new(
                kind,
                [0, 1],
                [&reference[0], &reference[1]],
                Vector3::new(0.5, 0.5, 0.5),
            );
            let mut rows = vec![];
            joint.evaluate([&reference[0], &reference[1]], &mut rows);
            assert!(rows.iter().all(|r| r.value.abs() < 1e-15));
        }
    }
}
