//! Rotations: SO(3) exponential and logarithm, the tangent operator, the
//! generic-scalar kernels the beam elements differentiate (paper eq. 7–14),
//! and the material frame of a straight rod ([`rod_frame`]), which the model
//! meshes rods with and revolute joints take their directors from.
//!
//! Conventions. A rotation vector `θ` (axis × angle) maps to `R = exp(θ̃)`
//! (Rodrigues, paper eq. 7); `θ̃` is the skew matrix with `θ̃ v = θ × v`.
//! Nodal rotations are stored as unit quaternions and updated multiplicatively
//! by a *spatial* increment, `R ← exp(δθ̃) R` (paper eq. 10), so no
//! parametrisation is ever evaluated at a large total angle: a rod may roll up
//! any number of times. The tangent operator `T(θ)` relates the increment to the
//! change of the rotation vector, `δθ_spatial = T(θ) δθ` (paper eq. 11–14).
//!
//! The `*_generic` kernels work on any scalar implementing
//! [`num_dual::DualNum`], so the element energies can be differentiated twice
//! exactly; near zero angle they switch to Taylor series in `θ²`, which stay
//! differentiable where `|θ|` is not.

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use num_dual::DualNum;

/// The skew matrix `ṽ` of a vector: `ṽ w = v × w`.
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// `exp(θ̃)` as a unit quaternion, any angle (paper eq. 7).
pub fn exp(theta: &Vector3<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::from_scaled_axis(*theta)
}

/// The rotation vector of `q` with angle in `[0, π]` (the principal logarithm).
pub fn log(q: &UnitQuaternion<f64>) -> Vector3<f64> {
    // Pick the hemisphere w ≥ 0 so the angle 2·atan2(|v|, w) is at most π.
    let (w, v) = if q.w >= 0.0 {
        (q.w, q.imag())
    } else {
        (-q.w, -q.imag())
    };
    let s = v.norm();
    if s < 1e-8 {
        // 2 atan(s/w)/s = (2/w)(1 − s²/(3w²) + …); s < 1e-8 leaves O(1e-16).
        v * (2.0 / w)
    } else {
        v * (2.0 * s.atan2(w) / s)
    }
}

/// The tangent operator `T(θ) = I + ((1 − cos θ)/θ²) θ̃ + ((θ − sin θ)/θ³) θ̃²`
/// (paper eq. 12): a spatial angular increment `δφ = T(θ) δθ` of `R = exp(θ̃)`.
pub fn tangent(theta: &Vector3<f64>) -> Matrix3<f64> {
    let t2 = theta.norm_squared();
    let (a, b) = if t2 < 1e-6 {
        (
            0.5 - t2 / 24.0 + t2 * t2 / 720.0,
            1.0 / 6.0 - t2 / 120.0 + t2 * t2 / 5040.0,
        )
    } else {
        let t = t2.sqrt();
        ((1.0 - t.cos()) / t2, (t - t.sin()) / (t2 * t))
    };
    let s = skew(theta);
    Matrix3::identity() + s * a + s * s * b
}

/// The inverse tangent operator
/// `T⁻¹(θ) = I − ½ θ̃ + (1 − (θ/2) cot(θ/2))/θ² θ̃²` (paper eq. 14).
///
/// # Panics
/// Where `|θ| ≥ 2π`, at which `T` is singular.
#[track_caller]
pub fn tangent_inverse(theta: &Vector3<f64>) -> Matrix3<f64> {
    let t2 = theta.norm_squared();
    assert!(
        t2 < (std::f64::consts::TAU).powi(2),
        "T(θ) is singular at |θ| = 2π"
    );
    let c = if t2 < 1e-4 {
        1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30240.0
    } else {
        let t = t2.sqrt();
        (1.0 - 0.5 * t / (0.5 * t).tan()) / t2
    };
    let s = skew(theta);
    Matrix3::identity() - s * 0.5 + s * s * c
}

// ---------------------------------------------------------------------------
// Generic-scalar kernels (3-vectors and 3×3 matrices as arrays, row-major).

