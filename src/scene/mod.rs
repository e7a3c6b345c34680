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
//!
//! The files: `error` (the error), `schema` (the TOML syntax: one struct per
//! table, and what a scene's values imply), `read` (text to a scene),
//! `validate` (every value against its range), `rod_properties` (the
//! measured-rods table), `template` (the commented scene `ringmesh init`
//! writes). The reference of every key is `docs/scene.md`.

mod error;
mod read;
mod rod_properties;
mod schema;
mod template;
mod validate;

pub use error::SceneError;
pub use rod_properties::{RodKind, RodProperties, RodPropertiesError, RodStiffness, TrussRod};
pub use schema::{
    membrane_tension_n, Cables, ChosenRings, Effects, FrontNet, Gravity, RearNet, Reflector, Scene,
    Supports, SurfaceSpec, Thermal, ThermalCase, Tolerances, Truss, TrussModel, UniformNet,
    Uniformity,
};
pub use template::template;
pub use validate::{
    modulus_range, MAX_BAYS, MAX_ELEMENTS_PER_ROD, MAX_HEIGHT_RATIO, MAX_MODULUS_PA, MAX_NAME_LEN,
    MIN_MODULUS_PA,
};
