//! Thermal distortion in orbit (`[effects.thermal]`, issue 35, DESIGN §13):
//! each material's expansion coefficient and the scene's named load cases,
//! each a field of temperature change ([`crate::scene::ThermalCase`]: a
//! uniform part, a gradient across the aperture, a front/rear difference).
//!
//! A temperature change `ΔT` gives a material of coefficient `α` the free
//! strain `ε = αΔT`: every dimension scales by `1 + ε` — a cable's
//! unstressed length and its diameter (its EA by `(1 + ε)²`), a tube's
//! length and its section (EA by `(1 + ε)²`, EI by `(1 + ε)⁴`:
//! [`crate::mechanics::ModelBuilder::stretch_rods`]). So with one `α ΔT`
//! everywhere the unloaded structure scales as a whole, stresses unchanged:
//! the built dish is the design's scaled, which refocusing removes
//! entirely (the test any implementation must pass). Each cable takes the
//! temperature at its midpoint, each rod at its own.
//!
//! The design is made at the build temperature: this effect acts only in
//! the error budget (`crate::budget`), which builds it when the scene asks
//! and turns each case into a perturbation of the design's assembly.

use super::{record, Effect, EffectKind};
use crate::geometry::RingTrussLayout;
use crate::network::CableGroup;
use crate::scene::{RodKind, Scene, Thermal, ThermalCase, TrussRod};

/// Which side of the dish an item is on, for a front/rear difference.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The front net and the top longerons.
    Front,
    /// The rear net and the bottom longerons.
    Rear,
    /// Ties, battens and diagonals: the mean of the two.
    Between,
}

/// The effect `[effects.thermal]`.
#[derive(Debug, Clone, PartialEq)]
pub struct ThermalExpansion {
    /// The scene's coefficients and cases.
    pub spec: Thermal,
    /// The aperture's plan centre, m: where a gradient is zero.
    pub centre_m: [f64; 2],
}

impl ThermalExpansion {
    /// The effect, when the scene asks for thermal cases.
    pub fn of(scene: &Scene) -> Option<Self> {
        let spec = scene.effects.thermal.clone()?;
        record(EffectKind::ThermalExpansion);
        Some(ThermalExpansion {
            spec,
            centre_m: [scene.reflector.offset_m, 0.0],
        })
    }

    /// The load cases, in the scene's order.
    pub fn cases(&self) -> &[ThermalCase] {
        &self.spec.cases
    }

    /// The temperature change of `case` at `point_m` on `side`, K.
    pub fn temperature_change_k(&self, case: &ThermalCase, point_m: [f64; 3], side: Side) -> f64 {
        let [dx, dy] = case.gradient_direction;
        let norm = dx.hypot(dy);
        let along = if norm > 0.0 {
            ((point_m[0] - self.centre_m[0]) * dx + (point_m[1] - self.centre_m[1]) * dy) / norm
        } else {
            0.0
        };
        let sided = match side {
            Side::Front => case.front_k,
            Side::Rear => case.rear_k,
            Side::Between => 0.5 * (case.front_k + case.rear_k),
        };
        case.uniform_k + case.gradient_k_per_m * along + sided
    }

    /// The stretch `1 + α ΔT` of every cable under `case`: cables `edges`
    /// between `nodes_m`, of `groups` (ties of their own coefficient).
    pub fn cable_stretch(
        &self,
        case: &ThermalCase,
        nodes_m: &[[f64; 3]],
        edges: &[[usize; 2]],
        groups: &[CableGroup],
    ) -> Vec<f64> {
        edges
            .iter()
            .zip(groups)
            .map(|(&[i, j], group)| {
                let mid = std::array::from_fn(|c| 0.5 * (nodes_m[i][c] + nodes_m[j][c]));
                let (side, alpha) = match group {
                    CableGroup::Front | CableGroup::Boundary => {
                        (Side::Front, self.spec.cable_expansion_per_k)
                    }
                    CableGroup::Rear | CableGroup::RearBoundary => {
                        (Side::Rear, self.spec.cable_expansion_per_k)
                    }
                    CableGroup::Tie => (
                        Side::Between,
                        self.spec
                            .tie_expansion_per_k
                            .unwrap_or(self.spec.cable_expansion_per_k),
                    ),
                };
                1.0 + alpha * self.temperature_change_k(case, mid, side)
            })
            .collect()
    }

    /// The stretch `1 + α ΔT` of every truss rod under `case`, in the
    /// frame's build order ([`TrussRod::all`]), each at its midpoint on the
    /// undeformed layout.
    pub fn rod_stretch(&self, case: &ThermalCase, layout: &RingTrussLayout) -> Vec<f64> {
        let n = layout.bays();
        let mix =
            |a: [f64; 3], b: [f64; 3], t: f64| std::array::from_fn(|c| a[c] + t * (b[c] - a[c]));
        TrussRod::all(n)
            .map(|rod| {
                let k = rod.bay;
                let next = (k + 1) % n;
                let (top, bottom) = (layout.top_m[k], layout.bottom_m[k]);
                let (mid, side) = match rod.kind {
                    RodKind::Batten => (mix(bottom, top, 0.5), Side::Between),
                    RodKind::TopLongeron => (mix(top, layout.top_m[next], 0.5), Side::Front),
                    RodKind::BottomLongeron => {
                        (mix(bottom, layout.bottom_m[next], 0.5), Side::Rear)
                    }
                    RodKind::DiagonalThick => {
                        (mix(bottom, layout.top_m[next], 0.25), Side::Between)
                    }
                    RodKind::DiagonalThin => (mix(bottom, layout.top_m[next], 0.75), Side::Between),
                };
                1.0 + self.spec.tube_expansion_per_k * self.temperature_change_k(case, mid, side)
            })
            .collect()
    }
}

impl Effect for ThermalExpansion {
    fn name(&self) -> &str {
        "thermal expansion"
    }
}
