//! Critical points along a followed path ([`super::path`]) and landing on
//! its target: each located between two converged steps by re-solving the
//! step from the first to a fraction `τ` of its size, the fraction found
//! by regula falsi (Illinois) on a scalar that changes sign in the step:
//!
//! * a limit point: the load's derivative along the path, `dλ/ds` — for
//!   the arc length `σ/√(‖t‖² + ψ²)`, `t = J⁻¹f̂` the tangent and `σ` its
//!   orientation, for displacement control `1/t_c` — zero where the load
//!   is extremal. The load factor there is the path's extremum, accurate
//!   to the square of the fraction's error. A sign change where the slope
//!   is at noise level at both ends ([`SLOPE_NOISE`]) is not one;
//! * a bifurcation point: a change of the tangent's inertia, the number of
//!   negative eigenvalues of the stiffness on the joints' constraints
//!   ([`super::stability::negative_eigenvalues`]), with no load extremum in
//!   the step: an eigenvalue crossed zero. It is located on the eigenvalue
//!   that changes sign — the least-magnitude eigenvalue
//!   ([`super::stability::lowest_eigenpair`]) signed by the inertia, so
//!   that a switch of the least eigenvalue between two modes of opposite
//!   signs, the inertia unchanged, is no crossing, and near the crossing
//!   the least eigenvalue is the crossing one. Every symmetric tangent has
//!   its inertia counted, whatever its size (dense or sparse); where it is
//!   not — an unsymmetric tangent (a moment fixed in space: no energy, no
//!   inertia to count), or a factorisation that met a pivot not finite —
//!   the least eigenvalue's own sign change is the test, and one that does
//!   not shrink towards zero as the fraction closes in is dropped;
//! * the target: the load factor or a node's displacement minus its value.
//!
//! At a bifurcation the path may leave for the other branch: one arc-length
//! step from the bifurcation point along the critical mode (the branch
//! crosses the path transversally there, in the direction of the mode).

use super::corrector::{Constraint, Corrected};
use super::follower::{load_slope, Control, Follower, Node, Run};
use super::path_spec::{CriticalKind, CriticalPoint, PathTarget};
use super::stability::{lowest_eigenpair, negative_eigenvalues, translations};

/// Largest number of re-solved fractions in one location.
const MAX_LOCATE: usize = 80;

/// A location stops when the fraction's bracket, in load-factor units of
/// the step, is below this (× max(1, |λ|)).
const LOCATE_TOLERANCE: f64 = 1e-11;

/// A located sign change of the lowest eigenvalue counts as a crossing when
/// the eigenvalue there is below this fraction of its values at the step's
/// ends.
const CROSSING: f64 = 1e-3;

/// A sign change of the load slope counts as a limit point only when the
/// slope at one end of the step exceeds this fraction of its value at the
/// start: on a branch whose load is flat to roundoff (a column just past
/// its bifurcation, λ − λ_c ~ 1e-10) the slope's sign is noise.
const SLOPE_NOISE: f64 = 1e-6;

/// Attempts, each with a step a quarter of the last, to leave a
/// bifurcation point along its mode.
const SWITCH_ATTEMPTS: usize = 4;

/// The step from `from` to the fraction of size `h` where `f` changes
/// sign, `f0` and `f1` its values at the step's start and end (of
/// opposite signs): regula falsi, Illinois variant. `f` computes only what
/// it needs of a re-solved step (`None`: no value there, the fraction is
/// halved as where the corrector fails). Returns the step where `|f|` was
/// least, with that value.
fn locate(
    follower: &Follower,
    from: &Node,
    previous: Option<(&[f64], f64)>,
    h: f64,
    (f0, f1): (f64, f64),
    f: impl Fn(&Corrected) -> Option<f64>,
) -> Option<(Corrected, f64)> {
    let (mut a, mut fa, mut b, mut fb) = (0.0, f0, 1.0, f1);
    let mut side = 0;
    let mut best: Option<(Corrected, f64)> = None;
    let scale = from.lambda.abs().max(1.0);
    for _ in 0..MAX_LOCATE {
        let mut tau = (a * fb - b * fa) / (fb - fa);
        if !(tau > a && tau < b) {
            tau = 0.5 * (a + b);
        }
        let found = follower
            .step(from, previous, tau * h)
            .and_then(|s| f(&s).map(|v| (s, v)));
        let Some((step, value)) = found else {
            // No equilibrium there (the corrector failed): halve instead.
            if (b - tau) > (tau - a) {
                b = 0.5 * (a + b);
            } else {
                a = 0.5 * (a + b);
            }
            continue;
        };
        if !value.is_finite() {
            break;
        }
        if best.as_ref().is_none_or(|(_, v)| value.abs() < v.abs()) {
            best = Some((step, value));
        }
        if value == 0.0 {
            break;
        }
        if (value < 0.0) == (fa < 0.0) {
            a = tau;
            fa = value;
            if side == -1 {
                fb *= 0.5;
            }
            side = -1;
        } else {
            b = tau;
            fb = value;
            if side == 1 {
                fa *= 0.5;
            }
            side = 1;
        }
        if (b - a) * h <= LOCATE_TOLERANCE * scale {
            break;
        }
    }
    best
}

