//! Path following ([`StaticSolver::follow_path`]): the equilibrium path
//! `F(u) = λ f̂` traced from the unstressed frame to a target — a load
//! factor, a node's displacement component, or a number of steps — through
//! limit points in load and in displacement and across `λ ≤ 0` and back,
//! with the stability of every converged step and the critical points on
//! the way located and listed.
//!
//! * Control: the spherical arc length (the load factor scaled by `ψ`, the
//!   length of the first tangent per unit load, so that a step of `h` moves
//!   the load by `h` along the linear path), or displacement control of one
//!   translation (Batoz & Dhatt), or the load factor itself; each step a
//!   tangent predictor and the corrector of [`super::corrector`].
//! * Direction: the predictor keeps the direction of the last step's
//!   increment (its dot product with the tangent, `ψ`-weighted, is
//!   positive), so it never turns back onto the path already travelled;
//!   the first step goes towards the target.
//! * Steps: adapted to ~5 Newton iterations (`√(5/iterations)`, × ¼ … 2),
//!   the load factor's change per step at most `max_step`; a step that
//!   fails is cut ÷4 down to `min_step`.
//! * Critical points ([`super::critical`]): a sign change of the load's
//!   derivative along the path is a limit point, one of the lowest
//!   eigenvalue without it a bifurcation; each is located between its two
//!   steps by re-solving the step to a fraction of its length.

use std::time::Instant;

use serde::Serialize;

use super::assembly::State;
use super::corrector::{Constraint, Corrected, Corrector};
use super::critical::{self, Indicators};
use super::model::MechanicsError;
use super::node::NodeId;
use super::settings::{PathControl, StaticSettings, StaticSolution, StaticTermination, StepRecord};
use super::solver::StaticSolver;
use super::stability::Mode;

/// Iterations a step aims for.
const TARGET_ITERATIONS: f64 = 5.0;

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

/// What to follow and record, beside the [`StaticSettings`].
#[derive(Debug, Clone, PartialEq)]
pub struct PathSpec {
    /// Where the path ends.
    pub target: PathTarget,
    /// The controlled translation `(node, component)` of
    /// [`PathControl::Displacement`].
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
    /// The lowest eigenvalue crosses zero with no load extremum: another
    /// branch of equilibria crosses the path here.
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
}

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
        let indicators = critical::indicators(
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
            iterations,
        }
    }

    /// The displacement of `(node, component)` at `state`.
    pub fn displacement(&self, state: &State, node: NodeId, component: usize) -> f64 {
        let reference = &self.corrector.solver.model().reference;
        state.frames[node].position_m[component] - reference[node].position_m[component]
    }
}

