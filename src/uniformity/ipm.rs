//! A structure-exploiting primal–dual interior-point method (Mehrotra
//! predictor–corrector) for the ratio LP of one uniformity set (DESIGN §4):
//!
//! ```text
//! min s   s.t.  A q = 0,  q_k ≥ 1/ℓ_k (k ∈ S),  q_k ≥ f/ℓ_k (k ∉ S),
//!               ℓ_k q_k − s + w_k = 0, w_k ≥ 0 (k ∈ S)
//! ```
//!
//! `A` is the equilibrium matrix of the cables in `D` coordinates per free node
//! (`D = 3` for the full problem, `D = 2` for the plan problem of a reflector,
//! see `plan.rs`). In the shifted variables `x = q − lb ≥ 0` (`ℓ_k lb_k = 1` on
//! the set) the constraints read `A x = b := −A lb` and `w = s·e − E x − 1 ≥ 0`,
//! with `E` the set's rows of `diag(ℓ)` (one nonzero per row). With multipliers
//! `y` (for `A x = b`), `λ ≥ 0` (for `w ≥ 0`) and `z ≥ 0` (for `x ≥ 0`), dual
//! feasibility is `z = Eᵀλ − Aᵀy`, `eᵀλ = 1`.
//!
//! Each Newton system is reduced by eliminating `dz`, `dw` and then `dλ` (whose
//! block `G = EΘEᵀ + Ω` is diagonal because every set row of `E` holds a single
//! cable) to the bordered system
//!
//! ```text
//! [ A Θ̃ Aᵀ   a ] [dy]   [r1]       Θ̃_k = θ_k ω_j / (ℓ_k² θ_k + ω_j)  (k = S_j),
//! [ aᵀ      −γ ] [ds] = [r2]       Θ̃_k = θ_k otherwise,
//! ```
//!
//! `Θ = X Z⁻¹`, `Ω = W Λ⁻¹`, `a = A α` with `α_k = θ_k ℓ_k / G_j`, `γ = Σ 1/G_j`.
//! The normal matrix `M = A Θ̃ Aᵀ` has the pattern of `D = C_fᵀ Q C_f` with dense
//! D×D blocks: its pattern, fill-reducing ordering (AMD on the node graph,
//! expanded blockwise) and symbolic Cholesky factorisation are built once; every
//! iteration refills the values, scales `M` to unit diagonal, and refactors
//! numerically. Dependent rows of `A` (mechanisms of the net) show up as
//! (near-)zero pivots, which faer's dynamic regularisation replaces by a huge
//! pivot, i.e. the direction is dropped. The border is eliminated with the same
//! factor (`t = M̂⁻¹ a` once per iteration). This reduction, with the factor
//! `M̂` in place of `M`, is only a preconditioner: each Newton direction is
//! completed by FGMRES on the rows of the *unreduced* system it does not solve
//! exactly (`A dx = r_p`, the `w` rows, `eᵀdλ = r_s`), whose residuals are
//! formed from moderate quantities. Refining the reduced system instead
//! measures residuals of `A Θ Aᵀ dy` with `Θ` spanning ~10^±20 near the optimum
//! and loses the primal residual there (the run stalled at 3·10⁴ nodes).

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::perm::PermRef;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

use super::UniformityError;
use crate::fdm::{d_sparsity, NONE};

/// Relative tolerance on the dual residual and the duality gap.
const TOLERANCE: f64 = 1e-9;
/// Relative primal residual accepted before the final projection ([`Program::polish`]),
/// which restores equilibrium to rounding: near the optimum `Θ = X Z⁻¹` spans
/// some twenty orders of magnitude and the normal equations no longer resolve
/// the primal residual, while the gap and the dual residual still converge.
const PRIMAL_TOLERANCE: f64 = 1e-6;
/// Residuals and gap of an iterate accepted at reduced accuracy when the
/// method stalls.
const REDUCED_TOLERANCE: f64 = 1e-6;
/// Iterations without a better iterate after which the method counts as stalled.
const STALL_ITERATIONS: usize = 8;
/// Relative primal residual after the final projection.
const POLISHED: f64 = 1e-12;
/// Iteration limit.
const MAX_ITERATIONS: usize = 100;
/// Pivots of the unit-diagonal normal matrix below this are treated as zero …
const PIVOT_EPSILON: f64 = 1e-13;
/// … and replaced by this, which drops the direction (dependent rows of `A`).
const PIVOT_DELTA: f64 = 1e64;
/// Added to the unit diagonal of the normal matrix before it is factored.
/// Cable nets are mechanisms (`A` has dependent rows: the infinitesimal
/// mechanisms a prestress stiffens), so `M` is singular; the shift makes the
/// factor well defined, and iterative refinement against the exact `M` removes
/// its effect on the range, where every right-hand side lives.
const REGULARIZATION: f64 = 1e-14;
/// Largest shift tried when a factorisation fails.
const MAX_REGULARIZATION: f64 = 1e-6;
/// Refinement steps per solve with the normal matrix (at most) …
const REFINEMENT_STEPS: usize = 20;
/// … and their relative residual target.
const REFINEMENT_TOLERANCE: f64 = 1e-12;
/// FGMRES steps per Newton direction (at most) …
const KRYLOV_STEPS: usize = 8;
/// … and their target for the rows the factor solves inexactly, relative to
/// their right-hand side.
const KRYLOV_TOLERANCE: f64 = 1e-13;

/// How the interior-point method stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum IpmStatus {
    /// Relative residuals and gap are below the tolerance.
    Converged,
    /// The iterate stopped improving with residuals and gap below
    /// [`REDUCED_TOLERANCE`] (clarabel's `AlmostSolved`); its best iterate.
    ReducedAccuracy,
    /// The iteration limit came first.
    MaxIterations,
    /// A factorisation failed or the iterate stopped being finite or interior.
    NumericalFailure,
}

