//! Pictures (plotters), one figure a file: the design front, the outer
//! loop's convergence, the surface error, the accuracy study, the aperture
//! study and a frame's equilibrium path. What they share — the font shipped
//! in the crate (plots render on a machine without system fonts), the
//! drawing areas and the writing of PNG and SVG — is in `canvas`; point
//! labels in `labels`.

mod accuracy_vs_time;
mod aperture;
mod canvas;
mod convergence;
mod frame_path;
mod front;
mod labels;
mod surface_error;

pub use accuracy_vs_time::study_plot;
pub use aperture::aperture_plot;
pub use convergence::convergence_plot;
pub use frame_path::{path_plot, PathFigure};
pub use front::front_plot;
pub use surface_error::{surface_plot, PanelContent, PanelRms, SurfaceFigure, SurfacePanel};

/// Floor for a logarithmic RMS axis, mm (an exact design has RMS ≈ 1e-12 mm).
const RMS_FLOOR_MM: f64 = 1e-9;
