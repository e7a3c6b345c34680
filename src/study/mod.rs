//! The cost of accuracy: wall time against achieved accuracy of the whole
//! design (outer loop to a converged net), one knob at a time.
//!
//! Knobs, each swept from the *baseline* — the scene's own settings: its
//! elements per rod, rings and `[effects] truss`, the `design` command's
//! tolerance (1e-6 m) and solver (`lp`):
//!
//! * [`Knob::Tolerance`] — the outer loop's `‖G(C) − C‖∞` tolerance, m;
//! * [`Knob::Elements`] — beam elements per truss rod;
//! * [`Knob::Rings`] — front-net density (rings of the sector grid);
//! * [`Knob::Truss`] — the loop's truss model (rigid, linear, exact);
//! * [`Knob::Solver`] — the uniformity solver.
//!
//! The *reference* run (point 0) has the finest settings: the tightest
//! tolerance and the most elements of the sweep (and of the scene), the exact
//! truss, `lp`, and the scene's net. Every design is judged the same way —
//! cut to length and assembled on the reference truss (exact, the reference's
//! elements per rod; [`crate::verify`]) — so a point's accuracy is what its
//! design would give as built:
//!
//! * `rms_mm` — RMS axial deviation of the assembled front net's free nodes
//!   from the paraboloid, mm;
//! * `built_ratio` — `Tmax/Tmin` of the assembled tensions over the uniformity
//!   sets (the largest), and `ratio_error = |built_ratio − ref|/ref` against
//!   the reference's;
//! * `tension_change_pct` — largest change of an assembled tension from the
//!   point's own design, %;
//! * `cut_length_error_mm` — largest difference of a cable's cut length from
//!   the reference's, mm (same net only);
//! * `facet_rms_mm` — RMS axial distance of the flat facets through the
//!   assembled nodes from the paraboloid, plan-area weighted ([`crate::surface::facet_rms`]).
//!
//! A net of other rings is another reflector: it cannot be compared cable by
//! cable (no `cut_length_error_mm`), its `ratio_error` is mostly the change of
//! the optimum with the net, and what its density buys is `facet_rms_mm`.
//!
//! A point that fails (no truss equilibrium, no assembled equilibrium) is a row
//! with its error, not a failed study; only a reference that fails or does not
//! converge stops it.
//! Points run in a deterministic order, so a sweep splits into shards
//! ([`crate::shard`]); every shard runs the reference itself to judge its
//! points.

mod aperture;
mod measure;
mod pareto;
mod plan;
mod row;

pub use aperture::{
    run_aperture_study, scaled, scaled_scenes, ApertureResult, ApertureSettings, ModelResult,
    MAX_APERTURE_M,
};
pub use measure::run_study;
pub use pareto::pareto_optimal;
pub use plan::{
    baseline, points, reference, value_name, Knob, RunSettings, StudyPoint, StudySettings,
};
pub use row::StudyRow;

/// A study that cannot run.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// An invalid study setting.
    #[error("study setting `{key}`: {reason}")]
    Setting {
        /// The setting (`tolerances_m`, `elements_per_rod`, `rings`,
        /// `max_iterations`).
        key: &'static str,
        /// Why the value is refused.
        reason: String,
    },
    /// The reference run failed: nothing can be judged.
    #[error("the study's reference run ({settings}) failed: {message}")]
    Reference {
        /// The reference's settings.
        settings: String,
        /// Why.
        message: String,
    },
    /// The worker threads could not be started.
    #[error("starting {jobs} worker threads: {message}")]
    Threads {
        /// Threads asked for.
        jobs: usize,
        /// The cause.
        message: String,
    },
}

impl StudyError {
    /// True when the input is at fault.
    pub fn is_bad_input(&self) -> bool {
        matches!(self, StudyError::Setting { .. })
    }
}
