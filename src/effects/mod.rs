//! The physics a scene asks for (DESIGN §8), and only that.
//!
//! An effect is an [`Effect`]: one type, in one file here, that says where it
//! acts through the hooks it overrides — nodal loads on the nets, dead loads
//! on the truss's frame, the section of a truss rod, the cable model of the
//! verification. [`SceneEffects`] is the bundle of the effects of one scene,
//! built once ([`SceneEffects::of`]) and handed to the nets
//! ([`crate::design::TiedNets`]), the truss builder
//! ([`crate::truss::RingTruss::builder`]) and the verification
//! ([`crate::verify::verify`]), which ask the bundle and never look at the
//! scene's `[effects]` themselves. A new effect is one file here and one line
//! in [`SceneEffects::of`]; one used only from code (a test's, say) is added
//! with [`SceneEffects::with`]. The design loop never changes.
//!
//! | effect | asked by | acts on |
//! |---|---|---|
//! | beam model of the ring truss | `truss = "linear" \| "exact"` (and every flexible verification) | the truss oracle, the assembly, the limit-load search (built by [`crate::truss::RingTruss::builder`]) |
//! | [`Gravity`] | `[effects.gravity]` | the nets' nodal loads (the cables' weight) and the truss's dead loads (rods and hinges) |
//! | [`MeasuredRods`] | `[effects] rod_properties_csv` | the sections of the rods the table names |
//! | [`InextensibleCables`] | `[effects] cable_elasticity = false` | the verification's cables |
//! | [`ThermalExpansion`] | `[effects.thermal]` | the error budget's load cases only (`crate::budget` builds it; the design is made at the build temperature) |
//!
//! Every construction is logged per thread ([`constructed`]; every
//! construction of one run happens on the thread that runs it), so that a
//! test can check what a run built — a rigid scene never constructs a beam
//! model — by counting, not by timing.

mod cable_elasticity;
mod gravity;
mod measured_rods;
mod thermal;

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::fmt;
use std::sync::Arc;

use serde::Serialize;

pub use cable_elasticity::{CableModel, InextensibleCables, INEXTENSIBLE_STIFFENING};
pub use gravity::{CableSelfWeight, Gravity};
pub use measured_rods::MeasuredRods;
pub use thermal::{Side, ThermalExpansion};

use crate::mechanics::{ModelBuilder, NodalLoad, NodeId, Rod, Section};
use crate::scene::{Scene, TrussRod};

/// One piece of physics: where it acts, by the hooks it overrides (each
/// defaults to "nothing").
pub trait Effect: fmt::Debug + Send + Sync {
    /// The effect's name in logs and messages.
    fn name(&self) -> &str;

    /// Nodal loads on the nets at the geometry `nodes_m` (n_nodes × 3, N), or
    /// `None` when the effect puts none there. Loads that depend on the
    /// geometry are recomputed as the design moves it.
    fn net_loads_n(&self, _nodes_m: &[[f64; 3]], _edges: &[[usize; 2]]) -> Option<Vec<[f64; 3]>> {
        None
    }

    /// Dead loads on the truss's frame `frame`, whose rods are `rods` and
    /// hinge bodies `hinges`.
    fn truss_dead_loads(
        &self,
        _frame: &ModelBuilder,
        _rods: &[Rod],
        _hinges: &[NodeId],
    ) -> Vec<NodalLoad> {
        Vec::new()
    }

    /// The section of the truss rod `rod`, given the one it has so far.
    fn rod_section(&self, _rod: TrussRod, section: Section) -> Section {
        section
    }

    /// The cable model of the verification, when the effect sets one.
    fn cable_model(&self) -> Option<CableModel> {
        None
    }
}

/// The effects of one scene, built once and handed to every stage.
#[derive(Debug, Clone, Default)]
pub struct SceneEffects {
    effects: Vec<Arc<dyn Effect>>,
}

