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
//!   derivative along the path is a limit point, a change of the tangent's
//!   inertia without it a bifurcation (under load control too); each is
//!   located between its two steps by re-solving the step to a fraction of
//!   its length. The last point's inertia says whether the path ended on
//!   an unstable branch.

use std::time::Instant;

use super::corrector::Corrector;
use super::critical;
use super::follower::{indicators, Control, Follower, Node, Run};
use super::model::MechanicsError;
use super::path_spec::{PathSolution, PathSpec, PathTarget};
use super::settings::{PathControl, StaticSettings, StaticSolution, StaticTermination};
use super::solver::StaticSolver;

/// Iterations a step aims for.
const TARGET_ITERATIONS: f64 = 5.0;

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
            if node >= nodes || component > 2 || self.system().unknown(node, component).is_none() {
                return bad(
                    "path.target",
                    format!(
                        "node {node} component {component} is not a free translation of the \
                         frame: it cannot reach a displacement"
                    ),
                );
            }
        }
        if settings.branch_switch && settings.path != PathControl::ArcLength {
            return bad(
                "solver.branch_switch",
                "leaving a bifurcation for its branch needs path = \"arc_length\"".into(),
            );
        }
        if spec.control.is_some() && settings.path != PathControl::Displacement {
            // The controlled translation drives displacement control only:
            // under another control it would be ignored.
            return bad(
                "path.control",
                format!(
                    "drives displacement control only, and the solver's path is {}: remove \
                     it, or set path = \"displacement\"",
                    match settings.path {
                        PathControl::Load => "\"load\"",
                        _ => "\"arc_length\"",
                    }
                ),
            );
        }
        if let PathTarget::Steps(0) = spec.target {
            return bad("path.target", "must be at least one step".into());
        }
        if self.load_scale() <= 0.0 {
            return bad("loads", "there are no loads to follow".into());
        }
        let corrector = Corrector::new(self, settings);
        if settings.path == PathControl::Load {
            return self.follow_load(spec, settings, corrector, clock);
        }
        let start = self.reference_state();
        let tangent = corrector
            .tangent(&start, 0.0)
            .ok_or_else(|| MechanicsError::Mechanism {
                detail: "the unstressed frame's tangent cannot be factored".into(),
            })?;
        let psi = corrector.dot(&tangent, &tangent).sqrt();
        let control = if settings.path == PathControl::ArcLength {
            Control::Arc { psi }
        } else {
            // Displacement control.
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
        let indicators = indicators(&follower, &start, 0.0, &tangent, None);
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
                if h < settings.min_step && follower.corrector.non_finite.get() {
                    break StaticTermination::Overflow {
                        load_factor: node.lambda,
                    };
                }
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
            final_negative_eigenvalues: node.indicators.negative,
        })
    }
}

impl StaticSolver {
    /// [`StaticSolver::follow_path`] under load control: the load ramped to
    /// λ = 1 by [`super::load_control`] (its branch tests end the path at a
    /// limit load instead of snapping through), every accepted step
    /// recorded. Load control stays on the branch it started on, past any
    /// bifurcation: with the stability test, the tangent's inertia at every
    /// converged step shows each one passed, located between its two steps
    /// as under arc length ([`critical::between`]), and the last point's
    /// inertia says whether the path ended on an unstable branch. A limit
    /// point ends the path (its termination says where); arc length follows
    /// through it.
    fn follow_load(
        &self,
        spec: &PathSpec,
        settings: &StaticSettings,
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
        let mut run = Run {
            points: vec![follower.point_at(&start, 0.0, 0)],
            critical_points: Vec::new(),
            steps: Vec::new(),
            newton_iterations: 0,
            rejected_steps: 0,
            reactions: Vec::new(),
        };
        // The last converged node, kept only to locate a critical point in
        // the next step (with the stability test).
        let node_at = |state: &super::assembly::State, lambda: f64| {
            let tangent = follower.corrector.tangent(state, lambda)?;
            let indicators = indicators(&follower, state, lambda, &tangent, None);
            Some(Node {
                state: state.clone(),
                lambda,
                tangent,
                indicators,
            })
        };
        let mut last = if settings.stability {
            node_at(&start, 0.0)
        } else {
            None
        };
        let mut final_negative = last.as_ref().and_then(|n| n.indicators.negative);
        let mut solution = super::load_control::follow_observed(
            self,
            start,
            0.0,
            settings,
            &mut |state, lambda, iterations| {
                if !settings.stability {
                    run.points
                        .push(follower.point_at(state, lambda, iterations));
                    return;
                }
                let Some(node) = node_at(state, lambda) else {
                    run.points
                        .push(follower.point_at(state, lambda, iterations));
                    last = None;
                    final_negative = None;
                    return;
                };
                run.points.push(follower.point(&node, iterations));
                if let Some(from) = &last {
                    let h = node.lambda - from.lambda;
                    critical::between(&follower, &mut run, from, None, h, &node, false);
                }
                final_negative = node.indicators.negative;
                last = Some(node);
            },
        );
        solution.time_s = clock.elapsed().as_secs_f64();
        Ok(PathSolution {
            solution,
            points: run.points,
            critical_points: run.critical_points,
            final_negative_eigenvalues: final_negative,
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
