//! The objective `J(q)` and its adjoint gradient (see the module
//! documentation of [`super`]).

use super::map::Map;
use super::settings::Gradient;
use crate::uniformity::{SurfaceTarget, UniformityError, UniformityProblem};

/// Upper edge of the barrier's free box, as a fraction of `[q]`.
const UPPER_FRACTION: f64 = 0.99;

/// Unit of the level term: a mean tension `LEVEL_UNIT` (relative) off its
/// target costs `κ`.
const LEVEL_UNIT: f64 = 1e-3;

/// Unit of the bound barrier: a force density `BARRIER_UNIT` (relative) beyond
/// its bound costs `ν`.
const BARRIER_UNIT: f64 = 1e-2;

/// Normalised log-sum-exp `(1/β) ln((1/n) Σ e^{β s_k})`, and its weights
/// `softmax(β s)` written into `weights`.
pub(super) fn soft_max(s: &[f64], beta: f64, weights: &mut [f64]) -> f64 {
    let top = s.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut sum = 0.0;
    for (w, &v) in weights.iter_mut().zip(s) {
        *w = (beta * (v - top)).exp();
        sum += *w;
    }
    for w in weights.iter_mut() {
        *w /= sum;
    }
    top + (sum / s.len() as f64).ln() / beta
}

/// `max s`, and the indicator of its first arg max written into `weights`
/// (a subgradient); the signature of [`soft_max`], the sharpness unused.
fn arg_max(s: &[f64], _beta: f64, weights: &mut [f64]) -> f64 {
    let (top, value) = s
        .iter()
        .copied()
        .enumerate()
        .fold((0, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a });
    weights.fill(0.0);
    weights[top] = 1.0;
    value
}

/// The first set's mean tension `T̄₀` at the tensions `tensions`, and the
/// level `ln(T̄₀/t₀)` the level term holds at zero.
pub(super) fn pretension_level(problem: &UniformityProblem, tensions: &[f64]) -> (f64, f64) {
    let first = &problem.sets()[0];
    let mean = first.edges.iter().map(|&k| tensions[k]).sum::<f64>() / first.edges.len() as f64;
    (mean, (mean / first.mean_tension_n).ln())
}

/// The objective of one problem with one set of settings.
#[derive(Clone)]
pub(super) struct Objective<'a> {
    pub(super) problem: &'a UniformityProblem,
    pub(super) map: Map,
    pub(super) weight: f64,
    pub(super) layout_weight: f64,
    sharpness: f64,
    /// The ratio term is the max/min themselves, not their soft versions:
    /// the objective the surrogate smooths (values only; its gradient is a
    /// subgradient).
    exact: bool,
    /// `κ / LEVEL_UNIT²`.
    pub(super) level_weight: f64,
    /// `ν / BARRIER_UNIT³`.
    barrier_weight: f64,
    /// `1/(n_s ε²)`.
    pub(super) surface_scale: f64,
    /// Free nodes that are not surface nodes.
    pub(super) other_free: Vec<usize>,
    /// Lower edge `q̲_k` of the barrier's box.
    pub(super) q_low: Vec<f64>,
    /// Upper edge `q̄` of the barrier's box.
    pub(super) q_high: f64,
}

impl<'a> Objective<'a> {
    pub(super) fn new(settings: &Gradient, problem: &'a UniformityProblem) -> Self {
        let lengths = problem.lengths_m();
        let tolerance = settings.surface_tolerance_m;
        let n_surface = problem.surface_nodes().len().max(1) as f64;
        let mut is_surface = vec![false; problem.network().n_nodes()];
        for &i in problem.surface_nodes() {
            is_surface[i] = true;
        }
        let min_tension = problem.min_other_tension_n();
        Objective {
            problem,
            map: Map::new(problem),
            weight: settings.weight,
            layout_weight: settings.layout_weight,
            sharpness: settings.sharpness,
            exact: false,
            level_weight: settings.level_weight / (LEVEL_UNIT * LEVEL_UNIT),
            barrier_weight: settings.barrier_weight / BARRIER_UNIT.powi(3),
            surface_scale: 1.0 / (n_surface * tolerance * tolerance),
            other_free: problem
                .structure()
                .free_nodes()
                .iter()
                .copied()
                .filter(|&i| !is_surface[i])
                .collect(),
            q_low: lengths.iter().map(|&l| min_tension / l).collect(),
            q_high: UPPER_FRACTION * problem.max_force_density_n_per_m,
        }
    }

    /// The same objective with the soft max/min's sharpness `β`.
    pub(super) fn with_sharpness(&self, sharpness: f64) -> Self {
        Objective {
            sharpness,
            ..self.clone()
        }
    }

    /// The same objective with the exact ratio term `ln(Tmax/Tmin)` per set.
    pub(super) fn exact(&self) -> Self {
        Objective {
            exact: true,
            ..self.clone()
        }
    }

    /// `J(θ)` and `dJ/dθ`.
    pub(super) fn evaluate_theta(&self, theta: &[f64]) -> Result<(f64, Vec<f64>), UniformityError> {
        let q: Vec<f64> = theta.iter().map(|&t| self.map.q(t)).collect();
        let (value, mut gradient) = self.evaluate_q(&q)?;
        for (g, &t) in gradient.iter_mut().zip(theta) {
            *g *= self.map.dq(t);
        }
        Ok((value, gradient))
    }

    /// `‖dJ/dθ‖∞` from `dJ/dq`.
    pub(super) fn theta_gradient_norm(&self, q: &[f64], dj_dq: &[f64]) -> f64 {
        q.iter()
            .zip(dj_dq)
            .map(|(&q, g)| (g * self.map.dq(self.map.theta(q))).abs())
            .fold(0.0, f64::max)
    }

