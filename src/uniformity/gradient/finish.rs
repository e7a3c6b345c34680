//! The exact finish ([`super::Gradient::exact_finish`]): sequential quadratic
//! programming on the objective the soft max/min smooths,
//!
//! $$J_{\text{exact}} = \frac{1}{n_s}\Big(\sum_i \frac{e_i^2}{ε^2} + λ_{\text{lay}}
//!   \sum_i \frac{d_i^2}{ε^2}\Big) + w \sum_g \ln\frac{T_{\max,g}}{T_{\min,g}}
//!   + κ \Big(\frac{\ln(\bar T_0/t_0)}{10^{-3}}\Big)^2 ,$$
//!
//! nonsmooth at every change of the cables at a set's extremes, where L-BFGS on
//! the smoothed objective spends its iterations. Each step linearises, about
//! the forward equilibrium `x(q)`, the equilibrium of the free nodes (eq. 2:
//! `δq_k u_k + q_k (δx_i − δx_j)` summed at each free node is zero), the
//! surface errors (Gauss–Newton) and `s_k = ln(T_k/t_g)`,
//!
//! $$δs_k = δq_k/q_k + u_k·(δx_i − δx_j)/ℓ_k^2 ,$$
//!
//! and solves, with clarabel, the quadratic program in `(δq, δx, ē, v, u_g, l_g)`
//!
//! $$\min\ \frac{1}{n_s ε^2}\Big(\sum ē^2 + λ_{\text{lay}}\sum (d + δx)^2\Big)
//!   \;+\; w \sum_g (u_g − l_g) \;+\; κ' (L + v)^2
//!   \quad\text{s.t.}\quad l_g ≤ s_k + δs_k ≤ u_g,$$
//!
//! the linearised equilibrium, `ē = e + ∇e·δx`, `v` the linearised change of
//! `ln T̄₀`, the box `f t₀/ℓ̂_k ≤ q_k + δq_k ≤ 0.99 [q]` (the barrier's) and the
//! trust region `|δq_k| ≤ r q_k`. The max/min enter exactly, as the bounds
//! `u_g`, `l_g` of every cable of the set: the step sees which cables are at
//! the extremes, as `lp` does, and the geometry's reply to `δq` at once.
//!
//! The step is taken on `q` alone (the geometry follows by a forward solve)
//! when `J_exact` falls by more than a tenth of the decrease the model
//! predicts; the radius doubles (to at most ½) when the model predicts well
//! and shrinks ×4 when it does not. The finish has converged when the model
//! predicts a decrease of at most [`FINISH_TOLERANCE`]`·J`: no step of the
//! linearised problem lowers `J_exact` further, a stationarity certificate of
//! the nonsmooth problem that does not depend on the net's size.

use super::objective::{pretension_level, Objective};
use crate::uniformity::conic::{Class, Cone, ConicProgram};
use crate::uniformity::{SurfaceTarget, Termination, UniformityError};

/// The finish has converged when the model's predicted decrease is at most
/// this times `J_exact`.
pub(super) const FINISH_TOLERANCE: f64 = 1e-9;
/// Most steps (quadratic programs) of the finish.
pub(super) const MAX_FINISH_STEPS: usize = 50;
/// The first trust radius, relative change of `q`.
const FIRST_RADIUS: f64 = 0.05;
/// The largest trust radius (`q` stays above half its value at a step).
const MAX_RADIUS: f64 = 0.5;
/// Below this radius a rejected step ends the finish.
const MIN_RADIUS: f64 = 1e-9;

/// What the finish returns.
pub(super) struct Finished {
    /// The last accepted force densities.
    pub(super) q: Vec<f64>,
    /// `J_exact` there.
    pub(super) objective: f64,
    /// Quadratic programs solved.
    pub(super) steps: usize,
    pub(super) termination: Termination,
    pub(super) warnings: Vec<String>,
}