impl SceneEffects {
    /// The effects `scene` asks for (the registry: one line per effect).
    pub fn of(scene: &Scene) -> Self {
        let mut effects: Vec<Arc<dyn Effect>> = Vec::new();
        effects.extend(Gravity::of(scene).map(|e| Arc::new(e) as Arc<dyn Effect>));
        effects.extend(MeasuredRods::of(scene).map(|e| Arc::new(e) as Arc<dyn Effect>));
        effects.extend(InextensibleCables::of(scene).map(|e| Arc::new(e) as Arc<dyn Effect>));
        SceneEffects { effects }
    }

    /// No effect at all: weightless, nominal rods, elastic cables.
    pub fn none() -> Self {
        SceneEffects::default()
    }

    /// The bundle with `effect` added.
    pub fn with(mut self, effect: impl Effect + 'static) -> Self {
        self.effects.push(Arc::new(effect));
        self
    }

    /// The names of the effects, in the order they act.
    pub fn names(&self) -> Vec<&str> {
        self.effects.iter().map(|e| e.name()).collect()
    }

    /// The sum of the effects' nodal loads on the nets at `nodes_m`, N, or
    /// `None` when no effect loads the nets.
    pub fn net_loads_n(&self, nodes_m: &[[f64; 3]], edges: &[[usize; 2]]) -> Option<Vec<[f64; 3]>> {
        let mut total: Option<Vec<[f64; 3]>> = None;
        for loads in self
            .effects
            .iter()
            .filter_map(|e| e.net_loads_n(nodes_m, edges))
        {
            match &mut total {
                None => total = Some(loads),
                Some(sum) => {
                    for (s, l) in sum.iter_mut().zip(&loads) {
                        for (a, b) in s.iter_mut().zip(l) {
                            *a += b;
                        }
                    }
                }
            }
        }
        total
    }

    /// Every effect's dead loads on the truss's frame.
    pub fn truss_dead_loads(
        &self,
        frame: &ModelBuilder,
        rods: &[Rod],
        hinges: &[NodeId],
    ) -> Vec<NodalLoad> {
        self.effects
            .iter()
            .flat_map(|e| e.truss_dead_loads(frame, rods, hinges))
            .collect()
    }

    /// The section of `rod` once every effect has acted on `nominal`.
    pub fn rod_section(&self, rod: TrussRod, nominal: Section) -> Section {
        self.effects
            .iter()
            .fold(nominal, |section, e| e.rod_section(rod, section))
    }

    /// The verification's cable model: the last effect's that sets one,
    /// else elastic.
    pub fn cable_model(&self) -> CableModel {
        self.effects
            .iter()
            .rev()
            .find_map(|e| e.cable_model())
            .unwrap_or(CableModel::Elastic)
    }
}

/// The effects the construction log counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EffectKind {
    /// A beam model of the ring truss (linear or exact oracle, flexible
    /// assembly, limit-load search).
    BeamModel,
    /// Nodal loads from the cables' self weight.
    CableSelfWeight,
    /// Dead loads from the self weight of the truss's rods and hinges.
    TrussSelfWeight,
    /// Measured per-rod sections (`[effects] rod_properties_csv`) applied to
    /// a beam model.
    RodProperties,
    /// Inextensible cables in a verification (`cable_elasticity = false`).
    InextensibleCables,
    /// Thermal load cases of an error budget (`[effects.thermal]`).
    ThermalExpansion,
}

thread_local! {
    static LOG: RefCell<BTreeMap<EffectKind, usize>> = const { RefCell::new(BTreeMap::new()) };
}

/// Log one construction of `kind` (called by the effect's constructor).
pub(crate) fn record(kind: EffectKind) {
    LOG.with(|log| *log.borrow_mut().entry(kind).or_insert(0) += 1);
}

/// How many times each effect was constructed on this thread since the last
/// [`reset_log`].
pub fn constructed() -> BTreeMap<EffectKind, usize> {
    LOG.with(|log| log.borrow().clone())
}

/// Clear this thread's construction log.
pub fn reset_log() {
    LOG.with(|log| log.borrow_mut().clear());
}
