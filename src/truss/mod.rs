//! The ring truss and its response to the net's pull (paper §3, DESIGN §5):
//! one trait, [`TrussOracle`], with three models of increasing fidelity.
//!
//! * [`RigidTruss`] — no deformation: the conventional method;
//! * [`LinearTruss`] — a small-displacement frame: one sparse solve;
//! * [`ExactTruss`] — geometrically exact beams, rigid hinges and joints,
//!   solved by Newton with adaptive load steps (warm-started across calls).
//!
//! Attachment points are the hinge bodies: top hinges `0..N` (front net), then
//! bottom hinges `N..2N` (rear net), the order of the net's fixed nodes.

mod builder;
mod exact;
mod linear;
mod margin;
mod registry;
mod response;
mod rigid;
mod scene_response;

pub use crate::scene::{RodKind, RodProperties, RodPropertiesError, RodStiffness, TrussRod};
pub use builder::{RingTruss, RingTrussBuilder};
pub use exact::ExactTruss;
pub use linear::LinearTruss;
pub use margin::{limit_margin, PRECISION as MARGIN_PRECISION, SEARCH_TO as MARGIN_SEARCH_TO};
pub use registry::{has_limit_load, oracle, oracle_on_frame, MODELS};
pub use response::{layout_points, TrussEquilibrium, TrussError, TrussOracle, TrussResponse};
pub use rigid::RigidTruss;
pub use scene_response::{
    read_loads, respond, AttachmentResponse, LoadsFile, SceneResponseError, SceneTrussResponse,
};
