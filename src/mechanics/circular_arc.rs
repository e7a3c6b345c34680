//! The reference geometry of a curved rod: a circular arc from the rod's start
//! to its end, given by its centre (and the normal it turns about, by default
//! the shorter way round) or by a point it passes through; checked with the
//! input at fault named ([`ArcError`]), and the reference frames of its nodes.
//!
//! The nodes are equally spaced in angle and each node's frame is the start's
//! frame turned about the normal by the node's angle, `R_i = exp(φ_i n̂) R_0`,
//! `x_i = c + exp(φ_i n̂) (x_0 − c)`. Two neighbours are then related by one
//! and the same relative frame: the relative rotation `Ω = Δφ R_0ᵀ n̂` and the
//! SE(3) logarithm `d₀ = log(H_i⁻¹ H_{i+1}) = ((R Δφ, 0, 0), Ω)`, a uniform
//! curvature `1/R` about the normal. A circular arc is a one-parameter
//! subgroup of SE(3), so the SE(3) element's helicoidal interpolation between
//! two such frames *is* the arc: the initial curvature is exact, not chords.

use std::f64::consts::{FRAC_PI_2, TAU};

use nalgebra::{Unit, UnitQuaternion, Vector3};

use super::node::Frame;
use super::rotation::rod_frame;

/// Relative tolerance of an arc's checks: the two ends' distances from the
/// centre agree, and the normal is across both radii, to 1e-9 relative (the
/// points of a file written to 10 digits pass; a typo does not).
pub const ARC_TOLERANCE: f64 = 1e-9;

/// Largest angle one element may span in the reference configuration, rad:
/// π/2. An element's relative rotation must stay below π under load (the
/// logarithm's branch), so a quarter turn leaves another quarter for bending.
pub const MAX_ELEMENT_ANGLE_RAD: f64 = FRAC_PI_2;

/// A circular arc from a rod's start to its end, as a frame file writes it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CircularArc {
    /// The arc about `centre_m` (m), turning from start to end about
    /// `normal` by the right-hand rule (any length, across the plane of the
    /// arc); without a normal the shorter arc, about
    /// `(start − centre) × (end − centre)`, which a half circle does not have.
    Centre {
        /// The centre of the circle, m.
        centre_m: Vector3<f64>,
        /// The axis the rod turns about from start to end, or `None` for the
        /// shorter arc.
        normal: Option<Vector3<f64>>,
    },
    /// The arc of the circle through the start, `through_m` (m) and the end,
    /// from the start via that point to the end.
    Through {
        /// A point of the arc between its ends, m.
        through_m: Vector3<f64>,
    },
}

/// The input of a [`CircularArc`] (or of its rod) at fault.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ArcInput {
    /// The centre (`centre_m`): the ends are not on one circle about it.
    Centre,
    /// The normal (`normal`): not across the arc's plane, or missing where
    /// start, centre and end are on one line.
    Normal,
    /// The point the arc passes through (`through_m`).
    Through,
}

impl ArcInput {
    /// The input's name, as the frame file writes it.
    pub fn name(self) -> &'static str {
        match self {
            ArcInput::Centre => "centre_m",
            ArcInput::Normal => "normal",
            ArcInput::Through => "through_m",
        }
    }
}

/// An arc that cannot be built: the input at fault and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}: {reason}", input.name())]
pub struct ArcError {
    /// The input at fault.
    pub input: ArcInput,
    /// What is wrong.
    pub reason: String,
}

fn fault(input: ArcInput, reason: impl Into<String>) -> ArcError {
    ArcError {
        input,
        reason: reason.into(),
    }
}

/// A checked arc: where it is and how far it turns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArcGeometry {
    /// The start, m.
    pub start_m: Vector3<f64>,
    /// The end, m.
    pub end_m: Vector3<f64>,
    /// The centre of the circle, m.
    pub centre_m: Vector3<f64>,
    /// The unit normal the rod turns about from start to end.
    pub axis: Unit<Vector3<f64>>,
    /// The radius `|start − centre|`, m.
    pub radius_m: f64,
    /// The angle from start to end about `axis`, in (0, 2π), rad.
    pub angle_rad: f64,
}

