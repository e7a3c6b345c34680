//! Reading a scene: text parsed by serde into the [`super::schema`], each
//! net's tension resolved, validated ([`super::validate`]), and the tables the
//! effects name read; and a scene written back as TOML.

use std::path::Path;

use super::error::SceneError;
use super::rod_properties::RodProperties;
use super::schema::{membrane_tension_n, Scene};

impl Scene {
    /// Reads, parses and validates a scene file; the name defaults to the file
    /// stem, and files the scene names (`effects.rod_properties_csv`) are
    /// relative to the scene file's folder.
    pub fn read(path: &Path) -> Result<Scene, SceneError> {
        let shown = path.display().to_string();
        let text = crate::input::read_input(path).map_err(|source| SceneError::Io {
            path: shown.clone(),
            source,
        })?;
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let folder = path.parent().unwrap_or(Path::new(""));
        Scene::from_toml_in(&text, &stem, folder).map_err(|e| match e {
            SceneError::Parse { message, .. } => SceneError::Parse {
                path: shown,
                message,
            },
            other => other,
        })
    }

    /// Parses and validates scene text; `default_name` is used when it has no
    /// `name`. Files the scene names are relative to the current directory.
    pub fn from_toml(text: &str, default_name: &str) -> Result<Scene, SceneError> {
        Scene::from_toml_in(text, default_name, Path::new(""))
    }

    /// [`Scene::from_toml`] with the files the scene names relative to `folder`.
    pub fn from_toml_in(
        text: &str,
        default_name: &str,
        folder: &Path,
    ) -> Result<Scene, SceneError> {
        let mut scene: Scene = toml::from_str(text).map_err(|e| SceneError::Parse {
            path: "<scene>".into(),
            message: e.to_string(),
        })?;
        if scene.name.is_empty() {
            scene.name = default_name.to_string();
        }
        if !scene.front_net.rings_to_choose() {
            scene.resolve_tensions();
        }
        scene.validate()?;
        scene.read_effect_files(folder)?;
        Ok(scene)
    }

    /// The scene as TOML text that [`Scene::from_toml`] reads back to an
    /// equal scene (a table the effects name stays a file name).
    ///
    /// # Errors
    /// A value TOML cannot hold (not one of a validated scene).
    pub fn to_toml(&self) -> Result<String, SceneError> {
        toml::to_string(self).map_err(|e| SceneError::Parse {
            path: format!("<scene {}>", self.name),
            message: e.to_string(),
        })
    }

    /// Reads the tables the effects name (only those asked for).
    fn read_effect_files(&mut self, folder: &Path) -> Result<(), SceneError> {
        if let Some(file) = &self.effects.rod_properties_csv {
            let table = RodProperties::read(&folder.join(file), self.truss.bays)?;
            self.effects.rod_properties = Some(table);
        }
        Ok(())
    }

    /// The scene with its front net's rings set to `rings` (a scene whose
    /// file left them to `[surface] rms_mm`): the mean tensions that a
    /// membrane stress gives resolved for that net, and the whole validated.
    ///
    /// # Errors
    /// A scene that is invalid with these rings, naming the key.
    pub fn with_rings(mut self, rings: usize) -> Result<Scene, SceneError> {
        self.front_net.rings = rings;
        self.front_net.chosen = None;
        // A mean tension given as a membrane stress follows the net's spacing.
        if self.front_net.membrane_stress_n_per_m.is_some() {
            self.front_net.mean_tension_n = 0.0;
        }
        if self.rear_net.membrane_stress_n_per_m.is_some() {
            self.rear_net.mean_tension_n = 0.0;
        }
        self.resolve_tensions();
        self.validate()?;
        Ok(self)
    }

    /// Sets each net's mean tension from its membrane stress, where the file
    /// gives that instead (`validate` then checks the pair).
    fn resolve_tensions(&mut self) {
        let per_unit_stress = membrane_tension_n(self, 1.0);
        for (mean, stress) in [
            (
                &mut self.front_net.mean_tension_n,
                self.front_net.membrane_stress_n_per_m,
            ),
            (
                &mut self.rear_net.mean_tension_n,
                self.rear_net.membrane_stress_n_per_m,
            ),
        ] {
            if let (0.0, Some(n)) = (*mean, stress) {
                *mean = n * per_unit_stress;
            }
        }
    }
}