/// If the step from `from` to `step` crossed the target, the equilibrium
/// exactly on it (the step re-solved to the fraction that reaches it, then
/// corrected onto it), with its node; `None` if it did not cross.
pub(super) fn land(
    follower: &Follower,
    target: PathTarget,
    from: &Node,
    previous: Option<(&[f64], f64)>,
    h: f64,
    step: &Corrected,
) -> Option<(Corrected, Node)> {
    let solver = follower.corrector.solver;
    let (q0, q1) = match target {
        PathTarget::Steps(_) => return None,
        PathTarget::LoadFactor(l) => (from.lambda - l, step.lambda - l),
        PathTarget::Displacement {
            node,
            component,
            value_m,
        } => (
            follower.displacement(&from.state, node, component) - value_m,
            follower.displacement(&step.state, node, component) - value_m,
        ),
    };
    if q0 == 0.0 || (q0 < 0.0) == (q1 < 0.0) && q1 != 0.0 {
        return None;
    }
    let quantity = |s: &Corrected| match target {
        PathTarget::LoadFactor(l) => s.lambda - l,
        PathTarget::Displacement {
            node,
            component,
            value_m,
        } => follower.displacement(&s.state, node, component) - value_m,
        PathTarget::Steps(_) => 0.0,
    };
    let (near, _) = locate(follower, from, previous, h, (q0, q1), |s| Some(quantity(s)))?;
    let constraint = match target {
        PathTarget::LoadFactor(l) => Constraint::Load { lambda: l },
        PathTarget::Displacement {
            node, component, ..
        } => Constraint::Displacement {
            dof: solver.system().unknown(node, component)?,
            increment: -quantity(&near),
        },
        PathTarget::Steps(_) => return None,
    };
    let zero = vec![0.0; near.increment.len()];
    let exact = follower
        .corrector
        .correct(&near.state, near.lambda, &zero, 0.0, constraint)?;
    // The landing step measured from `from`, as the path's steps are.
    let landed = Corrected {
        increment: near
            .increment
            .iter()
            .zip(&exact.increment)
            .map(|(a, b)| a + b)
            .collect(),
        d_lambda: near.d_lambda + exact.d_lambda,
        iterations: near.iterations + exact.iterations,
        ..exact
    };
    let node = follower.node(&landed)?;
    Some((landed, node))
}