impl CircularArc {
    /// The arc from `start_m` to `end_m` (finite points), checked: both ends
    /// at one distance from the centre (to [`ARC_TOLERANCE`]) and not at it,
    /// the normal across both radii, a non-zero angle; for
    /// [`CircularArc::Through`] the three points not on one line.
    ///
    /// # Errors
    /// The input at fault and why ([`ArcError`]).
    pub fn geometry(
        &self,
        start_m: Vector3<f64>,
        end_m: Vector3<f64>,
    ) -> Result<ArcGeometry, ArcError> {
        let finite = |v: &Vector3<f64>| v.iter().all(|c| c.is_finite());
        let (centre_m, normal) = match *self {
            CircularArc::Centre { centre_m, normal } => {
                if !finite(&centre_m) {
                    return Err(fault(ArcInput::Centre, "a component is not finite"));
                }
                (centre_m, normal)
            }
            CircularArc::Through { through_m } => {
                let (centre_m, normal) = circumcircle(start_m, through_m, end_m)?;
                (centre_m, Some(normal))
            }
        };
        let (a, b) = (start_m - centre_m, end_m - centre_m);
        let (ra, rb) = (a.norm(), b.norm());
        for (r, which) in [(ra, "start"), (rb, "end")] {
            if !(r.is_finite() && r > 0.0) {
                return Err(fault(
                    ArcInput::Centre,
                    if r == 0.0 {
                        format!("is the rod's {which}: the arc has no radius")
                    } else {
                        format!("the {which} is farther from it than a number can hold")
                    },
                ));
            }
        }
        let mismatch = (ra - rb).abs() / ra.max(rb);
        if mismatch > ARC_TOLERANCE {
            return Err(fault(
                ArcInput::Centre,
                format!(
                    "start is {ra:.3} m from the centre, end {rb:.3} m: not on one circle \
                     ({mismatch:.1e} relative, more than {ARC_TOLERANCE:.0e})"
                ),
            ));
        }
        let normal = match normal {
            Some(n) => {
                if !finite(&n) {
                    return Err(fault(ArcInput::Normal, "a component is not finite"));
                }
                if n.amax() == 0.0 {
                    return Err(fault(ArcInput::Normal, "must be a non-zero vector"));
                }
                // A direction of any finite length: one whose norm
                // overflows (1e300) or underflows (1e-320) is scaled by its
                // largest component first.
                if n.norm().is_normal() {
                    n
                } else {
                    n / n.amax()
                }
            }
            None => {
                let n = a.cross(&b);
                if n.norm() <= ARC_TOLERANCE * ra * rb {
                    return Err(fault(
                        ArcInput::Normal,
                        "missing: start, centre and end are on one line (a half circle), \
                         so the arc may turn either way: give the normal it turns about",
                    ));
                }
                n
            }
        };
        let axis = Unit::new_normalize(normal);
        let tilt = (axis.dot(&a) / ra).abs().max((axis.dot(&b) / rb).abs());
        if tilt > ARC_TOLERANCE {
            return Err(fault(
                ArcInput::Normal,
                format!(
                    "is not across the plane of the arc: it makes {:.6}° with a radius \
                     (must be 90°)",
                    tilt.acos().to_degrees()
                ),
            ));
        }
        let mut angle_rad = axis.dot(&a.cross(&b)).atan2(a.dot(&b));
        if angle_rad <= 0.0 {
            angle_rad += TAU;
        }
        if !(angle_rad > 0.0 && angle_rad < TAU) {
            return Err(fault(
                ArcInput::Centre,
                "start and end are one point of the circle: the arc turns by no angle",
            ));
        }
        Ok(ArcGeometry {
            start_m,
            end_m,
            centre_m,
            axis,
            radius_m: ra,
            angle_rad,
        })
    }
}

/// The centre of the circle through `p`, `m` and `q` and the normal about
/// which `p → m → q` turns (right-hand rule): with `A = m − p`, `B = q − p`,
/// `c = p + (|A|² B − |B|² A) × (A × B) / (2 |A × B|²)`, `n = A × B`.
fn circumcircle(
    p: Vector3<f64>,
    m: Vector3<f64>,
    q: Vector3<f64>,
) -> Result<(Vector3<f64>, Vector3<f64>), ArcError> {
    if !m.iter().all(|c| c.is_finite()) {
        return Err(fault(ArcInput::Through, "a component is not finite"));
    }
    if m == p || m == q {
        return Err(fault(
            ArcInput::Through,
            format!(
                "is the rod's {}: give a point of the arc between its ends",
                if m == p { "start" } else { "end" }
            ),
        ));
    }
    let (a, b) = (m - p, q - p);
    let n = a.cross(&b);
    if n.norm() <= ARC_TOLERANCE * a.norm() * b.norm() {
        return Err(fault(
            ArcInput::Through,
            "start, this point and end are on one line: no circle passes through them",
        ));
    }
    let centre =
        p + (b * a.norm_squared() - a * b.norm_squared()).cross(&n) / (2.0 * n.norm_squared());
    Ok((centre, n))
}

