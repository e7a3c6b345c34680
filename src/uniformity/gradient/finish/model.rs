//! The quadratic model of one step of the exact finish, as structured data:
//! the variables `z = (p | ξ | u_g, l_g)` — the relative change
//! `p_k = δq_k/q_k` of every cable, the displacement `ξ` of every free node
//! and the bounds of every set — the rows that tie them, and the objective
//! `½ zᵀHz + cᵀz + constant`. The interior point of `ipm.rs` works on this
//! form directly; [`StepModel::solve_with_clarabel`] states it as a generic
//! conic program (the cross-check, and the fallback).

use crate::fdm::NONE;
use crate::uniformity::conic::{Class, Cone, ConicProgram};

/// clarabel did not solve a step's program.
#[derive(Debug, thiserror::Error)]
#[error("clarabel ended with status {status}")]
pub(super) struct ClarabelFailed {
    /// clarabel's status, verbatim (`NumericalError`, `PrimalInfeasible`,
    /// `setup: …`).
    pub(super) status: String,
}

/// One cable of the step: where it goes and the linearisation about `q`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Cable {
    /// Free indices of its ends (`NONE` for a fixed end).
    pub(super) ends: [usize; 2],
    /// Its force density `q_k`.
    pub(super) q: f64,
    /// Its vector `x_a − x_b`, m.
    pub(super) u: [f64; 3],
    /// `u/ℓ²`: `δ ln T_k = p_k + g·(ξ_a − ξ_b)`.
    pub(super) g: [f64; 3],
    /// The box `lo ≤ p_k ≤ hi` (the barrier's box within the trust region).
    pub(super) lo: f64,
    pub(super) hi: f64,
    /// The model's curvature `c_k` in `p_k`, a term `½ c_k p_k²` (see
    /// `ipm::add_log_curvature`).
    pub(super) curvature: f64,
}

/// One surface error `ē = e + gradient·ξ_node` (Gauss–Newton).
#[derive(Debug, Clone, Copy)]
pub(super) struct ErrorRow {
    /// Free index of its node, or `NONE` (a node that cannot move).
    pub(super) node: usize,
    pub(super) gradient: [f64; 3],
    pub(super) value: f64,
}

/// The quadratic model of `J_exact` about one `q` (see the module
/// documentation of `finish`).
#[derive(Debug, Clone)]
pub(super) struct StepModel {
    pub(super) cables: Vec<Cable>,
    pub(super) n_free: usize,
    /// `1/Σ_k q_k` over the cables at each free node: the scale of its
    /// equilibrium rows.
    pub(super) row_scale: Vec<f64>,
    /// The errors, each weighted `error_weight ē²`.
    pub(super) errors: Vec<ErrorRow>,
    pub(super) error_weight: f64,
    /// `(ξ column, drift)`, each weighted `drift_weight (drift + ξ)²`.
    pub(super) drifts: Vec<(usize, f64)>,
    pub(super) drift_weight: f64,
    /// Per set, `(cable, s_k = ln(T_k/t_g))`: `l_g ≤ s_k + δs_k ≤ u_g`.
    pub(super) sets: Vec<Vec<(usize, f64)>>,
    /// The ratio terms' weight `w` on `u_g − l_g`.
    pub(super) weight: f64,
    /// The level term `κ (L + Σ_k w_k δs_k)²`: `(cable, w_k)`.
    pub(super) level_terms: Vec<(usize, f64)>,
    pub(super) level_weight: f64,
    pub(super) level: f64,
}

impl StepModel {
    /// Number of cables.
    pub(super) fn m(&self) -> usize {
        self.cables.len()
    }

    /// First column of `ξ`.
    pub(super) fn at_xi(&self) -> usize {
        self.m()
    }

    /// First column of `(u_g, l_g)`.
    pub(super) fn at_bounds(&self) -> usize {
        self.m() + 3 * self.n_free
    }

    /// Number of variables.
    pub(super) fn n(&self) -> usize {
        self.at_bounds() + 2 * self.sets.len()
    }

    /// `δ ln T_k = p_k + g·(ξ_a − ξ_b)` at `z`.
    pub(super) fn delta_s(&self, k: usize, z: &[f64]) -> f64 {
        let cable = &self.cables[k];
        let mut value = z[k];
        for (end, sign) in cable.ends.iter().zip([1.0, -1.0]) {
            if *end != NONE {
                let at = self.at_xi() + 3 * end;
                value += sign * (0..3).map(|d| cable.g[d] * z[at + d]).sum::<f64>();
            }
        }
        value
    }

