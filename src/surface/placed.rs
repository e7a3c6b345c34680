//! A paraboloid of revolution placed in space (apex, axis tilts, focal length)
//! and the three deviations of a point from it: axial, normal, half path length.
//!
//! The design paraboloid `z = (x² + y²)/(4F)` is the one placed at the origin
//! with its axis along z; a best fit moves it by six parameters.

use crate::geometry::Paraboloid;
use serde::Serialize;

/// The paraboloid `{a + R q : q_z = (q_x² + q_y²)/(4F)}`: the design paraboloid
/// of focal length `F` rotated by `R = R_x(rotation_about_x_rad)·R_y(rotation_about_y_rad)`
/// and moved so its apex is at `a`. Its axis is `R ẑ`, its focus `a + F R ẑ`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PlacedParaboloid {
    /// The apex `a`, m (the design paraboloid's is the origin).
    pub apex_m: [f64; 3],
    /// Rotation about the x axis, applied after the one about y, rad: tilts
    /// the axis towards −y.
    pub rotation_about_x_rad: f64,
    /// Rotation about the y axis, rad: tilts the axis towards +x.
    pub rotation_about_y_rad: f64,
    /// Focal length F, m.
    pub focal_length_m: f64,
}

/// The deviation of one point from a paraboloid, signed: positive on the
/// focus's side of the surface (above it, for the design paraboloid).
///
/// With `q` the point in the paraboloid's own frame (apex at the origin, axis
/// along z), `r² = q_x² + q_y²` and `α` the angle between the surface normal
/// at plan point `(q_x, q_y)` and the axis, `cos α = 2F/√(4F² + r²)`:
///
/// * **axial** `δz = q_z − r²/(4F)`, along the axis;
/// * **normal** `δn = δz cos α`, along the surface normal: the distance to
///   the surface to first order in `δz/F` (the exact distance differs by
///   `O(δz²/F)`, below a micrometre for millimetre deviations on metre focal
///   lengths);
/// * **half path length** `ε = δz cos² α = δz · 4F²/(4F² + r²)`: half the
///   change of the path of the ray the point reflects, the quantity Ruze's gain
///   loss takes (see [`crate::surface`] for the derivation).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PointDeviation {
    /// Axial deviation δz, m.
    pub axial_m: f64,
    /// Normal deviation δn = δz cos α, m.
    pub normal_m: f64,
    /// Half-path-length error ε = δz cos² α, m.
    pub half_path_m: f64,
}

impl PlacedParaboloid {
    /// The design paraboloid: apex at the origin, axis along z.
    pub fn design(paraboloid: &Paraboloid) -> PlacedParaboloid {
        PlacedParaboloid {
            apex_m: [0.0; 3],
            rotation_about_x_rad: 0.0,
            rotation_about_y_rad: 0.0,
            focal_length_m: paraboloid.focal_length_m,
        }
    }

    /// The rotation `R = R_x R_y` taking the design axes to this paraboloid's.
    pub fn rotation(&self) -> [[f64; 3]; 3] {
        let (sx, cx) = self.rotation_about_x_rad.sin_cos();
        let (sy, cy) = self.rotation_about_y_rad.sin_cos();
        // R_x = [1 0 0; 0 cx −sx; 0 sx cx], R_y = [cy 0 sy; 0 1 0; −sy 0 cy].
        [
            [cy, 0.0, sy],
            [sx * sy, cx, -sx * cy],
            [-cx * sy, sx, cx * cy],
        ]
    }

    /// Unit vector of the axis, `R ẑ`.
    pub fn axis(&self) -> [f64; 3] {
        let r = self.rotation();
        [r[0][2], r[1][2], r[2][2]]
    }

    /// The focus `a + F R ẑ`, m: where the feed belongs.
    pub fn focus_m(&self) -> [f64; 3] {
        let axis = self.axis();
        std::array::from_fn(|d| self.apex_m[d] + self.focal_length_m * axis[d])
    }

    /// `p` in the paraboloid's own frame, `q = Rᵀ (p − a)`.
    pub fn to_local(&self, p_m: [f64; 3]) -> [f64; 3] {
        local(&self.rotation(), self.apex_m, p_m)
    }

    /// The point of the surface above plan point `(x, y)` of its own frame,
    /// placed in space: `a + R (x, y, (x² + y²)/(4F))`.
    pub fn surface_point_m(&self, x: f64, y: f64) -> [f64; 3] {
        let r = self.rotation();
        let q = [x, y, (x * x + y * y) / (4.0 * self.focal_length_m)];
        std::array::from_fn(|i| self.apex_m[i] + r[i][0] * q[0] + r[i][1] * q[1] + r[i][2] * q[2])
    }

    /// The deviations of point `p_m` from this paraboloid (see [`PointDeviation`]).
    pub fn deviation(&self, p_m: [f64; 3]) -> PointDeviation {
        self.deviations()(p_m)
    }

