//! The preconditioned variables `φ = (ψ, b)` about a reference `q_r`: the
//! linearised equilibrium of the design geometry, factored once per run (see
//! the module documentation of [`super`]).

use std::cell::RefCell;

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::linalg::LltError;
use faer::sparse::{CreationError, FaerError, SparseColMat, Triplet};
use faer::{Mat, Side};

use super::map::Map;
use crate::uniformity::UniformityProblem;

/// Relative diagonal shift of `K` (dependent rows of `A`: flat nodes,
/// infinitesimal mechanisms).
const SHIFT: f64 = 1e-10;
/// How much more freely than a set cable's the other cables' force densities
/// absorb residual changes (`W`), in the start and the preconditioner.
const OTHER_FREEDOM: f64 = 1e4;
/// Where the positivity clamp `c(t)` leaves the identity.
const CLAMP_LOW: f64 = 0.25;

/// The positivity clamp `c(t)` of the preconditioned variables and `c'(t)`:
/// the identity on `[a, u_b]`, `a e^{(t−a)/a}` below `a` (→ 0), and
/// `u − (u − u_b) e^{−(t−u_b)/(u−u_b)}` above `u_b` (→ `u`, the bound); C¹.
pub(super) fn clamp(t: f64, upper: f64) -> (f64, f64) {
    let a = CLAMP_LOW;
    let start = a + 0.9 * (upper - a);
    if t < a {
        let e = ((t - a) / a).exp();
        (a * e, e)
    } else if t > start {
        let gap = upper - start;
        let e = (-(t - start) / gap).exp();
        (upper - gap * e, e)
    } else {
        (t, 1.0)
    }
}

/// Why `K = B W Bᵀ` of the linearised equilibrium could not be factored (the
/// preconditioner and the projected start fall back without it).
#[derive(Debug, thiserror::Error)]
pub(super) enum LinearisationError {
    /// The network has no free node, so `K` is empty.
    #[error("no free node")]
    NoFreeNode,
    /// Assembling `K` failed.
    #[error("{0:?}")]
    Assembly(CreationError),
    /// Its symbolic factorisation failed.
    #[error("{0:?}")]
    Symbolic(FaerError),
    /// Its numeric factorisation failed.
    #[error("{0:?}")]
    Numeric(LltError),
}

/// The linearised equilibrium of the design geometry around `q_r` (see the
/// module documentation): `B = A(x̂) diag(q_r)`, `K = B W Bᵀ` factored once,
/// `D_r = D(q_r)`.
pub(super) struct Preconditioner {
    q_ref: Vec<f64>,
    /// The map's floor `q_0`: `q` never goes below it.
    floor: f64,
    /// `c`'s upper asymptote `u_k = [q] / q_r,k` (times a hair below 1).
    upper: Vec<f64>,
    /// `W`.
    freedom: Vec<f64>,
    edges_vectors: Vec<[f64; 3]>,
    /// Free indices of every cable's end nodes.
    edges: Vec<[Option<usize>; 2]>,
    n_rows: usize,
    factor: Llt<usize, f64>,
    /// The last `(φ, Δ(φ))`: `Δ` of a nearby point is computed from it, so that
    /// the solve's rounding error scales with the step, not with `φ`.
    base: RefCell<(Vec<f64>, Vec<f64>)>,
}

impl Preconditioner {
    pub(super) fn new(
        problem: &UniformityProblem,
        q_ref: &[f64],
    ) -> Result<Self, LinearisationError> {
        Self::with_weights(problem, q_ref.to_vec(), q_ref)
    }