/// A 3-vector of a generic scalar.
pub(crate) type V3<S> = [S; 3];
/// A 3×3 matrix of a generic scalar, row-major.
pub(crate) type M3<S> = [[S; 3]; 3];

pub(crate) fn lift_v(v: &Vector3<f64>) -> V3<f64> {
    [v.x, v.y, v.z]
}

pub(crate) fn lift_m(m: &Matrix3<f64>) -> M3<f64> {
    [
        [m[(0, 0)], m[(0, 1)], m[(0, 2)]],
        [m[(1, 0)], m[(1, 1)], m[(1, 2)]],
        [m[(2, 0)], m[(2, 1)], m[(2, 2)]],
    ]
}

pub(crate) fn dot<S: DualNum<f64> + Copy>(a: &V3<S>, b: &V3<S>) -> S {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The material frame of a rod: first axis along `axis`, second as close to
/// `up` as possible (or to a global axis, when `up` is along the rod).
pub fn rod_frame(axis: &Vector3<f64>, up: &Vector3<f64>) -> UnitQuaternion<f64> {
    let e1 = axis.normalize();
    let mut helper = *up - e1 * e1.dot(up);
    if helper.norm() < 1e-8 * up.norm().max(1.0) {
        // Any axis the rod is least aligned with.
        let k = e1.iamin();
        let mut g = Vector3::zeros();
        g[k] = 1.0;
        helper = g - e1 * e1.dot(&g);
    }
    let e2 = helper.normalize();
    let e3 = e1.cross(&e2);
    let m = Matrix3::from_columns(&[e1, e2, e3]);
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(m))
}

#[cfg(test)]
pub(crate) fn sub<S: DualNum<f64> + Copy>(a: &V3<S>, b: &V3<S>) -> V3<S> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(crate) fn scale<S: DualNum<f64> + Copy>(a: &V3<S>, s: S) -> V3<S> {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// `A b`.
pub(crate) fn mat_vec<S: DualNum<f64> + Copy>(a: &M3<S>, b: &V3<S>) -> V3<S> {
    [dot(&a[0], b), dot(&a[1], b), dot(&a[2], b)]
}

/// `Aᵀ b`.
#[cfg(test)]
pub(crate) fn mat_t_vec<S: DualNum<f64> + Copy>(a: &M3<S>, b: &V3<S>) -> V3<S> {
    std::array::from_fn(|j| a[0][j] * b[0] + a[1][j] * b[1] + a[2][j] * b[2])
}

/// `A B`.
#[cfg(test)]
pub(crate) fn mat_mat<S: DualNum<f64> + Copy>(a: &M3<S>, b: &M3<S>) -> M3<S> {
    std::array::from_fn(|i| {
        std::array::from_fn(|j| a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j])
    })
}

/// `Aᵀ B`.
#[cfg(test)]
pub(crate) fn mat_t_mat<S: DualNum<f64> + Copy>(a: &M3<S>, b: &M3<S>) -> M3<S> {
    std::array::from_fn(|i| {
        std::array::from_fn(|j| a[0][i] * b[0][j] + a[1][i] * b[1][j] + a[2][i] * b[2][j])
    })
}

/// `I + α ṽ + β ṽ²` — the shape of every SO(3) series (exp, T, T⁻¹, V⁻¹).
fn rodrigues_form<S: DualNum<f64> + Copy>(v: &V3<S>, alpha: S, beta: S) -> M3<S> {
    let vv = dot(v, v);
    let skew = [
        [S::zero(), -v[2], v[1]],
        [v[2], S::zero(), -v[0]],
        [-v[1], v[0], S::zero()],
    ];
    // ṽ² = v vᵀ − |v|² I.
    std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            let id = if i == j { S::one() } else { S::zero() };
            let sq = v[i] * v[j] - if i == j { vv } else { S::zero() };
            id + skew[i][j] * alpha + sq * beta
        })
    })
}

