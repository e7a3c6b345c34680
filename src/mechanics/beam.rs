//! Geometrically exact 2-node beam elements (paper §3.2): the paper's
//! Simo–Reissner element with Crisfield–Jelenić interpolation, and the
//! helicoidal SE(3) element (Sonneville, Cardona, Brüls 2014).
//!
//! Both are hyperelastic: an element is its strain energy `W(x_A, R_A, x_B, R_B)`.
//! The residual and the consistent tangent come from `W` by forward-mode
//! automatic differentiation (second-order dual numbers, [`num_dual`]) with
//! respect to the perturbation `ξ = (δx_A, δθ_A, δx_B, δθ_B)` of the current
//! configuration, `x ← x + δx`, `R ← exp(δθ̃) R` (spatial increments):
//!
//! * residual `r = ∂W/∂ξ |₀` (internal force and spatial moment per node);
//! * tangent `K = ∂²W/∂ξ² |₀ − ½ blockdiag(0, r̃_θA, 0, r̃_θB)`: the second term is
//!   the Lie bracket of spatial rotation increments, which makes `K` the exact
//!   derivative of `r` along `R ← exp(δθ̃) R` (it vanishes at equilibrium,
//!   leaving the symmetric Hessian).
//!
//! Material frame: the nodal rotation's first column is the rod axis, the other
//! two the principal axes of the section; `C_N = diag(EA, GA₂, GA₃)`,
//! `C_M = diag(GJ, EI₂, EI₃)` (paper eq. 21).

use nalgebra::{Matrix3, SMatrix, SVector, UnitQuaternion, Vector3};
use num_dual::{hessian, DualNum};
use serde::{Deserialize, Serialize};

use super::rotation::{
    exp_generic, exp_second_order, left_jacobian_inverse_generic, lift_m, lift_v, log_generic,
    mat_mat, mat_t_mat, mat_t_vec, mat_vec, scale, sub, M3, V3,
};

/// Which beam element a rod is meshed with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum ElementKind {
    /// Helicoidal interpolation on SE(3): strains from the logarithm of the
    /// relative nodal frame, constant per element; exact for uniformly bent
    /// rods and free of shear locking. The default.
    #[default]
    Se3,
    /// The paper's element (eq. 17–21): Crisfield–Jelenić interpolation of
    /// rotations about the mid-element reference rotation, linear centreline,
    /// one-point (reduced) integration against shear locking.
    CrisfieldJelenic,
}

impl ElementKind {
    /// The name used in files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ElementKind::Se3 => "se3",
            ElementKind::CrisfieldJelenic => "crisfield-jelenic",
        }
    }
}

/// Section stiffnesses of a rod (paper eq. 21): `EA`, `GA₂`, `GA₃` in N,
/// `GJ`, `EI₂`, `EI₃` in N·m².
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Section {
    /// Axial stiffness EA, N.
    pub axial_n: f64,
    /// Shear stiffnesses GA₂, GA₃ (shear area included), N.
    pub shear_n: [f64; 2],
    /// Torsional stiffness GJ, N·m².
    pub torsion_nm2: f64,
    /// Bending stiffnesses EI₂, EI₃, N·m².
    pub bending_nm2: [f64; 2],
}

impl Section {
    /// A circular tube of outer/inner diameter `d_o`, `d_i` (m): `A = π(d_o² − d_i²)/4`,
    /// `I = π(d_o⁴ − d_i⁴)/64`, `J = 2I`, shear coefficient `κ = 2(1+ν)/(4+3ν)`
    /// of a thin tube (Cowper), with `ν = E/(2G) − 1`.
    pub fn tube(d_o: f64, d_i: f64, youngs_modulus_pa: f64, shear_modulus_pa: f64) -> Section {
        let area = std::f64::consts::PI * (d_o * d_o - d_i * d_i) / 4.0;
        let inertia = std::f64::consts::PI * (d_o.powi(4) - d_i.powi(4)) / 64.0;
        let nu = youngs_modulus_pa / (2.0 * shear_modulus_pa) - 1.0;
        let kappa = 2.0 * (1.0 + nu) / (4.0 + 3.0 * nu);
        let ga = kappa * shear_modulus_pa * area;
        Section {
            axial_n: youngs_modulus_pa * area,
            shear_n: [ga, ga],
            torsion_nm2: shear_modulus_pa * 2.0 * inertia,
            bending_nm2: [youngs_modulus_pa * inertia; 2],
        }
    }

    /// The six stiffnesses `(EA, GA₂, GA₃, GJ, EI₂, EI₃)`.
    pub fn diagonal(&self) -> [f64; 6] {
        [
            self.axial_n,
            self.shear_n[0],
            self.shear_n[1],
            self.torsion_nm2,
            self.bending_nm2[0],
            self.bending_nm2[1],
        ]
    }

    /// The first invalid stiffness (`"axial_n"`, …), if any is not finite and positive.
    pub fn invalid_field(&self) -> Option<&'static str> {
        let names = [
            "axial_n",
            "shear_n",
            "shear_n",
            "torsion_nm2",
            "bending_nm2",
            "bending_nm2",
        ];
        self.diagonal()
            .iter()
            .zip(names)
            .find(|(v, _)| !(v.is_finite() && **v > 0.0))
            .map(|(_, n)| n)
    }
}

