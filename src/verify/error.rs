//! Why an assembly cannot be built or solved ([`VerifyError`]).

use crate::mechanics::{MechanicsError, StaticTermination};
use crate::surface::SurfaceError;
use crate::truss::TrussError;

/// An assembly that cannot be built or solved.
#[derive(Debug, thiserror::Error)]
pub enum VerifyError {
    /// The design does not belong to the network.
    #[error(
        "verification: the design has {design_cables} cables and {design_nodes} nodes, the \
         network {network_cables} and {network_nodes}"
    )]
    DesignOfAnotherNetwork {
        /// Cables of the design.
        design_cables: usize,
        /// Nodes of the design.
        design_nodes: usize,
        /// Cables of the network.
        network_cables: usize,
        /// Nodes of the network.
        network_nodes: usize,
    },
    /// The network's fixed nodes are not the truss's attachment points.
    #[error(
        "verification: the network has {fixed_nodes} fixed nodes, the truss {attachments} \
         attachment points"
    )]
    NetworkOfAnotherTruss {
        /// Fixed nodes of the network.
        fixed_nodes: usize,
        /// Attachment points of the truss.
        attachments: usize,
    },
    /// The truss that gives the assembly its starting guess failed.
    #[error("verification: {0}")]
    Truss(#[from] TrussError),
    /// The assembled model is invalid (a cable of zero length, …), named.
    #[error("assembled model: {0}")]
    Mechanics(#[from] MechanicsError),
    /// The surface as built cannot be measured (no free front node, a
    /// non-finite position).
    #[error("the surface as built: {0}")]
    Surface(#[from] SurfaceError),
    /// A perturbation of the wrong size or with invalid values.
    #[error("perturbation of the assembly: {field}: {reason}")]
    Perturbation {
        /// The field at fault.
        field: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// A perturbation the assembly cannot take (rods or hinges of a rigid
    /// truss, inextensible cables).
    #[error("perturbation of the assembly: {0}")]
    Unsupported(String),
    /// The assembly found no equilibrium.
    #[error(
        "the assembled net and truss found no equilibrium: the solve {termination} (last \
         converged prestrain factor {load_factor:.4})"
    )]
    NoEquilibrium {
        /// How the static solve ended.
        termination: StaticTermination,
        /// The largest prestrain factor reached.
        load_factor: f64,
    },
    /// The inextensible assembly lost its equilibrium while its cables were
    /// stiffened from the elastic one ([`CableModel::Inextensible`](crate::effects::CableModel::Inextensible)).
    #[error(
        "the assembled net and truss found no equilibrium with cables {stiffening:e} × stiffer \
         than the scene's on the way to inextensible ones ({termination:?}, last converged \
         prestrain factor {load_factor:.4} of that stage)"
    )]
    NoInextensibleEquilibrium {
        /// The stiffening `EA*/EA` of the stage that failed.
        stiffening: f64,
        /// How the stage's static solve ended.
        termination: StaticTermination,
        /// The largest prestrain factor reached in that stage.
        load_factor: f64,
    },
}

impl VerifyError {
    /// True when the input is at fault (an invalid element, named).
    pub fn is_bad_input(&self) -> bool {
        matches!(self, VerifyError::Mechanics(MechanicsError::Invalid { .. }))
    }
}