/// `exp(θ̃)` to second order, `I + θ̃ + ½ θ̃²`: exact value, first and second
/// derivatives at `θ = 0`, which is all a perturbation of the current
/// configuration needs.
pub(crate) fn exp_second_order<S: DualNum<f64> + Copy>(theta: &V3<S>) -> M3<S> {
    rodrigues_form(theta, S::one(), S::from(0.5))
}

/// `exp(θ̃)` for any angle (paper eq. 7), smooth through `θ = 0`.
pub(crate) fn exp_generic<S: DualNum<f64> + Copy>(theta: &V3<S>) -> M3<S> {
    let t2 = dot(theta, theta);
    let (a, b) = if t2.re() < 1e-4 {
        // sin θ/θ and (1 − cos θ)/θ² to O(θ⁸): error < 1e-20 at θ² = 1e-4.
        (
            S::one() - t2 / 6.0 + t2 * t2 / 120.0 - t2 * t2 * t2 / 5040.0,
            S::from(0.5) - t2 / 24.0 + t2 * t2 / 720.0 - t2 * t2 * t2 / 40320.0,
        )
    } else {
        let t = t2.sqrt();
        let (s, c) = t.sin_cos();
        (s / t, (S::one() - c) / t2)
    };
    rodrigues_form(theta, a, b)
}

/// The rotation vector of a rotation matrix whose angle is below π
/// (element-relative rotations), smooth through `θ = 0`.
pub(crate) fn log_generic<S: DualNum<f64> + Copy>(r: &M3<S>) -> V3<S> {
    // s = sin θ · n from the skew part, cos θ from the trace.
    let s = [
        (r[2][1] - r[1][2]) * 0.5,
        (r[0][2] - r[2][0]) * 0.5,
        (r[1][0] - r[0][1]) * 0.5,
    ];
    let c = (r[0][0] + r[1][1] + r[2][2] - 1.0) * 0.5;
    let s2 = dot(&s, &s);
    let factor = if s2.re() < 1e-4 && c.re() > 0.0 {
        // θ/sin θ = arcsin(x)/x with x = sin θ: 1 + x²/6 + 3x⁴/40 + 5x⁶/112 + 35x⁸/1152.
        S::one()
            + s2 / 6.0
            + s2 * s2 * 0.075
            + s2 * s2 * s2 * (5.0 / 112.0)
            + s2 * s2 * s2 * s2 * (35.0 / 1152.0)
    } else {
        let sn = s2.sqrt();
        // num_dual's atan2 is atan(y/x) with the value put right: at x = 0
        // exactly (θ = π/2, which the reference of a quarter-circle element
        // meets) its derivatives are 0/0. There, the same function as
        // π/2 − atan(x/y), y = |s| = 1; elsewhere atan2 as it always was.
        let angle = if c.re() == 0.0 {
            S::from(std::f64::consts::FRAC_PI_2) - (c / sn).atan()
        } else {
            sn.atan2(c)
        };
        angle / sn
    };
    scale(&s, factor)
}