/// One 2-node element: its kind, section, and reference strains.
#[derive(Debug, Clone)]
pub(crate) struct BeamElement {
    pub kind: ElementKind,
    pub nodes: [usize; 2],
    pub length_m: f64,
    stiffness: [f64; 6],
    /// Strains of the reference configuration (`Γ₀`, `K₀`, or `d₀/L`).
    reference_strain: [f64; 6],
}

/// A node's configuration: position and rotation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Position, m.
    pub position_m: Vector3<f64>,
    /// Rotation from the material to the spatial frame.
    pub rotation: UnitQuaternion<f64>,
}

/// The element's configuration as seen by the energy kernels.
struct Configuration {
    x: [V3<f64>; 2],
    r: [M3<f64>; 2],
}

impl Configuration {
    fn of(frames: [&Frame; 2]) -> Self {
        Configuration {
            x: frames.map(|f| lift_v(&f.position_m)),
            r: frames.map(|f| lift_m(f.rotation.to_rotation_matrix().matrix())),
        }
    }

    /// Positions and rotations perturbed by `ξ = (δx_A, δθ_A, δx_B, δθ_B)`.
    fn perturbed<S: DualNum<f64> + Copy>(&self, xi: &[S; 12]) -> ([V3<S>; 2], [M3<S>; 2]) {
        let x = std::array::from_fn(|n| std::array::from_fn(|c| xi[6 * n + c] + self.x[n][c]));
        let r = std::array::from_fn(|n| {
            let e = exp_second_order(&[xi[6 * n + 3], xi[6 * n + 4], xi[6 * n + 5]]);
            let rn: M3<S> = self.r[n].map(|row| row.map(S::from));
            mat_mat(&e, &rn)
        });
        (x, r)
    }
}

/// Strains `(Γ, K)` of the element (before subtracting the reference).
fn strains<S: DualNum<f64> + Copy>(
    kind: ElementKind,
    length_m: f64,
    x: &[V3<S>; 2],
    r: &[M3<S>; 2],
) -> [S; 6] {
    let chord = sub(&x[1], &x[0]);
    let relative = mat_t_mat(&r[0], &r[1]);
    let phi = log_generic(&relative);
    let inv_l = 1.0 / length_m;
    match kind {
        ElementKind::Se3 => {
            // d = log(H_A⁻¹ H_B) = (V⁻¹(Ω) R_Aᵀ (x_B − x_A), Ω); ε = d / L.
            let t = mat_t_vec(&r[0], &chord);
            let u = mat_vec(&left_jacobian_inverse_generic(&phi), &t);
            [
                u[0] * inv_l,
                u[1] * inv_l,
                u[2] * inv_l,
                phi[0] * inv_l,
                phi[1] * inv_l,
                phi[2] * inv_l,
            ]
        }
        ElementKind::CrisfieldJelenic => {
            // Reference rotation R_r = R_A exp(φ/2) (eq. 17); local rotations
            // ∓φ/2 interpolated linearly (eq. 18) give K = φ/L along the
            // element; Γ = R_rᵀ x′ at the one integration point (eq. 21).
            let half = scale(&phi, S::from(0.5));
            let r_ref = mat_mat(&r[0], &exp_generic(&half));
            let gamma = mat_t_vec(&r_ref, &chord);
            [
                gamma[0] * inv_l,
                gamma[1] * inv_l,
                gamma[2] * inv_l,
                phi[0] * inv_l,
                phi[1] * inv_l,
                phi[2] * inv_l,
            ]
        }
    }
}

impl BeamElement {
    /// An element between `nodes` whose reference configuration is `frames`.
    pub fn new(
        kind: ElementKind,
        nodes: [usize; 2],
        frames: [&Frame; 2],
        section: &Section,
    ) -> Self {
        let length_m = (frames[1].position_m - frames[0].position_m).norm();
        let c = Configuration::of(frames);
        let reference_strain = strains(kind, length_m, &c.x, &c.r);
        BeamElement {
            kind,
            nodes,
            length_m,
            stiffness: section.diagonal(),
            reference_strain,
        }
    }

    /// Strain energy `W = (L/2) εᵀ C ε` at the perturbed configuration.
    fn energy<S: DualNum<f64> + Copy>(&self, c: &Configuration, xi: &[S; 12]) -> S {
        let (x, r) = c.perturbed(xi);
        let e = strains(self.kind, self.length_m, &x, &r);
        let mut w = S::zero();
        for ((e, e0), c) in e.iter().zip(&self.reference_strain).zip(&self.stiffness) {
            let d = *e - *e0;
            w += d * d * *c;
        }
        w * (0.5 * self.length_m)
    }

    /// Axial stiffness over length, `EA/L`, N/m.
    pub fn axial_stiffness(&self) -> f64 {
        self.stiffness[0] / self.length_m
    }