    /// The entries of `∂(δ ln T_k)/∂z`: `p_k`, then `±g` at each free end.
    pub(super) fn delta_s_entries(&self, k: usize) -> Vec<(usize, f64)> {
        let cable = &self.cables[k];
        let mut entries = vec![(k, 1.0)];
        for (end, sign) in cable.ends.iter().zip([1.0, -1.0]) {
            if *end != NONE {
                let at = self.at_xi() + 3 * end;
                entries.extend((0..3).map(|d| (at + d, sign * cable.g[d])));
            }
        }
        entries
    }

    /// Adds `factor ∂(δ ln T_k)/∂z` into `out`.
    pub(super) fn add_delta_s_gradient(&self, k: usize, factor: f64, out: &mut [f64]) {
        let cable = &self.cables[k];
        out[k] += factor;
        for (end, sign) in cable.ends.iter().zip([1.0, -1.0]) {
            if *end != NONE {
                let at = self.at_xi() + 3 * end;
                for d in 0..3 {
                    out[at + d] += factor * sign * cable.g[d];
                }
            }
        }
    }

    /// The level change `v = Σ_k w_k δs_k` at `z`.
    pub(super) fn level_change(&self, z: &[f64]) -> f64 {
        self.level_terms
            .iter()
            .map(|&(k, w)| w * self.delta_s(k, z))
            .sum()
    }

    /// The model's value at `z`.
    pub(super) fn value(&self, z: &[f64]) -> f64 {
        let at_xi = self.at_xi();
        let errors: f64 = self
            .errors
            .iter()
            .map(|row| {
                let mut e = row.value;
                if row.node != NONE {
                    e += (0..3)
                        .map(|d| row.gradient[d] * z[at_xi + 3 * row.node + d])
                        .sum::<f64>();
                }
                e * e
            })
            .sum();
        let drifts: f64 = self
            .drifts
            .iter()
            .map(|&(column, drift)| (drift + z[at_xi + column]).powi(2))
            .sum();
        let level = self.level + self.level_change(z);
        let bounds = &z[self.at_bounds()..];
        let ratios: f64 = bounds.chunks(2).map(|b| b[0] - b[1]).sum();
        let curvature: f64 = self
            .cables
            .iter()
            .zip(z)
            .map(|(cable, p)| cable.curvature * p * p)
            .sum();
        0.5 * curvature
            + self.error_weight * errors
            + self.drift_weight * drifts
            + self.level_weight * level * level
            + self.weight * ratios
    }

    /// The gradient `Hz + c` of the model at `z`.
    pub(super) fn gradient(&self, z: &[f64]) -> Vec<f64> {
        let mut out = self.quadratic_terms(z, 1.0);
        let at = self.at_bounds();
        for g in 0..self.sets.len() {
            out[at + 2 * g] += self.weight;
            out[at + 2 * g + 1] -= self.weight;
        }
        out
    }

    /// The product `H v` of the model's Hessian.
    pub(super) fn hessian_mul(&self, v: &[f64]) -> Vec<f64> {
        self.quadratic_terms(v, 0.0)
    }

    /// The gradient of the surface, drift and level terms at `z`, their
    /// constant parts (`e`, the drift, `L`) times `constants`: `Hz + c` with
    /// 1, `Hz` with 0.
    fn quadratic_terms(&self, z: &[f64], constants: f64) -> Vec<f64> {
        let at_xi = self.at_xi();
        let mut out = vec![0.0; self.n()];
        for ((o, cable), p) in out.iter_mut().zip(&self.cables).zip(z) {
            *o = cable.curvature * p;
        }
        for row in &self.errors {
            if row.node == NONE {
                continue;
            }
            let at = at_xi + 3 * row.node;
            let e =
                constants * row.value + (0..3).map(|d| row.gradient[d] * z[at + d]).sum::<f64>();
            for d in 0..3 {
                out[at + d] += 2.0 * self.error_weight * e * row.gradient[d];
            }
        }
        for &(column, drift) in &self.drifts {
            out[at_xi + column] +=
                2.0 * self.drift_weight * (constants * drift + z[at_xi + column]);
        }
        let level = 2.0 * self.level_weight * (constants * self.level + self.level_change(z));
        for &(k, w) in &self.level_terms {
            self.add_delta_s_gradient(k, level * w, &mut out);
        }
        out
    }

