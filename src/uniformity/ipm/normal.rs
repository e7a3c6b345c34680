//! The normal system `M = A Θ̃ Aᵀ` of the reduced Newton system: its pattern,
//! fill-reducing ordering and symbolic Cholesky factorisation (once), its
//! numeric factorisation per iteration (scaled to unit diagonal, shifted when a
//! pivot fails), the products with `A` and `Aᵀ`, and solves with iterative
//! refinement against the exact `M`.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::linalg::solvers::LltError;
use faer::perm::PermRef;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{FaerError, SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

use super::{IpmSettings, RatioLp};
use crate::algebra::norm_inf;
use crate::fdm::{d_sparsity, NONE};

/// The factorisation and the solves run on one thread: on super-100m's plan
/// LP (84 362 net nodes, 31 iterations) the interior point took 8.0 s with
/// faer's parallel supernodal kernels on two cores, 5.7 s sequential — a
/// solve with one right-hand side is memory-bound, and the supernodes of a
/// net's normal matrix are too small for the fork-join to pay.
const PAR: Par = Par::Seq;

/// Why the normal matrix could not be set up or factored.
#[derive(Debug, thiserror::Error)]
pub(crate) enum NormalError {
    /// A workspace could not be allocated.
    #[error("out of memory for {0}")]
    OutOfMemory(&'static str),
    /// The fill-reducing ordering of the node graph failed.
    #[error("AMD ordering: {0:?}")]
    Ordering(FaerError),
    /// The symbolic Cholesky factorisation failed.
    #[error("symbolic factorisation: {0:?}")]
    Symbolic(FaerError),
    /// The numeric factorisation failed even with the largest diagonal shift.
    #[error("numeric factorisation with a diagonal shift of {shift:.1e}: {error:?}")]
    Numeric {
        /// The last shift tried.
        shift: f64,
        /// faer's error.
        error: LltError,
    },
}

/// The normal matrix `M = A Θ̃ Aᵀ` (lower triangle, D×D blocks per node pair),
/// its symbolic factorisation, and the numeric factor of the current iteration.
pub(super) struct NormalMatrix<const D: usize> {
    pub(super) n_rows: usize,
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
    settings: IpmSettings,
}

impl<const D: usize> NormalMatrix<D> {
    pub(super) fn new(lp: &RatioLp<D>, settings: &IpmSettings) -> Result<Self, NormalError> {
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
                .map_err(|_| NormalError::OutOfMemory("the AMD ordering"))?;
            amd::order(
                &mut perm,
                &mut perm_inv,
                graph.as_ref(),
                amd::Control::default(),
                MemStack::new(&mut mem),
            )
            .map_err(NormalError::Ordering)?;
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
        .map_err(NormalError::Symbolic)?;
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(PAR, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, PAR),
        ]);
        let buffer =
            MemBuffer::try_new(req).map_err(|_| NormalError::OutOfMemory("the factorisation"))?;
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
            settings: *settings,
        })
    }

    /// `out = A v` (n_rows).
    pub(super) fn a_mul(&self, v: &[f64], out: &mut [f64]) {
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
    pub(super) fn at_mul(&self, y: &[f64], out: &mut [f64]) {
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
    pub(super) fn factorize(&mut self, theta: &[f64]) -> Result<(), NormalError> {
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
        let settings = &self.settings;
        let mut shift = settings.regularization;
        loop {
            for j in 0..self.n_rows {
                values[col_ptr[j]] += shift;
            }
            let factored = self.symbolic.factorize_numeric_llt(
                &mut self.factor,
                SparseColMatRef::new(self.pattern.as_ref(), values),
                Side::Lower,
                LltRegularization {
                    dynamic_regularization_delta: settings.pivot_delta,
                    dynamic_regularization_epsilon: settings.pivot_epsilon,
                },
                PAR,
                MemStack::new(&mut self.buffer),
                Default::default(),
            );
            match factored {
                Ok(_) => return Ok(()),
                Err(error) if shift >= settings.max_regularization => {
                    return Err(NormalError::Numeric { shift, error })
                }
                Err(_) => {
                    for j in 0..self.n_rows {
                        values[col_ptr[j]] -= shift;
                    }
                    shift *= settings.regularization_growth;
                }
            }
        }
    }

    /// `r ← M̂⁻¹ r` with the current (regularised) factor `M̂`.
    pub(super) fn precondition(&mut self, r: &mut [f64]) {
        for (v, s) in r.iter_mut().zip(&self.scale) {
            *v *= s;
        }
        let n = self.n_rows;
        let factor = LltRef::new(&self.symbolic, &self.factor);
        factor.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(r, n, 1),
            PAR,
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
    pub(super) fn solve(&mut self, theta: &[f64], b: &[f64]) -> Vec<f64> {
        let n = self.n_rows;
        let b_norm = norm_inf(b);
        let mut x = b.to_vec();
        self.precondition(&mut x);
        let mut scratch = vec![0.0; theta.len()];
        let mut mx = vec![0.0; n];
        let mut previous = f64::INFINITY;
        for _ in 0..self.settings.refinement_steps {
            self.at_mul(&x, &mut scratch);
            scratch.iter_mut().zip(theta).for_each(|(v, t)| *v *= t);
            self.a_mul(&scratch, &mut mx);
            let mut r: Vec<f64> = b.iter().zip(&mx).map(|(b, m)| b - m).collect();
            let norm = norm_inf(&r);
            if norm <= self.settings.refinement_tolerance * b_norm || norm > 0.5 * previous {
                break;
            }
            previous = norm;
            self.precondition(&mut r);
            x.iter_mut().zip(&r).for_each(|(x, r)| *x += r);
        }
        x
    }
}