/// `V⁻¹(Ω) = I − ½ Ω̃ + (1 − (θ/2) cot(θ/2))/θ² Ω̃²`: the translational part of
/// the SE(3) logarithm is `U = V⁻¹(Ω) t` (Sonneville, Cardona, Brüls 2014).
pub(crate) fn left_jacobian_inverse_generic<S: DualNum<f64> + Copy>(omega: &V3<S>) -> M3<S> {
    let t2 = dot(omega, omega);
    let c = if t2.re() < 1e-2 {
        // 1/12 + θ²/720 + θ⁴/30240 + θ⁶/1209600: error < 1e-17 at θ² = 1e-2.
        S::from(1.0 / 12.0) + t2 / 720.0 + t2 * t2 / 30240.0 + t2 * t2 * t2 / 1209600.0
    } else {
        let t = t2.sqrt();
        let half = t * 0.5;
        (S::one() - half * half.cos() / half.sin()) / t2
    };
    rodrigues_form(omega, S::from(-0.5), c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn to_matrix(m: &M3<f64>) -> Matrix3<f64> {
        Matrix3::from_fn(|i, j| m[i][j])
    }

    #[test]
    fn generic_exp_and_log_match_quaternions() {
        for &angle in &[1e-9, 1e-3, 0.05, 0.3, 1.0, 2.0, 3.0] {
            let theta = Vector3::new(0.3, -0.5, 0.8).normalize() * angle;
            let r = exp(&theta).to_rotation_matrix().into_inner();
            let rg = to_matrix(&exp_generic(&lift_v(&theta)));
            assert!((r - rg).norm() < 1e-15, "exp at {angle}");
            let back = log_generic(&lift_m(&r));
            let back = Vector3::new(back[0], back[1], back[2]);
            assert!(
                (back - theta).norm() < 1e-13 * angle.max(1e-3),
                "log at {angle}"
            );
        }
    }

    #[test]
    fn generic_log_is_differentiable_at_a_quarter_turn() {
        // A quarter turn about y whose trace is exactly 1 (cos θ = 0, where
        // atan2 of dual numbers divides by zero): the gradient and Hessian of
        // a component mix of log(R exp(p̃)) at p = 0 are finite and match
        // central differences of the f64 logarithm.
        use nalgebra::SVector;
        use num_dual::{hessian, Dual2SVec64};
        let r = [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]];
        let weights = [0.3, -0.5, 0.8];
        fn mix<S: DualNum<f64> + Copy>(r: &M3<f64>, w: &[f64; 3], e: &M3<S>) -> S {
            let q: M3<S> = std::array::from_fn(|i| {
                std::array::from_fn(|j| e[0][j] * r[i][0] + e[1][j] * r[i][1] + e[2][j] * r[i][2])
            });
            let l = log_generic(&q);
            l[0] * w[0] + l[1] * w[1] + l[2] * w[2]
        }
        let (_, g, h) = hessian(
            |p: SVector<Dual2SVec64<3>, 3>| {
                mix(&r, &weights, &exp_second_order(&[p[0], p[1], p[2]]))
            },
            SVector::<f64, 3>::zeros(),
        );
        let at = |p: Vector3<f64>| mix(&r, &weights, &exp_generic(&lift_v(&p)));
        let unit = |i: usize| Vector3::from_fn(|k, _| if k == i { 1.0 } else { 0.0 });
        for i in 0..3 {
            let d = 1e-6;
            let fd = (at(unit(i) * d) - at(-unit(i) * d)) / (2.0 * d);
            assert!((g[i] - fd).abs() < 1e-9, "gradient {i}: {} vs {fd}", g[i]);
            for j in 0..3 {
                let d = 1e-4;
                let (a, b) = (unit(i) * d, unit(j) * d);
                let fd = (at(a + b) - at(a - b) - at(b - a) + at(-a - b)) / (4.0 * d * d);
                assert!(
                    (h[(i, j)] - fd).abs() < 1e-6,
                    "Hessian {i}{j}: {} vs {fd}",
                    h[(i, j)]
                );
            }
        }
    }

    #[test]
    fn tangent_inverse_inverts_tangent() {
        for &angle in &[0.0, 1e-4, 0.5, 3.0, 6.0] {
            let theta = Vector3::new(-0.2, 0.9, 0.4).normalize() * angle;
            let p = tangent(&theta) * tangent_inverse(&theta);
            assert!((p - Matrix3::identity()).norm() < 1e-12, "angle {angle}");
        }
    }

    #[test]
    fn tangent_maps_parameter_change_to_spatial_increment() {
        // exp(θ + h δθ) ≈ exp(h T(θ) δθ) exp(θ) for small h.
        let theta = Vector3::new(0.7, -1.1, 2.0);
        let d = Vector3::new(0.3, 0.2, -0.5);
        let h = 1e-6;
        let lhs = exp(&(theta + d * h)) * exp(&theta).inverse();
        let spatial = log(&lhs) / h;
        assert!((spatial - tangent(&theta) * d).norm() < 1e-6);
        let _ = PI;
    }
}
