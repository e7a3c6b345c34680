//! The problem file: a reflector scene in TOML, with SI units in every key name.
//!
//! [`Scene::read`] parses (unknown keys are rejected) and validates every value
//! once; an invalid scene is a [`SceneError`] naming the key and the reason.
//! Geometric checks that need the generated nets (ties of positive length, an
//! unfolded grid, no degenerate cable) are made by [`crate::geometry::build_mesh`]
//! with the same error type.
//!
//! # Ranges
//!
//! Every scene within these ranges validates, builds and has an `lp` design
//! (the property test `tests/properties.rs` draws them at random):
//! `aperture_diameter_m` 1…100; `focal_length_m / aperture_diameter_m`
//! 0.15…5; `offset_m` 0…0.5 × aperture; `bays` 3…36; `rings` 2…8;
//! `boundary_sag_ratio` 0.02…0.2; `rear_net.focal_length_m` 1…4 × the front
//! focal length; `height_m` 1.1…2 × what the nets need,
//! `R² (1/F + 1/F_rear)/4` (R the aperture radius); mean tensions 1…1000 N;
//! a bound `max_force_density_n_per_m` the design does not meet is reported
//! by the solver. Outside them a scene may still be valid; what is not is
//! refused with the key named.
//!
//! The measured-rods table a scene may name (`[effects] rod_properties_csv`)
//! is an input of the scene too: its format lives in `rod_properties.rs`.

mod rod_properties;

use std::path::Path;

use serde::{Deserialize, Serialize};

pub use rod_properties::{RodKind, RodProperties, RodPropertiesError, RodStiffness, TrussRod};

/// Longest scene name: it names the results folder and files made from it.
pub const MAX_NAME_LEN: usize = 128;

/// Largest elastic modulus a scene may give, Pa (diamond: 1.2e12).
pub const MAX_MODULUS_PA: f64 = 1e13;

/// Tallest truss, as a multiple of the aperture diameter (real rings:
/// 0.1–0.6).
pub const MAX_HEIGHT_RATIO: f64 = 10.0;

/// A whole reflector scene: the input of one run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Name of the scene; results go to `results/<name>/`. Defaults to the file stem.
    #[serde(default)]
    pub name: String,
    /// The reflecting surface.
    pub reflector: Reflector,
    /// The ring truss that carries the nets.
    pub truss: Truss,
    /// The front (reflecting) net.
    pub front_net: FrontNet,
    /// The rear net.
    pub rear_net: RearNet,
    /// Cable properties (all nets and ties).
    pub cables: Cables,
    /// Which cables the design makes uniform (DESIGN §4).
    #[serde(default)]
    pub uniformity: Uniformity,
    /// Which physics the model includes (DESIGN §8).
    #[serde(default)]
    pub effects: Effects,
}

/// A net whose interior tensions can be made uniform.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum UniformNet {
    /// The front net's interior cables (target `front_net.mean_tension_n`).
    Front,
    /// The rear net's interior cables (target `rear_net.mean_tension_n`).
    Rear,
}

/// The uniformity groups of the design: each its own tension level, one common
/// ratio `Tmax/Tmin` minimised. The first group's mean tension is held at its
/// target; the others' levels follow from equilibrium.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Uniformity {
    /// The groups, first one fixing the pretension level.
    pub groups: Vec<UniformNet>,
    /// Cables outside every group keep at least this fraction of the first
    /// group's smallest tension (so every q is strictly positive).
    pub min_tension_fraction: f64,
}

impl Default for Uniformity {
    fn default() -> Self {
        Uniformity {
            groups: vec![UniformNet::Front],
            min_tension_fraction: 1e-3,
        }
    }
}

/// The paraboloid `z = (x² + y²)/(4F)` and the aperture on it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Reflector {
    /// Diameter of the aperture circle (plan), m.
    pub aperture_diameter_m: f64,
    /// Focal length F of the paraboloid, m.
    pub focal_length_m: f64,
    /// Distance h from the paraboloid axis to the aperture centre (plan), m;
    /// 0 for a centre-fed reflector.
    #[serde(default)]
    pub offset_m: f64,
}

/// How the ring truss is supported.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Supports {
    /// A 3-2-1 statically determinate support: the self-equilibrated net loads
    /// deform the truss without reactions.
    #[default]
    Isostatic,
}

