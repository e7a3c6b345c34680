//! The small-displacement frame: `K₀ u = f` with the tangent of the
//! unstressed truss, one sparse solve per response.

use std::time::Instant;

use super::builder::RingTruss;
use super::exact::set_attachment_loads;
use super::response::{layout_points, TrussError, TrussOracle, TrussResponse};
use crate::geometry::RingTrussLayout;
use crate::mechanics::{NodalLoad, StaticSolver};

/// The ring truss as a linear frame.
pub struct LinearTruss {
    solver: StaticSolver,
    attachments: Vec<usize>,
    dead_loads: Vec<NodalLoad>,
    points: Vec<[f64; 3]>,
}

impl LinearTruss {
    /// The linear model of a ring-truss frame.
    ///
    /// # Errors
    /// A frame faer cannot analyse.
    pub fn new(truss: RingTruss, layout: &RingTrussLayout) -> Result<Self, TrussError> {
        Ok(LinearTruss {
            solver: StaticSolver::new(truss.model)?,
            attachments: truss.attachments,
            dead_loads: truss.dead_loads,
            points: layout_points(layout),
        })
    }
}

impl TrussOracle for LinearTruss {
    fn name(&self) -> &'static str {
        "linear"
    }

    fn attachments(&self) -> &[[f64; 3]] {
        &self.points
    }

    fn respond(&mut self, loads_n: &[[f64; 3]]) -> Result<TrussResponse, TrussError> {
        let clock = Instant::now();
        set_attachment_loads(
            &mut self.solver,
            &self.attachments,
            &self.dead_loads,
            loads_n,
        )?;
        let state = self.solver.linear_response()?;
        Ok(TrussResponse {
            positions_m: super::exact::positions(&state, &self.attachments),
            newton_iterations: 0,
            load_steps: 0,
            time_s: clock.elapsed().as_secs_f64(),
        })
    }
}
