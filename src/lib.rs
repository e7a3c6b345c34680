//! # ringmesh
//!
//! Pretension design of the cable mesh of large ring-truss deployable reflector
//! antennas (Hu, Wang, Yang 2023, "The Pretension Design of Cable Mesh considering
//! the Large Deformation of Ring Truss").
//!
//! The problem: find the force density `q` of every cable so that the front net's
//! nodes lie on the paraboloid `z = (x² + y²)/(4F)` and the cable tension is as
//! uniform as possible, for the ring truss as it deforms under the net's pull.
//!
//! The pipeline, layer by layer:
//!
//! * [`status`] — how an iterative computation ends ([`Termination`]), one
//!   vocabulary for the solvers, the outer loop and the statics engine;
//! * [`scene`] — the problem file (TOML), validated once into a [`Scene`];
//! * [`geometry`] — the paraboloid, the ring-truss layout and the net generators,
//!   which turn a scene into a cable [`Network`];
//! * [`surface`] — surface accuracy: node, facet and best-fit RMS about the
//!   paraboloid, the half-path-length error and Ruze's gain loss, the net for a
//!   facet RMS target;
//! * [`network`] — nodes, cables, groups, the fixed/free split and the
//!   interchange JSON format;
//! * [`fdm`] — the force density method: forward equilibrium, reactions, the
//!   equilibrium matrix `A(x)` of the inverse form and adjoint sensitivities;
//! * [`uniformity`] — the tension-uniformity problem (paper eq. 5) and its
//!   pluggable solvers (bisection, LP, gradient, least squares);
//! * [`mechanics`] — the multibody statics engine: geometrically exact beams,
//!   rigid bodies, joints, cables, Newton with load steps or arc length;
//! * [`frame`] — the engine's inputs: the frame file (TOML) and the paper's
//!   cantilever benchmark;
//! * [`truss`] — the ring truss and its response oracles (rigid, linear, exact);
//! * [`design`] — the outer loop: net design and truss response to a fixed point;
//! * [`verify`] — the design cut to length and assembled on the flexible truss;
//! * [`report`] — files a run writes (atomically): JSON, CSV, VTK, plots;
//! * [`study`] — what accuracy costs in time: one knob at a time against a
//!   converged reference;
//! * [`shard`] — sweeps split across machines and merged back;
//! * [`resources`] — the memory a run will take, checked before it starts;
//! * [`input`] — input files read with a size cap.
#![warn(missing_docs)]

pub mod algebra;
pub mod budget;
pub mod design;
pub mod effects;
pub mod fdm;
pub mod frame;
pub mod geometry;
pub mod input;
pub mod mechanics;
pub mod network;
pub mod report;
pub mod resources;
pub mod run;
pub mod scene;
pub mod shard;
pub mod sizing;
pub mod status;
pub mod study;
pub mod surface;
pub mod truss;
pub mod uniformity;
pub mod verify;

pub use fdm::{Equilibrium, FdmError, FdmStructure};
pub use network::{CableGroup, Network, NetworkError};
pub use scene::{Scene, SceneError};
pub use status::{Status, Termination};

/// Every error the library returns, one variant per module.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// An invalid scene file.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// An invalid or inconsistent network.
    #[error(transparent)]
    Network(#[from] NetworkError),
    /// The force density method failed on a valid network.
    #[error(transparent)]
    Fdm(#[from] FdmError),
    /// A uniformity problem or solver failed.
    #[error(transparent)]
    Uniformity(#[from] uniformity::UniformityError),
    /// Reading or writing a file.
    #[error(transparent)]
    Report(#[from] report::ReportError),
    /// The ring truss cannot respond to its loads.
    #[error(transparent)]
    Truss(#[from] truss::TrussError),
    /// An invalid frame file, or a frame that cannot be built.
    #[error(transparent)]
    Frame(#[from] frame::FrameFileError),
    /// The outer design loop failed.
    #[error(transparent)]
    Design(#[from] design::DesignError),
    /// The assembled verification failed.
    #[error(transparent)]
    Verify(#[from] verify::VerifyError),
    /// The accuracy study cannot run.
    #[error(transparent)]
    Study(#[from] study::StudyError),
    /// A truss that cannot be sized.
    #[error(transparent)]
    Sizing(#[from] sizing::SizingError),
    /// A bad shard, or shards that cannot be merged.
    #[error(transparent)]
    Shard(#[from] shard::ShardError),
    /// A workload beyond the memory limit.
    #[error(transparent)]
    Memory(#[from] resources::MemoryError),
    /// A surface that cannot be measured, or a net target no net meets.
    #[error(transparent)]
    Surface(#[from] surface::SurfaceError),
    /// An error budget that cannot be made.
    #[error(transparent)]
    Budget(#[from] budget::BudgetError),
}

impl From<truss::SceneResponseError> for Error {
    fn from(e: truss::SceneResponseError) -> Self {
        match e {
            truss::SceneResponseError::Scene(e) => Error::Scene(e),
            truss::SceneResponseError::Net(e) => Error::Fdm(e),
            truss::SceneResponseError::Truss(e) => Error::Truss(e),
        }
    }
}

impl Error {
    /// True when the error is the user's input (exit code 2), false for I/O and
    /// internal failures (exit code 1).
    pub fn is_bad_input(&self) -> bool {
        match self {
            Error::Scene(_) | Error::Network(_) | Error::Memory(_) => true,
            Error::Fdm(e) => e.is_bad_input(),
            Error::Uniformity(e) => e.is_bad_input(),
            Error::Report(e) => e.is_bad_input(),
            Error::Truss(e) => e.is_bad_input(),
            Error::Frame(e) => e.is_bad_input(),
            Error::Design(e) => e.is_bad_input(),
            Error::Study(e) => e.is_bad_input(),
            Error::Shard(e) => e.is_bad_input(),
            Error::Sizing(e) => e.is_bad_input(),
            Error::Surface(e) => e.is_bad_input(),
            Error::Verify(e) => e.is_bad_input(),
            Error::Budget(e) => e.is_bad_input(),
        }
    }
}