/// The outcome of [`solve`]: the last iterate, unscaled (the smallest set
/// tension is ≈ 1), and how the method stopped.
#[derive(Debug, Clone)]
pub(crate) struct IpmSolution {
    /// Force densities, N/m per unit tension: n_edges.
    pub q: Vec<f64>,
    /// Interior-point iterations.
    pub iterations: usize,
    /// How the method stopped.
    pub status: IpmStatus,
    /// Final relative primal residual, dual residual and gap.
    pub residuals: [f64; 3],
}

/// The data of the ratio LP in `D` coordinates per free node.
#[derive(Debug, Clone)]
pub(crate) struct RatioLp<const D: usize> {
    /// Number of free nodes (rows of `A`: `D` per free node).
    pub n_free: usize,
    /// Free indices of each cable's ends (`None` for a fixed end): n_cables.
    pub ends: Vec<[Option<usize>; 2]>,
    /// Edge vectors `x_i − x_j` in the `D` coordinates, m: n_cables.
    pub vectors: Vec<[f64; D]>,
    /// Lengths `ℓ_k` whose product with `q_k` is the tension, m: n_cables.
    pub lengths: Vec<f64>,
    /// Whether each cable is in the uniformity set: n_cables.
    pub in_set: Vec<bool>,
    /// Smallest tension of a cable outside the set, per unit smallest set tension.
    pub min_other_tension: f64,
}

/// The normal matrix `M = A Θ̃ Aᵀ` (lower triangle, D×D blocks per node pair),
/// its symbolic factorisation, and the numeric factor of the current iteration.
struct NormalMatrix<const D: usize> {
    n_rows: usize,
    /// Free indices of each cable's ends (`NONE` for a fixed end).
    ends: Vec<[usize; 2]>,
    /// Edge vectors in the `D` coordinates.
    u: Vec<[f64; D]>,
    /// For a cable with two free ends: the index of its upper end in the lower
    /// end's neighbour list (its off-diagonal block in that block column).
    neighbour: Vec<usize>,
    col_ptr: Vec<usize>,
    pattern: SymbolicSparseColMat<usize>,
    symbolic: SymbolicCholesky<usize>,
    /// Values of `M`, scaled to unit diagonal.
    values: Vec<f64>,
    /// `1/√M_ii`.
    scale: Vec<f64>,
    factor: Vec<f64>,
    buffer: MemBuffer,
    par: Par,
}

