//! The registry of truss models: the one place a [`TrussModel`] (what a scene
//! file names) becomes a [`TrussOracle`], and the one place that lists the
//! models ([`MODELS`], what the study sweeps) and says what each can do
//! ([`has_limit_load`], what sizing needs). A new model is its own file in
//! this module, a variant of [`TrussModel`], its arms here and its place in
//! [`MODELS`] (a test fails while a variant is missing from it).

use super::builder::{RingTruss, RingTrussBuilder};
use super::exact::ExactTruss;
use super::linear::LinearTruss;
use super::response::{TrussError, TrussOracle};
use super::rigid::RigidTruss;
use crate::effects::SceneEffects;
use crate::geometry::RingTrussLayout;
use crate::scene::{Scene, TrussModel};

/// Every truss model, in order of increasing fidelity.
pub const MODELS: &[TrussModel] = &[TrussModel::Rigid, TrussModel::Linear, TrussModel::Exact];

/// True when `model` has a limit load under the net's pull — it follows the
/// truss's geometry as it deforms — so that a section can be sized for a
/// margin to it ([`crate::sizing`]). A rigid truss does not deform; a linear
/// frame's response grows without bound with the load.
pub fn has_limit_load(model: TrussModel) -> bool {
    match model {
        TrussModel::Rigid | TrussModel::Linear => false,
        TrussModel::Exact => true,
    }
}

/// The oracle of `model` for `scene`'s truss on `layout`, with the scene's
/// `effects`: only that model is built — a rigid scene never constructs a
/// beam model.
///
/// # Errors
/// A frame that cannot be built.
pub fn oracle(
    model: TrussModel,
    scene: &Scene,
    layout: &RingTrussLayout,
    effects: &SceneEffects,
) -> Result<Box<dyn TrussOracle>, TrussError> {
    oracle_on_frame(model, layout, || RingTruss::builder(scene, layout, effects))
}

/// The oracle of `model` on `layout`, its beam model (if it has one) made
/// from the frame `frame` gives: a caller that keeps one frame for several
/// stages hands out a copy; `frame` is not called for a model without one.
///
/// # Errors
/// A frame that cannot be built.
pub fn oracle_on_frame(
    model: TrussModel,
    layout: &RingTrussLayout,
    frame: impl FnOnce() -> RingTrussBuilder,
) -> Result<Box<dyn TrussOracle>, TrussError> {
    let ring = || RingTruss::from_frame(frame());
    Ok(match model {
        TrussModel::Rigid => Box::new(RigidTruss::new(layout)),
        TrussModel::Linear => Box::new(LinearTruss::new(ring()?, layout)?),
        TrussModel::Exact => Box::new(ExactTruss::new(ring()?, layout)?),
    })
}