/// Sequential QP steps on `J_exact` from `q0` (see the module documentation).
pub(super) fn finish(objective: &Objective, q0: &[f64]) -> Result<Finished, UniformityError> {
    let exact = objective.exact();
    let mut q = q0.to_vec();
    let mut j = exact.evaluate_q(&q)?.0;
    let mut radius = FIRST_RADIUS;
    let mut warnings = Vec::new();
    let mut steps = 0;
    let termination = loop {
        if steps == MAX_FINISH_STEPS {
            warnings.push(format!(
                "the exact finish did not converge in {MAX_FINISH_STEPS} steps"
            ));
            break Termination::MaxIterations;
        }
        steps += 1;
        let model = Model::new(objective, &q, radius)?;
        let Some((dq, value)) = model.solve() else {
            warnings.push(format!(
                "the exact finish stopped: its quadratic program failed at step {steps}"
            ));
            break Termination::Stalled;
        };
        let predicted = j - value;
        if predicted <= FINISH_TOLERANCE * j.abs() {
            break Termination::Converged;
        }
        let trial: Vec<f64> = q.iter().zip(&dq).map(|(&a, &d)| a + d).collect();
        // A trial whose forward solve fails is a rejected step.
        let j_trial = exact.evaluate_q(&trial).map_or(f64::INFINITY, |(v, _)| v);
        let agreement = (j - j_trial) / predicted;
        if agreement > 0.1 {
            q = trial;
            j = j_trial;
            if agreement > 0.75 {
                radius = (2.0 * radius).min(MAX_RADIUS);
            }
        } else {
            radius *= 0.25;
            if radius < MIN_RADIUS {
                warnings.push(format!(
                    "the exact finish stopped: no step within the trust radius lowers J \
                     (the model predicts {predicted:.2e})"
                ));
                break Termination::Stalled;
            }
        }
    };
    Ok(Finished {
        q,
        objective: j,
        steps,
        termination,
        warnings,
    })
}

/// The quadratic model of `J_exact` about one `q`: variables
/// `(δq | δx per free node | ē | v | u_g, l_g per set)`, the program's rows,
/// and the objective `½ xᵀ diag(p) x + cᵀx + constant`.
struct Model {
    program: ConicProgram,
    p: Vec<f64>,
    c: Vec<f64>,
    constant: f64,
    n_edges: usize,
}

