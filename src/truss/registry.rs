//! The registry of truss models: the one place a [`TrussModel`] (what a scene
//! file names) becomes a [`TrussOracle`]. A new model is its own file in
//! this module, a variant of [`TrussModel`] and one arm here.

use super::builder::{RingTruss, RingTrussBuilder};
use super::exact::ExactTruss;
use super::linear::LinearTruss;
use super::response::{TrussError, TrussOracle};
use super::rigid::RigidTruss;
use crate::effects::SceneEffects;
use crate::geometry::RingTrussLayout;
use crate::scene::{Scene, TrussModel};

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