    /// `out = E z`: the linearised equilibrium of every free node (eq. 2),
    /// `Σ_k ±(q_k u_k p_k + q_k (ξ_a − ξ_b))`, times the node's row scale.
    pub(super) fn equilibrium_mul(&self, z: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        let at_xi = self.at_xi();
        for (k, cable) in self.cables.iter().enumerate() {
            let mut f = cable.u.map(|u| cable.q * u * z[k]);
            for (end, sign) in cable.ends.iter().zip([1.0, -1.0]) {
                if *end != NONE {
                    for d in 0..3 {
                        f[d] += sign * cable.q * z[at_xi + 3 * end + d];
                    }
                }
            }
            for (end, sign) in cable.ends.iter().zip([1.0, -1.0]) {
                if *end != NONE {
                    for d in 0..3 {
                        out[3 * end + d] += sign * self.row_scale[*end] * f[d];
                    }
                }
            }
        }
    }

    /// `‖E‖∞`, the largest absolute row sum of the linearised equilibrium.
    pub(super) fn equilibrium_norm(&self) -> f64 {
        let mut sums = vec![0.0; 3 * self.n_free];
        for cable in &self.cables {
            // A row's entries: `q u_d` on p_k, `q` on ξ_d of each free end.
            let free_ends = cable.ends.iter().filter(|&&f| f != NONE);
            let n_free_ends = free_ends.clone().count() as f64;
            for &f in free_ends {
                for d in 0..3 {
                    sums[3 * f + d] +=
                        self.row_scale[f] * cable.q * (cable.u[d].abs() + n_free_ends);
                }
            }
        }
        sums.into_iter().fold(0.0, f64::max)
    }

    /// `out += Eᵀ y`.
    pub(super) fn equilibrium_transpose_mul(&self, y: &[f64], out: &mut [f64]) {
        let at_xi = self.at_xi();
        for (k, cable) in self.cables.iter().enumerate() {
            // The cable's force change per unit of each variable, seen by y.
            let mut w = [0.0; 3];
            for (end, sign) in cable.ends.iter().zip([1.0, -1.0]) {
                if *end != NONE {
                    for d in 0..3 {
                        w[d] += sign * self.row_scale[*end] * y[3 * end + d];
                    }
                }
            }
            out[k] += cable.q * (0..3).map(|d| cable.u[d] * w[d]).sum::<f64>();
            for (end, sign) in cable.ends.iter().zip([1.0, -1.0]) {
                if *end != NONE {
                    for d in 0..3 {
                        out[at_xi + 3 * end + d] += sign * cable.q * w[d];
                    }
                }
            }
        }
    }

    /// The force densities `q_k (1 + p_k)` of the step `z` from `q`, each
    /// `p_k` held to its cable's box.
    pub(super) fn force_densities(&self, q: &[f64], z: &[f64]) -> Vec<f64> {
        q.iter()
            .zip(z)
            .zip(&self.cables)
            .map(|((&q, &p), cable)| q * (1.0 + p.clamp(cable.lo, cable.hi)))
            .collect()
    }

    /// The feasible point of `p`, the relative changes in `z`: `p` clamped
    /// to its box, `ξ` the linearised equilibrium's answer to it (`D ξ =
    /// −Σ_k ±q_k u_k p_k` at every free node, eq. 3–4, with `solve_d` solving
    /// `D`), and `u_g`, `l_g` the extremes of `s_k + δs_k`. A solver meets
    /// the rows to its tolerance only; the model's value at its point can lie
    /// below the optimum by more than the finish's test (`10⁻⁹ J`) resolves,
    /// which would read as a decrease that no step gives.
    pub(super) fn feasible_point(&self, z: &[f64], solve_d: impl Fn(&mut [[f64; 3]])) -> Vec<f64> {
        let mut z = z.to_vec();
        let mut rhs = vec![[0.0; 3]; self.n_free];
        for (k, cable) in self.cables.iter().enumerate() {
            z[k] = z[k].clamp(cable.lo, cable.hi);
            for (end, sign) in cable.ends.iter().zip([-1.0, 1.0]) {
                if *end != NONE {
                    for (r, u) in rhs[*end].iter_mut().zip(cable.u) {
                        *r += sign * cable.q * u * z[k];
                    }
                }
            }
        }
        solve_d(&mut rhs);
        let at_xi = self.at_xi();
        for (f, xi) in rhs.iter().enumerate() {
            z[at_xi + 3 * f..at_xi + 3 * f + 3].copy_from_slice(xi);
        }
        let at = self.at_bounds();
        for (g, set) in self.sets.iter().enumerate() {
            let s = set.iter().map(|&(k, s)| s + self.delta_s(k, &z));
            let (high, low) = s.fold((f64::NEG_INFINITY, f64::INFINITY), |(h, l), v| {
                (h.max(v), l.min(v))
            });
            z[at + 2 * g] = high;
            z[at + 2 * g + 1] = low;
        }
        z
    }

