//! Geometry of a reflector scene: the paraboloid, the ring-truss layout and the
//! net generators that turn a [`crate::Scene`] into a cable [`crate::Network`].

mod net;
mod paraboloid;
mod truss_layout;

pub use net::{build_mesh, ReflectorMesh, MAX_NODES, MIN_CABLE_LENGTH_RATIO};
pub use paraboloid::{Aperture, Paraboloid};
pub use truss_layout::RingTrussLayout;