/// The ring truss (paper §3, Table 3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Truss {
    /// Number of bays N (= vertical battens = top hinges).
    pub bays: usize,
    /// Batten length: vertical distance from bottom to top hinges, m.
    pub height_m: f64,
    /// Outer diameter of the tubes, m.
    pub tube_outer_diameter_m: f64,
    /// Inner diameter of the tubes, m.
    pub tube_inner_diameter_m: f64,
    /// Young's modulus of the tubes, Pa.
    pub youngs_modulus_pa: f64,
    /// Shear modulus of the tubes, Pa.
    pub shear_modulus_pa: f64,
    /// Density of the tube material, kg/m³.
    pub density_kg_per_m3: f64,
    /// The supports.
    #[serde(default)]
    pub supports: Supports,
    /// Beam elements per rod of the flexible truss models (1…64).
    #[serde(default = "default_elements_per_rod")]
    pub elements_per_rod: usize,
    /// Beam element of the flexible truss models.
    #[serde(default)]
    pub element: crate::mechanics::ElementKind,
    /// Mass of one hinge body, kg (its weight acts under `[effects.gravity]`).
    #[serde(default)]
    pub hinge_mass_kg: f64,
}

impl Truss {
    /// Cross-section area of the tubes, m².
    pub fn tube_area_m2(&self) -> f64 {
        std::f64::consts::PI
            * (self.tube_outer_diameter_m.powi(2) - self.tube_inner_diameter_m.powi(2))
            / 4.0
    }
}

/// Largest number of beam elements per truss rod.
pub const MAX_ELEMENTS_PER_ROD: usize = 64;

fn default_elements_per_rod() -> usize {
    4
}

/// The front net: sector subdivision of the N-gon of top hinges.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrontNet {
    /// Subdivisions of each sector's radial edge (rings of the grid).
    pub rings: usize,
    /// Inward sag of the boundary at mid-bay, as a fraction of the bay chord.
    pub boundary_sag_ratio: f64,
    /// Target mean tension of the front net's interior cables, N: given, or
    /// resolved from `membrane_stress_n_per_m` when the file gives that.
    #[serde(default)]
    pub mean_tension_n: f64,
    /// The membrane stress the net carries, N/m: the alternative to
    /// `mean_tension_n` that keeps its meaning as the net is refined
    /// ([`membrane_tension_n`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub membrane_stress_n_per_m: Option<f64>,
}

/// The rear net: the front net's plan grid on a paraboloid opening towards the
/// front net, through the bottom hinges.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RearNet {
    /// Focal length of the rear paraboloid, m: its rise above the bottom hinges
    /// is `(R² − ρ²)/(4 F_rear)` at plan distance ρ from the aperture centre.
    pub focal_length_m: f64,
    /// Target mean tension of the rear net's interior cables, N: given, or
    /// resolved from `membrane_stress_n_per_m`.
    #[serde(default)]
    pub mean_tension_n: f64,
    /// The rear net's membrane stress, N/m (the alternative to
    /// `mean_tension_n`, see [`membrane_tension_n`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub membrane_stress_n_per_m: Option<f64>,
}

/// Cable properties.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cables {
    /// Cable diameter, m.
    pub diameter_m: f64,
    /// Young's modulus of the cables, Pa.
    pub youngs_modulus_pa: f64,
    /// Density of the cable material, kg/m³.
    pub density_kg_per_m3: f64,
    /// Upper bound `[q]` on any force density, N/m (paper eq. 5).
    pub max_force_density_n_per_m: f64,
}

impl Cables {
    /// Cross-section area of one cable, m².
    pub fn area_m2(&self) -> f64 {
        std::f64::consts::PI * self.diameter_m * self.diameter_m / 4.0
    }

    /// Axial stiffness `EA` of one cable, N.
    pub fn axial_stiffness_n(&self) -> f64 {
        self.youngs_modulus_pa * self.area_m2()
    }

    /// Unstressed (cut) length of a cable of length `length_m` under `tension_n`:
    /// `L0 = ℓ/(1 + T/EA)` (DESIGN §7).
    pub fn cut_length_m(&self, length_m: f64, tension_n: f64) -> f64 {
        length_m / (1.0 + tension_n / self.axial_stiffness_n())
    }
}

/// Which truss model the design loop uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum TrussModel {
    /// No deformation: the conventional method.
    Rigid,
    /// Small-displacement frame.
    Linear,
    /// Geometrically exact beams and rigid hinges (paper §3).
    #[default]
    Exact,
}

