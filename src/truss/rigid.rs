//! The rigid truss: attachment points never move (the conventional method).

use super::response::{check_loads, layout_points, TrussError, TrussOracle, TrussResponse};
use crate::geometry::RingTrussLayout;

/// A ring truss that does not deform.
#[derive(Debug, Clone)]
pub struct RigidTruss {
    points: Vec<[f64; 3]>,
}

impl RigidTruss {
    /// The rigid truss of a layout.
    pub fn new(layout: &RingTrussLayout) -> Self {
        RigidTruss {
            points: layout_points(layout),
        }
    }
}

impl TrussOracle for RigidTruss {
    fn name(&self) -> &'static str {
        "rigid"
    }

    fn attachments(&self) -> &[[f64; 3]] {
        &self.points
    }

    fn respond(&mut self, loads_n: &[[f64; 3]]) -> Result<TrussResponse, TrussError> {
        check_loads(loads_n, self.points.len())?;
        Ok(TrussResponse {
            positions_m: self.points.clone(),
            newton_iterations: 0,
            load_steps: 0,
            time_s: 0.0,
        })
    }

    fn deforms(&self) -> bool {
        false
    }
}