impl<const D: usize> NormalMatrix<D> {
    fn new(lp: &RatioLp<D>) -> Result<Self, UniformityError> {
        let n_free = lp.n_free;
        let n_rows = D * n_free;
        let u = lp.vectors.clone();
        let ends: Vec<[usize; 2]> = lp
            .ends
            .iter()
            .map(|e| e.map(|i| i.unwrap_or(NONE)))
            .collect();

        // The node graph is the pattern of `D = C_fᵀ Q C_f` (lower triangle, the
        // diagonal first in each column); a fixed end maps to an extra node that
        // is not free.
        let free_index: Vec<usize> = (0..n_free).chain([NONE]).collect();
        let node_edges: Vec<[usize; 2]> = ends
            .iter()
            .map(|e| e.map(|i| if i == NONE { n_free } else { i }))
            .collect();
        let (graph, slots) = d_sparsity(&node_edges, &free_index, n_free);
        let (graph_ptr, graph_idx) = (graph.col_ptr(), graph.row_idx());
        // A cable between free nodes: its place among the neighbours of its lower end.
        let neighbour = ends
            .iter()
            .zip(&slots)
            .map(|(&[a, b], slot)| {
                if a == NONE || b == NONE {
                    NONE
                } else {
                    slot.off_diagonal - graph_ptr[a.min(b)] - 1
                }
            })
            .collect();
        let neighbours = |f: usize| &graph_idx[graph_ptr[f] + 1..graph_ptr[f + 1]];

        // Fill-reducing ordering of the node graph, expanded to the D×D blocks.
        let mut perm = vec![0usize; n_free];
        let mut perm_inv = vec![0usize; n_free];
        {
            let mut mem = MemBuffer::try_new(amd::order_scratch::<usize>(n_free, graph_idx.len()))
                .map_err(|_| failed("out of memory for the AMD ordering"))?;
            amd::order(
                &mut perm,
                &mut perm_inv,
                graph.as_ref(),
                amd::Control::default(),
                MemStack::new(&mut mem),
            )
            .map_err(|e| failed(&format!("AMD ordering: {e:?}")))?;
        }
        let block_perm: Vec<usize> = (0..n_rows).map(|r| D * perm[r / D] + r % D).collect();
        let block_perm_inv: Vec<usize> = (0..n_rows).map(|r| D * perm_inv[r / D] + r % D).collect();

        // Pattern of M: column Df+c holds rows Df+c..Df+D of the diagonal block,
        // then the D rows of each neighbour block, ascending.
        let mut col_ptr = vec![0usize; n_rows + 1];
        for f in 0..n_free {
            let n_nb = neighbours(f).len();
            for c in 0..D {
                col_ptr[D * f + c + 1] = col_ptr[D * f + c] + (D - c) + D * n_nb;
            }
        }
        let mut row_idx = Vec::with_capacity(col_ptr[n_rows]);
        for f in 0..n_free {
            for c in 0..D {
                row_idx.extend(D * f + c..D * f + D);
                for &r in neighbours(f) {
                    row_idx.extend(D * r..D * r + D);
                }
            }
        }
        let pattern =
            SymbolicSparseColMat::new_checked(n_rows, n_rows, col_ptr.clone(), None, row_idx);
        let symbolic = factorize_symbolic_cholesky(
            pattern.as_ref(),
            Side::Lower,
            SymmetricOrdering::Custom(PermRef::new_checked(&block_perm, &block_perm_inv, n_rows)),
            Default::default(),
        )
        .map_err(|e| failed(&format!("symbolic factorisation: {e:?}")))?;
        let par = faer::get_global_parallelism();
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, par),
        ]);
        let buffer =
            MemBuffer::try_new(req).map_err(|_| failed("out of memory for the factorisation"))?;
        let factor = vec![0.0; symbolic.len_val()];
        Ok(NormalMatrix {
            n_rows,
            ends,
            u,
            neighbour,
            values: vec![0.0; col_ptr[n_rows]],
            col_ptr,
            pattern,
            symbolic,
            scale: vec![1.0; n_rows],
            factor,
            buffer,
            par,
        })
    }

    /// `out = A v` (n_rows).
    fn a_mul(&self, v: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        for ((&[a, b], uk), &vk) in self.ends.iter().zip(&self.u).zip(v) {
            if a != NONE {
                for c in 0..D {
                    out[D * a + c] += uk[c] * vk;
                }
            }
            if b != NONE {
                for c in 0..D {
                    out[D * b + c] -= uk[c] * vk;
                }
            }
        }
    }

    /// `out = Aᵀ y` (n_edges).
    fn at_mul(&self, y: &[f64], out: &mut [f64]) {
        for ((&[a, b], uk), o) in self.ends.iter().zip(&self.u).zip(out.iter_mut()) {
            let mut sum = 0.0;
            for c in 0..D {
                if a != NONE {
                    sum += uk[c] * y[D * a + c];
                }
                if b != NONE {
                    sum -= uk[c] * y[D * b + c];
                }
            }
            *o = sum;
        }
    }

    /// Fills `M = A diag(theta) Aᵀ`, scales it to unit diagonal and factors it.
    fn factorize(&mut self, theta: &[f64]) -> Result<(), String> {
        let values = &mut self.values;
        values.fill(0.0);
        let col_ptr = &self.col_ptr;
        for (k, (&[a, b], uk)) in self.ends.iter().zip(&self.u).enumerate() {
            let t = theta[k];
            for end in [a, b] {
                if end != NONE {
                    for c in 0..D {
                        let base = col_ptr[D * end + c];
                        let tc = t * uk[c];
                        for r in c..D {
                            values[base + r - c] += tc * uk[r];
                        }
                    }
                }
            }
            if a != NONE && b != NONE {
                let lo = a.min(b);
                for c in 0..D {
                    let base = col_ptr[D * lo + c] + (D - c) + D * self.neighbour[k];
                    let tc = t * uk[c];
                    for r in 0..D {
                        values[base + r] -= tc * uk[r];
                    }
                }
            }
        }
        for (i, s) in self.scale.iter_mut().enumerate() {
            let d = values[col_ptr[i]];
            *s = if d > 0.0 && d.is_finite() {
                1.0 / d.sqrt()
            } else {
                1.0
            };
        }
        let row_idx = self.pattern.row_idx();
        for j in 0..self.n_rows {
            let sj = self.scale[j];
            for p in col_ptr[j]..col_ptr[j + 1] {
                values[p] *= sj * self.scale[row_idx[p]];
            }
        }
        // The smallest shift that factors: near the optimum a pivot can lose
        // positivity to rounding; a larger shift only slows the refinement.
        let mut shift = REGULARIZATION;
        loop {
            for j in 0..self.n_rows {
                values[col_ptr[j]] += shift;
            }
            let factored = self.symbolic.factorize_numeric_llt(
                &mut self.factor,
                SparseColMatRef::new(self.pattern.as_ref(), values),
                Side::Lower,
                LltRegularization {
                    dynamic_regularization_delta: PIVOT_DELTA,
                    dynamic_regularization_epsilon: PIVOT_EPSILON,
                },
                self.par,
                MemStack::new(&mut self.buffer),
                Default::default(),
            );
            match factored {
                Ok(_) => return Ok(()),
                Err(e) if shift >= MAX_REGULARIZATION => return Err(format!("{e:?}")),
                Err(_) => {
                    for j in 0..self.n_rows {
                        values[col_ptr[j]] -= shift;
                    }
                    shift *= 100.0;
                }
            }
        }
    }

    /// `r ← M̂⁻¹ r` with the current (regularised) factor `M̂`.
    fn precondition(&mut self, r: &mut [f64]) {
        for (v, s) in r.iter_mut().zip(&self.scale) {
            *v *= s;
        }
        let n = self.n_rows;
        let factor = LltRef::new(&self.symbolic, &self.factor);
        factor.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(r, n, 1),
            self.par,
            MemStack::new(&mut self.buffer),
        );
        for (v, s) in r.iter_mut().zip(&self.scale) {
            *v *= s;
        }
    }

    /// `M⁻¹ b` for `M = A diag(theta) Aᵀ`: a solve with the factor of the
    /// regularised `M̂`, then iterative refinement against the exact `M` until
    /// the residual stops halving. `M` is singular when the net has mechanisms;
    /// every right-hand side lies in its range. (Conjugate gradients with the
    /// same preconditioner were tried: they lose the primal residual near the
    /// optimum, where refinement keeps it.)
    fn solve(&mut self, theta: &[f64], b: &[f64]) -> Vec<f64> {
        let n = self.n_rows;
        let b_norm = inf_norm(b);
        let mut x = b.to_vec();
        self.precondition(&mut x);
        let mut scratch = vec![0.0; theta.len()];
        let mut mx = vec![0.0; n];
        let mut previous = f64::INFINITY;
        for _ in 0..REFINEMENT_STEPS {
            self.at_mul(&x, &mut scratch);
            scratch.iter_mut().zip(theta).for_each(|(v, t)| *v *= t);
            self.a_mul(&scratch, &mut mx);
            let mut r: Vec<f64> = b.iter().zip(&mx).map(|(b, m)| b - m).collect();
            let norm = inf_norm(&r);
            if norm <= REFINEMENT_TOLERANCE * b_norm || norm > 0.5 * previous {
                break;
            }
            previous = norm;
            self.precondition(&mut r);
            x.iter_mut().zip(&r).for_each(|(x, r)| *x += r);
        }
        x
    }
}