    /// `B = A(x̂) diag(g)` (g = q_r here; `dq/dθ` for the projected start).
    pub(super) fn with_weights(
        problem: &UniformityProblem,
        q_ref: Vec<f64>,
        g: &[f64],
    ) -> Result<Self, LinearisationError> {
        let structure = problem.structure();
        let edges: Vec<[Option<usize>; 2]> = structure
            .edges()
            .iter()
            .map(|&[i, j]| [structure.free_index(i), structure.free_index(j)])
            .collect();
        let n_rows = 3 * structure.free_nodes().len();
        if n_rows == 0 {
            return Err(LinearisationError::NoFreeNode);
        }
        let mut freedom = vec![OTHER_FREEDOM; edges.len()];
        for set in problem.sets() {
            for &k in &set.edges {
                freedom[k] = 1.0;
            }
        }
        let edges_vectors = problem.network().edges_vectors();
        let q_max = problem.max_force_density_n_per_m * (1.0 - 1e-6);
        let upper = q_ref.iter().map(|&q| q_max / q).collect();
        let factor = factor_k(&edges, &edges_vectors, &freedom, n_rows, g)?;
        Ok(Preconditioner {
            q_ref,
            floor: Map::new(problem).floor(),
            upper,
            freedom,
            edges_vectors,
            edges,
            n_rows,
            factor,
            base: RefCell::new((Vec::new(), Vec::new())),
        })
    }

    /// Refactors `K` for new column weights `g`.
    pub(super) fn refactor(&mut self, g: &[f64]) -> Result<(), LinearisationError> {
        self.factor = factor_k(
            &self.edges,
            &self.edges_vectors,
            &self.freedom,
            self.n_rows,
            g,
        )?;
        Ok(())
    }

    /// Number of variables `φ = (ψ, b)`.
    pub(super) fn dim(&self) -> usize {
        self.q_ref.len() + self.n_rows
    }

    /// `A(x̂) diag(g) v`.
    pub(super) fn b_times(&self, g: &[f64], v: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.n_rows];
        for (k, ends) in self.edges.iter().enumerate() {
            let value = g[k] * v[k];
            for (end, sign) in ends.iter().zip([1.0, -1.0]) {
                if let Some(f) = end {
                    for c in 0..3 {
                        out[3 * f + c] += sign * self.edges_vectors[k][c] * value;
                    }
                }
            }
        }
        out
    }

    /// `W diag(g) A(x̂)ᵀ μ`.
    pub(super) fn w_bt_times(&self, g: &[f64], mu: &[f64]) -> Vec<f64> {
        self.edges
            .iter()
            .enumerate()
            .map(|(k, ends)| {
                let mut sum = 0.0;
                for (end, sign) in ends.iter().zip([1.0, -1.0]) {
                    if let Some(f) = end {
                        for c in 0..3 {
                            sum += sign * self.edges_vectors[k][c] * mu[3 * f + c];
                        }
                    }
                }
                self.freedom[k] * g[k] * sum
            })
            .collect()
    }

    /// `D_r b`, per coordinate.
    pub(super) fn d_times(&self, b: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.n_rows];
        for (k, &[fi, fj]) in self.edges.iter().enumerate() {
            for c in 0..3 {
                let bi = fi.map_or(0.0, |f| b[3 * f + c]);
                let bj = fj.map_or(0.0, |f| b[3 * f + c]);
                let d = self.q_ref[k] * (bi - bj);
                if let Some(f) = fi {
                    out[3 * f + c] += d;
                }
                if let Some(f) = fj {
                    out[3 * f + c] -= d;
                }
            }
        }
        out
    }

    /// `K⁻¹ v`.
    pub(super) fn k_solve(&self, v: &[f64]) -> Vec<f64> {
        let mut rhs = Mat::<f64>::from_fn(self.n_rows, 1, |r, _| v[r]);
        self.factor.solve_in_place(rhs.as_mut());
        (0..self.n_rows).map(|r| rhs[(r, 0)]).collect()
    }

    /// `Δ(φ)`, from the last point evaluated: `Δ(φ₀) + Δ(φ − φ₀)` (linear).
    pub(super) fn delta(&self, phi: &[f64]) -> Vec<f64> {
        let mut base = self.base.borrow_mut();
        let delta = if base.0.len() == phi.len() {
            let step: Vec<f64> = phi.iter().zip(&base.0).map(|(a, b)| a - b).collect();
            let change = self.delta_linear(&step);
            base.1.iter().zip(&change).map(|(a, b)| a + b).collect()
        } else {
            self.delta_linear(phi)
        };
        *base = (phi.to_vec(), delta.clone());
        delta
    }

    /// `Δ(φ) = ψ + W Bᵀ K⁻¹ (D_r b − B ψ)`.
    pub(super) fn delta_linear(&self, phi: &[f64]) -> Vec<f64> {
        let m = self.q_ref.len();
        let (psi, b) = phi.split_at(m);
        let mut rhs = self.d_times(b);
        for (r, v) in rhs.iter_mut().zip(self.b_times(&self.q_ref, psi)) {
            *r -= v;
        }
        let back = self.w_bt_times(&self.q_ref, &self.k_solve(&rhs));
        psi.iter().zip(&back).map(|(p, b)| p + b).collect()
    }

    /// `q(φ)`, with `Δ(φ)` computed afresh.
    pub(super) fn q_exact(&self, phi: &[f64]) -> Vec<f64> {
        self.q_of_delta(&self.delta_linear(phi)).0
    }

    /// `q(φ) = max(q_r ∘ c(1 + Δ), q_0)` and `dq/dΔ`.
    pub(super) fn q(&self, phi: &[f64]) -> (Vec<f64>, Vec<f64>) {
        self.q_of_delta(&self.delta(phi))
    }

    pub(super) fn q_of_delta(&self, delta: &[f64]) -> (Vec<f64>, Vec<f64>) {
        delta
            .iter()
            .enumerate()
            .map(|(k, d)| {
                let (c, dc) = clamp(1.0 + d, self.upper[k]);
                let q = self.q_ref[k] * c;
                if q > self.floor {
                    (q, self.q_ref[k] * dc)
                } else {
                    (self.floor, 0.0)
                }
            })
            .unzip()
    }

    /// `dJ/dφ` from `dJ/dΔ`: `(g − Bᵀ K⁻¹ B W g, D_r K⁻¹ B W g)`.
    pub(super) fn pull_back(&self, gradient: &[f64]) -> Vec<f64> {
        let weighted: Vec<f64> = gradient
            .iter()
            .zip(&self.freedom)
            .map(|(g, f)| g * f)
            .collect();
        let y = self.k_solve(&self.b_times(&self.q_ref, &weighted));
        let mut back = self.w_bt_times(&self.q_ref, &y);
        for (b, f) in back.iter_mut().zip(&self.freedom) {
            *b /= f;
        }
        let mut out: Vec<f64> = gradient.iter().zip(&back).map(|(g, b)| g - b).collect();
        out.extend(self.d_times(&y));
        out
    }

    /// The equilibrium residual `A(x̂) q − p` of the design geometry.
    pub(super) fn residual(&self, q: &[f64], loads: &[f64]) -> Vec<f64> {
        let ones = vec![1.0; q.len()];
        let mut r = self.b_times(q, &ones);
        for (r, p) in r.iter_mut().zip(loads) {
            *r -= p;
        }
        r
    }
}

