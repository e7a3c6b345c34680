//! The scene's TOML syntax, as serde reads and writes it: one struct per
//! table, SI units in every key, unknown keys rejected; and what a scene's
//! values imply (areas, cut lengths, the uniformity targets, the tension of
//! a membrane stress). Nothing here is validated: [`super::validate`] does
//! that, naming the key at fault.

use serde::{Deserialize, Serialize};

use super::rod_properties::RodProperties;

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
    /// The surface accuracy the dish must hold, and its band.
    #[serde(default, skip_serializing_if = "SurfaceSpec::is_empty")]
    pub surface: SurfaceSpec,
    /// Manufacturing tolerances of the error budget (`ringmesh budget`);
    /// absent: none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerances: Option<Tolerances>,
}

/// Manufacturing tolerances (`[tolerances]`): standard deviations of
/// independent, zero-mean normal errors, each drawn per item.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Tolerances {
    /// Cut length of each net cable (front, rear, boundaries), m.
    pub cable_length_sigma_m: f64,
    /// Cut length of each tie, m.
    pub tie_length_sigma_m: f64,
    /// Length of each truss rod (batten, longeron, diagonal tube), m.
    pub rod_length_sigma_m: f64,
    /// Axial stiffness EA of each cable, relative (0.02: 2 %).
    pub cable_stiffness_sigma: f64,
    /// Position of each hinge (where the nets attach), each component, m.
    pub hinge_position_sigma_m: f64,
    /// Monte Carlo samples (`ringmesh budget --samples` overrides).
    pub samples: Option<usize>,
    /// Seed of the samples (`--seed` overrides).
    pub seed: Option<u64>,
}

impl Tolerances {
    /// The standard deviations by name, as the scene's keys name them.
    pub fn sigmas(&self) -> [(&'static str, f64); 5] {
        [
            ("tolerances.cable_length_sigma_m", self.cable_length_sigma_m),
            ("tolerances.tie_length_sigma_m", self.tie_length_sigma_m),
            ("tolerances.rod_length_sigma_m", self.rod_length_sigma_m),
            (
                "tolerances.cable_stiffness_sigma",
                self.cable_stiffness_sigma,
            ),
            (
                "tolerances.hinge_position_sigma_m",
                self.hinge_position_sigma_m,
            ),
        ]
    }
}

/// Thermal distortion in orbit (`[effects.thermal]`): expansion coefficients
/// per material and named load cases, each a field of temperature change
/// from the temperature the dish was built at. The hinges are rigid bodies
/// of the tube material; in this frame every joint sits at its hinge's
/// position (bodies of no extent), so they have nothing to expand.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Thermal {
    /// Expansion coefficient of the net cables, 1/K.
    pub cable_expansion_per_k: f64,
    /// Of the ties, 1/K (absent: the cables').
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tie_expansion_per_k: Option<f64>,
    /// Of the truss tubes (and hinge bodies), 1/K.
    pub tube_expansion_per_k: f64,
    /// The load cases.
    pub cases: Vec<ThermalCase>,
}

/// One thermal load case: the temperature change at a point, the sum of a
/// uniform part, a linear gradient across the aperture and a front/rear
/// difference (front net and top longerons at `front_k`, rear net and
/// bottom longerons at `rear_k`, ties, battens and diagonals at their
/// mean), each term 0 unless given.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermalCase {
    /// The case's name in the budget.
    pub name: String,
    /// Uniform temperature change, K.
    #[serde(default)]
    pub uniform_k: f64,
    /// Gradient across the aperture, K/m, zero at the aperture's centre.
    #[serde(default)]
    pub gradient_k_per_m: f64,
    /// Its plan direction `[x, y]` (any length but zero).
    #[serde(default = "x_direction")]
    pub gradient_direction: [f64; 2],
    /// Temperature change of the front side, K.
    #[serde(default)]
    pub front_k: f64,
    /// Temperature change of the rear side, K.
    #[serde(default)]
    pub rear_k: f64,
}

fn x_direction() -> [f64; 2] {
    [1.0, 0.0]
}

/// The surface a dish must hold, as its engineer states it (`[surface]`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SurfaceSpec {
    /// Target facet RMS of the design surface, mm: the flat facets of the
    /// front net with their corners on the paraboloid, their axial deviation
    /// integrated over plan area (`surface::facet_rms`). Without
    /// `front_net.rings`, the coarsest net that meets it is chosen; with
    /// them, whether it is met is reported.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rms_mm: Option<f64>,
    /// Operating frequency, GHz: the gain lost to the surface error (Ruze)
    /// is reported at it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frequency_ghz: Option<f64>,
}

/// The front net's rings as chosen for a facet RMS target: the coarsest net
/// whose design surface meets it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChosenRings {
    /// The target, mm.
    pub target_rms_mm: f64,
    /// Facet RMS of the chosen net's design surface, mm (at most the target).
    pub facet_rms_mm: f64,
    /// The net one ring coarser and its facet RMS, mm (above the target);
    /// absent when the chosen net is the coarsest the generator makes.
    pub next_coarser: Option<(usize, f64)>,
    /// Nets generated and measured to choose.
    pub nets_built: usize,
}

impl FrontNet {
    /// True when the file left the rings to the surface target: the scene is
    /// complete once they are chosen (`surface::resolve_front_rings`).
    pub fn rings_to_choose(&self) -> bool {
        self.rings == 0
    }
}

impl SurfaceSpec {
    /// True when the scene states neither a target nor a band.
    pub fn is_empty(&self) -> bool {
        self.rms_mm.is_none() && self.frequency_ghz.is_none()
    }
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

fn default_elements_per_rod() -> usize {
    4
}

/// The front net: sector subdivision of the N-gon of top hinges.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrontNet {
    /// Subdivisions of each sector's radial edge (rings of the grid); absent
    /// (or 0, read as absent) when `[surface] rms_mm` is to choose them
    /// ([`FrontNet::rings_to_choose`]).
    #[serde(default)]
    pub rings: usize,
    /// How the rings were chosen for `[surface] rms_mm`, when the file left
    /// them to it (set with them, never read from or written to a file).
    #[serde(skip)]
    pub chosen: Option<ChosenRings>,
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
    /// Thermal load cases of the error budget (`ringmesh budget`); absent:
    /// none. The design itself is made at the build temperature.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thermal: Option<Thermal>,
}

impl Default for Effects {
    fn default() -> Self {
        Effects {
            truss: TrussModel::default(),
            gravity: None,
            rod_properties_csv: None,
            rod_properties: None,
            cable_elasticity: true,
            thermal: None,
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

impl Scene {
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