fn failed(status: &str) -> UniformityError {
    UniformityError::SolverFailed {
        solver: "lp",
        status: format!("interior point: {status}"),
    }
}

/// The LP's data in the kernel's form: the set, lengths, bounds.
struct Program {
    m: usize,
    /// Cables of the set, `S_j`.
    set: Vec<usize>,
    /// Set index of each cable, or `NONE`.
    in_set: Vec<usize>,
    lengths: Vec<f64>,
    lower: Vec<f64>,
}

/// The per-iteration scaling of the reduced system.
struct Scaling {
    theta: Vec<f64>,
    /// `1/G_j`.
    g_inv: Vec<f64>,
    /// `Θ̃`.
    theta_tilde: Vec<f64>,
    /// `α`, nonzero on the set.
    alpha: Vec<f64>,
    /// `a = A α`.
    a: Vec<f64>,
    /// `t = M̂⁻¹ a`.
    t: Vec<f64>,
    /// `aᵀ t + γ`.
    schur: f64,
}

/// The best iterate so far, by its largest residual relative to its tolerance.
struct Best {
    score: f64,
    x: Vec<f64>,
    iteration: usize,
    residuals: [f64; 3],
    max_tension: f64,
}

/// A Newton direction.
struct Direction {
    dx: Vec<f64>,
    dz: Vec<f64>,
    dw: Vec<f64>,
    dlam: Vec<f64>,
    dy: Vec<f64>,
    ds: f64,
}

/// Right-hand sides of the Newton system.
struct Rhs<'a> {
    /// `b − A x`.
    rp: &'a [f64],
    /// `−(s e − E x − 1 − w)`.
    rw: &'a [f64],
    /// `Eᵀλ − Aᵀy − z`.
    rd: &'a [f64],
    /// `1 − eᵀλ`.
    rs: f64,
    /// Complementarity: `Z dx + X dz = r_xz`.
    rxz: &'a [f64],
    /// `Λ dw + W dλ = r_wλ`.
    rwl: &'a [f64],
}

impl Program {
    fn scaling<const D: usize>(
        &self,
        normal: &mut NormalMatrix<D>,
        theta: Vec<f64>,
        omega: &[f64],
    ) -> Result<Scaling, String> {
        let p = self.set.len();
        let mut g_inv = vec![0.0; p];
        let mut theta_tilde = theta.clone();
        let mut alpha = vec![0.0; self.m];
        let mut gamma = 0.0;
        for (j, &k) in self.set.iter().enumerate() {
            let l = self.lengths[k];
            let g = l * l * theta[k] + omega[j];
            g_inv[j] = 1.0 / g;
            theta_tilde[k] = theta[k] * omega[j] / g;
            alpha[k] = theta[k] * l / g;
            gamma += 1.0 / g;
        }
        let mut a = vec![0.0; normal.n_rows];
        normal.a_mul(&alpha, &mut a);
        normal.factorize(&theta_tilde)?;
        let mut t = a.clone();
        normal.precondition(&mut t);
        let schur = dot(&a, &t) + gamma;
        Ok(Scaling {
            theta,
            g_inv,
            theta_tilde,
            alpha,
            a,
            t,
            schur,
        })
    }

    /// Solves the bordered system `[M̂ a; aᵀ −γ] [dy; ds] = [r1; r2]` with the
    /// factor `M̂` of `M` by eliminating the border: `dy = M̂⁻¹ r1 − t ds`,
    /// `ds = (aᵀ M̂⁻¹ r1 − r2)/(aᵀ t + γ)`. Linear in the right-hand side: the
    /// preconditioner of [`Program::direction`].
    fn solve_bordered<const D: usize>(
        &self,
        normal: &mut NormalMatrix<D>,
        sc: &Scaling,
        r1: &[f64],
        r2: f64,
    ) -> (Vec<f64>, f64) {
        let mut u = r1.to_vec();
        normal.precondition(&mut u);
        let ds = (dot(&sc.a, &u) - r2) / sc.schur;
        let dy = u.iter().zip(&sc.t).map(|(ui, ti)| ui - ti * ds).collect();
        (dy, ds)
    }

    /// Solves the reduced Newton system for a given `θ`-scaling, with
    /// `g = X⁻¹ r_xz − r_d` and `h = r_w + Λ⁻¹ r_wλ` already formed:
    /// returns `(dx, dλ, dy, ds)` with `dx = Θ(Aᵀdy − Eᵀdλ + g)`.
    fn solve_reduced<const D: usize>(
        &self,
        normal: &mut NormalMatrix<D>,
        sc: &Scaling,
        g: &[f64],
        h: &[f64],
        rp: &[f64],
        rs: f64,
    ) -> (Vec<f64>, Vec<f64>, Vec<f64>, f64) {
        // r1 = r_p + A(−Θ̃ g + α h),  r2 = r_s − Σ_j (h_j + ℓ θ g)_j / G_j.
        let mut v: Vec<f64> = g
            .iter()
            .zip(&sc.theta_tilde)
            .map(|(gk, t)| -t * gk)
            .collect();
        let mut r2 = rs;
        for (j, &k) in self.set.iter().enumerate() {
            v[k] += sc.alpha[k] * h[j];
            r2 -= (h[j] + self.lengths[k] * sc.theta[k] * g[k]) * sc.g_inv[j];
        }
        let mut r1 = vec![0.0; normal.n_rows];
        normal.a_mul(&v, &mut r1);
        for (r, p) in r1.iter_mut().zip(rp) {
            *r += p;
        }
        let (dy, ds) = self.solve_bordered(normal, sc, &r1, r2);
        let mut atdy = vec![0.0; self.m];
        normal.at_mul(&dy, &mut atdy);
        let mut dlam = vec![0.0; self.set.len()];
        for (j, &k) in self.set.iter().enumerate() {
            let lt = self.lengths[k] * sc.theta[k];
            dlam[j] = (h[j] + lt * (g[k] + atdy[k]) - ds) * sc.g_inv[j];
        }
        let dx = (0..self.m)
            .map(|k| {
                let et = match self.in_set[k] {
                    NONE => 0.0,
                    j => self.lengths[k] * dlam[j],
                };
                sc.theta[k] * (atdy[k] - et + g[k])
            })
            .collect();
        (dx, dlam, dy, ds)
    }