impl Model {
    fn new(objective: &Objective, q: &[f64], radius: f64) -> Result<Self, UniformityError> {
        let problem = objective.problem;
        let structure = problem.structure();
        let design = &problem.network().nodes;
        let eq = problem.forward(q)?;
        let x = &eq.nodes_xyz_m;
        let tensions = &eq.edges_forces_n;
        let m = q.len();
        let n_free = structure.free_nodes().len();
        let per_node = match problem.surface() {
            SurfaceTarget::Paraboloid(_) => 1,
            SurfaceTarget::Prescribed => 3,
        };
        let sets = problem.sets();
        let at_x = m;
        let at_e = at_x + 3 * n_free;
        let at_v = at_e + per_node * problem.surface_nodes().len();
        let at_u = at_v + 1;
        let n = at_u + 2 * sets.len();
        let mut model = Model {
            program: ConicProgram::new(n),
            p: vec![0.0; n],
            c: vec![0.0; n],
            constant: 0.0,
            n_edges: m,
        };
        let free = |i: usize| structure.free_index(i);

        // Linearised equilibrium: the internal force at every free node
        // does not change.
        let mut rows: Vec<Vec<(usize, f64)>> = vec![Vec::new(); 3 * n_free];
        for (k, &[a, b]) in structure.edges().iter().enumerate() {
            let u = eq.edges_vectors_m[k];
            for (node, sign) in [(a, 1.0), (b, -1.0)] {
                let Some(f) = free(node) else { continue };
                for d in 0..3 {
                    let row = &mut rows[3 * f + d];
                    row.push((k, sign * u[d]));
                    for (end, end_sign) in [(a, 1.0), (b, -1.0)] {
                        if let Some(g) = free(end) {
                            row.push((at_x + 3 * g + d, sign * end_sign * q[k]));
                        }
                    }
                }
            }
        }
        for row in &rows {
            model.program.row(Cone::Zero, row, 0.0);
        }

        // Surface errors ē = e + ∇e·δx, and the layout drift.
        let scale = objective.surface_scale;
        let layout = objective.layout_weight * scale;
        let mut e_at = at_e;
        for &i in problem.surface_nodes() {
            let point = x[i];
            match problem.surface() {
                SurfaceTarget::Paraboloid(parab) => {
                    let e = parab.axial_deviation(point);
                    let two_f = 2.0 * parab.focal_length_m;
                    let grad = [-point[0] / two_f, -point[1] / two_f, 1.0];
                    model.error_row(e_at, e, free(i).map(|f| (at_x + 3 * f, grad)), scale);
                    e_at += 1;
                    if let Some(f) = free(i) {
                        for d in 0..2 {
                            model.drift(at_x + 3 * f + d, point[d] - design[i][d], layout);
                        }
                    }
                }
                SurfaceTarget::Prescribed => {
                    for d in 0..3 {
                        let mut unit = [0.0; 3];
                        unit[d] = 1.0;
                        let e = point[d] - design[i][d];
                        model.error_row(e_at, e, free(i).map(|f| (at_x + 3 * f, unit)), scale);
                        e_at += 1;
                    }
                }
            }
        }
        if layout > 0.0 {
            for &i in &objective.other_free {
                if let Some(f) = free(i) {
                    for d in 0..3 {
                        model.drift(at_x + 3 * f + d, x[i][d] - design[i][d], layout);
                    }
                }
            }
        }

        // δs_k, scaled by `factor`: the row entries of one cable's ln T.
        let delta_s = |k: usize, factor: f64| -> Vec<(usize, f64)> {
            let [a, b] = structure.edges()[k];
            let u = eq.edges_vectors_m[k];
            let l2 = eq.edges_lengths_m[k].powi(2);
            let mut row = vec![(k, factor / q[k])];
            for (end, sign) in [(a, 1.0), (b, -1.0)] {
                if let Some(f) = free(end) {
                    for (d, &ud) in u.iter().enumerate() {
                        row.push((at_x + 3 * f + d, factor * sign * ud / l2));
                    }
                }
            }
            row
        };

        // Level: v = Σ_k T_k δs_k / (n₀ T̄₀), the term κ'(L + v)².
        let first = &sets[0];
        let n0 = first.edges.len() as f64;
        let (mean, level) = pretension_level(problem, tensions);
        let mut row = vec![(at_v, 1.0)];
        for &k in &first.edges {
            row.extend(delta_s(k, -tensions[k] / (n0 * mean)));
        }
        model.program.row(Cone::Zero, &row, 0.0);
        let kappa = objective.level_weight;
        model.p[at_v] = 2.0 * kappa;
        model.c[at_v] = 2.0 * kappa * level;
        model.constant += kappa * level * level;

        // The extremes: l_g ≤ s_k + δs_k ≤ u_g.
        for (g, set) in sets.iter().enumerate() {
            let (at_high, at_low) = (at_u + 2 * g, at_u + 2 * g + 1);
            model.c[at_high] = objective.weight;
            model.c[at_low] = -objective.weight;
            for &k in &set.edges {
                let s = (tensions[k] / set.mean_tension_n).ln();
                // u − s − δs ≥ 0.
                let mut high = delta_s(k, 1.0);
                high.push((at_high, -1.0));
                model.program.row(Cone::Nonnegative, &high, -s);
                // s + δs − l ≥ 0.
                let mut low = delta_s(k, -1.0);
                low.push((at_low, 1.0));
                model.program.row(Cone::Nonnegative, &low, s);
            }
        }

        // The barrier's box within the trust region: lo ≤ δq_k ≤ hi.
        for (k, &qk) in q.iter().enumerate() {
            let reach = radius * qk;
            let lo = (objective.q_low[k] - qk).clamp(-reach, reach);
            let hi = (objective.q_high - qk).clamp(lo, reach);
            model.program.row(Cone::Nonnegative, &[(k, -1.0)], -lo);
            model.program.row(Cone::Nonnegative, &[(k, 1.0)], hi);
        }
        Ok(model)
    }

    /// The row `ē = e + g·δx` of the error variable at `at` (`g` and the
    /// node's first `δx` column, or none for a node that cannot move), and its
    /// term `scale ē²`.
    fn error_row(&mut self, at: usize, e: f64, gradient: Option<(usize, [f64; 3])>, scale: f64) {
        let mut row = vec![(at, 1.0)];
        if let Some((column, g)) = gradient {
            row.extend((0..3).map(|d| (column + d, -g[d])));
        }
        self.program.row(Cone::Zero, &row, e);
        self.p[at] = 2.0 * scale;
    }

    /// The term `weight (drift + δx)²` of one coordinate at `column`.
    fn drift(&mut self, column: usize, drift: f64, weight: f64) {
        self.p[column] += 2.0 * weight;
        self.c[column] += 2.0 * weight * drift;
        self.constant += weight * drift * drift;
    }

    /// `δq` and the model's value at the program's solution, or `None` when
    /// clarabel fails.
    fn solve(self) -> Option<(Vec<f64>, f64)> {
        let Model {
            program,
            p,
            c,
            constant,
            n_edges,
        } = self;
        let outcome = program.solve_quadratic(&p, &c);
        if outcome.class != Class::Feasible {
            return None;
        }
        let x = &outcome.x;
        let value = constant
            + x.iter()
                .zip(p.iter().zip(&c))
                .map(|(&x, (&p, &c))| 0.5 * p * x * x + c * x)
                .sum::<f64>();
        Some((x[..n_edges].to_vec(), value))
    }
}