    /// Strain energy at `frames`, J.
    #[cfg(test)]
    pub fn strain_energy(&self, frames: [&Frame; 2]) -> f64 {
        self.energy(&Configuration::of(frames), &[0.0; 12])
    }

    /// Residual (internal nodal forces and spatial moments, 12) and consistent
    /// tangent (12 × 12) at `frames`.
    pub fn residual_tangent(
        &self,
        frames: [&Frame; 2],
    ) -> (SVector<f64, 12>, SMatrix<f64, 12, 12>) {
        let c = Configuration::of(frames);
        let (_, r, mut k) = hessian(
            |xi: SVector<_, 12>| {
                let xi: [_; 12] = std::array::from_fn(|i| xi[i]);
                self.energy(&c, &xi)
            },
            SVector::<f64, 12>::zeros(),
        );
        for node in 0..2 {
            let m = Vector3::new(r[6 * node + 3], r[6 * node + 4], r[6 * node + 5]);
            let half_skew: Matrix3<f64> = super::rotation::skew(&m) * 0.5;
            let o = 6 * node + 3;
            for i in 0..3 {
                for j in 0..3 {
                    k[(o + i, o + j)] -= half_skew[(i, j)];
                }
            }
        }
        (r, k)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::rotation::exp;

    fn section() -> Section {
        Section::tube(0.024, 0.022, 160e9, 61.5e9)
    }

    /// A bent, twisted, stretched element far from its straight reference.
    fn deformed(kind: ElementKind) -> (BeamElement, [Frame; 2]) {
        let rot = exp(&Vector3::new(0.1, -0.2, 0.3));
        let a0 = Frame {
            position_m: Vector3::new(0.0, 0.0, 0.0),
            rotation: rot,
        };
        let b0 = Frame {
            position_m: Vector3::new(0.0, 0.0, 0.0) + rot * Vector3::new(0.7, 0.0, 0.0),
            rotation: rot,
        };
        let element = BeamElement::new(kind, [0, 1], [&a0, &b0], &section());
        let a = Frame {
            position_m: Vector3::new(0.01, -0.02, 0.005),
            rotation: exp(&Vector3::new(0.3, 0.2, -0.4)) * rot,
        };
        let b = Frame {
            position_m: Vector3::new(0.6, 0.25, -0.1),
            rotation: exp(&Vector3::new(-0.5, 0.6, 0.7)) * rot,
        };
        (element, [a, b])
    }

    fn perturb(frames: &[Frame; 2], i: usize, h: f64) -> [Frame; 2] {
        let mut f = *frames;
        let node = i / 6;
        let c = i % 6;
        if c < 3 {
            f[node].position_m[c] += h;
        } else {
            let mut t = Vector3::zeros();
            t[c - 3] = h;
            f[node].rotation = exp(&t) * f[node].rotation;
        }
        f
    }

    #[test]
    fn residual_matches_energy_differences() {
        for kind in [ElementKind::Se3, ElementKind::CrisfieldJelenic] {
            let (e, frames) = deformed(kind);
            let (r, _) = e.residual_tangent([&frames[0], &frames[1]]);
            let scale = r.amax();
            for i in 0..12 {
                let h = 1e-6;
                let p = perturb(&frames, i, h);
                let m = perturb(&frames, i, -h);
                let fd =
                    (e.strain_energy([&p[0], &p[1]]) - e.strain_energy([&m[0], &m[1]])) / (2.0 * h);
                assert!(
                    (fd - r[i]).abs() < 1e-6 * scale,
                    "{kind:?} dof {i}: {fd} vs {}",
                    r[i]
                );
            }
        }
    }

    #[test]
    fn tangent_matches_residual_differences() {
        for kind in [ElementKind::Se3, ElementKind::CrisfieldJelenic] {
            let (e, frames) = deformed(kind);
            let (_, k) = e.residual_tangent([&frames[0], &frames[1]]);
            let scale = k.amax();
            for j in 0..12 {
                let h = 1e-7;
                let p = perturb(&frames, j, h);
                let m = perturb(&frames, j, -h);
                let (rp, _) = e.residual_tangent([&p[0], &p[1]]);
                let (rm, _) = e.residual_tangent([&m[0], &m[1]]);
                let fd = (rp - rm) / (2.0 * h);
                for i in 0..12 {
                    assert!(
                        (fd[i] - k[(i, j)]).abs() < 1e-6 * scale,
                        "{kind:?} K[{i},{j}]: fd {} vs {}",
                        fd[i],
                        k[(i, j)]
                    );
                }
            }
        }
    }

    #[test]
    fn reference_configuration_is_stress_free() {
        for kind in [ElementKind::Se3, ElementKind::CrisfieldJelenic] {
            let (e, _) = deformed(kind);
            let rot = exp(&Vector3::new(0.1, -0.2, 0.3));
            let a = Frame {
                position_m: Vector3::zeros(),
                rotation: rot,
            };
            let b = Frame {
                position_m: rot * Vector3::new(0.7, 0.0, 0.0),
                rotation: rot,
            };
            let (r, _) = e.residual_tangent([&a, &b]);
            assert!(r.amax() < 1e-9, "{kind:?}: {}", r.amax());
        }
    }
}