    /// One Newton direction for the current iterate: the reduction
    /// ([`Program::direction_once`]) as a right preconditioner of FGMRES on
    /// the rows it solves only up to the factor's regularisation.
    #[allow(clippy::too_many_arguments)]
    fn direction<const D: usize>(
        &self,
        normal: &mut NormalMatrix<D>,
        sc: &Scaling,
        x: &[f64],
        z: &[f64],
        w: &[f64],
        lam: &[f64],
        rhs: &Rhs,
    ) -> Direction {
        let (m, p, n) = (self.m, self.set.len(), normal.n_rows);
        let mut d = self.direction_once(normal, sc, x, z, w, lam, rhs);
        // Measured limitation: on the full 3-D problem, whose `A` has dependent
        // rows (mechanisms), FGMRES makes the small test scenes stall at
        // reduced accuracy; there the reduction alone converges. The plan
        // problem (D = 2, a triangulated plan net) is where FGMRES is needed.
        if D == 3 {
            return d;
        }
        // Rows the reduction solves only up to the factor's regularisation:
        // A dx = r_p, dw + E dx − ds e = −r_w, eᵀdλ = r_s. The other rows hold
        // to rounding for any right-hand side, so FGMRES runs on these.
        let len = n + p + 1;
        let mut f = vec![0.0; len];
        f[..n].copy_from_slice(rhs.rp);
        for j in 0..p {
            f[n + j] = -rhs.rw[j];
        }
        f[n + p] = rhs.rs;
        let f_norm = norm2(&f);
        let mut kd = vec![0.0; len];
        self.krylov_rows(normal, &d, &mut kd);
        let mut r: Vec<f64> = f.iter().zip(&kd).map(|(a, b)| a - b).collect();
        let beta = norm2(&r);
        let tolerance = KRYLOV_TOLERANCE * f_norm;
        if beta.is_nan() || beta <= tolerance {
            return d;
        }
        let zero_m = vec![0.0; m];
        let zero_p = vec![0.0; p];
        r.iter_mut().for_each(|v| *v /= beta);
        let mut basis = vec![r];
        let mut zs: Vec<Direction> = Vec::new();
        let mut h: Vec<Vec<f64>> = Vec::new();
        let (mut cs, mut sn): (Vec<f64>, Vec<f64>) = (Vec::new(), Vec::new());
        let mut g = vec![beta];
        let mut rw = vec![0.0; p];
        for it in 0..KRYLOV_STEPS {
            let v = &basis[it];
            rw.iter_mut().zip(&v[n..n + p]).for_each(|(a, b)| *a = -b);
            let zj = self.direction_once(
                normal,
                sc,
                x,
                z,
                w,
                lam,
                &Rhs {
                    rp: &v[..n],
                    rw: &rw,
                    rd: &zero_m,
                    rs: v[n + p],
                    rxz: &zero_m,
                    rwl: &zero_p,
                },
            );
            let mut wv = vec![0.0; len];
            self.krylov_rows(normal, &zj, &mut wv);
            let mut col = vec![0.0; it + 2];
            for (i, vi) in basis.iter().enumerate() {
                let hij = dot(&wv, vi);
                col[i] = hij;
                wv.iter_mut().zip(vi).for_each(|(a, b)| *a -= hij * b);
            }
            let wn = norm2(&wv);
            col[it + 1] = wn;
            for i in 0..it {
                let (c, s_) = (cs[i], sn[i]);
                let (a, b) = (col[i], col[i + 1]);
                col[i] = c * a + s_ * b;
                col[i + 1] = -s_ * a + c * b;
            }
            let rho = col[it].hypot(col[it + 1]);
            let (c, s_) = if rho == 0.0 {
                (1.0, 0.0)
            } else {
                (col[it] / rho, col[it + 1] / rho)
            };
            col[it] = rho;
            col[it + 1] = 0.0;
            cs.push(c);
            sn.push(s_);
            g.push(-s_ * g[it]);
            g[it] *= c;
            h.push(col);
            zs.push(zj);
            let res = g[it + 1].abs();
            if res <= tolerance || wn == 0.0 || !res.is_finite() {
                break;
            }
            wv.iter_mut().for_each(|a| *a /= wn);
            basis.push(wv);
        }
        // Back substitution for the coefficients, then d += Σ y_i z_i.
        let k = zs.len();
        let mut y = vec![0.0; k];
        for i in (0..k).rev() {
            let mut v = g[i];
            for j in i + 1..k {
                v -= h[j][i] * y[j];
            }
            y[i] = v / h[i][i];
        }
        for (zi, yi) in zs.iter().zip(&y) {
            d.dx.iter_mut().zip(&zi.dx).for_each(|(a, b)| *a += yi * b);
            d.dz.iter_mut().zip(&zi.dz).for_each(|(a, b)| *a += yi * b);
            d.dw.iter_mut().zip(&zi.dw).for_each(|(a, b)| *a += yi * b);
            d.dlam
                .iter_mut()
                .zip(&zi.dlam)
                .for_each(|(a, b)| *a += yi * b);
            d.dy.iter_mut().zip(&zi.dy).for_each(|(a, b)| *a += yi * b);
            d.ds += yi * zi.ds;
        }
        d
    }

