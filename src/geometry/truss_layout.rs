//! The ring-truss layout: where the hinges of the N bays are.

use super::{Aperture, Paraboloid};

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

    /// Number of bays.
    pub fn bays(&self) -> usize {
        self.top_m.len()
    }
}
