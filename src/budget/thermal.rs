//! A thermal load case as a perturbation of the design's assembly
//! ([`crate::effects::ThermalExpansion`] says what a case is and how a
//! temperature change stretches cables and rods).

use crate::effects::ThermalExpansion;
use crate::geometry::ReflectorMesh;
use crate::network::Network;
use crate::scene::ThermalCase;
use crate::verify::Perturbation;

/// The perturbation of `case`: every cable's unstressed length × `s`, its
/// EA × `s²`; every rod stretched by its `s` in length and section; `s =
/// 1 + α ΔT` at each item (cables of `network` at the design's geometry
/// `nodes_m`, rods on `mesh`'s layout).
pub fn thermal_perturbation(
    effect: &ThermalExpansion,
    case: &ThermalCase,
    mesh: &ReflectorMesh,
    network: &Network,
    nodes_m: &[[f64; 3]],
) -> Perturbation {
    let cables = effect.cable_stretch(case, nodes_m, &network.edges, &mesh.groups);
    let rods = effect.rod_stretch(case, &mesh.truss);
    Perturbation {
        cable_stiffness_factors: Some(cables.iter().map(|s| s * s).collect()),
        cable_length_factors: Some(cables),
        rod_stretch: Some(rods.iter().map(|&s| [s, s]).collect()),
        hinge_offsets_m: None,
    }
}
