//! The reflecting paraboloid `z = (x² + y²)/(4F)` and the aperture circle on it.

/// The paraboloid of revolution `z = (x² + y²)/(4F)` about the z axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Paraboloid {
    /// Focal length F, m.
    pub focal_length_m: f64,
}

impl Paraboloid {
    /// Height of the surface above plan point `(x, y)`, m.
    pub fn z(&self, x: f64, y: f64) -> f64 {
        (x * x + y * y) / (4.0 * self.focal_length_m)
    }

    /// Vertical distance of `p` above the surface, m.
    pub fn axial_deviation(&self, p: [f64; 3]) -> f64 {
        p[2] - self.z(p[0], p[1])
    }
}

/// The aperture: a circle in plan, centred at `(offset, 0)` (offset 0: centre-fed).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aperture {
    /// Radius R of the plan circle, m.
    pub radius_m: f64,
    /// Distance h of the aperture centre from the paraboloid axis, m.
    pub offset_m: f64,
}

impl Aperture {
    /// Plan centre `(h, 0)`.
    pub fn centre(&self) -> [f64; 2] {
        [self.offset_m, 0.0]
    }

    /// Plan point at angle `theta` on the aperture circle.
    pub fn rim_point(&self, angle_rad: f64) -> [f64; 2] {
        [
            self.offset_m + self.radius_m * angle_rad.cos(),
            self.radius_m * angle_rad.sin(),
        ]
    }

    /// Height of the plane through the paraboloid's rim above plan point `(x, y)`:
    /// on the aperture circle `x² + y² = R² − h² + 2hx`, so the rim of the
    /// paraboloid lies on the plane `z = (R² − h² + 2hx)/(4F)`.
    pub fn rim_plane_z(&self, paraboloid: &Paraboloid, x: f64) -> f64 {
        let (r, h) = (self.radius_m, self.offset_m);
        (r * r - h * h + 2.0 * h * x) / (4.0 * paraboloid.focal_length_m)
    }

    /// Squared plan distance from the aperture centre, m².
    pub fn rho_squared(&self, x: f64, y: f64) -> f64 {
        let dx = x - self.offset_m;
        dx * dx + y * y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rim_of_offset_paraboloid_is_planar() {
        let p = Paraboloid {
            focal_length_m: 7.0,
        };
        let a = Aperture {
            radius_m: 5.0,
            offset_m: 6.0,
        };
        for k in 0..12 {
            let [x, y] = a.rim_point(k as f64 * 0.5);
            let err = p.z(x, y) - a.rim_plane_z(&p, x);
            assert!(err.abs() < 1e-13, "rim point {k}: {err}");
        }
    }
}