    /// The model as a generic conic program for clarabel: the variables `z`,
    /// then one `ē` per error row and the level change `v`. Returns `z` at
    /// the optimum.
    ///
    /// # Errors
    /// clarabel's status when it did not solve the program.
    pub(super) fn solve_with_clarabel(&self) -> Result<Vec<f64>, ClarabelFailed> {
        let n = self.n();
        let at_xi = self.at_xi();
        let at_e = n;
        let at_v = at_e + self.errors.len();
        let mut program = ConicProgram::new(at_v + 1);
        let mut p = vec![0.0; at_v + 1];
        let mut c = vec![0.0; at_v + 1];
        // The rows of `E` (equilibrium_mul's), gathered per free node.
        let mut rows: Vec<Vec<(usize, f64)>> = vec![Vec::new(); 3 * self.n_free];
        for (k, cable) in self.cables.iter().enumerate() {
            for (end, sign) in cable.ends.iter().zip([1.0, -1.0]) {
                if *end == NONE {
                    continue;
                }
                let scale = sign * self.row_scale[*end];
                for d in 0..3 {
                    let row = &mut rows[3 * end + d];
                    row.push((k, scale * cable.q * cable.u[d]));
                    for (other, other_sign) in cable.ends.iter().zip([1.0, -1.0]) {
                        if *other != NONE {
                            row.push((at_xi + 3 * other + d, scale * other_sign * cable.q));
                        }
                    }
                }
            }
        }
        for row in &rows {
            program.row(Cone::Zero, row, 0.0);
        }
        for (i, row) in self.errors.iter().enumerate() {
            let mut entries = vec![(at_e + i, 1.0)];
            if row.node != NONE {
                entries.extend((0..3).map(|d| (at_xi + 3 * row.node + d, -row.gradient[d])));
            }
            program.row(Cone::Zero, &entries, row.value);
            p[at_e + i] = 2.0 * self.error_weight;
        }
        for &(column, drift) in &self.drifts {
            p[at_xi + column] += 2.0 * self.drift_weight;
            c[at_xi + column] += 2.0 * self.drift_weight * drift;
        }
        let mut level = vec![0.0; n];
        for &(k, w) in &self.level_terms {
            self.add_delta_s_gradient(k, -w, &mut level);
        }
        let mut row: Vec<(usize, f64)> = level
            .iter()
            .enumerate()
            .filter(|(_, &v)| v != 0.0)
            .map(|(i, &v)| (i, v))
            .collect();
        row.push((at_v, 1.0));
        program.row(Cone::Zero, &row, 0.0);
        p[at_v] = 2.0 * self.level_weight;
        c[at_v] = 2.0 * self.level_weight * self.level;
        let at = self.at_bounds();
        for (g, set) in self.sets.iter().enumerate() {
            let (high, low) = (at + 2 * g, at + 2 * g + 1);
            c[high] = self.weight;
            c[low] = -self.weight;
            for &(k, s) in set {
                let phi = self.delta_s_entries(k);
                // u − s − δs ≥ 0.
                let mut upper = phi.clone();
                upper.push((high, -1.0));
                program.row(Cone::Nonnegative, &upper, -s);
                // s + δs − l ≥ 0.
                let mut lower: Vec<(usize, f64)> = phi.iter().map(|&(i, v)| (i, -v)).collect();
                lower.push((low, 1.0));
                program.row(Cone::Nonnegative, &lower, s);
            }
        }
        // lo ≤ p_k ≤ hi.
        for (k, cable) in self.cables.iter().enumerate() {
            p[k] = cable.curvature;
            program.row(Cone::Nonnegative, &[(k, -1.0)], -cable.lo);
            program.row(Cone::Nonnegative, &[(k, 1.0)], cable.hi);
        }
        let outcome = program.solve_quadratic(&p, &c);
        if outcome.class == Class::Feasible {
            Ok(outcome.x[..n].to_vec())
        } else {
            Err(ClarabelFailed {
                status: outcome.status,
            })
        }
    }
}
