//! `ringmesh init [PATH]`: writes the commented starting scene
//! ([`crate::scene::template`]), never over an existing file.

use std::path::{Path, PathBuf};

use super::Summary;
use crate::report::{write_atomic, ReportError};
use crate::Error;

/// Where `ringmesh init` writes without a path: `runs/my-dish.toml` (under
/// the git-ignored `runs/`).
pub fn default_init_path() -> PathBuf {
    Path::new(super::RUNS_DIR).join("my-dish.toml")
}

/// What `init` wrote.
#[derive(Debug, Clone)]
pub struct InitOutcome {
    /// The scene file.
    pub path: PathBuf,
    /// The scene's name (the file's stem).
    pub name: String,
}

impl InitOutcome {
    /// What the command prints: the file and the next command.
    pub fn summary(&self) -> Summary {
        Summary {
            lines: vec![
                format!(
                    "wrote {} (scene `{}`; its keys: docs/scene.md)",
                    self.path.display(),
                    self.name
                ),
                format!("next: ringmesh design {}", self.path.display()),
            ],
            ended_early: None,
        }
    }
}

/// Writes the starting scene to `path` (default [`default_init_path`]),
/// named after the file's stem.
///
/// # Errors
/// [`ReportError::Exists`] when a file is there already (nothing is
/// written), a stem that cannot name a scene, and the writer's errors.
pub fn init(path: Option<&Path>) -> Result<InitOutcome, Error> {
    let path = path.map_or_else(default_init_path, Path::to_path_buf);
    if path.symlink_metadata().is_ok() {
        return Err(ReportError::Exists { path }.into());
    }
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let text = crate::scene::template(&name);
    // The stem names the scene: refused here, with the key, if it cannot.
    crate::Scene::from_toml(&text, &name)?;
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|source| ReportError::Io {
            path: parent.to_path_buf(),
            source,
        })?;
    }
    write_atomic(&path, text.as_bytes())?;
    Ok(InitOutcome { path, name })
}
