//! What a truss model is to its callers, below the models themselves: the
//! [`TrussOracle`] trait, its [`TrussResponse`] and [`TrussError`], the
//! attachment points of a layout, and the check of the loads every model
//! makes.

use serde::Serialize;

use crate::geometry::RingTrussLayout;
use crate::mechanics::{LimitBound, MechanicsError, State, StaticTermination};

/// A truss model that cannot respond.
#[derive(Debug, thiserror::Error)]
pub enum TrussError {
    /// The frame could not be built or analysed.
    #[error("ring truss: {0}")]
    Mechanics(#[from] MechanicsError),
    /// The loads do not match the attachment points.
    #[error(
        "truss loads: {given} given, {expected} attachment points (top hinges, then bottom hinges)"
    )]
    LoadCount {
        /// Loads given.
        given: usize,
        /// Attachment points.
        expected: usize,
    },
    /// A loads file that cannot be read as `{"loads_n": [[fx, fy, fz], …]}`.
    #[error("{path}: {reason}")]
    LoadsFile {
        /// The file.
        path: String,
        /// What is wrong.
        reason: String,
    },
    /// A load is not finite.
    #[error("truss loads: the load on attachment point {point} is not finite")]
    NonFiniteLoad {
        /// The attachment point.
        point: usize,
    },
    /// The net's pull exceeds the truss's limit load (DESIGN §9).
    #[error(
        "the net's pull exceeds the ring truss's limit load: its equilibrium is stable up to \
         {} × the pull, {bound} — stiffer tubes, lower tensions or a coarser net",
        significant(*.stable_to)
    )]
    PastLimitLoad {
        /// The largest multiple of the pull found stable.
        stable_to: f64,
        /// What bounds the limit from above.
        bound: LimitBound,
    },
    /// No equilibrium under the full load: the truss buckles or collapses.
    #[error(
        "the ring truss found no equilibrium under its loads (the net's pull, or the loads \
         given): it {termination}; they exceed what the truss can carry (last converged load \
         factor {load_factor:.4})"
    )]
    NoEquilibrium {
        /// How the static solve ended.
        termination: StaticTermination,
        /// The largest load factor reached.
        load_factor: f64,
    },
}

impl TrussError {
    /// True when the input (the loads or the scene) is at fault.
    pub fn is_bad_input(&self) -> bool {
        matches!(
            self,
            TrussError::Mechanics(MechanicsError::Invalid { .. })
                | TrussError::LoadCount { .. }
                | TrussError::LoadsFile { .. }
                | TrussError::NonFiniteLoad { .. }
        )
    }
}

/// `x` to three significant digits.
fn significant(x: f64) -> String {
    let digits = if x == 0.0 || !x.is_finite() {
        3
    } else {
        (2 - x.abs().log10().floor() as i32).max(0) as usize
    };
    format!("{x:.digits$}")
}

/// The truss's answer to one set of attachment loads.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrussResponse {
    /// Deformed attachment points, m: 2N × 3.
    pub positions_m: Vec<[f64; 3]>,
    /// Newton iterations spent (0 for the rigid and linear models).
    pub newton_iterations: usize,
    /// Converged load steps (0 for the rigid and linear models).
    pub load_steps: usize,
    /// Wall time, s.
    pub time_s: f64,
}

/// The response of a ring truss to forces at its attachment points: the
/// oracle every outer design iteration queries (DESIGN §5–6).
pub trait TrussOracle: Send {
    /// The model's name: `rigid`, `linear` or `exact`.
    fn name(&self) -> &'static str;
    /// Undeformed attachment points, m: 2N × 3.
    fn attachments(&self) -> &[[f64; 3]];
    /// Deformed attachment points under `loads_n` (N, one per attachment point,
    /// the pull of the net on the hinge).
    fn respond(&mut self, loads_n: &[[f64; 3]]) -> Result<TrussResponse, TrussError>;
    /// Whether the model deforms: a design for it is verified on the
    /// flexible truss, with its limit margin (the rigid model: no).
    fn deforms(&self) -> bool {
        true
    }
    /// The frame's last equilibrium, for models that have one (the exact
    /// truss): the state an assembly of the same truss starts from.
    fn equilibrium(&self) -> Option<TrussEquilibrium> {
        None
    }
}

/// An equilibrium of the exact truss's frame, as the start of a model that
/// extends it (the assembly of the net on the truss, [`crate::verify`]).
#[derive(Debug, Clone)]
pub struct TrussEquilibrium {
    /// The frame's state: the truss's nodes, then its joints' multipliers.
    pub state: State,
    /// The frame's constraint scale, by which its multipliers are divided.
    pub constraint_scale: f64,
}

/// The reference attachment points of a layout: top hinges, then bottom hinges.
pub fn layout_points(layout: &RingTrussLayout) -> Vec<[f64; 3]> {
    layout
        .top_m
        .iter()
        .chain(&layout.bottom_m)
        .copied()
        .collect()
}

/// Check the count and values of attachment loads.
pub(crate) fn check_loads(loads_n: &[[f64; 3]], expected: usize) -> Result<(), TrussError> {
    if loads_n.len() != expected {
        return Err(TrussError::LoadCount {
            given: loads_n.len(),
            expected,
        });
    }
    match loads_n
        .iter()
        .position(|l| !l.iter().all(|v| v.is_finite()))
    {
        Some(point) => Err(TrussError::NonFiniteLoad { point }),
        None => Ok(()),
    }
}