impl StaticSolver {
    /// Follow the equilibrium path from the unstressed frame to
    /// `spec.target` (module doc), recording every step and the critical
    /// points on the way.
    ///
    /// # Errors
    /// Invalid settings or spec (a node out of range, a controlled
    /// translation that is fixed, no loads to follow), a frame whose
    /// reference tangent cannot be factored.
    pub fn follow_path(
        &self,
        spec: &PathSpec,
        settings: &StaticSettings,
    ) -> Result<PathSolution, MechanicsError> {
        settings.validate()?;
        self.check_resolvable()?;
        let clock = Instant::now();
        let nodes = self.model().node_count();
        let bad = |item: &str, why: String| Err(MechanicsError::invalid(item, why));
        for &n in &spec.record {
            if n >= nodes {
                return bad(
                    "path.record",
                    format!("node {n} is not in the frame ({nodes} nodes)"),
                );
            }
        }
        if let PathTarget::Displacement {
            node, component, ..
        } = spec.target
        {
            if node >= nodes || component > 2 {
                return bad(
                    "path.target",
                    format!("node {node} component {component} is not a translation of the frame"),
                );
            }
        }
        if let PathTarget::Steps(0) = spec.target {
            return bad("path.target", "must be at least one step".into());
        }
        if self.load_scale() <= 0.0 {
            return bad("loads", "there are no loads to follow".into());
        }
        let corrector = Corrector::new(self, settings);
        let start = self.reference_state();
        let tangent = corrector
            .tangent(&start, 0.0)
            .ok_or_else(|| MechanicsError::Mechanism {
                detail: "the unstressed frame's tangent cannot be factored".into(),
            })?;
        let psi = corrector.dot(&tangent, &tangent).sqrt();
        let control = match settings.path {
            PathControl::Load => {
                return self.follow_load(spec, settings, tangent, corrector, clock);
            }
            PathControl::ArcLength => Control::Arc { psi },
            PathControl::Displacement => {
                let Some((node, component)) = spec.control else {
                    return bad(
                        "path.control",
                        "displacement control needs the controlled node and component".into(),
                    );
                };
                let dof = (node < nodes && component < 3)
                    .then(|| self.system().unknown(node, component))
                    .flatten();
                let Some(dof) = dof else {
                    return bad(
                        "path.control",
                        format!("node {node} component {component} is not a free translation"),
                    );
                };
                if tangent[dof] == 0.0 {
                    return bad(
                        "path.control",
                        format!(
                            "node {node} component {component} does not move under the loads \
                             at the start: it cannot drive the path"
                        ),
                    );
                }
                Control::Displacement {
                    dof,
                    scale: tangent[dof],
                }
            }
        };
        let mut follower = Follower {
            corrector,
            control,
            sense: 1.0,
            stability: settings.stability,
            record: spec.record.clone(),
            start_slope: 0.0,
        };
        follower.sense = first_sense(&follower, spec, &tangent);
        let indicators = critical::indicators(&follower, &start, 0.0, &tangent, None);
        follower.start_slope = indicators.load_slope.abs();
        let mut node = Node {
            state: start,
            lambda: 0.0,
            tangent,
            indicators,
        };
        let mut run = Run {
            points: vec![follower.point(&node, 0)],
            critical_points: Vec::new(),
            steps: Vec::new(),
            newton_iterations: 0,
            rejected_steps: 0,
            reactions: vec![[0.0; 6]; nodes],
        };
        let mut previous: Option<(Vec<f64>, f64)> = None;
        let mut h = settings.initial_step.min(settings.max_step);
        let mut switched = false;
        let termination = loop {
            if run.steps.len() >= settings.max_steps {
                break StaticTermination::MaxSteps {
                    load_factor: node.lambda,
                };
            }
            let last = previous.as_ref().map(|(du, dl)| (du.as_slice(), *dl));
            let next = follower
                .step(&node, last, h)
                .and_then(|step| follower.node(&step).map(|n| (step, n)));
            let Some((step, next)) = next else {
                run.newton_iterations += settings.max_iterations;
                run.rejected_steps += 1;
                h *= 0.25;
                if h < settings.min_step {
                    break StaticTermination::Stalled {
                        load_factor: node.lambda,
                    };
                }
                continue;
            };
            run.newton_iterations += step.iterations;
            if let Some((landed, at)) =
                critical::land(&follower, spec.target, &node, last, h, &step)
            {
                run.accept(&follower, &landed, &at);
                critical::between(&follower, &mut run, &node, last, h, &at, false);
                node = at;
                break StaticTermination::Converged;
            }
            run.accept(&follower, &step, &next);
            let switch = settings.branch_switch && !switched;
            let found = critical::between(&follower, &mut run, &node, last, h, &next, switch);
            match found {
                Some((bifurcation, branch)) => {
                    // Leave the fundamental path: the point beyond the
                    // bifurcation is dropped, the path goes on from the
                    // bifurcation along the mode.
                    switched = true;
                    run.points.pop();
                    run.points.push(follower.point(&bifurcation, 0));
                    run.accept(&follower, &branch.0, &branch.1);
                    previous = Some((branch.0.increment.clone(), branch.0.d_lambda));
                    node = branch.1;
                }
                None => {
                    previous = Some((step.increment.clone(), step.d_lambda));
                    node = next;
                }
            }
            if let PathTarget::Steps(n) = spec.target {
                if run.steps.len() >= n {
                    break StaticTermination::Converged;
                }
            }
            // Iterations set the step; the load factor's change per step is
            // capped (the displacement's is not: a buckled branch moves
            // metres at a nearly constant load).
            let factor = (TARGET_ITERATIONS / step.iterations.max(1) as f64)
                .sqrt()
                .clamp(0.25, 2.0);
            let d_lambda = step.d_lambda.abs() * factor;
            h *= factor * (settings.max_step / d_lambda).min(1.0);
        };
        let solution = StaticSolution {
            load_factor: node.lambda,
            state: node.state,
            termination,
            steps: run.steps,
            newton_iterations: run.newton_iterations,
            rejected_steps: run.rejected_steps,
            reactions: run.reactions,
            time_s: clock.elapsed().as_secs_f64(),
        };
        Ok(PathSolution {
            solution,
            points: run.points,
            critical_points: run.critical_points,
        })
    }
}