/// The physics a scene asks for (DESIGN §8); what is not asked for is not built.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Effects {
    /// The truss model of the design loop.
    pub truss: TrussModel,
    /// Self weight of cables, rods and hinges (a ground test); absent: orbit.
    pub gravity: Option<Gravity>,
    /// Measured rod properties: a CSV table of EA/EI (GJ, GA) per rod that
    /// overrides the nominal tube section of the rods it names, relative to
    /// the scene file's folder (format and rod names:
    /// [`RodProperties`]). Absent: every rod is the nominal tube.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rod_properties_csv: Option<std::path::PathBuf>,
    /// The table of `rod_properties_csv`, read and validated by
    /// [`Scene::read`] / [`Scene::from_toml_in`] (only when the key is given).
    #[serde(skip)]
    pub rod_properties: Option<RodProperties>,
    /// Whether verification assembles elastic cables (`true`, the default:
    /// EA of `[cables]`, cut to `L₀ = ℓ/(1 + T/EA)`) or inextensible ones
    /// (`false`; see [`crate::verify::CableModel`]).
    pub cable_elasticity: bool,
}

impl Default for Effects {
    fn default() -> Self {
        Effects {
            truss: TrussModel::default(),
            gravity: None,
            rod_properties_csv: None,
            rod_properties: None,
            cable_elasticity: true,
        }
    }
}

/// Gravity: the self weight of the cables (nodal loads of the force density
/// method) and of the truss's rods and hinges (dead loads of its model).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Gravity {
    /// Gravitational acceleration, m/s² (9.81 on the ground).
    pub acceleration_m_per_s2: f64,
    /// Its direction in the scene's frame (z is the reflector's axis,
    /// pointing from the vertex to the focus): `[0, 0, -1]` for a test with
    /// the aperture facing up, `[1, 0, 0]` with the axis horizontal.
    pub direction: [f64; 3],
}

impl Gravity {
    /// The acceleration vector, m/s².
    pub fn vector_m_per_s2(&self) -> [f64; 3] {
        let d = self.direction;
        let norm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        d.map(|c| self.acceleration_m_per_s2 * c / norm)
    }
}

/// An invalid scene: every variant names the file or the key.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// Reading the file failed.
    #[error("reading {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// The file is not valid TOML of the scene format (unknown or missing key, wrong
    /// type); the message names the key and the line.
    #[error("{path}: {message}")]
    Parse {
        /// The file.
        path: String,
        /// The parser's message.
        message: String,
    },
    /// The table of `effects.rod_properties_csv` cannot be read or is
    /// invalid; the message names the file, the line and the rod or column.
    #[error("`effects.rod_properties_csv`: {0}")]
    RodProperties(#[from] RodPropertiesError),
    /// A value is out of its valid range.
    #[error("`{key}`: {reason}")]
    Invalid {
        /// The dotted key, e.g. `truss.tube_inner_diameter_m`.
        key: &'static str,
        /// Why the value is rejected.
        reason: String,
    },
}