/// Critical points in the step from `from` to `to` (both converged, `to`
/// already recorded in `run`): a limit point, else a bifurcation, located
/// and added to `run`. With `switch`, a bifurcation is also left for its
/// branch: returned are the bifurcation's node and the first step on the
/// branch with its node.
pub(super) fn between(
    follower: &Follower,
    run: &mut Run,
    from: &Node,
    previous: Option<(&[f64], f64)>,
    h: f64,
    to: &Node,
    switch: bool,
) -> Option<(Node, (Corrected, Node))> {
    let (g0, g1) = (from.indicators.load_slope, to.indicators.load_slope);
    let after_point = run.points.len().saturating_sub(2);
    let noise = SLOPE_NOISE * follower.start_slope;
    if g0 * g1 < 0.0 && g0.abs().max(g1.abs()) > noise {
        let slope = |s: &Corrected| {
            let t = follower.corrector.tangent(&s.state, s.lambda)?;
            Some(load_slope(follower, &t, Some((&s.increment, s.d_lambda))))
        };
        let (step, _) = locate(follower, from, previous, h, (g0, g1), slope)?;
        let node = follower.node(&step)?;
        let kind = if g0 > 0.0 {
            CriticalKind::LimitMaximum
        } else {
            CriticalKind::LimitMinimum
        };
        run.critical_points
            .push(critical_point(follower, kind, &node, after_point, false));
        return None;
    }
    let solver = follower.corrector.solver;
    let node = match (from.indicators.negative, to.indicators.negative) {
        (Some(n0), Some(n1)) => {
            if n0 == n1 {
                // No eigenvalue crossed zero, whatever the least one did.
                return None;
            }
            // The crossing eigenvalue: the least in magnitude, positive
            // while the inertia is the start's.
            let size = |e: Option<f64>| e.map_or(1.0, f64::abs);
            let (f0, f1) = (
                size(from.indicators.eigenvalue),
                -size(to.indicators.eigenvalue),
            );
            let crossing = |s: &Corrected| {
                let n = negative_eigenvalues(solver, &s.state, s.lambda)?;
                let least = lowest_eigenpair(solver, &s.state, s.lambda).ok()?;
                let sign = if n == n0 { 1.0 } else { -1.0 };
                Some(sign * least.eigenvalue.abs())
            };
            let (step, _) = locate(follower, from, previous, h, (f0, f1), crossing)?;
            follower.node(&step)?
        }
        _ => {
            let (Some(m0), Some(m1)) = (from.indicators.eigenvalue, to.indicators.eigenvalue)
            else {
                return None;
            };
            if m0 * m1 >= 0.0 {
                return None;
            }
            let eigenvalue = |s: &Corrected| {
                lowest_eigenpair(solver, &s.state, s.lambda)
                    .ok()
                    .map(|pair| pair.eigenvalue)
            };
            let (step, value) = locate(follower, from, previous, h, (m0, m1), eigenvalue)?;
            if value.abs() > CROSSING * m0.abs().max(m1.abs()) {
                return None;
            }
            follower.node(&step)?
        }
    };
    let branch = if switch {
        switch_branch(follower, &node, h)
    } else {
        None
    };
    run.critical_points.push(critical_point(
        follower,
        CriticalKind::Bifurcation,
        &node,
        after_point,
        branch.is_some(),
    ));
    branch.map(|b| (node, b))
}

/// The critical point at `node`.
fn critical_point(
    follower: &Follower,
    kind: CriticalKind,
    node: &Node,
    after_point: usize,
    switched_branch: bool,
) -> CriticalPoint {
    CriticalPoint {
        kind,
        load_factor: node.lambda,
        displacements_m: follower.displacements(&node.state),
        lowest_stiffness_n_per_m: node.indicators.eigenvalue,
        after_point,
        switched_branch,
        mode: node
            .indicators
            .vector
            .as_ref()
            .map(|v| translations(follower.corrector.solver, v))
            .unwrap_or_default(),
    }
}

/// One arc-length step from the bifurcation point `at` along its critical
/// mode (sign: its largest weighted component positive), of size `h`,
/// quartered up to [`SWITCH_ATTEMPTS`] times; `None` if none converges or
/// the control is not the arc length.
fn switch_branch(follower: &Follower, at: &Node, h: f64) -> Option<(Corrected, Node)> {
    let Control::Arc { psi } = follower.control else {
        return None;
    };
    let mode = at.indicators.vector.as_ref()?;
    let largest = mode
        .iter()
        .zip(&follower.corrector.w)
        .map(|(v, w)| v * w)
        .fold(0.0_f64, |m, v| if v.abs() > m.abs() { v } else { m });
    let sign = if largest < 0.0 { -1.0 } else { 1.0 };
    let mut size = h;
    for _ in 0..SWITCH_ATTEMPTS {
        let length = size * psi * std::f64::consts::SQRT_2;
        let du: Vec<f64> = mode.iter().map(|v| sign * length * v).collect();
        let step = follower.corrector.correct(
            &at.state,
            at.lambda,
            &du,
            0.0,
            Constraint::Arc { length, psi },
        );
        if let Some(step) = step {
            if let Some(node) = follower.node(&step) {
                return Some((step, node));
            }
        }
        size *= 0.25;
    }
    None
}