impl StaticSolver {
    /// [`StaticSolver::follow_path`] under load control: the load ramped to
    /// λ = 1 by [`super::load_control`] (its branch tests end the path at a
    /// limit load instead of snapping through), every accepted step
    /// recorded. No critical point is located: the termination says where a
    /// limit stopped it; arc length follows through and locates.
    fn follow_load(
        &self,
        spec: &PathSpec,
        settings: &StaticSettings,
        tangent: Vec<f64>,
        corrector: Corrector,
        clock: Instant,
    ) -> Result<PathSolution, MechanicsError> {
        if spec.target != PathTarget::LoadFactor(1.0) {
            return Err(MechanicsError::invalid(
                "path.target",
                "load control ends at the full load (load_factor = 1): follow another target \
                 by arc length or displacement control",
            ));
        }
        let follower = Follower {
            corrector,
            control: Control::Load,
            sense: 1.0,
            stability: settings.stability,
            record: spec.record.clone(),
            start_slope: 1.0,
        };
        let start = self.reference_state();
        let indicators = critical::indicators(&follower, &start, 0.0, &tangent, None);
        let at = |state: &State, lambda: f64| Node {
            state: state.clone(),
            lambda,
            tangent: Vec::new(),
            indicators: critical::indicators(&follower, state, lambda, &[], None),
        };
        let mut points = vec![follower.point(
            &Node {
                state: start.clone(),
                lambda: 0.0,
                tangent,
                indicators,
            },
            0,
        )];
        let mut solution = super::load_control::follow_observed(
            self,
            start,
            0.0,
            settings,
            &mut |state, lambda, iterations| {
                points.push(follower.point(&at(state, lambda), iterations))
            },
        );
        solution.time_s = clock.elapsed().as_secs_f64();
        Ok(PathSolution {
            solution,
            points,
            critical_points: Vec::new(),
        })
    }
}

/// The direction of the first step, towards the target: [`Follower::sense`]
/// — the load factor's, or the controlled displacement's.
fn first_sense(follower: &Follower, spec: &PathSpec, tangent: &[f64]) -> f64 {
    let system = follower.corrector.solver.system();
    let sign = |x: f64| if x < 0.0 { -1.0 } else { 1.0 };
    let controlled = match follower.control {
        Control::Displacement { dof, scale } => Some((dof, scale)),
        _ => None,
    };
    let load = match spec.target {
        PathTarget::LoadFactor(l) => sign(l),
        PathTarget::Steps(_) => 1.0,
        PathTarget::Displacement {
            node,
            component,
            value_m,
        } => {
            let dof = system.unknown(node, component);
            if controlled.is_some_and(|(c, _)| Some(c) == dof) {
                return sign(value_m);
            }
            // The load's direction that moves the node towards the value,
            // to first order.
            sign(value_m) * sign(dof.map_or(1.0, |i| tangent[i]))
        }
    };
    controlled.map_or(load, |(_, scale)| load * sign(scale))
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