    /// The rows of the Newton system that FGMRES works on, applied to `d`:
    /// `(A dx, dw + E dx − ds e, eᵀdλ)`.
    fn krylov_rows<const D: usize>(
        &self,
        normal: &NormalMatrix<D>,
        d: &Direction,
        out: &mut [f64],
    ) {
        let n = normal.n_rows;
        let p = self.set.len();
        normal.a_mul(&d.dx, &mut out[..n]);
        for (j, &k) in self.set.iter().enumerate() {
            out[n + j] = d.dw[j] + self.lengths[k] * d.dx[k] - d.ds;
        }
        out[n + p] = d.dlam.iter().sum();
    }

    /// One solve of the Newton system through its reduction.
    #[allow(clippy::too_many_arguments)]
    fn direction_once<const D: usize>(
        &self,
        normal: &mut NormalMatrix<D>,
        sc: &Scaling,
        x: &[f64],
        z: &[f64],
        w: &[f64],
        lam: &[f64],
        rhs: &Rhs,
    ) -> Direction {
        let g: Vec<f64> = (0..self.m).map(|k| rhs.rxz[k] / x[k] - rhs.rd[k]).collect();
        let h: Vec<f64> = (0..self.set.len())
            .map(|j| rhs.rw[j] + rhs.rwl[j] / lam[j])
            .collect();
        let (dx, dlam, dy, ds) = self.solve_reduced(normal, sc, &g, &h, rhs.rp, rhs.rs);
        let dz = (0..self.m)
            .map(|k| (rhs.rxz[k] - z[k] * dx[k]) / x[k])
            .collect();
        let dw = (0..self.set.len())
            .map(|j| (rhs.rwl[j] - w[j] * dlam[j]) / lam[j])
            .collect();
        Direction {
            dx,
            dz,
            dw,
            dlam,
            dy,
            ds,
        }
    }
}

