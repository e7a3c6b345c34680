//! A tension-only elastic cable between the positions of two nodes (DESIGN §7):
//! the element that assembles a designed net onto the flexible truss.
//!
//! Tension `T = EA (ℓ − L₀)/L₀` while `ℓ > L₀`. A slack cable keeps a stiffness
//! of [`SLACK_STIFFNESS_RATIO`] × EA so that a node held only by slack cables
//! does not make the tangent singular; the force it carries then is negligible
//! and the cable is reported slack.
//!
//! The unstressed length is ramped with the load factor λ, from the reference
//! distance of the nodes (no stress at λ = 0) to the cut length (at λ = 1):
//! the prestrain enters as load steps.

use nalgebra::{Matrix3, Vector3};

use super::node::NodeId;

/// Axial stiffness of a slack cable, as a fraction of its EA.
pub const SLACK_STIFFNESS_RATIO: f64 = 1e-9;

/// A cable element.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cable {
    /// End nodes (frames or points; only their positions are used).
    pub(crate) nodes: [NodeId; 2],
    /// Axial stiffness EA, N.
    pub(crate) axial_n: f64,
    /// Unstressed length at λ = 0 and at λ = 1, m.
    pub(crate) rest_lengths_m: [f64; 2],
}

/// A cable's state at a configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CableState {
    /// Length, m.
    pub length_m: f64,
    /// Tension, N (≤ 0 only by the slack regularisation).
    pub tension_n: f64,
    /// True when the cable is not longer than its unstressed length.
    pub slack: bool,
}

impl Cable {
    /// Unstressed length at load factor `lambda`, m.
    pub fn rest_length_m(&self, lambda: f64) -> f64 {
        let [start, end] = self.rest_lengths_m;
        start + lambda * (end - start)
    }

    /// Axial stiffness EA, N.
    pub fn axial_n(&self) -> f64 {
        self.axial_n
    }

    /// End nodes.
    pub fn nodes(&self) -> [NodeId; 2] {
        self.nodes
    }

    /// Length, tension and slackness between positions `a` and `b` at `lambda`.
    pub fn state(&self, a: &Vector3<f64>, b: &Vector3<f64>, lambda: f64) -> CableState {
        let length_m = (b - a).norm();
        let rest = self.rest_length_m(lambda);
        let slack = length_m <= rest;
        CableState {
            length_m,
            tension_n: self.modulus(slack) * (length_m - rest) / rest,
            slack,
        }
    }

    fn modulus(&self, slack: bool) -> f64 {
        if slack {
            SLACK_STIFFNESS_RATIO * self.axial_n
        } else {
            self.axial_n
        }
    }

    /// Internal force on the end node `b` (the force on `a` is its negative),
    /// `T e` with `e = (b − a)/ℓ`: [`Cable::force_tangent`]'s force alone.
    pub(crate) fn force(&self, a: &Vector3<f64>, b: &Vector3<f64>, lambda: f64) -> Vector3<f64> {
        let s = self.state(a, b, lambda);
        (b - a) / s.length_m * s.tension_n
    }

    /// Internal force on the end node `b` (the force on `a` is its negative),
    /// `T e` with `e = (b − a)/ℓ`, and its derivative with respect to `x_b`:
    /// `k = (EA/L₀) e eᵀ + (T/ℓ)(I − e eᵀ)` (the element tangent is
    /// `[k −k; −k k]`), where a slack cable's axial term is
    /// `slack_tangent_ratio × EA/L₀`: [`SLACK_STIFFNESS_RATIO`] for the
    /// exact derivative, more for an iteration matrix that keeps part of a
    /// slack cable's stiffness (the force is the same either way).
    pub(crate) fn force_tangent(
        &self,
        a: &Vector3<f64>,
        b: &Vector3<f64>,
        lambda: f64,
        slack_tangent_ratio: f64,
    ) -> (Vector3<f64>, Matrix3<f64>) {
        let u = b - a;
        let s = self.state(a, b, lambda);
        let e = u / s.length_m;
        let eet = e * e.transpose();
        let modulus = if s.slack {
            slack_tangent_ratio * self.axial_n
        } else {
            self.axial_n
        };
        let axial = modulus / self.rest_length_m(lambda);
        let k = eet * axial + (Matrix3::identity() - eet) * (s.tension_n / s.length_m);
        (e * s.tension_n, k)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cable() -> Cable {
        Cable {
            nodes: [0, 1],
            axial_n: 1e6,
            rest_lengths_m: [2.0, 1.9],
        }
    }

    #[test]
    fn tension_follows_the_ramped_rest_length() {
        let c = cable();
        let (a, b) = (Vector3::zeros(), Vector3::new(2.0, 0.0, 0.0));
        assert_eq!(c.state(&a, &b, 0.0).tension_n, 0.0);
        let s = c.state(&a, &b, 1.0);
        assert!((s.tension_n - 1e6 * 0.1 / 1.9).abs() < 1e-9);
        assert!(!s.slack);
        assert!(c.state(&a, &Vector3::new(1.5, 0.0, 0.0), 1.0).slack);
    }

    #[test]
    fn tangent_matches_central_differences_taut_and_slack() {
        let c = cable();
        let a = Vector3::new(0.1, -0.2, 0.3);
        for b in [Vector3::new(1.7, 0.9, -0.4), Vector3::new(0.9, 0.5, 0.2)] {
            let (_, k) = c.force_tangent(&a, &b, 0.7, SLACK_STIFFNESS_RATIO);
            let h = 1e-6;
            for j in 0..3 {
                let mut d = Vector3::zeros();
                d[j] = h;
                let fd = (c.force_tangent(&a, &(b + d), 0.7, SLACK_STIFFNESS_RATIO).0
                    - c.force_tangent(&a, &(b - d), 0.7, SLACK_STIFFNESS_RATIO).0)
                    / (2.0 * h);
                let scale = k.amax();
                assert!(
                    (fd - k.column(j)).amax() <= 1e-6 * scale,
                    "column {j}: {fd} vs {}",
                    k.column(j)
                );
            }
        }
    }

    /// An iteration matrix's slack ratio changes a slack cable's axial
    /// stiffness only: not its force, not a taut cable.
    #[test]
    fn a_slack_tangent_ratio_changes_only_a_slack_cables_axial_stiffness() {
        let c = cable();
        let a = Vector3::new(0.1, -0.2, 0.3);
        let slack = Vector3::new(0.9, 0.5, 0.2);
        let taut = Vector3::new(1.7, 0.9, -0.4);
        let (f0, k0) = c.force_tangent(&a, &taut, 0.7, SLACK_STIFFNESS_RATIO);
        let (f1, k1) = c.force_tangent(&a, &taut, 0.7, 0.01);
        assert_eq!((f0, k0), (f1, k1));
        let (f0, k0) = c.force_tangent(&a, &slack, 0.7, SLACK_STIFFNESS_RATIO);
        let (f1, k1) = c.force_tangent(&a, &slack, 0.7, 0.01);
        assert_eq!(f0, f1);
        let e = (slack - a).normalize();
        let extra = (0.01 - SLACK_STIFFNESS_RATIO) * c.axial_n / c.rest_length_m(0.7);
        assert!((k1 - k0 - e * e.transpose() * extra).amax() <= 1e-9 * extra);
    }
}
