//! The margin of a ring truss to its limit load under a net's pull
//! (DESIGN §9): a design whose pull the truss cannot carry stably is an
//! error, not a result.
//!
//! The one-step equilibrium the design loop asks of the exact truss cannot
//! tell a stable state from one past a bifurcation: a ring under a symmetric
//! pull stays on its symmetric branch past its buckling load. The margin is
//! found on the state instead ([`crate::mechanics::Stability`]): the pull is
//! multiplied in growing steps until an equilibrium is certified unstable,
//! then bisected ([`crate::mechanics::limit_load_factor`]); a load no solve
//! reaches bounds the limit only as [`LimitBound::NotReached`], never as
//! an instability.

use super::builder::RingTruss;
use super::exact::nodal_loads;
use super::response::{check_loads, TrussError};
#[cfg(doc)]
use crate::mechanics::LimitBound;
use crate::mechanics::{limit_load_factor, LimitSearch, StaticSettings, StaticSolver};

/// How far the margin is searched: a truss stable at this multiple of the
/// pull is reported as such, without its limit load.
pub const SEARCH_TO: f64 = 4.0;

/// Relative width of the bracket on the limit load (issue 16: 0.5 %).
pub const PRECISION: f64 = 0.005;

/// The limit load of `truss` under multiples of `pull_n` (one force per
/// attachment point, N) with its self weight, searched up to [`SEARCH_TO`] ×
/// the loads.
///
/// # Errors
/// Bad loads, or a frame that cannot be analysed.
pub fn limit_margin(truss: RingTruss, pull_n: &[[f64; 3]]) -> Result<LimitSearch, TrussError> {
    check_loads(pull_n, truss.attachments.len())?;
    let mut model = truss.model;
    let mut loads = nodal_loads(&truss.attachments, pull_n);
    loads.extend(truss.dead_loads);
    model.set_loads(loads)?;
    let mut solver = StaticSolver::new(model)?;
    // Each solve of the search starts from a stable state close by: a step
    // that needs cutting twice is beyond the limit, or so close to it that
    // bisection learns as much from calling it unstable.
    let settings = StaticSettings {
        min_step: 1.0 / 16.0,
        ..StaticSettings::default()
    };
    Ok(limit_load_factor(
        &mut solver,
        SEARCH_TO,
        PRECISION,
        &settings,
    )?)
}
