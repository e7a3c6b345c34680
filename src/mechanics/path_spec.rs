//! What path following ([`StaticSolver::follow_path`]) takes and returns,
//! as plain data: the target and the recorded nodes ([`PathSpec`]), every
//! converged step ([`PathPoint`]), the critical points ([`CriticalPoint`])
//! and the whole path ([`PathSolution`]).
//!
//! [`StaticSolver::follow_path`]: super::StaticSolver::follow_path

use serde::Serialize;

use super::node::NodeId;
use super::settings::StaticSolution;
use super::stability::Mode;

/// Where a path ends.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PathTarget {
    /// The load factor reaches this value (the first time along the path).
    LoadFactor(f64),
    /// The translation `component` (0 = x, 1 = y, 2 = z) of `node`,
    /// position minus reference position, reaches `value_m`.
    Displacement {
        /// The node.
        node: NodeId,
        /// Its translation component, 0 … 2.
        component: usize,
        /// The displacement to reach, m.
        value_m: f64,
    },
    /// This many converged steps.
    Steps(usize),
}

/// What to follow and record, beside the
/// [`StaticSettings`](super::StaticSettings).
#[derive(Debug, Clone, PartialEq)]
pub struct PathSpec {
    /// Where the path ends.
    pub target: PathTarget,
    /// The controlled translation `(node, component)` of
    /// [`PathControl::Displacement`](super::PathControl::Displacement).
    pub control: Option<(NodeId, usize)>,
    /// Nodes whose displacement every recorded point carries.
    pub record: Vec<NodeId>,
}

/// One equilibrium on the path.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PathPoint {
    /// Load factor.
    pub load_factor: f64,
    /// Displacement of each recorded node ([`PathSpec::record`]), m.
    pub displacements_m: Vec<[f64; 3]>,
    /// The lowest eigenvalue of the stiffness on the joints' constraints
    /// (signed, rotations × the mean element length), N/m; `None` without
    /// the stability test.
    pub lowest_stiffness_n_per_m: Option<f64>,
    /// How many eigenvalues of that stiffness are negative (the tangent's
    /// inertia: 0 on a stable branch); `None` without the stability test
    /// or for an unsymmetric tangent (loads that are not conservative).
    pub negative_eigenvalues: Option<usize>,
    /// Newton iterations of the step that reached it.
    pub iterations: usize,
}

/// The kind of a critical point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CriticalKind {
    /// A load maximum along the path.
    LimitMaximum,
    /// A load minimum along the path.
    LimitMinimum,
    /// An eigenvalue crosses zero with no load extremum (the tangent's
    /// inertia changes): another branch of equilibria crosses the path
    /// here.
    Bifurcation,
}

impl CriticalKind {
    /// `limit` or `bifurcation`.
    pub fn family(self) -> &'static str {
        match self {
            CriticalKind::LimitMaximum | CriticalKind::LimitMinimum => "limit",
            CriticalKind::Bifurcation => "bifurcation",
        }
    }
}

/// A critical point of the path, located between two converged steps.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CriticalPoint {
    /// Limit (maximum or minimum) or bifurcation.
    pub kind: CriticalKind,
    /// Its load factor.
    pub load_factor: f64,
    /// Displacement of each recorded node, m.
    pub displacements_m: Vec<[f64; 3]>,
    /// The lowest eigenvalue there, N/m (near zero).
    pub lowest_stiffness_n_per_m: Option<f64>,
    /// The index in the path of the last point before it.
    pub after_point: usize,
    /// True where the path left for the bifurcated branch.
    pub switched_branch: bool,
    /// The critical mode: the eigenvector of the lowest eigenvalue.
    #[serde(skip)]
    pub mode: Mode,
}

/// The equilibrium path followed.
#[derive(Debug, Clone)]
pub struct PathSolution {
    /// The last equilibrium and how the path ended: `Converged` when the
    /// target was reached; `MaxSteps` or `Stalled` before it.
    pub solution: StaticSolution,
    /// Every converged step, the start first.
    pub points: Vec<PathPoint>,
    /// Limit and bifurcation points, in path order.
    pub critical_points: Vec<CriticalPoint>,
    /// How many eigenvalues of the stiffness on the constraints are
    /// negative at the last point: more than 0, the path ended on an
    /// unstable branch (past a bifurcation it did not leave); `None` where
    /// not counted.
    pub final_negative_eigenvalues: Option<usize>,
}
