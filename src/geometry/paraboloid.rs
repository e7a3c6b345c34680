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

    /// RMS axial distance between the paraboloid and the flat triangular
    /// facets `triangles` (node indices into `nodes_m`), weighted by plan
    /// area, m: the surface a faceted net really makes, between its nodes as
    /// well as at them.
    ///
    /// On a facet the distance `d = Σ λᵢ zᵢ − z(Σ λᵢ xᵢ, Σ λᵢ yᵢ)` (λ the
    /// barycentric coordinates) is quadratic in plan, so `d²` is integrated
    /// exactly by Dunavant's 6-point rule of degree 4. With every node on the
    /// paraboloid an equilateral facet of side `L` gives `L²/(4√15 F)`.
    /// Zero when there are no facets.
    pub fn facet_rms_m(&self, nodes_m: &[[f64; 3]], triangles: &[[usize; 3]]) -> f64 {
        const RULE: [([f64; 3], f64); 6] = [
            ([A, A, B], WA),
            ([A, B, A], WA),
            ([B, A, A], WA),
            ([C, C, D], WC),
            ([C, D, C], WC),
            ([D, C, C], WC),
        ];
        const A: f64 = 0.445_948_490_915_965;
        const B: f64 = 0.108_103_018_168_070;
        const WA: f64 = 0.223_381_589_678_011;
        const C: f64 = 0.091_576_213_509_771;
        const D: f64 = 0.816_847_572_980_459;
        const WC: f64 = 0.109_951_743_655_322;
        let (mut integral, mut area) = (0.0, 0.0);
        for t in triangles {
            let [p, q, r] = t.map(|i| nodes_m[i]);
            let plan_area =
                0.5 * ((q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])).abs();
            let mean_square: f64 = RULE
                .iter()
                .map(|(l, w)| {
                    let at = |c: usize| l[0] * p[c] + l[1] * q[c] + l[2] * r[c];
                    let d = at(2) - self.z(at(0), at(1));
                    w * d * d
                })
                .sum();
            integral += plan_area * mean_square;
            area += plan_area;
        }
        if area > 0.0 {
            (integral / area).sqrt()
        } else {
            0.0
        }
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
    fn equilateral_facet_on_the_paraboloid_has_the_closed_form_rms() {
        let p = Paraboloid {
            focal_length_m: 3.0,
        };
        let side = 0.7;
        // Anywhere on the paraboloid: the distance depends on the facet only.
        let corner = [2.0, -1.0];
        let plan = [
            corner,
            [corner[0] + side, corner[1]],
            [corner[0] + 0.5 * side, corner[1] + 0.75f64.sqrt() * side],
        ];
        let nodes: Vec<[f64; 3]> = plan.iter().map(|&[x, y]| [x, y, p.z(x, y)]).collect();
        let rms = p.facet_rms_m(&nodes, &[[0, 1, 2]]);
        let exact = side * side / (4.0 * 15f64.sqrt() * p.focal_length_m);
        assert!((rms - exact).abs() <= 1e-12 * exact, "{rms} vs {exact}");
        assert_eq!(p.facet_rms_m(&nodes, &[]), 0.0);
    }

    #[test]
    fn facet_rms_of_a_lifted_facet_is_its_lift() {
        // A plane facet under a flat "paraboloid" (F → ∞) lifted by h.
        let p = Paraboloid {
            focal_length_m: 1e30,
        };
        let h = 2.5e-3;
        let nodes = [[0.0, 0.0, h], [1.0, 0.0, h], [0.0, 1.0, h], [1.0, 1.0, h]];
        let rms = p.facet_rms_m(&nodes, &[[0, 1, 2], [1, 3, 2]]);
        assert!((rms - h).abs() < 1e-15, "{rms}");
    }

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
