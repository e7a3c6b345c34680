//! The geometrically exact truss (paper §3): beams, hinge bodies and joints
//! in large displacement, solved to equilibrium under the net's pull.
//!
//! Warm start: each response starts from the previous equilibrium (the outer
//! design loop changes the loads little between iterations) and falls back to
//! a load ramp from the unstressed truss when that does not converge.

use std::time::Instant;

use nalgebra::Vector3;

use super::builder::RingTruss;
use super::response::{
    check_loads, layout_points, TrussEquilibrium, TrussError, TrussOracle, TrussResponse,
};
use crate::geometry::RingTrussLayout;
use crate::mechanics::{NodalLoad, NodeId, State, StaticSettings, StaticSolver};

/// The first load step of a solve from the unloaded truss, as a fraction of
/// the loads. Load control tells a step that jumps past a limit point by the
/// jump of the path's slope against the previous step; a first step has no
/// previous one. In one full step the small hexagonal ring at 10 × its net's
/// pull (limit ≈ 6.6 ×) converged on a far equilibrium in 3 Newton iterations;
/// starting with half the load, every later step has a slope to compare with
/// and the solve stops at the limit point (λ = 0.6555, the arc-length limit
/// 0.65547), and a load the ring carries costs one step more.
const COLD_FIRST_STEP: f64 = 0.5;

/// The ring truss in large displacement.
pub struct ExactTruss {
    solver: StaticSolver,
    attachments: Vec<NodeId>,
    dead_loads: Vec<NodalLoad>,
    points: Vec<[f64; 3]>,
    settings: StaticSettings,
    previous: Option<State>,
}

pub(crate) fn nodal_loads(attachments: &[NodeId], loads_n: &[[f64; 3]]) -> Vec<NodalLoad> {
    attachments
        .iter()
        .zip(loads_n)
        .map(|(&node, f)| NodalLoad {
            node,
            force_n: Vector3::new(f[0], f[1], f[2]),
            moment_nm: Vector3::zeros(),
        })
        .collect()
}

pub(crate) fn positions(state: &State, attachments: &[NodeId]) -> Vec<[f64; 3]> {
    attachments
        .iter()
        .map(|&n| {
            let p = state.frames[n].position_m;
            [p.x, p.y, p.z]
        })
        .collect()
}

impl ExactTruss {
    /// The exact model of a ring-truss frame.
    ///
    /// # Errors
    /// A frame faer cannot analyse.
    pub fn new(truss: RingTruss, layout: &RingTrussLayout) -> Result<Self, TrussError> {
        Ok(ExactTruss {
            solver: StaticSolver::new(truss.model)?,
            attachments: truss.attachments,
            dead_loads: truss.dead_loads,
            points: layout_points(layout),
            settings: StaticSettings {
                initial_step: COLD_FIRST_STEP,
                ..StaticSettings::default()
            },
            previous: None,
        })
    }

    /// The static solver settings (tolerance, steps).
    pub fn settings_mut(&mut self) -> &mut StaticSettings {
        &mut self.settings
    }

    /// The last equilibrium state, if any.
    pub fn state(&self) -> Option<&State> {
        self.previous.as_ref()
    }
}

impl TrussOracle for ExactTruss {
    fn name(&self) -> &'static str {
        "exact"
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
        let mut iterations = 0;
        let mut solution = None;
        if let Some(previous) = self.previous.take() {
            // One full step from the previous equilibrium; no cuts.
            let warm = StaticSettings {
                initial_step: 1.0,
                min_step: 0.5,
                ..self.settings.clone()
            };
            let s = self.solver.solve_from(previous, 0.0, &warm)?;
            iterations += s.newton_iterations;
            if s.converged() {
                solution = Some(s);
            }
        }
        let solution = match solution {
            Some(s) => s,
            None => {
                let s = self.solver.solve(&self.settings)?;
                iterations += s.newton_iterations;
                if !s.converged() {
                    return Err(TrussError::NoEquilibrium {
                        termination: s.termination,
                        load_factor: s.load_factor,
                    });
                }
                s
            }
        };
        let response = TrussResponse {
            positions_m: positions(&solution.state, &self.attachments),
            newton_iterations: iterations,
            load_steps: solution.steps.len(),
            time_s: clock.elapsed().as_secs_f64(),
        };
        self.previous = Some(solution.state);
        Ok(response)
    }

    fn equilibrium(&self) -> Option<TrussEquilibrium> {
        self.previous.clone().map(|state| TrussEquilibrium {
            state,
            constraint_scale: self.solver.constraint_scale(),
        })
    }
}

/// Check `loads_n` against the attachment points and set them, with the
/// truss's `self_weight`, as the dead loads of `solver`'s frame (forces at
/// the hinge bodies `attachments`).
pub(super) fn set_attachment_loads(
    solver: &mut crate::mechanics::StaticSolver,
    attachments: &[crate::mechanics::NodeId],
    self_weight: &[crate::mechanics::NodalLoad],
    loads_n: &[[f64; 3]],
) -> Result<(), TrussError> {
    check_loads(loads_n, attachments.len())?;
    let mut loads = nodal_loads(attachments, loads_n);
    loads.extend_from_slice(self_weight);
    solver.model_mut().set_loads(loads)?;
    Ok(())
}
