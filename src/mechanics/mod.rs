//! A multibody statics engine for frames of geometrically exact rods, rigid
//! bodies and joints (paper §3, DESIGN §5): the ring truss is one such frame.
//!
//! * [`rotation`] — SO(3): exponential, logarithm, tangent operator (eq. 7–14);
//! * [`beam`] — the 2-node beam elements: Crisfield–Jelenić (eq. 17–21) and SE(3);
//! * [`joint`] — fixed, revolute and spherical joints as constraints (eq. 22–25);
//! * [`model`] — nodes, rods, bodies, joints, supports, loads: a validated frame;
//! * [`stability`] — stability of an equilibrium and the limit load;
//! * [`statics`] — Newton–Raphson with adaptive load stepping, and
//!   arc-length continuation (`arc_length`) through limit points.

mod arc_length;
mod assembly;
pub mod beam;
pub mod cable;
pub mod joint;
mod limit;
mod load_control;
pub mod model;
mod node;
pub mod rotation;
mod settings;
mod solver;
pub mod stability;
pub mod statics;

pub(crate) use assembly::constraint_scale;
pub use assembly::State;
pub use beam::{ElementKind, Section};
pub use cable::{Cable, CableState};
pub use joint::JointKind;
pub use limit::{limit_load_factor, LimitSearch};
pub use model::{MechanicsError, Model, ModelBuilder, NodalLoad, Rod, RodSpec};
pub use node::{Frame, NodeId};
pub use settings::{PathControl, StaticSettings, StaticSolution, StaticTermination, StepRecord};
pub use solver::StaticSolver;
pub use stability::Stability;