    /// The stationarity `‖dJ/dθ‖∞ / J` of `J(q) = j` with `dJ/dq = dj_dq`:
    /// `θ ≈ ln q` where the bound is far, so this is the largest relative
    /// change of `J` per relative change of one force density, free of the
    /// problem's scale and of the start.
    pub(super) fn stationarity(&self, q: &[f64], j: f64, dj_dq: &[f64]) -> f64 {
        self.theta_gradient_norm(q, dj_dq) / j.abs().max(f64::MIN_POSITIVE)
    }

    /// `J(q)` and `dJ/dq`.
    pub(super) fn evaluate_q(&self, q: &[f64]) -> Result<(f64, Vec<f64>), UniformityError> {
        let problem = self.problem;
        let structure = problem.structure();
        let design = &problem.network().nodes;
        let eq = problem.forward(q)?;
        let x = &eq.nodes_xyz_m;
        let mut dj_dx = vec![[0.0; 3]; x.len()];
        let mut value = 0.0;

        // Surface error, and the plan drift of the surface nodes.
        let layout = self.layout_weight * self.surface_scale;
        for &i in problem.surface_nodes() {
            let p = x[i];
            match problem.surface() {
                SurfaceTarget::Paraboloid(parab) => {
                    let e = parab.axial_deviation(p);
                    value += self.surface_scale * e * e;
                    let c = 2.0 * self.surface_scale * e;
                    let two_f = 2.0 * parab.focal_length_m;
                    dj_dx[i][0] -= c * p[0] / two_f;
                    dj_dx[i][1] -= c * p[1] / two_f;
                    dj_dx[i][2] += c;
                    for d in 0..2 {
                        let drift = p[d] - design[i][d];
                        value += layout * drift * drift;
                        dj_dx[i][d] += 2.0 * layout * drift;
                    }
                }
                SurfaceTarget::Prescribed => {
                    for d in 0..3 {
                        let e = p[d] - design[i][d];
                        value += self.surface_scale * e * e;
                        dj_dx[i][d] += 2.0 * self.surface_scale * e;
                    }
                }
            }
        }
        // Layout: the other free nodes near their design positions.
        if layout > 0.0 {
            for &i in &self.other_free {
                for d in 0..3 {
                    let drift = x[i][d] - design[i][d];
                    value += layout * drift * drift;
                    dj_dx[i][d] += 2.0 * layout * drift;
                }
            }
        }

        // Ratio surrogate and level: dJ/dT per cable.
        let tensions = &eq.edges_forces_n;
        let mut dj_dt = vec![0.0; q.len()];
        let mut s = Vec::new();
        let mut up = Vec::new();
        let mut down = Vec::new();
        for set in problem.sets() {
            // ln T in units of the set's target: the same numbers at any level.
            s.clear();
            s.extend(
                set.edges
                    .iter()
                    .map(|&k| (tensions[k] / set.mean_tension_n).ln()),
            );
            up.resize(s.len(), 0.0);
            down.resize(s.len(), 0.0);
            let extreme = if self.exact { arg_max } else { soft_max };
            let high = extreme(&s, self.sharpness, &mut up);
            for v in s.iter_mut() {
                *v = -*v;
            }
            let low = -extreme(&s, self.sharpness, &mut down);
            value += self.weight * (high - low);
            for (n, &k) in set.edges.iter().enumerate() {
                dj_dt[k] += self.weight * (up[n] - down[n]) / tensions[k];
            }
        }
        let first = &problem.sets()[0];
        let n0 = first.edges.len() as f64;
        let (mean, level) = pretension_level(problem, tensions);
        value += self.level_weight * level * level;
        for &k in &first.edges {
            dj_dt[k] += 2.0 * self.level_weight * level / (n0 * mean);
        }

        // T_k = q_k ℓ_k(x): explicit in q, and through the positions.
        let mut dj_dq = vec![0.0; q.len()];
        for (k, (&g, &[i, j])) in dj_dt.iter().zip(structure.edges()).enumerate() {
            if g == 0.0 {
                continue;
            }
            let l = eq.edges_lengths_m[k];
            dj_dq[k] += g * l;
            let u = eq.edges_vectors_m[k];
            for c in 0..3 {
                let d = g * q[k] * u[c] / l;
                dj_dx[i][c] += d;
                dj_dx[j][c] -= d;
            }
        }
        let mut gradient = eq.sensitivities(structure, &dj_dx, Some(&dj_dq));

        // Bound barrier, in ln q.
        if self.barrier_weight > 0.0 {
            for (k, g) in gradient.iter_mut().enumerate() {
                let below = (self.q_low[k] / q[k]).ln();
                if below > 0.0 {
                    value += self.barrier_weight * below.powi(3);
                    *g -= 3.0 * self.barrier_weight * below * below / q[k];
                }
                let above = (q[k] / self.q_high).ln();
                if above > 0.0 {
                    value += self.barrier_weight * above.powi(3);
                    *g += 3.0 * self.barrier_weight * above * above / q[k];
                }
            }
        }
        Ok((value, gradient))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn soft_max_lies_between_mean_and_max() {
        let s = [0.1, 0.5, -0.3, 0.45, 0.2];
        let mut weights = [0.0; 5];
        for beta in [1.0, 10.0, 100.0, 1000.0] {
            let v = soft_max(&s, beta, &mut weights);
            let mean = s.iter().sum::<f64>() / 5.0;
            assert!(v >= mean - 1e-15 && v <= 0.5 + 1e-15, "β = {beta}: {v}");
            assert!((weights.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        }
        let sharp = soft_max(&s, 1e4, &mut weights);
        assert!((sharp - 0.5).abs() < 2.0 * (5f64).ln() / 1e4);
    }
}