    /// [`PlacedParaboloid::deviation`] for many points: the rotation is
    /// formed once (formed per point, its sines and cosines were half the
    /// time of super-100m's surface fits: 1.70 → 0.88 s).
    pub fn deviations(&self) -> impl Fn([f64; 3]) -> PointDeviation {
        let (r, apex, f) = (self.rotation(), self.apex_m, self.focal_length_m);
        move |p_m| {
            let q = local(&r, apex, p_m);
            let r2 = q[0] * q[0] + q[1] * q[1];
            let axial_m = q[2] - r2 / (4.0 * f);
            let cos2 = 4.0 * f * f / (4.0 * f * f + r2);
            PointDeviation {
                axial_m,
                normal_m: axial_m * cos2.sqrt(),
                half_path_m: axial_m * cos2,
            }
        }
    }
}

/// `p` in the frame of rotation `r` and apex `a`: `q = Rᵀ (p − a)`.
fn local(r: &[[f64; 3]; 3], apex_m: [f64; 3], p_m: [f64; 3]) -> [f64; 3] {
    let d: [f64; 3] = std::array::from_fn(|k| p_m[k] - apex_m[k]);
    std::array::from_fn(|i| r[0][i] * d[0] + r[1][i] * d[1] + r[2][i] * d[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tilted() -> PlacedParaboloid {
        PlacedParaboloid {
            apex_m: [0.3, -0.2, 0.1],
            rotation_about_x_rad: 0.05,
            rotation_about_y_rad: -0.03,
            focal_length_m: 5.0,
        }
    }

    #[test]
    fn rotation_is_orthonormal_and_local_frame_inverts_placement() {
        let p = tilted();
        let r = p.rotation();
        for i in 0..3 {
            for j in 0..3 {
                let dot: f64 = (0..3).map(|k| r[k][i] * r[k][j]).sum();
                let expected = if i == j { 1.0 } else { 0.0 };
                assert!((dot - expected).abs() < 1e-15, "RᵀR[{i}][{j}] = {dot}");
            }
        }
        let point = p.surface_point_m(1.5, -2.0);
        let q = p.to_local(point);
        assert!(
            (q[0] - 1.5).abs() < 1e-14 && (q[1] + 2.0).abs() < 1e-14,
            "{q:?}"
        );
        assert!(p.deviation(point).axial_m.abs() < 1e-14);
    }

    #[test]
    fn rotations_tilt_the_axis_as_documented() {
        let mut p = PlacedParaboloid::design(&Paraboloid {
            focal_length_m: 2.0,
        });
        p.rotation_about_y_rad = 0.1;
        assert!(p.axis()[0] > 0.0 && p.axis()[1].abs() < 1e-15);
        p.rotation_about_y_rad = 0.0;
        p.rotation_about_x_rad = 0.1;
        assert!(p.axis()[1] < 0.0 && p.axis()[0].abs() < 1e-15);
        let f = p.focus_m();
        assert!((f[1] + 2.0 * 0.1f64.sin()).abs() < 1e-15, "{f:?}");
    }

    #[test]
    fn deviations_along_the_normal_and_the_path_scale_by_cos_alpha() {
        let f = 3.0;
        let p = PlacedParaboloid::design(&Paraboloid { focal_length_m: f });
        // At r = 2F the normal is at 45° to the axis (tan α = r/(2F) = 1).
        let (r, lift) = (2.0 * f, 1e-3);
        let d = p.deviation([r, 0.0, r * r / (4.0 * f) + lift]);
        assert!((d.axial_m - lift).abs() < 1e-15);
        assert!((d.normal_m - lift / 2f64.sqrt()).abs() < 1e-15);
        assert!((d.half_path_m - lift / 2.0).abs() < 1e-15);
    }

    #[test]
    fn half_path_error_is_half_the_path_change_of_the_reflected_ray() {
        // A ray parallel to the axis, from the plane z = Z down to the surface
        // and from there to the focus: on the paraboloid its length is Z + F
        // wherever it lands. Move the reflecting point up by h on the same ray:
        // the path changes by −2ε + O(h²), whatever the reflected direction
        // does (Fermat: the path is stationary in it).
        let f = 4.0;
        let p = PlacedParaboloid::design(&Paraboloid { focal_length_m: f });
        let z_plane = 20.0;
        let path = |r: f64, z: f64| (z_plane - z) + (r * r + (f - z) * (f - z)).sqrt();
        for r in [0.0, 1.0, 4.0, 8.0, 13.0] {
            let z = r * r / (4.0 * f);
            assert!((path(r, z) - (z_plane + f)).abs() < 1e-12);
            for h in [1e-3, -2e-4] {
                let change = path(r, z + h) - path(r, z);
                let eps = p.deviation([r, 0.0, z + h]).half_path_m;
                // The remainder: h² r²/(2(F + z)³) to second order (the distance
                // to the focus is F + z), with 1 % for the third.
                let bound = 1.01 * h * h * (r * r) / (2.0 * (f + z).powi(3)) + 1e-13;
                assert!(
                    (change + 2.0 * eps).abs() <= bound,
                    "r {r}, h {h}: path change {change}, −2ε {}",
                    -2.0 * eps
                );
            }
        }
    }
}