impl SceneError {
    /// The key at fault, when the error is about one value.
    pub fn key(&self) -> Option<&'static str> {
        match self {
            SceneError::Invalid { key, .. } => Some(key),
            SceneError::RodProperties(_) => Some("effects.rod_properties_csv"),
            _ => None,
        }
    }

    pub(crate) fn invalid(key: &'static str, reason: impl Into<String>) -> Self {
        SceneError::Invalid {
            key,
            reason: reason.into(),
        }
    }
}

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
        scene.resolve_tensions();
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

    /// Checks every value against its valid range.
    pub fn validate(&self) -> Result<(), SceneError> {
        if self.name.is_empty()
            || !self
                .name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c))
            || self.name.starts_with('.')
        {
            return Err(SceneError::invalid(
                "name",
                format!(
                    "{:?} must be non-empty and use only letters, digits, '-', '_' and '.' \
                     (it names the results folder)",
                    self.name
                ),
            ));
        }
        if self.name.len() > MAX_NAME_LEN {
            return Err(SceneError::invalid(
                "name",
                format!(
                    "{} characters, at most {MAX_NAME_LEN}: it names the results folder and \
                     files (`<name>-sized.toml`, `<name>-at-100m.toml`) that file systems \
                     limit to 255 bytes",
                    self.name.len()
                ),
            ));
        }
        let r = &self.reflector;
        positive("reflector.aperture_diameter_m", r.aperture_diameter_m)?;
        positive("reflector.focal_length_m", r.focal_length_m)?;
        non_negative("reflector.offset_m", r.offset_m)?;

        let t = &self.truss;
        if t.bays < 3 {
            return Err(SceneError::invalid(
                "truss.bays",
                format!("{} bays: a ring truss needs at least 3", t.bays),
            ));
        }
        if t.bays > MAX_BAYS {
            return Err(SceneError::invalid(
                "truss.bays",
                format!("{} bays: more than the {MAX_BAYS} supported", t.bays),
            ));
        }
        positive("truss.height_m", t.height_m)?;
        let diameter = self.reflector.aperture_diameter_m;
        if t.height_m > MAX_HEIGHT_RATIO * diameter {
            return Err(SceneError::invalid(
                "truss.height_m",
                format!(
                    "{:e} m is more than {MAX_HEIGHT_RATIO} × the aperture ({diameter} m): the \
                     ties would span decades more than the net's cables, beyond what one \
                     force density solve balances",
                    t.height_m
                ),
            ));
        }
        if !(1..=MAX_ELEMENTS_PER_ROD).contains(&t.elements_per_rod) {
            return Err(SceneError::invalid(
                "truss.elements_per_rod",
                format!("{} must be in 1…{MAX_ELEMENTS_PER_ROD}", t.elements_per_rod),
            ));
        }
        positive("truss.tube_outer_diameter_m", t.tube_outer_diameter_m)?;
        non_negative("truss.tube_inner_diameter_m", t.tube_inner_diameter_m)?;
        if t.tube_inner_diameter_m >= t.tube_outer_diameter_m {
            return Err(SceneError::invalid(
                "truss.tube_inner_diameter_m",
                format!(
                    "{} m must be smaller than truss.tube_outer_diameter_m = {} m",
                    t.tube_inner_diameter_m, t.tube_outer_diameter_m
                ),
            ));
        }
        modulus("truss.youngs_modulus_pa", t.youngs_modulus_pa)?;
        modulus("truss.shear_modulus_pa", t.shear_modulus_pa)?;
        positive("truss.density_kg_per_m3", t.density_kg_per_m3)?;
        non_negative("truss.hinge_mass_kg", t.hinge_mass_kg)?;

        let f = &self.front_net;
        if f.rings < 2 {
            return Err(SceneError::invalid(
                "front_net.rings",
                format!(
                    "{} ring(s): at least 2 are needed for free boundary nodes between \
                     the truss attachments",
                    f.rings
                ),
            ));
        }
        positive("front_net.boundary_sag_ratio", f.boundary_sag_ratio)?;
        if f.boundary_sag_ratio >= 0.5 {
            return Err(SceneError::invalid(
                "front_net.boundary_sag_ratio",
                format!(
                    "{} must be below 0.5 (sag as a fraction of the bay chord)",
                    f.boundary_sag_ratio
                ),
            ));
        }
        let tension = membrane_tension_n(self, 1.0);
        one_tension_of(
            "front_net",
            f.mean_tension_n,
            f.membrane_stress_n_per_m,
            tension,
        )?;
        positive("rear_net.focal_length_m", self.rear_net.focal_length_m)?;
        let r = &self.rear_net;
        one_tension_of(
            "rear_net",
            r.mean_tension_n,
            r.membrane_stress_n_per_m,
            tension,
        )?;

        let u = &self.uniformity;
        if u.groups.is_empty() {
            return Err(SceneError::invalid(
                "uniformity.groups",
                "at least one group is needed",
            ));
        }
        if let Some(g) = u
            .groups
            .iter()
            .enumerate()
            .find_map(|(i, g)| u.groups[..i].contains(g).then_some(g))
        {
            return Err(SceneError::invalid(
                "uniformity.groups",
                format!("{g:?} is listed twice"),
            ));
        }
        if !(u.min_tension_fraction > 0.0 && u.min_tension_fraction < 1.0) {
            return Err(SceneError::invalid(
                "uniformity.min_tension_fraction",
                format!("{} must lie in (0, 1)", u.min_tension_fraction),
            ));
        }

        if self
            .effects
            .rod_properties_csv
            .as_ref()
            .is_some_and(|f| f.as_os_str().is_empty())
        {
            return Err(SceneError::invalid(
                "effects.rod_properties_csv",
                "must name a CSV file (relative to the scene's folder)",
            ));
        }
        if let Some(table) = &self.effects.rod_properties {
            table.check_bays(t.bays)?;
        }

        let c = &self.cables;
        positive("cables.diameter_m", c.diameter_m)?;
        modulus("cables.youngs_modulus_pa", c.youngs_modulus_pa)?;
        positive("cables.density_kg_per_m3", c.density_kg_per_m3)?;
        positive(
            "cables.max_force_density_n_per_m",
            c.max_force_density_n_per_m,
        )?;
        if let Some(g) = &self.effects.gravity {
            non_negative(
                "effects.gravity.acceleration_m_per_s2",
                g.acceleration_m_per_s2,
            )?;
            let norm = g.direction.iter().map(|c| c * c).sum::<f64>().sqrt();
            if !(norm.is_finite() && norm > 0.0) {
                return Err(SceneError::invalid(
                    "effects.gravity.direction",
                    format!("{:?} must be a finite, non-zero vector", g.direction),
                ));
            }
        }
        Ok(())
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

    /// The uniformity groups with their target mean tensions, N.
    pub fn uniformity_targets(&self) -> Vec<(crate::CableGroup, f64)> {
        self.uniformity
            .groups
            .iter()
            .map(|g| match g {
                UniformNet::Front => (crate::CableGroup::Front, self.front_net.mean_tension_n),
                UniformNet::Rear => (crate::CableGroup::Rear, self.rear_net.mean_tension_n),
            })
            .collect()
    }

    /// Radius of the aperture circle, m.
    pub fn aperture_radius_m(&self) -> f64 {
        0.5 * self.reflector.aperture_diameter_m
    }
}

