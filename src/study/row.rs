//! A row of the study: a point, its cost and its accuracy as built (the
//! columns of `accuracy-vs-time.csv`, written by [`crate::report::study_csv`]).

use serde::Serialize;

use super::{Knob, RunSettings};
use crate::design::LoopSummary;

/// One row of `accuracy-vs-time.csv`: a point, its cost and its accuracy.
/// Missing numbers (a failed point, another net's cut lengths) are NaN.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StudyRow {
    /// What the point varies.
    pub knob: Knob,
    /// The knob's value as shown.
    pub value: String,
    /// The point's settings.
    pub settings: RunSettings,
    /// Wall time of the design: mesh, problem and outer loop, s (the
    /// study's cost; measured for a failed point too).
    pub time_s: f64,
    /// How the outer loop ended, its iterations and final residual; none
    /// when the point failed before its loop ended. Its `time_s` is the
    /// loop's alone: `accuracy-vs-time.csv` holds the design's (`time_s`
    /// above), so a row read back has NaN there. Not flattened: its
    /// `time_s` would collide with the row's.
    pub summary: Option<LoopSummary>,
    /// The design's `Tmax/Tmin` (largest set).
    pub ratio: f64,
    /// `Tmax/Tmin` as built on the reference truss (largest set).
    pub built_ratio: f64,
    /// `|built_ratio − reference's|/reference's`.
    pub ratio_error: f64,
    /// RMS axial deviation of the front net's free nodes as built, mm.
    pub rms_mm: f64,
    /// Largest axial deviation of a front-net free node as built, mm.
    pub max_deviation_mm: f64,
    /// RMS axial distance of the built facets from the paraboloid, mm.
    pub facet_rms_mm: f64,
    /// Largest change of a built tension from the design, %.
    pub tension_change_pct: f64,
    /// Largest difference of a cut length from the reference's, mm (NaN for
    /// another net).
    pub cut_length_error_mm: f64,
    /// Why the point failed.
    pub error: Option<String>,
}

impl StudyRow {
    /// True when the point designs the reference's net (its accuracy is
    /// comparable cable by cable).
    pub fn same_net_as(&self, reference: &StudyRow) -> bool {
        self.settings.rings == reference.settings.rings
    }
}