/// Factors `K = A G W G Aᵀ` (`G = diag(g)`, `W = diag(freedom)`), its diagonal
/// raised by [`SHIFT`].
pub(super) fn factor_k(
    edges: &[[Option<usize>; 2]],
    edges_vectors: &[[f64; 3]],
    freedom: &[f64],
    n_rows: usize,
    g: &[f64],
) -> Result<Llt<usize, f64>, LinearisationError> {
    let mut diagonal = vec![0.0; n_rows];
    let mut triplets = Vec::with_capacity(n_rows + 15 * g.len());
    let mut column: Vec<(usize, f64)> = Vec::with_capacity(6);
    for (k, (ends, u)) in edges.iter().zip(edges_vectors).enumerate() {
        column.clear();
        for (end, sign) in ends.iter().zip([1.0, -1.0]) {
            if let Some(f) = end {
                for (c, &uc) in u.iter().enumerate() {
                    column.push((3 * f + c, sign * uc));
                }
            }
        }
        // Rows ascending: (ra, rb) with b < a is in the lower triangle.
        column.sort_by_key(|&(r, _)| r);
        let scale = g[k] * g[k] * freedom[k];
        for (a, &(ra, va)) in column.iter().enumerate() {
            diagonal[ra] += va * va * scale;
            for &(rb, vb) in &column[..a] {
                triplets.push(Triplet::new(ra, rb, va * vb * scale));
            }
        }
    }
    triplets.extend(
        diagonal
            .iter()
            .enumerate()
            .map(|(r, &d)| Triplet::new(r, r, d * (1.0 + SHIFT))),
    );
    let k = SparseColMat::try_new_from_triplets(n_rows, n_rows, &triplets)
        .map_err(LinearisationError::Assembly)?;
    let symbolic =
        SymbolicLlt::try_new(k.symbolic(), Side::Lower).map_err(LinearisationError::Symbolic)?;
    Llt::try_new_with_symbolic(symbolic, k.as_ref(), Side::Lower)
        .map_err(LinearisationError::Numeric)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algebra::{dot, norm2};
    use crate::uniformity::gradient::fixtures::pattern;
    use crate::uniformity::gradient::fixtures::small_hex;

    #[test]
    fn clamp_is_continuously_differentiable_and_bounded() {
        let upper = 40.0;
        let h = 1e-7;
        for t in [-5.0, 0.0, CLAMP_LOW, 1.0, 30.0, 36.0, 50.0] {
            let (c, dc) = clamp(t, upper);
            assert!(c > 0.0 && c < upper, "c({t}) = {c}");
            let fd = (clamp(t + h, upper).0 - clamp(t - h, upper).0) / (2.0 * h);
            assert!((fd - dc).abs() <= 1e-6, "c'({t}) = {dc} vs {fd}");
        }
        assert_eq!(clamp(1.0, upper), (1.0, 1.0));
    }

    #[test]
    fn pull_back_is_the_transpose_of_the_preconditioner() {
        let problem = small_hex();
        let p = Preconditioner::new(&problem, &problem.network().q).unwrap();
        let m = problem.network().n_edges();
        let phi = pattern(p.dim(), 1);
        let g = pattern(m, 2);
        let lhs = dot(&g, &p.delta_linear(&phi));
        let rhs = dot(&p.pull_back(&g), &phi);
        // K's solves are accurate to about ε / SHIFT, its scaled condition.
        let tolerance = f64::EPSILON / SHIFT;
        assert!(
            (lhs - rhs).abs() <= tolerance * lhs.abs().max(rhs.abs()),
            "{lhs} vs {rhs}"
        );
    }

    #[test]
    fn self_stress_directions_keep_the_design_residual() {
        let problem = small_hex();
        let q_ref = &problem.network().q;
        let p = Preconditioner::new(&problem, q_ref).unwrap();
        let m = q_ref.len();
        let mut phi = vec![0.0; p.dim()];
        for (v, w) in phi[..m].iter_mut().zip(pattern(m, 3)) {
            *v = 0.1 * w;
        }
        let loads = problem.free_loads();
        let before = p.residual(q_ref, &loads);
        let after = p.residual(&p.q_exact(&phi), &loads);
        let change = norm2(
            &before
                .iter()
                .zip(&after)
                .map(|(a, b)| a - b)
                .collect::<Vec<_>>(),
        );
        // Without the projection, ψ alone would move it by B ψ.
        let unprojected = norm2(&p.b_times(q_ref, &phi[..m]));
        // The shift of K leaves the near-mechanism modes partly unprojected.
        assert!(
            change <= 1e-3 * unprojected,
            "residual moved by {change:e} of {unprojected:e}"
        );
    }

    #[test]
    fn cached_and_fresh_steps_agree() {
        let problem = small_hex();
        let p = Preconditioner::new(&problem, &problem.network().q).unwrap();
        let a: Vec<f64> = pattern(p.dim(), 4).iter().map(|v| 1e-3 * v).collect();
        let b: Vec<f64> = pattern(p.dim(), 5).iter().map(|v| 1e-3 * v).collect();
        p.delta(&a);
        let cached = p.delta(&b);
        let fresh = p.delta_linear(&b);
        // Both are accurate to about ε / SHIFT (K's scaled condition) of Δ.
        let size = fresh.iter().map(|v| v.abs()).fold(0.0, f64::max);
        let tolerance = 10.0 * f64::EPSILON / SHIFT * size;
        for (c, f) in cached.iter().zip(&fresh) {
            assert!((c - f).abs() <= tolerance, "{c} vs {f}");
        }
    }
}