impl ArcGeometry {
    /// The arc length `R θ`, m.
    pub fn length_m(&self) -> f64 {
        self.radius_m * self.angle_rad
    }

    /// The fewest elements that mesh the arc with at most
    /// [`MAX_ELEMENT_ANGLE_RAD`] each (a quarter circle: 1; a half: 2).
    pub fn fewest_elements(&self) -> usize {
        // The slack keeps a quarter circle whose angle rounds above π/2 at 1.
        let ratio = self.angle_rad / MAX_ELEMENT_ANGLE_RAD;
        ((ratio * (1.0 - ARC_TOLERANCE)).ceil() as usize).max(1)
    }

    /// The reference frames of the `elements + 1` nodes of the arc, start to
    /// end, equally spaced in angle: `R_i = exp(φ_i n̂) R_0` and
    /// `x_i = c + exp(φ_i n̂) (x_0 − c)` with `φ_i = θ i / elements`, `R_0` the
    /// material frame of the start ([`rod_frame`] of the start's tangent
    /// `n̂ × (x_0 − c)` and `up`, so `up` holds at the start and is carried
    /// along the arc). The end nodes are placed at the given start and end
    /// exactly (the rotation would put the end a rounding error away).
    pub fn frames(&self, up: &Vector3<f64>, elements: usize) -> Vec<Frame> {
        let radius = self.start_m - self.centre_m;
        let tangent = self.axis.cross(&radius);
        let start = rod_frame(&tangent, up);
        (0..=elements)
            .map(|i| {
                let turn = UnitQuaternion::from_axis_angle(
                    &self.axis,
                    self.angle_rad * i as f64 / elements as f64,
                );
                let position_m = match i {
                    0 => self.start_m,
                    i if i == elements => self.end_m,
                    _ => self.centre_m + turn * radius,
                };
                Frame {
                    position_m,
                    rotation: turn * start,
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn through_a_point_finds_the_circle_and_the_way_round() {
        // The unit circle about (1, 2, 3) in the x–y plane: from 0° via 270°
        // to 90° is three quarters clockwise, i.e. about −z.
        let c = Vector3::new(1.0, 2.0, 3.0);
        let at = |deg: f64| c + Vector3::new(deg.to_radians().cos(), deg.to_radians().sin(), 0.0);
        let arc = CircularArc::Through {
            through_m: at(270.0),
        };
        let g = arc.geometry(at(0.0), at(90.0)).unwrap();
        assert!((g.centre_m - c).norm() < 1e-15, "{:?}", g.centre_m);
        assert!((g.axis.into_inner() + Vector3::z()).norm() < 1e-15);
        assert!((g.angle_rad - 1.5 * std::f64::consts::PI).abs() < 1e-14);
        assert_eq!(g.fewest_elements(), 3);
        // Via 45°: the quarter counter-clockwise, one element.
        let g = CircularArc::Through {
            through_m: at(45.0),
        }
        .geometry(at(0.0), at(90.0))
        .unwrap();
        assert!((g.axis.into_inner() - Vector3::z()).norm() < 1e-15);
        assert!((g.angle_rad - FRAC_PI_2).abs() < 1e-15);
        assert_eq!(g.fewest_elements(), 1);
    }

    #[test]
    fn frames_turn_about_the_normal_by_equal_angles() {
        let arc = CircularArc::Centre {
            centre_m: Vector3::zeros(),
            normal: None,
        };
        let g = arc
            .geometry(Vector3::new(2.0, 0.0, 0.0), Vector3::new(0.0, 2.0, 0.0))
            .unwrap();
        let frames = g.frames(&Vector3::z(), 4);
        for (i, f) in frames.iter().enumerate() {
            let phi = FRAC_PI_2 * i as f64 / 4.0;
            let expected = Vector3::new(2.0 * phi.cos(), 2.0 * phi.sin(), 0.0);
            assert!((f.position_m - expected).norm() < 1e-15);
            let e1 = f.rotation * Vector3::x();
            assert!((e1 - Vector3::new(-phi.sin(), phi.cos(), 0.0)).norm() < 1e-15);
            // `up` = z is normal to the arc's plane: the second axis stays z.
            assert!((f.rotation * Vector3::y() - Vector3::z()).norm() < 1e-15);
        }
    }
}
