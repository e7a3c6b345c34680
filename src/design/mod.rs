//! The outer design loop (paper §4, Figure 7; DESIGN §6): design the net for a
//! boundary `C_k`, apply its pull to the truss, get the deformed boundary
//! `M_{k+1} = G(C_k)`, relax, repeat until the boundary the net was designed
//! for is the boundary the truss takes under that net.
//!
//! Any [`UniformitySolver`](crate::uniformity::UniformitySolver) and any
//! [`TrussOracle`](crate::truss::TrussOracle) plug in. The stopping test
//! is the true fixed-point residual `‖G(C_k) − C_k‖∞ ≤ tol` (largest distance
//! of an attachment point from where the design assumed it). Each design is
//! the two-stage design of [`TiedNets`]: the front net on the paraboloid, the
//! rear net's shape following the deformed bottom hinges. The paper's own
//! criterion, the change `|ξ_k − ξ_{k−1}|` of `ξ_k = ‖G(C_k) − C_k‖∞`, is
//! logged beside it: it can be small while the residual is not.
//!
//! Relaxation policies: the [`Relaxation`] trait, one file per policy
//! (`paper`, `aitken`, `anderson`), named by [`RelaxationKind`].
//!
//! The files, in the order data flows:
//!
//! * `scene_nets.rs` — a scene's nets and their two-stage design problem,
//!   with the effects the scene asks for ([`SceneNets`]);
//! * `tied_nets.rs` — the two-stage design for one boundary ([`TiedNets`]);
//! * `outer_loop.rs` — the fixed-point iteration ([`design_loop`]);
//! * `relaxation/` — how the next boundary is chosen;
//! * `summary.rs` — what a run of the loop says about itself
//!   ([`LoopSummary`]);
//! * `pipeline.rs` — the whole job of `ringmesh design` ([`run`]): loop,
//!   limit margin, verification by assembly, the conventional design
//!   (the loop's iteration 0) verified on the same truss.

mod observer;
mod outer_loop;
mod pipeline;
mod relaxation;
mod scene_nets;
mod summary;
mod tied_nets;

pub use observer::{DesignObserver, DesignStage};
pub use outer_loop::{
    design_loop, design_loop_with, IterationRecord, LoopOutcome, LoopSettings, DIVERGENCE_FACTOR,
};
pub use pipeline::{
    design_margin, run, run_observed, DesignReport, DesignRun, DesignSettings, LoopRun, Timings,
};
pub use relaxation::{
    aitken_factor, paper_step, Aitken, Anderson, Paper, Relaxation, RelaxationKind, Step,
};
pub use scene_nets::{default_solver, scene_problem, SceneNets};
pub use summary::LoopSummary;
pub use tied_nets::{TiedDesign, TiedNetSettings, TiedNets};

use crate::scene::SceneError;
use crate::status::Termination;
use crate::surface::SurfaceError;
use crate::truss::TrussError;
use crate::uniformity::UniformityError;
use crate::verify::VerifyError;

/// The outer loop cannot go on.
#[derive(Debug, thiserror::Error)]
pub enum DesignError {
    /// An invalid loop setting.
    #[error("design loop setting `{key}`: {reason}")]
    Setting {
        /// The setting (`tolerance_m`, `max_iterations`, `anderson_depth`,
        /// `tied_nets.…`).
        key: &'static str,
        /// Why the value is refused.
        reason: String,
    },
    /// A uniformity design failed.
    #[error("outer iteration {iteration}: {source}")]
    Uniformity {
        /// The outer iteration.
        iteration: usize,
        /// What failed.
        #[source]
        source: UniformityError,
    },
    /// A uniformity solver stopped without a design (infeasible, numerical).
    #[error("outer iteration {iteration}: the `{solver}` solver stopped {termination:?}")]
    NoDesign {
        /// The outer iteration.
        iteration: usize,
        /// The solver.
        solver: String,
        /// How it stopped.
        termination: Termination,
    },
    /// The truss could not respond.
    #[error("outer iteration {iteration}: {source}")]
    Truss {
        /// The outer iteration.
        iteration: usize,
        /// What failed.
        #[source]
        source: TrussError,
    },
    /// The scene's nets cannot be built.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The design problem cannot be stated (bounds, loads, groups).
    #[error(transparent)]
    Problem(#[from] UniformityError),
    /// The ring truss cannot be built, or the design's pull is past its limit
    /// load ([`TrussError::PastLimitLoad`]).
    #[error(transparent)]
    RingTruss(#[from] TrussError),
    /// The design cannot be assembled as built.
    #[error(transparent)]
    Verify(#[from] VerifyError),
    /// The surface's target no net meets, or a surface that cannot be measured.
    #[error(transparent)]
    Surface(#[from] SurfaceError),
}

impl DesignError {
    /// True when the input is at fault.
    pub fn is_bad_input(&self) -> bool {
        match self {
            DesignError::Setting { .. } => true,
            DesignError::Uniformity { source, .. } => source.is_bad_input(),
            DesignError::NoDesign { termination, .. } => *termination == Termination::Infeasible,
            DesignError::Truss { source, .. } | DesignError::RingTruss(source) => {
                source.is_bad_input()
            }
            DesignError::Scene(_) => true,
            DesignError::Problem(e) => e.is_bad_input(),
            DesignError::Verify(e) => e.is_bad_input(),
            DesignError::Surface(e) => e.is_bad_input(),
        }
    }
}
