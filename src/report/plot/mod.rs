//! Pictures (plotters), one figure a file: the design front, the outer
//! loop's convergence, the surface error, the accuracy study and its
//! solvers' strategies, the aperture study, the truss sizing and a frame's
//! equilibrium path. What they share — the font shipped in the crate (plots render on a machine without system fonts), the
//! drawing areas and the writing of PNG and SVG — is in `canvas`; point
//! labels in `labels`.

mod accuracy_vs_time;
mod aperture;
mod budget;
mod canvas;
mod convergence;
mod frame_path;
mod front;
#[cfg(test)]
mod label_check;
mod labels;
mod sizing;
mod strategies;
mod surface_error;

pub use accuracy_vs_time::{study_plot, StudyRms};
pub use aperture::aperture_plot;
pub use budget::budget_plot;
pub use convergence::convergence_plot;
pub use frame_path::{path_plot, PathFigure};
pub use front::{front_plot, FrontRms, FrontY};
pub use sizing::sizing_plot;
pub use strategies::{strategies_plot, strategy_series, StrategySeries};
pub use surface_error::{surface_plot, PanelContent, PanelRms, SurfaceFigure, SurfacePanel};

/// Floor for a logarithmic RMS axis, mm (an exact design has RMS ≈ 1e-12 mm).
const RMS_FLOOR_MM: f64 = 1e-9;

/// Which surface RMS the design front and the accuracy study are drawn
/// against (issue 34).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum RmsAxis {
    /// The design's own: the front's forward-solve RMS, the study's RMS as
    /// built (node RMS of the free front nodes, axial).
    #[default]
    Design,
    /// The total `√(facets² + design²)`, with the facet RMS of the net's
    /// design surface ([`crate::surface::design_surface_facets`]): the
    /// number a user trades, as the surface error budget combines it.
    Total,
}

/// The total RMS of a net's design-surface facet RMS and a design's RMS,
/// `√(facets² + design²)`, mm (the budget's root-sum-square,
/// [`crate::surface::SurfaceBudget::total`]).
pub fn total_rms_mm(facets_mm: f64, design_mm: f64) -> f64 {
    facets_mm.hypot(design_mm)
}
