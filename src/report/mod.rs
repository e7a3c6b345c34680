//! Files a run writes: JSON, CSV, VTK, plots. Every file is written to a temporary file in
//! its folder and renamed into place, so a reader never sees half a file; a
//! command's files go into the target folder together or not at all
//! ([`OutputSet`]).

mod atomic;
mod csv;
mod error;
mod folder;
mod number;
mod output_path;
mod output_set;
mod pending;
mod plot;
mod vtk;

pub use atomic::{json_bytes, write_atomic, write_json};
pub use csv::{
    aperture_csv, cables_csv, convergence_csv, front_csv, front_row, json_name, parse_front_row,
    parse_study_row, sizing_csv, study_csv, study_row, FrontRow, FRONT_COLUMNS, STUDY_COLUMNS,
};
pub use error::{DrawError, ReportError};
pub use number::{decimal, readable};
pub use output_path::OutputPath;
pub use output_set::{check_manifest, FileRecord, OutputSet, RunRecord, WithRun};
pub use pending::abandon_all_and_exit;
pub use plot::{
    aperture_plot, budget_plot, convergence_plot, front_plot, path_plot, sizing_plot,
    strategies_plot, strategy_series, study_plot, surface_plot, total_rms_mm, FrontRms, FrontY,
    PanelContent, PanelRms, PathFigure, RmsAxis, StrategySeries, StudyRms, SurfaceFigure,
    SurfacePanel,
};
pub use vtk::{assembly_vtu, network_vtu};
