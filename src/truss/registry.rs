//! The registry of truss models: the one place a [`TrussModel`] (what a scene
//! file names) becomes a [`TrussOracle`]. A new model is its own file in
//! this module, a variant of [`TrussModel`] and one arm here.

use super::builder::RingTruss;
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
    let ring = || RingTruss::new(scene, layout, effects);
    Ok(match model {
        TrussModel::Rigid => Box::new(RigidTruss::new(layout)),
        TrussModel::Linear => Box::new(LinearTruss::new(ring()?, layout)?),
        TrussModel::Exact => Box::new(ExactTruss::new(ring()?, layout)?),
    })
}