fn norm2(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn inf_norm(a: &[f64]) -> f64 {
    a.iter().fold(0.0, |m, v| m.max(v.abs()))
}

/// Largest step in `[0, 1]` keeping `v + α dv ≥ 0`.
fn max_step(v: &[f64], dv: &[f64]) -> f64 {
    v.iter().zip(dv).fold(
        1.0f64,
        |alpha, (&vi, &di)| {
            if di < 0.0 {
                alpha.min(-vi / di)
            } else {
                alpha
            }
        },
    )
}

/// Solves the ratio LP with the structured interior-point method. The returned
/// `q` is unscaled (smallest set tension ≈ 1); the caller rescales it.
///
/// # Panics
/// If the per-cable vectors of `lp` differ in length.
pub(crate) fn solve<const D: usize>(lp: &RatioLp<D>) -> Result<IpmSolution, UniformityError> {
    let m = lp.lengths.len();
    assert!(
        lp.ends.len() == m && lp.vectors.len() == m && lp.in_set.len() == m,
        "ratio LP: per-cable data of different lengths"
    );
    let f = lp.min_other_tension;
    if !(f.is_finite() && f > 0.0) {
        return Err(UniformityError::Invalid(format!(
            "minimum tension fraction {f} must be > 0"
        )));
    }
    let set: Vec<usize> = (0..m).filter(|&k| lp.in_set[k]).collect();
    if set.is_empty() {
        return Err(UniformityError::Invalid(
            "the uniformity set has no cable".into(),
        ));
    }
    let mut in_set = vec![NONE; m];
    for (j, &k) in set.iter().enumerate() {
        in_set[k] = j;
    }
    let lower: Vec<f64> = (0..m)
        .map(|k| if lp.in_set[k] { 1.0 } else { f } / lp.lengths[k])
        .collect();
    let program = Program {
        m,
        set,
        in_set,
        lengths: lp.lengths.clone(),
        lower,
    };
    let mut normal = NormalMatrix::new(lp)?;
    Ok(program.run(&mut normal))
}

impl Program {
    /// Projects `q` onto `A q = 0` in the metric of relative changes:
    /// `q ← q − W Aᵀ (A W Aᵀ)⁻¹ A q`, `W = diag(q²)`, so every cable moves by
    /// about the residual relative to its own force density (cables at a bound
    /// stay there to that order). Returns `q` and its relative residual.
    fn polish<const D: usize>(
        &self,
        normal: &mut NormalMatrix<D>,
        mut q: Vec<f64>,
        max_tension: f64,
    ) -> (Vec<f64>, f64) {
        let n = normal.n_rows;
        let mut residual = vec![0.0; n];
        let mut correction = vec![0.0; self.m];
        let weights: Vec<f64> = q.iter().map(|v| v * v).collect();
        if normal.factorize(&weights).is_err() {
            return (q, f64::INFINITY);
        }
        for _ in 0..2 {
            normal.a_mul(&q, &mut residual);
            if inf_norm(&residual) <= 0.1 * POLISHED * max_tension {
                break;
            }
            let v = normal.solve(&weights, &residual);
            normal.at_mul(&v, &mut correction);
            for ((qk, ck), wk) in q.iter_mut().zip(&correction).zip(&weights) {
                *qk -= wk * ck;
            }
        }
        normal.a_mul(&q, &mut residual);
        (q, inf_norm(&residual) / max_tension)
    }

    fn run<const D: usize>(&self, normal: &mut NormalMatrix<D>) -> IpmSolution {
        let m = self.m;
        let p = self.set.len();
        let n = normal.n_rows;
        let n_compl = (m + p) as f64;
        // b = −A lb.
        let mut b = vec![0.0; n];
        normal.a_mul(&self.lower, &mut b);
        b.iter_mut().for_each(|v| *v = -*v);

        // Starting point (Mehrotra): least-norm primal point with Θ = I, Ω = I,
        // then shifted into the interior together with the dual.
        let (mut x, mut w, mut s) = {
            let Ok(sc) = self.scaling(normal, vec![1.0; m], &vec![1.0; p]) else {
                return IpmSolution {
                    q: self.lower.clone(),
                    iterations: 0,
                    status: IpmStatus::NumericalFailure,
                    residuals: [f64::NAN; 3],
                };
            };
            let (dx, dlam, _, ds) =
                self.solve_reduced(normal, &sc, &vec![0.0; m], &vec![1.0; p], &b, 0.0);
            let w: Vec<f64> = dlam.iter().map(|v| -v).collect();
            (dx, w, ds)
        };
        let mut lam = vec![1.0 / p as f64; p];
        let mut y = vec![0.0; n];
        let mut z: Vec<f64> = (0..m)
            .map(|k| match self.in_set[k] {
                NONE => 0.0,
                j => self.lengths[k] * lam[j],
            })
            .collect();
        {
            let min_p = x.iter().chain(&w).fold(f64::INFINITY, |a, &v| a.min(v));
            let min_d = z.iter().chain(&lam).fold(f64::INFINITY, |a, &v| a.min(v));
            let dp = (-1.5 * min_p).max(0.0);
            let dd = (-1.5 * min_d).max(0.0);
            x.iter_mut().chain(w.iter_mut()).for_each(|v| *v += dp);
            z.iter_mut().chain(lam.iter_mut()).for_each(|v| *v += dd);
            let xz = dot(&x, &z) + dot(&w, &lam);
            let sum_p: f64 = x.iter().chain(&w).sum();
            let sum_d: f64 = z.iter().chain(&lam).sum();
            let dp = 0.5 * xz / sum_d;
            let dd = 0.5 * xz / sum_p;
            x.iter_mut().chain(w.iter_mut()).for_each(|v| *v += dp);
            z.iter_mut().chain(lam.iter_mut()).for_each(|v| *v += dd);
        }

        let mut rp = vec![0.0; n];
        let mut rd = vec![0.0; m];
        let mut rw = vec![0.0; p];
        let mut aty = vec![0.0; m];
        let mut residuals = [f64::INFINITY; 3];
        let mut best: Option<Best> = None;
        let mut failed = false;
        let mut iterations = 0;
        for iteration in 0..=MAX_ITERATIONS {
            iterations = iteration;
            // Residuals.
            normal.a_mul(&x, &mut rp);
            for (r, bi) in rp.iter_mut().zip(&b) {
                *r = bi - *r;
            }
            normal.at_mul(&y, &mut aty);
            let mut et_lam_norm = 0.0f64;
            for k in 0..m {
                let et = match self.in_set[k] {
                    NONE => 0.0,
                    j => self.lengths[k] * lam[j],
                };
                et_lam_norm = et_lam_norm.max(et.abs());
                rd[k] = et - aty[k] - z[k];
            }
            for (j, &k) in self.set.iter().enumerate() {
                rw[j] = w[j] + 1.0 + self.lengths[k] * x[k] - s;
            }
            let rs = 1.0 - lam.iter().sum::<f64>();
            let max_tension = (0..m)
                .map(|k| self.lengths[k] * (x[k] + self.lower[k]))
                .fold(0.0, f64::max);
            let primal = (inf_norm(&rp) / max_tension).max(inf_norm(&rw) / s.abs().max(1.0));
            let dual_scale = et_lam_norm.max(inf_norm(&aty)).max(inf_norm(&z));
            let dual = (inf_norm(&rd) / dual_scale).max(rs.abs());
            let complementarity = dot(&x, &z) + dot(&w, &lam);
            let gap = complementarity / s.abs().max(1.0);
            residuals = [primal, dual, gap];
            if !(primal.is_finite() && dual.is_finite() && gap.is_finite()) {
                failed = true;
                break;
            }
            let converged = primal <= PRIMAL_TOLERANCE && dual <= TOLERANCE && gap <= TOLERANCE;
            let score = (primal / PRIMAL_TOLERANCE)
                .max(dual / TOLERANCE)
                .max(gap / TOLERANCE);
            if converged || best.as_ref().is_none_or(|b: &Best| score < b.score) {
                best = Some(Best {
                    score,
                    x: x.clone(),
                    iteration,
                    residuals,
                    max_tension,
                });
            }
            let stalled = best
                .as_ref()
                .is_some_and(|b| iteration >= b.iteration + STALL_ITERATIONS);
            if converged || stalled {
                break;
            }
            if iteration == MAX_ITERATIONS {
                break;
            }
            let mu = complementarity / n_compl;

            // Factor the scaled normal matrix.
            let theta: Vec<f64> = x.iter().zip(&z).map(|(a, b)| a / b).collect();
            let omega: Vec<f64> = w.iter().zip(&lam).map(|(a, b)| a / b).collect();
            let Ok(sc) = self.scaling(normal, theta, &omega) else {
                failed = true;
                break;
            };

            // Predictor.
            let rxz: Vec<f64> = x.iter().zip(&z).map(|(a, b)| -a * b).collect();
            let rwl: Vec<f64> = w.iter().zip(&lam).map(|(a, b)| -a * b).collect();
            // Both directions share the factor and differ in the complementarity rows.
            let mut direction = |rxz: &[f64], rwl: &[f64]| {
                self.direction(
                    normal,
                    &sc,
                    &x,
                    &z,
                    &w,
                    &lam,
                    &Rhs {
                        rp: &rp,
                        rw: &rw,
                        rd: &rd,
                        rs,
                        rxz,
                        rwl,
                    },
                )
            };
            let affine = direction(&rxz, &rwl);
            let ap = max_step(&x, &affine.dx).min(max_step(&w, &affine.dw));
            let ad = max_step(&z, &affine.dz).min(max_step(&lam, &affine.dlam));
            let mu_aff = ((0..m)
                .map(|k| (x[k] + ap * affine.dx[k]) * (z[k] + ad * affine.dz[k]))
                .sum::<f64>()
                + (0..p)
                    .map(|j| (w[j] + ap * affine.dw[j]) * (lam[j] + ad * affine.dlam[j]))
                    .sum::<f64>())
                / n_compl;
            let sigma = (mu_aff / mu).powi(3).clamp(0.0, 1.0);

            // Corrector.
            let rxz: Vec<f64> = (0..m)
                .map(|k| sigma * mu - x[k] * z[k] - affine.dx[k] * affine.dz[k])
                .collect();
            let rwl: Vec<f64> = (0..p)
                .map(|j| sigma * mu - w[j] * lam[j] - affine.dw[j] * affine.dlam[j])
                .collect();
            let d = direction(&rxz, &rwl);
            let eta = (1.0 - mu.min(0.1)).clamp(0.9, 0.99995);
            let ap = (eta * max_step(&x, &d.dx).min(max_step(&w, &d.dw))).min(1.0);
            let ad = (eta * max_step(&z, &d.dz).min(max_step(&lam, &d.dlam))).min(1.0);
            let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
            if !(ap.is_finite()
                && ad.is_finite()
                && d.ds.is_finite()
                && finite(&d.dx)
                && finite(&d.dz)
                && finite(&d.dy))
            {
                failed = true;
                break;
            }
            for k in 0..m {
                x[k] += ap * d.dx[k];
                z[k] += ad * d.dz[k];
            }
            for j in 0..p {
                w[j] += ap * d.dw[j];
                lam[j] += ad * d.dlam[j];
            }
            s += ap * d.ds;
            for (yi, di) in y.iter_mut().zip(&d.dy) {
                *yi += ad * di;
            }
        }
        // The best iterate: converged, or accepted at reduced accuracy.
        let Some(best) = best.filter(|b| b.score * TOLERANCE <= REDUCED_TOLERANCE) else {
            return IpmSolution {
                q: x.iter().zip(&self.lower).map(|(a, l)| a + l).collect(),
                iterations,
                status: if failed {
                    IpmStatus::NumericalFailure
                } else {
                    IpmStatus::MaxIterations
                },
                residuals,
            };
        };
        let q: Vec<f64> = best.x.iter().zip(&self.lower).map(|(a, l)| a + l).collect();
        let (q, primal) = self.polish(normal, q, best.max_tension);
        let mut residuals = best.residuals;
        residuals[0] = primal;
        IpmSolution {
            q,
            iterations,
            status: if primal > POLISHED {
                IpmStatus::NumericalFailure
            } else if best.score <= 1.0 {
                IpmStatus::Converged
            } else {
                IpmStatus::ReducedAccuracy
            },
            residuals,
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::uniformity::lp::solve_full;
    use crate::uniformity::UniformityProblem;

    fn problem(path: &str) -> UniformityProblem {
        let scene = crate::Scene::read(std::path::Path::new(path)).expect("scene");
        crate::design::scene_problem(&scene).expect("problem").1
    }

    /// `Tmax/Tmin` of `q` over the problem's first set.
    pub(crate) fn set_ratio(problem: &UniformityProblem, q: &[f64]) -> f64 {
        let lengths = problem.lengths_m();
        let (min, max) = problem.sets()[0]
            .edges
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(min, max), &k| {
                (min.min(q[k] * lengths[k]), max.max(q[k] * lengths[k]))
            });
        max / min
    }

    /// The full (three-dimensional) ratio LP of a problem.
    fn full_lp(problem: &UniformityProblem) -> RatioLp<3> {
        let structure = problem.structure();
        let network = problem.network();
        let mut in_set = vec![false; network.n_edges()];
        for &k in &problem.sets()[0].edges {
            in_set[k] = true;
        }
        RatioLp {
            n_free: structure.free_nodes().len(),
            ends: network
                .edges
                .iter()
                .map(|e| e.map(|i| structure.free_index(i)))
                .collect(),
            vectors: network.edges_vectors(),
            lengths: problem.lengths_m().to_vec(),
            in_set,
            min_other_tension: problem.min_tension_fraction,
        }
    }

    /// The kernel on the full 3-D problem (mechanisms and all) reaches clarabel's
    /// optimum, balances the geometry, and keeps the bounds it was given.
    fn matches_clarabel(path: &str) {
        let problem = problem(path);
        let solution = solve(&full_lp(&problem)).expect("ipm");
        assert_eq!(solution.status, IpmStatus::Converged);
        let lengths = problem.lengths_m();
        let set = &problem.sets()[0].edges;
        let tension = |k: usize| solution.q[k] * lengths[k];
        let min = set
            .iter()
            .map(|&k| tension(k))
            .fold(f64::INFINITY, f64::min);
        let ratio = set_ratio(&problem, &solution.q);
        let (q, _) = solve_full(&problem, &mut Vec::new()).expect("clarabel");
        let reference = set_ratio(&problem, &q);
        assert!(
            (ratio - reference).abs() <= 1e-6 * reference,
            "{ratio} vs {reference}"
        );
        assert!(min >= 1.0 - 1e-8, "smallest set tension {min}");
        let max_tension = (0..lengths.len()).map(tension).fold(0.0, f64::max);
        let floor = problem.min_tension_fraction * (1.0 - 1e-8);
        assert!(problem.other_edges().iter().all(|&k| tension(k) >= floor));
        let residual = problem.prescribed_residual_n(&solution.q);
        assert!(
            residual <= 1e-9 * max_tension,
            "{residual} vs {max_tension}"
        );
    }

    #[test]
    fn full_problem_matches_clarabel_small_hex() {
        matches_clarabel("problems/small-hex.toml");
    }

    #[test]
    fn full_problem_matches_clarabel_small_offset() {
        matches_clarabel("problems/small-offset.toml");
    }
}
