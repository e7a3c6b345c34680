//! How verification models the cables (`[effects] cable_elasticity`, issue 6,
//! DESIGN §7–8): elastic as they will be built, or inextensible.
//!
//! * **Elastic** (`cable_elasticity = true`, the default): each cable a
//!   tension-only element of the scene's `EA`, cut to `L₀ = ℓ/(1 + T/EA)`.
//! * **Inextensible** (`cable_elasticity = false`): each cable keeps its
//!   design length `ℓ` and carries whatever tension equilibrium asks, none
//!   when slack. Modelled by penalty: the same tension-only elements with
//!   `EA* = κ·EA`, κ = [`INEXTENSIBLE_STIFFENING`], cut to
//!   `L₀ = ℓ/(1 + T/EA*)` — the elastic rule with `EA*`, so that `L₀ → ℓ` as
//!   κ grows (the strain `T/EA*` is 7e-7 for 70 N on a 5 mm cable at
//!   50 GPa, κ = 100).
//!
//! What κ changes. Where the design is an equilibrium of the truss it is
//! assembled on — a rigid-truss design on the rigid truss, a design for the
//! deforming truss on the flexible one — it is the assembled equilibrium for
//! *any* cable stiffness: κ changes nothing (small-hex, design for the exact
//! truss: RMS 9.7e-7 mm for κ = 10 … 10⁶). Where it is not — the
//! conventional design on the flexible truss — inextensible cables cut to
//! the lengths of the undeformed truss admit no prestress in the limit: any
//! tension compresses the ring, shortens the chords the cables span and
//! slackens them. The net keeps about `1/(1 + a·κ)` of its prestress, the
//! cables and the truss acting as springs in series (small-hex: 95 % of the
//! total tension with elastic cables, 75 % at κ = 10, 27 % at 100, 3.8 % at
//! 10³, measured), and the limit is a slack net, a mechanism without a
//! unique shape: the verdict (more tension lost than with elastic cables,
//! slack cables, hinges that move less) holds for every κ, its figures are
//! those of κ.
//!
//! Why κ = 100. It brings the stiffest cable (`EA*/ℓ` ≈ 1.5e8 N/m for
//! small-hex's shortest, a 0.66 m tie of 5 mm) to the level of the stiffest
//! tube element (`EA/ℓ` ≈ 1.6e8 N/m, a 60/56 mm batten meshed in 0.375 m
//! elements): the assembly's stiffness
//! range, its constraint scale and the roundoff floor of its forces stay
//! the truss's, and a cable stretches 1 % of what the same misfit stretches
//! an elastic one. Each further decade costs a decade of force accuracy
//! (a rigid assembly's tension error is 3e-8 % at κ = 100, 4e-6 % at 10⁴)
//! and, for a design whose net goes slack, far more load steps (small-hex's
//! conventional design: 2 s at κ = 100, 11 s at 10³, no equilibrium within
//! 500 steps at 10⁴; realistic-26m's: 42 s at κ = 100).
//!
//! How it is solved. The stiff assembly solved at once fails: Newton flips
//! cables between taut and slack, a misfit of the design loop's tolerance
//! (1e-6 m) being worth hundreds of newtons in a penalised cable. The
//! elastic equilibrium is found first and continued in stages of ×10
//! stiffness (`stiffen` in `crate::verify`), each starting from the last equilibrium.

use serde::Serialize;

use super::{record, Effect, EffectKind};
use crate::scene::{Cables, Scene};

/// The stiffening `EA*/EA` that makes the cables inextensible by penalty
/// (why 100: the module's docs).
pub const INEXTENSIBLE_STIFFENING: f64 = 100.0;

/// The cable model of an assembly.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CableModel {
    /// Tension-only elastic cables of the scene's `EA`.
    Elastic,
    /// Tension-only cables of the design length, inextensible by penalty.
    Inextensible,
}

impl CableModel {
    /// The model the scene asks for (`[effects] cable_elasticity`).
    pub fn of(scene: &Scene) -> Self {
        match InextensibleCables::of(scene) {
            Some(effect) => effect.cable_model().unwrap_or(CableModel::Elastic),
            None => CableModel::Elastic,
        }
    }

    /// Axial stiffness of every cable of the assembly, N.
    pub fn axial_stiffness_n(self, cables: &Cables) -> f64 {
        match self {
            CableModel::Elastic => cables.axial_stiffness_n(),
            CableModel::Inextensible => INEXTENSIBLE_STIFFENING * cables.axial_stiffness_n(),
        }
    }

    /// Unstressed length of a cable of design length `length_m` and tension
    /// `tension_n` in the assembly, m: `ℓ/(1 + T/EA)` with this model's `EA`.
    pub fn cut_length_m(self, cables: &Cables, length_m: f64, tension_n: f64) -> f64 {
        length_m / (1.0 + tension_n / self.axial_stiffness_n(cables))
    }
}

/// The effect `cable_elasticity = false`: the verification assembles
/// inextensible cables.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct InextensibleCables;

impl InextensibleCables {
    /// The effect, when the scene asks for inextensible cables.
    pub fn of(scene: &Scene) -> Option<Self> {
        (!scene.effects.cable_elasticity).then(|| {
            record(EffectKind::InextensibleCables);
            InextensibleCables
        })
    }
}

impl Effect for InextensibleCables {
    fn name(&self) -> &str {
        "inextensible cables"
    }

    fn cable_model(&self) -> Option<CableModel> {
        Some(CableModel::Inextensible)
    }
}
