//! The ring-truss layout: where the hinges of the N bays are.

use super::{Aperture, Paraboloid};
use crate::algebra::norm3;
use crate::scene::Scene;

/// Hinge points of a ring truss of N bays: top hinges on the paraboloid's rim
/// at the vertices of a regular N-gon inscribed in the aperture circle (angles
/// `2πk/N`), bottom hinges one batten length below them.
#[derive(Debug, Clone, PartialEq)]
pub struct RingTrussLayout {
    /// Top hinge points (front-net attachments), m: N × 3.
    pub top_m: Vec<[f64; 3]>,
    /// Bottom hinge points (rear-net attachments), m: N × 3.
    pub bottom_m: Vec<[f64; 3]>,
}

impl RingTrussLayout {
    /// The layout of `bays` vertical battens of length `height_m`.
    pub fn new(paraboloid: &Paraboloid, aperture: &Aperture, bays: usize, height_m: f64) -> Self {
        let top_m: Vec<[f64; 3]> = (0..bays)
            .map(|k| {
                let angle = std::f64::consts::TAU * k as f64 / bays as f64;
                let [x, y] = aperture.rim_point(angle);
                [x, y, paraboloid.z(x, y)]
            })
            .collect();
        let bottom_m = top_m
            .iter()
            .map(|&[x, y, z]| [x, y, z - height_m])
            .collect();
        RingTrussLayout { top_m, bottom_m }
    }

    /// The layout of `scene`'s truss.
    pub fn of(scene: &Scene) -> Self {
        let paraboloid = Paraboloid {
            focal_length_m: scene.reflector.focal_length_m,
        };
        let aperture = Aperture {
            radius_m: scene.aperture_radius_m(),
            offset_m: scene.reflector.offset_m,
        };
        RingTrussLayout::new(
            &paraboloid,
            &aperture,
            scene.truss.bays,
            scene.truss.height_m,
        )
    }

    /// Number of bays.
    pub fn bays(&self) -> usize {
        self.top_m.len()
    }

    /// The summed length of the truss's rods, m: per bay a batten, a top
    /// and a bottom longeron and a diagonal (as [`crate::truss::RingTruss`]
    /// builds them).
    pub fn rod_length_m(&self) -> f64 {
        let n = self.bays();
        let distance = |a: &[f64; 3], b: &[f64; 3]| norm3(std::array::from_fn(|i| a[i] - b[i]));
        (0..n)
            .map(|k| {
                let next = (k + 1) % n;
                let (top, bottom) = (&self.top_m, &self.bottom_m);
                distance(&top[k], &bottom[k])
                    + distance(&top[k], &top[next])
                    + distance(&bottom[k], &bottom[next])
                    + distance(&bottom[k], &top[next])
            })
            .sum()
    }
}
