//! Why a result cannot be written ([`ReportError`]), naming the file as the
//! user will find it.

use std::path::{Path, PathBuf};

/// Writing a result failed.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// The file system refused.
    #[error("writing {}: {source}", shown(path).display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A plot could not be drawn.
    #[error("drawing {}: {source}", shown(path).display())]
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
        /// The folder given (`-o`), never the staging folder.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The output folder holds a mount point, which a swap of the folder
    /// would carry away: found before any computing.
    #[error(
        "the output folder {} holds a mount point: {} (a run swaps its folder in whole, \
         which would carry what is mounted there away); choose another output folder (-o)",
        path.display(),
        mounts.iter().map(|m| m.display().to_string()).collect::<Vec<_>>().join(", ")
    )]
    MountPoint {
        /// The folder.
        path: PathBuf,
        /// The mount points in it.
        mounts: Vec<PathBuf>,
    },
    /// An `-o` that names neither a file nor a folder the command can write
    /// ([`OutputPath`](super::OutputPath)).
    #[error("-o {}: {reason}", path.display())]
    OutputPath {
        /// The path given.
        path: PathBuf,
        /// Why it cannot be.
        reason: String,
    },
    /// A file a run's manifest names cannot be read
    /// ([`check_manifest`](super::check_manifest)).
    #[error("{file}: {source} (run {run})")]
    ManifestUnreadable {
        /// The file's name in the folder.
        file: String,
        /// The run whose manifest names it.
        run: String,
        /// The cause.
        source: std::io::Error,
    },
    /// A file is not the one a run's manifest records
    /// ([`check_manifest`](super::check_manifest)).
    #[error("{file} is not the file run {run} wrote: the folder mixes two runs")]
    MixedRuns {
        /// The file's name in the folder.
        file: String,
        /// The run whose manifest records it.
        run: String,
    },
    /// A file that must not be written over is there (`ringmesh init`).
    #[error("{path} exists: nothing was written; name a new file")]
    Exists {
        /// The file.
        path: PathBuf,
    },
    /// A value could not be serialised (a non-finite number in JSON, say).
    #[error("serialising {}: {source}", shown(path).display())]
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
            ReportError::Busy { .. }
                | ReportError::Name { .. }
                | ReportError::Unwritable { .. }
                | ReportError::MountPoint { .. }
                | ReportError::OutputPath { .. }
                | ReportError::Exists { .. }
        )
    }
}

/// What a drawing fails with: the plotting backend's error.
pub type DrawError = Box<dyn std::error::Error + Send + Sync>;

/// Where a file staged at `path` goes: `path` itself unless it lies in a
/// staging folder — `.NAME.staging-RUN` beside the folder `NAME`, then the
/// same name in `NAME`; `.staging-RUN` in the folder, then the same name in
/// that folder — (what a message about the file should name).
fn shown(path: &Path) -> PathBuf {
    let staged = || {
        let dir = path.parent()?;
        let name = dir.file_name()?.to_str()?;
        if name.starts_with(".staging-") {
            return Some(dir.parent()?.join(path.file_name()?));
        }
        let (folder, _) = dir
            .file_name()?
            .to_str()?
            .strip_prefix('.')?
            .split_once(".staging-")?;
        Some(dir.parent()?.join(folder).join(path.file_name()?))
    };
    staged().unwrap_or_else(|| path.to_path_buf())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_the_target_not_the_staging_folder() {
        assert_eq!(
            shown(Path::new("/r/.small-hex.staging-17-5-3/cables.csv")),
            Path::new("/r/small-hex/cables.csv")
        );
        assert_eq!(shown(Path::new("/r/out/a.csv")), Path::new("/r/out/a.csv"));
        assert_eq!(
            shown(Path::new("/r/out/.staging-17-5-3/x.json")),
            Path::new("/r/out/x.json")
        );
    }
}
