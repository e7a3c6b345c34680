//! A multibody statics engine for frames of geometrically exact rods, rigid
//! bodies and joints (paper §3, DESIGN §5): the ring truss is one such frame.
//! The engine knows nothing of files: [`crate::frame`] reads frame files into
//! its [`Model`].
//!
//! Its files, each using only those above it in this list:
//!
//! * [`rotation`] — SO(3): exponential, logarithm, tangent operator (eq. 7–14),
//!   and the material frame of a rod; `node` — a node's id and configuration;
//!   `circular_arc` — the reference geometry of a curved rod and its nodes'
//!   frames;
//! * `beam` — the 2-node beam elements: Crisfield–Jelenić (eq. 17–21) and
//!   SE(3); `cable` — tension-only cables; `joint` — fixed, revolute and
//!   spherical joints as constraints (eq. 22–25);
//! * `model` — nodes, rods, bodies, joints, supports, loads: a validated frame;
//! * `assembly` — the residual and the consistent tangent, factored;
//!   `condensed` — the factor of a tangent with a cable net, the net
//!   condensed onto the frame;
//! * `settings` — what a solve takes and returns; `solver` — the solver's
//!   core: convergence test, weighted norm of increments;
//! * `load_control` — Newton–Raphson with adaptive load stepping;
//!   `arc_length` — arc-length continuation through limit points;
//!   `stability` — the stability of one equilibrium;
//! * `path_spec` — what path following takes and returns; `corrector` —
//!   Newton on equilibrium and one path constraint (load, arc length, a
//!   displacement); `follower` — one step along the path and the critical
//!   points' indicators where it lands; `critical` — limit and bifurcation
//!   points located between two steps, landing on the target, branch
//!   switching; `path` — path following to a target
//!   ([`StaticSolver::follow_path`]), every step recorded;
//! * `statics` — the solver's entry points ([`StaticSolver::solve`], …);
//! * `limit` — the limit load ([`limit_load_factor`]).
//!
//! Only [`rotation`], a namespace of functions (`rotation::exp`, …), is a
//! public module; everything else is re-exported here.

mod arc_length;
mod assembly;
mod beam;
mod cable;
mod circular_arc;
mod condensed;
mod corrector;
mod critical;
mod follower;
mod inertia;
mod joint;
mod limit;
mod load_control;
mod model;
mod node;
mod path;
mod path_spec;
pub mod rotation;
mod settings;
mod solver;
mod sparse_lu;
mod stability;
mod statics;

pub use assembly::State;
pub use beam::{ElementKind, Section};
pub use cable::{Cable, CableState};
pub use circular_arc::{
    ArcError, ArcGeometry, ArcInput, CircularArc, ARC_TOLERANCE, MAX_ELEMENT_ANGLE_RAD,
};
pub use joint::JointKind;
pub use limit::{limit_load_factor, LimitBound, LimitSearch};
pub use model::{MechanicsError, Model, ModelBuilder, NodalLoad, Rod, RodSpec};
pub use node::{Frame, NodeId};
pub use path_spec::{CriticalKind, CriticalPoint, PathPoint, PathSolution, PathSpec, PathTarget};
pub use settings::{PathControl, StaticSettings, StaticSolution, StaticTermination, StepRecord};
pub use solver::StaticSolver;
pub use stability::{Mode, Stability};
pub use statics::Linearisation;
