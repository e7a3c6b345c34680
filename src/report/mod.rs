//! Files a run writes: JSON, CSV, VTK, plots. Every file is written to a temporary file in
//! its folder and renamed into place, so a reader never sees half a file; a
//! command's files go into the target folder together or not at all
//! ([`OutputSet`]).

mod csv;
mod output_set;
mod plot;
mod vtk;

use std::io::Write;
use std::path::{Path, PathBuf};

use serde::Serialize;

pub use csv::{
    aperture_csv, cables_csv, convergence_csv, front_csv, front_row, json_name, parse_front_row,
    parse_study_row, sizing_csv, study_csv, study_row, FrontRow, FRONT_COLUMNS, STUDY_COLUMNS,
};
pub use output_set::{abandon_all_and_exit, check_manifest, FileRecord, OutputSet, RunRecord};
pub use plot::{
    aperture_plot, convergence_plot, front_plot, path_plot, study_plot, surface_plot, NodePanel,
    PathFigure, SurfaceFigure,
};
pub use vtk::{assembly_vtu, network_vtu};

/// Writing a result failed.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// The file system refused.
    #[error("writing {}: {source}", output_set::shown(path).display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A plot could not be drawn.
    #[error("drawing {}: {source}", output_set::shown(path).display())]
    Plot {
        /// The file.
        path: PathBuf,
        /// The backend's error.
        source: DrawError,
    },
    /// Another run holds the output folder ([`OutputSet`]).
    #[error(
        "another ringmesh run is writing into {path}: nothing was computed or written; \
         wait for it to finish, or choose another output folder (-o)"
    )]
    Busy {
        /// The folder.
        path: PathBuf,
    },
    /// An output file name no file system takes.
    #[error("`{name}` cannot name an output file: {reason}")]
    Name {
        /// The name (its first 80 characters).
        name: String,
        /// Why not.
        reason: &'static str,
    },
    /// The output folder cannot be created or written: found before any
    /// computing.
    #[error("cannot write into the output folder {path}: {source}")]
    Unwritable {
        /// The folder, or the staging folder beside it.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A file a run's manifest names cannot be read ([`check_manifest`]).
    #[error("{file}: {source} (run {run})")]
    ManifestUnreadable {
        /// The file's name in the folder.
        file: String,
        /// The run whose manifest names it.
        run: String,
        /// The cause.
        source: std::io::Error,
    },
    /// A file is not the one a run's manifest records ([`check_manifest`]).
    #[error("{file} is not the file run {run} wrote: the folder mixes two runs")]
    MixedRuns {
        /// The file's name in the folder.
        file: String,
        /// The run whose manifest records it.
        run: String,
    },
    /// A value could not be serialised (a non-finite number in JSON, say).
    #[error("serialising {}: {source}", output_set::shown(path).display())]
    Json {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: serde_json::Error,
    },
}

impl ReportError {
    /// Refusals before any computing (a folder in use or not writable, a
    /// name that cannot be a file's) are the input's; failures while
    /// writing are not.
    pub fn is_bad_input(&self) -> bool {
        matches!(
            self,
            ReportError::Busy { .. } | ReportError::Name { .. } | ReportError::Unwritable { .. }
        )
    }
}

/// Writes `bytes` to `path` atomically: a temporary file beside it, flushed and
/// synced, then renamed over `path`. Creates the parent folder if needed.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), ReportError> {
    let io = |source| ReportError::Io {
        path: path.to_path_buf(),
        source,
    };
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let file_name = path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let temporary = parent.join(format!(".{file_name}.{}.tmp", std::process::id()));
    let result = (|| {
        let mut file = output_set::create_registered(&temporary)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        std::fs::rename(&temporary, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&temporary);
    }
    output_set::unregister(&temporary);
    result.map_err(io)
}

/// `v` in plain decimal with at most `digits` significant digits, trailing
/// zeros dropped (`41.65`, `0.002731`, `12.5`): no exponent where a person,
/// or a cutting sheet, reads one badly.
pub fn decimal(v: f64, digits: usize) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let decimals = (digits as i32 - 1 - v.abs().log10().floor() as i32).clamp(0, 30) as usize;
    without_trailing_zeros(&format!("{v:.decimals$}"))
}

/// `v` for a reader and for a table: [`decimal`] from 1e-3 to 1e6 in
/// magnitude, scientific beyond (`2.134e-7`), at most `digits` significant
/// digits either way; non-finite values as Rust writes them (`NaN`, `inf`).
pub fn readable(v: f64, digits: usize) -> String {
    if v == 0.0 || !v.is_finite() || (1e-3..1e6).contains(&v.abs()) {
        decimal(v, digits)
    } else {
        let text = format!("{v:.*e}", digits.saturating_sub(1));
        let (mantissa, exponent) = text.split_once('e').expect("scientific notation");
        format!("{}e{exponent}", without_trailing_zeros(mantissa))
    }
}

/// `12.500` → `12.5`, `3.000` → `3`; a number without a point is kept.
fn without_trailing_zeros(text: &str) -> String {
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text.to_string()
    }
}

/// What a drawing fails with: the plotting backend's error.
pub type DrawError = Box<dyn std::error::Error + Send + Sync>;

/// A run's JSON report with its [`RunRecord`] first (`"run": {…}`).
#[derive(Serialize)]
pub struct WithRun<'a, T: Serialize> {
    /// The run's identifier and files.
    pub run: &'a RunRecord,
    /// The report.
    #[serde(flatten)]
    pub report: &'a T,
}

/// Serialises `value` as pretty JSON and writes it atomically.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), ReportError> {
    let mut bytes = serde_json::to_vec_pretty(value).map_err(|source| ReportError::Json {
        path: path.to_path_buf(),
        source,
    })?;
    bytes.push(b'\n');
    write_atomic(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_write_replaces_whole_file_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sub/out.json");
        write_json(&path, &vec![1, 2, 3]).unwrap();
        write_json(&path, &vec![4]).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(serde_json::from_str::<Vec<i32>>(&text).unwrap(), vec![4]);
        let entries = std::fs::read_dir(path.parent().unwrap()).unwrap().count();
        assert_eq!(entries, 1);
    }

    #[test]
    fn numbers_read_as_written_in_plain_decimal_where_a_reader_wants_it() {
        assert_eq!(decimal(41.4916, 4), "41.49");
        assert_eq!(decimal(12.5, 13), "12.5");
        assert_eq!(decimal(100.0, 13), "100");
        assert_eq!(decimal(-0.002_731_04, 4), "-0.002731");
        assert_eq!(readable(2.134_04e-7, 4), "2.134e-7");
        assert_eq!(readable(1e-7, 7), "1e-7");
        assert_eq!(readable(2.5e9, 3), "2.5e9");
        assert_eq!(readable(0.0, 7), "0");
        // Every digit kept is a digit read back.
        for v in [
            std::f64::consts::PI * 1e-9,
            2.692_821_634_6,
            6.513_434_591_361e1,
        ] {
            let back: f64 = readable(v, 11).parse().unwrap();
            assert!((back / v - 1.0).abs() < 1e-10, "{v} → {back}");
        }
    }
}
