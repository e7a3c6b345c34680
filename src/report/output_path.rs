//! What a command's `-o` names when the command writes one file (`fdm`,
//! `uniformity`, `truss`, `cantilever`, `frame` with its companions): one
//! rule, so that a path is a file or a folder, never both by chance.
//!
//! - an existing folder, or a path ending in `/`, is a **folder**: the
//!   command writes its file there under its default name;
//! - otherwise a path ending in `.json` is the **file**;
//! - otherwise a path with another extension (`x.csv`, `x.png`) is refused:
//!   the command writes JSON;
//! - otherwise (no extension) it is a **folder**, created.
//!
//! So `-o` never replaces a folder (a folder named `x.json` is a folder),
//! and the files written beside a file (`frame`'s path CSV and plots) are
//! named after it, not over it.

use std::path::{Path, PathBuf};

use super::error::ReportError;

/// Where a single-file command writes, as its `-o` names it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum OutputPath {
    /// A folder; the command's file goes there under its default name.
    Folder(PathBuf),
    /// A file: its folder and its name.
    File {
        /// The folder holding it (`.` for a bare name).
        folder: PathBuf,
        /// The file's name.
        name: String,
    },
}

impl OutputPath {
    /// What `path` names, by the rule of the module's documentation.
    ///
    /// # Errors
    /// [`ReportError::OutputPath`] for a path with another extension than
    /// `.json` that is not an existing folder.
    pub fn resolve(path: &Path) -> Result<OutputPath, ReportError> {
        let text = path.as_os_str().to_string_lossy();
        if path.is_dir() || text.ends_with('/') {
            return Ok(OutputPath::Folder(path.to_path_buf()));
        }
        let Some(name) = path.file_name().map(|n| n.to_string_lossy().into_owned()) else {
            return Ok(OutputPath::Folder(path.to_path_buf()));
        };
        let folder = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .map_or_else(|| PathBuf::from("."), Path::to_path_buf);
        match path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
        {
            Some(e) if e == "json" => Ok(OutputPath::File { folder, name }),
            Some(e) => Err(ReportError::OutputPath {
                path: path.to_path_buf(),
                reason: format!(
                    "the command writes JSON: name a .json file, or a folder (an existing \
                     one, or end the path with /), not a .{e} file"
                ),
            }),
            None => Ok(OutputPath::Folder(path.to_path_buf())),
        }
    }

    /// The folder written into and the file's name there (`default_name` in a folder).
    pub fn folder_and_name(&self, default_name: &str) -> (PathBuf, String) {
        match self {
            OutputPath::Folder(folder) => (folder.clone(), default_name.to_string()),
            OutputPath::File { folder, name } => (folder.clone(), name.clone()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_path_is_a_file_or_a_folder_by_one_rule() {
        let root = tempfile::tempdir().unwrap();
        let existing = root.path().join("k.json");
        std::fs::create_dir(&existing).unwrap();
        // An existing folder is a folder, whatever its name.
        assert_eq!(
            OutputPath::resolve(&existing).unwrap(),
            OutputPath::Folder(existing.clone())
        );
        assert_eq!(
            OutputPath::resolve(Path::new("d/x.json")).unwrap(),
            OutputPath::File {
                folder: "d".into(),
                name: "x.json".into()
            }
        );
        assert_eq!(
            OutputPath::resolve(Path::new("x.JSON")).unwrap(),
            OutputPath::File {
                folder: ".".into(),
                name: "x.JSON".into()
            }
        );
        for folder in ["out", "out/x.json/", "d/sub/"] {
            assert_eq!(
                OutputPath::resolve(Path::new(folder)).unwrap(),
                OutputPath::Folder(folder.into()),
                "{folder}"
            );
        }
        let e = OutputPath::resolve(Path::new("d/frame-path.csv")).unwrap_err();
        assert!(e.is_bad_input());
        assert!(
            e.to_string()
                .starts_with("-o d/frame-path.csv: the command writes JSON"),
            "{e}"
        );
        assert_eq!(
            OutputPath::Folder("d".into()).folder_and_name("fdm.json"),
            (PathBuf::from("d"), "fdm.json".to_string())
        );
    }
}
