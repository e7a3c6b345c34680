//! One step along an equilibrium path ([`super::path`]): the follower — the
//! corrector, the control (load, arc length, a displacement), the
//! direction — its predictor and the point it reaches, with the indicators
//! of critical points there (the load's slope along the path, the lowest
//! eigenvalue); and what a run gathers.

use super::assembly::State;
use super::corrector::{Constraint, Corrected, Corrector};
use super::node::NodeId;
use super::path_spec::{CriticalPoint, PathPoint};
use super::settings::StepRecord;
use super::stability::{lowest_eigenpair, negative_eigenvalues};

/// A converged point of the path and what the next step needs of it.
#[derive(Clone)]
pub(super) struct Node {
    pub state: State,
    pub lambda: f64,
    /// The tangent `J⁻¹ f̂` there.
    pub tangent: Vec<f64>,
    /// The critical-point indicators there.
    pub indicators: Indicators,
}

/// One way of moving along the path: the predictor and the constraint of
/// a step of size `h` (load-factor units) from a node.
#[derive(Debug, Clone, Copy)]
pub(super) enum Control {
    Load,
    Arc {
        /// `ψ`, m per unit λ: the first tangent's length.
        psi: f64,
    },
    Displacement {
        dof: usize,
        /// The controlled unknown's first tangent component, m per unit λ.
        scale: f64,
    },
}

/// The path follower: the corrector, the control, the direction.
pub(super) struct Follower<'a> {
    pub corrector: Corrector<'a>,
    pub control: Control,
    /// `+1` or `−1`: the direction of the load factor (load control), of
    /// the controlled displacement, or of the first arc-length step.
    pub sense: f64,
    /// Compute the lowest eigenvalue at each point.
    pub stability: bool,
    pub record: Vec<NodeId>,
    /// `|dλ/dp|` at the start: the scale of the load slope's noise.
    pub start_slope: f64,
}

impl Follower<'_> {
    /// The step of size `h` from `from`, the previous increment
    /// `previous` (none at the start) setting the direction; `None` when
    /// the corrector fails.
    pub fn step(&self, from: &Node, previous: Option<(&[f64], f64)>, h: f64) -> Option<Corrected> {
        let t = &from.tangent;
        let (d_lambda, constraint) = match self.control {
            Control::Load => {
                let d = self.sense * h;
                (
                    d,
                    Constraint::Load {
                        lambda: from.lambda + d,
                    },
                )
            }
            Control::Arc { psi } => {
                let tn2 = self.corrector.dot(t, t);
                let length = h * psi * std::f64::consts::SQRT_2;
                let sigma = self.orientation(t, previous);
                (
                    sigma * length / (tn2 + psi * psi).sqrt(),
                    Constraint::Arc { length, psi },
                )
            }
            Control::Displacement { dof, scale } => {
                let increment = self.sense * h * scale.abs();
                (
                    increment / t[dof],
                    Constraint::Displacement { dof, increment },
                )
            }
        };
        if !d_lambda.is_finite() {
            return None;
        }
        let du: Vec<f64> = t.iter().map(|t| d_lambda * t).collect();
        self.corrector
            .correct(&from.state, from.lambda, &du, d_lambda, constraint)
    }

    /// `+1` or `−1`: the direction along the tangent `(t, 1)` that keeps
    /// the previous increment's (`ψ`-weighted dot product positive), or
    /// [`Follower::sense`] without one.
    pub fn orientation(&self, t: &[f64], previous: Option<(&[f64], f64)>) -> f64 {
        let Some((du, dl)) = previous else {
            return self.sense;
        };
        let psi = match self.control {
            Control::Arc { psi } => psi,
            _ => 0.0,
        };
        let along = self.corrector.dot(t, du) + psi * psi * dl;
        if along < 0.0 {
            -1.0
        } else {
            1.0
        }
    }

    /// The node reached by a converged step: its tangent and indicators.
    /// `None` when the tangent cannot be factored there.
    pub fn node(&self, step: &Corrected) -> Option<Node> {
        let tangent = self.corrector.tangent(&step.state, step.lambda)?;
        let indicators = indicators(
            self,
            &step.state,
            step.lambda,
            &tangent,
            Some((&step.increment, step.d_lambda)),
        );
        Some(Node {
            state: step.state.clone(),
            lambda: step.lambda,
            tangent,
            indicators,
        })
    }

    /// Displacements of the recorded nodes at `state`.
    pub fn displacements(&self, state: &State) -> Vec<[f64; 3]> {
        let reference = &self.corrector.solver.model().reference;
        self.record
            .iter()
            .map(|&n| (state.frames[n].position_m - reference[n].position_m).into())
            .collect()
    }

    /// The path point of a node.
    pub fn point(&self, node: &Node, iterations: usize) -> PathPoint {
        PathPoint {
            load_factor: node.lambda,
            displacements_m: self.displacements(&node.state),
            lowest_stiffness_n_per_m: node.indicators.eigenvalue,
            negative_eigenvalues: node.indicators.negative,
            iterations,
        }
    }

    /// The path point of an equilibrium `(state, lambda)` reached in
    /// `iterations`, its lowest eigenvalue and inertia computed if asked
    /// for.
    pub fn point_at(&self, state: &State, lambda: f64, iterations: usize) -> PathPoint {
        let lowest = self.stability.then(|| {
            lowest_eigenpair(self.corrector.solver, state, lambda)
                .ok()
                .map(|pair| pair.eigenvalue)
        });
        let negative = self
            .stability
            .then(|| negative_eigenvalues(self.corrector.solver, state, lambda));
        PathPoint {
            load_factor: lambda,
            displacements_m: self.displacements(state),
            lowest_stiffness_n_per_m: lowest.flatten(),
            negative_eigenvalues: negative.flatten(),
            iterations,
        }
    }

    /// The displacement of `(node, component)` at `state`.
    pub fn displacement(&self, state: &State, node: NodeId, component: usize) -> f64 {
        let reference = &self.corrector.solver.model().reference;
        state.frames[node].position_m[component] - reference[node].position_m[component]
    }
}

