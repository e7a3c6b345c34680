//! The physics a scene asks for (DESIGN §8), and only that: each effect is
//! built from the scene's `[effects]` by its own constructor, which returns
//! nothing when the scene does not ask for it, and logs every construction.
//!
//! | effect | asked by | built by | acts on |
//! |---|---|---|---|
//! | beam model of the ring truss | `truss = "linear" \| "exact"` (and every flexible verification) | [`crate::truss::RingTruss::builder`] | the truss oracle, the assembly, the limit-load search |
//! | cable self weight | `[effects.gravity]` | [`CableSelfWeight::of`] | the nets' nodal loads (front and rear design stages, the assembly) |
//! | truss self weight | `[effects.gravity]` | [`truss_self_weight`] | dead loads of the truss model |
//! | measured rods | `[effects] rod_properties_csv` | [`crate::truss::RingTruss::builder`] (the table: [`crate::scene::Scene::read`]) | the sections of the rods the table names |
//! | inextensible cables | `[effects] cable_elasticity = false` | [`crate::verify::CableModel::of`] | the verification's cables |
//!
//! A new effect is one module here and one line in [`EffectKind`]; the design
//! loop never changes: the nets and the truss oracle carry the effects in.
//!
//! The construction log is per thread (every construction of one run happens
//! on the thread that runs it), so that a test can check what a run built —
//! a rigid scene never constructs a beam model — by counting, not by timing.

mod gravity;

use std::cell::RefCell;
use std::collections::BTreeMap;

use serde::Serialize;

pub use gravity::{truss_self_weight, CableSelfWeight};

/// The effects the registry can construct.
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