/// The uniform cable tension, N, at which the front net's interior cables
/// carry the isotropic membrane stress `stress_n_per_m`, N/m, on the plan grid
/// of the scene's sector subdivision (the rear net shares it).
///
/// A uniform-tension net in a homogeneous isotropic stress state `N` has
/// `Σ_k T ℓ_k = tr(σ) A = 2 N A`, so `T = 2 N A / Σ_k ℓ_k` (on an equilateral
/// grid of spacing `a` this is `T = N a/√3`, as the net is refined). `A` and
/// `Σ ℓ` are those of the plan grid without the boundary sag, in closed form:
/// `N` sectors of apex `θ = 2π/N`, radial edge `R` (the aperture radius),
/// chord `c = 2R sin(θ/2)`, each subdivided into `r²` triangles, whose edges
/// total `(r + 1)(2R + c)/2`; the interior cables leave out the boundary
/// chords and count each radial edge once.
pub fn membrane_tension_n(scene: &Scene, stress_n_per_m: f64) -> f64 {
    let n = scene.truss.bays as f64;
    let r = scene.front_net.rings as f64;
    let radius = scene.aperture_radius_m();
    let theta = std::f64::consts::TAU / n;
    let chord = 2.0 * radius * (0.5 * theta).sin();
    let area = n * 0.5 * radius * radius * theta.sin();
    let interior = n * (0.5 * (r + 1.0) * (2.0 * radius + chord) - chord - radius);
    2.0 * stress_n_per_m * area / interior
}

/// Exactly one of `<net>.mean_tension_n` and `<net>.membrane_stress_n_per_m`
/// (a resolved scene has both, consistent: `tension_per_stress` N per N/m).
fn one_tension_of(
    net: &'static str,
    mean_tension_n: f64,
    stress: Option<f64>,
    tension_per_stress: f64,
) -> Result<(), SceneError> {
    let (mean_key, stress_key) = match net {
        "front_net" => (
            "front_net.mean_tension_n",
            "front_net.membrane_stress_n_per_m",
        ),
        _ => (
            "rear_net.mean_tension_n",
            "rear_net.membrane_stress_n_per_m",
        ),
    };
    match stress {
        None if mean_tension_n == 0.0 => Err(SceneError::invalid(
            mean_key,
            format!("missing: give `{mean_key}` (N) or `{stress_key}` (N/m)"),
        )),
        None => positive(mean_key, mean_tension_n),
        Some(n) => {
            positive(stress_key, n)?;
            let resolved = n * tension_per_stress;
            if (mean_tension_n - resolved).abs() > 1e-12 * resolved {
                return Err(SceneError::invalid(
                    stress_key,
                    format!(
                        "give either `{mean_key}` or `{stress_key}`, not both (the stress \
                         means {resolved:.6} N)"
                    ),
                ));
            }
            Ok(())
        }
    }
}

/// Largest number of bays a scene may ask for.
pub const MAX_BAYS: usize = 1_000;

/// An elastic modulus: positive, and at most [`MAX_MODULUS_PA`] (stiffer than
/// any material; 1e300 made the truss's Newton 'converge' in 0 iterations).
fn modulus(key: &'static str, value: f64) -> Result<(), SceneError> {
    positive(key, value)?;
    if value > MAX_MODULUS_PA {
        return Err(SceneError::invalid(
            key,
            format!("{value:e} Pa is stiffer than any material (at most {MAX_MODULUS_PA:e} Pa)"),
        ));
    }
    Ok(())
}

fn positive(key: &'static str, value: f64) -> Result<(), SceneError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(SceneError::invalid(
            key,
            format!("{value} must be a finite number > 0"),
        ))
    }
}

fn non_negative(key: &'static str, value: f64) -> Result<(), SceneError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(SceneError::invalid(
            key,
            format!("{value} must be a finite number ≥ 0"),
        ))
    }
}