/// What a path run has gathered.
pub(super) struct Run {
    pub points: Vec<PathPoint>,
    pub critical_points: Vec<CriticalPoint>,
    pub steps: Vec<StepRecord>,
    pub newton_iterations: usize,
    pub rejected_steps: usize,
    pub reactions: Vec<[f64; 6]>,
}

impl Run {
    /// Record a converged step reaching `node`.
    pub fn accept(&mut self, follower: &Follower, step: &Corrected, node: &Node) {
        self.points.push(follower.point(node, step.iterations));
        self.steps.push(StepRecord {
            load_factor: step.lambda,
            iterations: step.iterations,
            residuals: step.residuals.clone(),
        });
        self.reactions.clone_from(&step.reactions);
    }
}

/// What the critical points are detected by, at one converged point.
#[derive(Debug, Clone, Default)]
pub(super) struct Indicators {
    /// The load's derivative along the path (per unit arc length or
    /// controlled displacement, in the direction of travel); the load
    /// control's direction under load control.
    pub load_slope: f64,
    /// The lowest eigenvalue on the constraints, N/m.
    pub eigenvalue: Option<f64>,
    /// Its eigenvector, unknown order, weighted norm 1.
    pub vector: Option<Vec<f64>>,
    /// How many eigenvalues on the constraints are negative: the tangent's
    /// inertia ([`negative_eigenvalues`]; `None` where not counted).
    pub negative: Option<usize>,
}

/// The indicators at `(state, lambda)` with tangent `t`, reached by the
/// increment `previous` (none at the start).
pub(super) fn indicators(
    follower: &Follower,
    state: &super::assembly::State,
    lambda: f64,
    t: &[f64],
    previous: Option<(&[f64], f64)>,
) -> Indicators {
    let (eigenvalue, vector) = if follower.stability {
        match lowest_eigenpair(follower.corrector.solver, state, lambda) {
            Ok(pair) => (Some(pair.eigenvalue), Some(pair.vector)),
            Err(_) => (None, None),
        }
    } else {
        (None, None)
    };
    let negative = follower
        .stability
        .then(|| negative_eigenvalues(follower.corrector.solver, state, lambda))
        .flatten();
    Indicators {
        load_slope: load_slope(follower, t, previous),
        eigenvalue,
        vector,
        negative,
    }
}

/// The load's derivative along the path at a point of tangent `t`,
/// reached by the increment `previous` ([`Indicators::load_slope`]).
pub(super) fn load_slope(follower: &Follower, t: &[f64], previous: Option<(&[f64], f64)>) -> f64 {
    match follower.control {
        Control::Load => follower.sense,
        Control::Arc { psi } => {
            follower.orientation(t, previous) / (follower.corrector.dot(t, t) + psi * psi).sqrt()
        }
        Control::Displacement { dof, .. } => follower.sense / t[dof],
    }
}
