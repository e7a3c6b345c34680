//! The normal system `M = A Θ̃ Aᵀ` of the reduced Newton system: its pattern,
//! fill-reducing ordering and symbolic Cholesky factorisation (once), its
//! numeric factorisation per iteration (scaled by node, shifted when a pivot
//! fails), the products with `A` and `Aᵀ`,
//! and solves with the factor (`supernodal.rs`'s kernel on a supernodal
//! factor) and with iterative refinement against the exact `M`.

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::LltRef;
use faer::sparse::SparseColMatRef;
use faer::{Conj, MatMut, Par, Side};

use super::data::RatioLp;
use super::error::NormalError;
use super::settings::IpmSettings;
use super::supernodal::Supernodes;
use crate::algebra::norm_inf;
use crate::fdm::NONE;
use crate::uniformity::block_pattern::BlockPattern;

/// The factorisation and the solves run on one thread: on super-100m's plan
/// LP (84 362 net nodes, 31 iterations) the interior point took 8.0 s with
/// faer's parallel supernodal kernels on two cores, 5.7 s sequential — a
/// solve with one right-hand side is memory-bound, and the supernodes of a
/// net's normal matrix are too small for the fork-join to pay.
const PAR: Par = Par::Seq;

/// The normal matrix `M = A Θ̃ Aᵀ` (lower triangle, D×D blocks per node pair),
/// its symbolic factorisation, and the numeric factor of the current iteration.
pub(super) struct NormalMatrix<const D: usize> {
    pub(super) n_rows: usize,
    /// Edge vectors in the `D` coordinates.
    u: Vec<[f64; D]>,
    /// The pattern, its ordering and symbolic factorisation, and the
    /// cables' ends it was made of: shared with the LPs of neighbouring
    /// geometries of the same net ([`super::WarmStart`]).
    structure: Arc<BlockPattern>,
    /// Values of `M`, scaled by node.
    values: Vec<f64>,
    /// Per free node, the scaling `S_i` of its rows and columns
    /// ([`NormalMatrix::scale_by_node_blocks`]).
    scaling: Vec<Block<D>>,
    factor: Vec<f64>,
    /// The factor's supernodes for the solves of
    /// [`NormalMatrix::precondition`] (`None` when faer chose a simplicial
    /// factor, which faer's own solve serves).
    supernodes: Option<Supernodes>,
    buffer: MemBuffer,
    settings: IpmSettings,
}

impl<const D: usize> NormalMatrix<D> {
    /// The normal matrix of `lp`, its symbolic analysis `reuse`d where that
    /// was made for the same net ([`BlockPattern::fits`]): the LP of a
    /// neighbouring geometry refactors numerically only.
    pub(super) fn new(
        lp: &RatioLp<D>,
        settings: &IpmSettings,
        reuse: Option<&Arc<BlockPattern>>,
    ) -> Result<Self, NormalError> {
        let n_free = lp.n_free;
        let n_rows = D * n_free;
        let u = lp.vectors.clone();
        let ends: Vec<[usize; 2]> = lp
            .ends
            .iter()
            .map(|e| e.map(|i| i.unwrap_or(NONE)))
            .collect();

        let structure = match reuse {
            Some(shared) if shared.fits(&ends, n_free, D) => Arc::clone(shared),
            _ => Arc::new(BlockPattern::new(&ends, n_free, D)?),
        };
        let symbolic = &structure.symbolic;
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(PAR, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, PAR),
        ]);
        let buffer =
            MemBuffer::try_new(req).map_err(|_| NormalError::OutOfMemory("the factorisation"))?;
        let factor = vec![0.0; symbolic.len_val()];
        let supernodes = Supernodes::of(symbolic);
        Ok(NormalMatrix {
            n_rows,
            u,
            values: vec![0.0; structure.col_ptr[n_rows]],
            structure,
            scaling: vec![Block::<D>::identity(); n_free],
            factor,
            supernodes,
            buffer,
            settings: *settings,
        })
    }

    /// The pattern and its analysis, for a neighbouring LP.
    pub(super) fn pattern(&self) -> Arc<BlockPattern> {
        Arc::clone(&self.structure)
    }

    /// `out = A v` (n_rows).
    pub(super) fn a_mul(&self, v: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        for ((&[a, b], uk), &vk) in self.structure.ends.iter().zip(&self.u).zip(v) {
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
        for ((&[a, b], uk), o) in self.structure.ends.iter().zip(&self.u).zip(out.iter_mut()) {
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

    /// Fills `M = A diag(theta) Aᵀ`, scales it by node
    /// ([`Self::scale_by_node_blocks`]) and factors it.
    pub(super) fn factorize(&mut self, theta: &[f64]) -> Result<(), NormalError> {
        let values = &mut self.values;
        values.fill(0.0);
        let col_ptr = &self.structure.col_ptr;
        for (k, (&[a, b], uk)) in self.structure.ends.iter().zip(&self.u).enumerate() {
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
                    let base = col_ptr[D * lo + c] + (D - c) + D * self.structure.neighbour[k];
                    let tc = t * uk[c];
                    for r in 0..D {
                        values[base + r] -= tc * uk[r];
                    }
                }
            }
        }
        self.scale_by_node_blocks();
        let (values, col_ptr) = (&mut self.values, &self.structure.col_ptr);
        // The smallest shift that factors: near the optimum a pivot can lose
        // positivity to rounding; a larger shift only slows the refinement.
        let settings = &self.settings;
        let mut shift = settings.regularization;
        loop {
            for j in 0..self.n_rows {
                values[col_ptr[j]] += shift;
            }
            let factored = self.structure.symbolic.factorize_numeric_llt(
                &mut self.factor,
                SparseColMatRef::new(self.structure.pattern.as_ref(), values),
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

    /// Scales `M` in place to `S M Sᵀ`, `S` block diagonal with `S_i = L_i⁻¹`
    /// for the Cholesky factor `L_i` of node `i`'s diagonal block `B_i`
    /// raised by [`NODE_BLOCK_FLOOR`] of its trace (`1` for a block without
    /// weight): every node's block becomes the identity but in directions
    /// weaker than that floor (the plan problem, `D = 2`).
    ///
    /// A unit diagonal is not enough. Near the optimum `Θ` spans ~10^±20, and
    /// at a node whose stiff cables run one way (the sagged boundary: its
    /// short cables carry 90× the set's least tension at `θ ≈ 6·10¹⁸`, the
    /// set's cables there sit at their floor) the block is stiff along the
    /// boundary and weak across it, while its diagonal mixes the two; scaled
    /// to a unit diagonal, the modes that only the weak directions resist sat
    /// under the static shift, and the factor dropped them. The plan LP of
    /// super-100m (84 242 free nodes) then stalled with a primal residual of
    /// 2.2e-7 of the largest tension at the boundary — 1.6e-5 of the set's
    /// least — and ended 3.1e-6 above clarabel's optimum after 43
    /// iterations; with the node blocks scaled it ends 7e-11 from it, the
    /// residual at 3e-12, after 26.
    ///
    /// The 3-D problem (`D = 3`) keeps the unit diagonal: its blocks hold the
    /// net's mechanisms (dependent rows of `A`), which the factor's dynamic
    /// regularisation drops pivot by pivot; scaled by blocks, small-hex's
    /// full LP stalled (`ipm::tests::full_problem_matches_clarabel_small_hex`).
    ///
    /// The floor: a direction of `B_i` weaker than `ε λ_max` is rounding
    /// (its entries carry absolute errors of `ε λ_max`); scaled up to unity
    /// it lifts those errors above the static shift and the scaled matrix is
    /// no longer positive definite (the six-sector grid of issue 38 at 2 431
    /// free nodes then factored with pivots of 10⁻³⁶ and its directions
    /// overflowed). Raised by `10⁻² tr B_i`, the errors stay below
    /// `ε/10⁻² ≈ 10⁻¹⁴`, under the shift of 10⁻¹³.
    fn scale_by_node_blocks(&mut self) {
        let (values, col_ptr) = (&mut self.values, &self.structure.col_ptr);
        let row_idx = self.structure.pattern.row_idx();
        let diagonal_block = |values: &[f64], i: usize| {
            Block::<D>::from_fn(|r, c| {
                let (r, c) = (r.max(c), r.min(c));
                values[col_ptr[D * i + c] + r - c]
            })
        };
        for (i, s) in self.scaling.iter_mut().enumerate() {
            let block = diagonal_block(values, i);
            *s = if D == 2 {
                let floor = NODE_BLOCK_FLOOR * block.trace();
                inverse_cholesky(block + Block::<D>::from_diagonal_element(floor))
            } else {
                unit_diagonal(&block)
            };
        }
        for (lo, s_lo) in self.scaling.iter().enumerate() {
            let scaled = s_lo * diagonal_block(values, lo) * s_lo.transpose();
            for c in 0..D {
                for r in c..D {
                    values[col_ptr[D * lo + c] + r - c] = scaled[(r, c)];
                }
            }
            // The blocks below the diagonal, one per higher neighbour: rows
            // `D·hi..`, after the diagonal block's `D − c` entries of column `c`.
            let neighbours = (col_ptr[D * lo + 1] - col_ptr[D * lo] - D) / D;
            for nb in 0..neighbours {
                let at = |c: usize| col_ptr[D * lo + c] + (D - c) + D * nb;
                let hi = row_idx[at(0)] / D;
                let block = Block::<D>::from_fn(|r, c| values[at(c) + r]);
                let scaled = self.scaling[hi] * block * s_lo.transpose();
                for c in 0..D {
                    for r in 0..D {
                        values[at(c) + r] = scaled[(r, c)];
                    }
                }
            }
        }
    }

    /// `r ← M̂⁻¹ r` with the current (regularised) factor `M̂` of `S M Sᵀ`:
    /// `M̂⁻¹ r = Sᵀ (S M Sᵀ)⁻¹ S r`.
    pub(super) fn precondition(&mut self, r: &mut [f64]) {
        self.apply_scaling(r, false);
        match &mut self.supernodes {
            Some(supernodes) => supernodes.solve(&self.factor, r),
            None => {
                let n = self.n_rows;
                LltRef::new(&self.structure.symbolic, &self.factor).solve_in_place_with_conj(
                    Conj::No,
                    MatMut::from_column_major_slice_mut(r, n, 1),
                    PAR,
                    MemStack::new(&mut self.buffer),
                );
            }
        }
        self.apply_scaling(r, true);
    }

    /// `r ← S r` (or `Sᵀ r`), node by node.
    fn apply_scaling(&self, r: &mut [f64], transposed: bool) {
        for (s, ri) in self.scaling.iter().zip(r.chunks_exact_mut(D)) {
            let v = nalgebra::SVector::<f64, D>::from_column_slice(ri);
            let scaled = if transposed { s.tr_mul(&v) } else { s * v };
            ri.copy_from_slice(scaled.as_slice());
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

/// A D×D block of the normal matrix.
type Block<const D: usize> = nalgebra::SMatrix<f64, D, D>;

/// The floor of a node's block in [`NormalMatrix::scale_by_node_blocks`],
/// relative to its trace.
const NODE_BLOCK_FLOOR: f64 = 1e-2;

/// `L⁻¹` for the Cholesky factor `L` of `block`, or the identity for a block
/// that has none (a node without weight).
fn inverse_cholesky<const D: usize>(block: Block<D>) -> Block<D> {
    block
        .cholesky()
        .and_then(|c| c.l().solve_lower_triangular(&Block::<D>::identity()))
        .filter(|s| s.iter().all(|v| v.is_finite()))
        .unwrap_or_else(Block::<D>::identity)
}

/// `diag(B)^(-1/2)` (`1` where a diagonal entry is not positive): the
/// scaling of `M` to a unit diagonal.
fn unit_diagonal<const D: usize>(block: &Block<D>) -> Block<D> {
    Block::<D>::from_diagonal(&block.diagonal().map(|d| {
        if d > 0.0 && d.is_finite() {
            1.0 / d.sqrt()
        } else {
            1.0
        }
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The plan LP of an `n × n` triangulated grid of free nodes inside a
    /// ring of fixed ones, every cable in the set.
    fn grid_lp(n: usize) -> RatioLp<2> {
        let id = |i: usize, j: usize| {
            (1..=n)
                .contains(&i)
                .then_some(())
                .and((1..=n).contains(&j).then_some((i - 1) * n + j - 1))
        };
        let (mut ends, mut vectors, mut lengths) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..=n + 1 {
            for j in 0..=n + 1 {
                for (di, dj) in [(1, 0), (0, 1), (1, 1)] {
                    let (a, b) = (id(i, j), id(i + di, j + dj));
                    if i + di <= n + 1 && j + dj <= n + 1 && (a.is_some() || b.is_some()) {
                        // A slightly sheared grid: no two cables alike.
                        let u = [di as f64 + 0.01 * j as f64, dj as f64 + 0.02 * i as f64];
                        ends.push([a, b]);
                        vectors.push(u);
                        lengths.push(u[0].hypot(u[1]));
                    }
                }
            }
        }
        let m = ends.len();
        RatioLp {
            n_free: n * n,
            ends,
            vectors,
            lengths,
            in_set: vec![true; m],
            min_other_tension: 1.0,
        }
    }

    /// A node held by a stiff cable one way (`θ = 10¹²`) and a slack one
    /// across (`θ = 1`), both oblique to the axes, as the sagged boundary's
    /// nodes near the optimum: the factor keeps the direction across, lifted
    /// to 10⁻¹⁰ by the node block's floor (the solve 1e-3 off). Scaled to a
    /// unit diagonal instead, that direction's eigenvalue is 2.7·10⁻¹², and
    /// the plan's static shift of 10⁻¹³ puts its solve 3.6 % off.
    #[test]
    fn node_blocks_keep_the_direction_across_a_stiff_cable() {
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let (along, across) = ([c, s], [-s, c]);
        let theta = [1e12, 1.0];
        let lp = RatioLp {
            n_free: 1,
            ends: vec![[Some(0), None]; 2],
            vectors: vec![along, across],
            lengths: vec![1.0; 2],
            in_set: vec![true; 2],
            min_other_tension: 1.0,
        };
        let mut normal = NormalMatrix::new(&lp, &IpmSettings::plan(), None).expect("normal matrix");
        normal.factorize(&theta).expect("factor");
        for b in [across, along, [1.0, 0.0]] {
            let mut x = b.to_vec();
            normal.precondition(&mut x);
            // M⁻¹ b = Σ_k u_k (u_kᵀ b)/θ_k for the orthonormal u_k.
            let exact: Vec<f64> = (0..2)
                .map(|i| {
                    [along, across]
                        .iter()
                        .zip(theta)
                        .map(|(u, t)| u[i] * (u[0] * b[0] + u[1] * b[1]) / t)
                        .sum()
                })
                .collect();
            let error = (x[0] - exact[0]).hypot(x[1] - exact[1]) / exact[0].hypot(exact[1]);
            assert!(error <= 1e-2, "M⁻¹ b off by {error:e} for b = {b:?}");
        }
    }

    /// The solves with the factor's own supernodal kernel agree with faer's
    /// supernodal solve to rounding (they differ only in the order of the
    /// sums; measured 5·10⁻¹⁴ of the solution), with `Θ` spanning twelve
    /// orders of magnitude (as near an optimum).
    #[test]
    fn own_supernodal_solve_matches_faer() {
        let lp = grid_lp(60);
        let mut normal = NormalMatrix::new(&lp, &IpmSettings::plan(), None).expect("normal matrix");
        assert!(
            normal.supernodes.is_some(),
            "faer chose a simplicial factor"
        );
        let m = lp.ends.len();
        let theta: Vec<f64> = (0..m)
            .map(|k| 10f64.powi((k * 7919 % 13) as i32 - 6))
            .collect();
        normal.factorize(&theta).expect("factor");
        let b: Vec<f64> = (0..normal.n_rows)
            .map(|i| ((i * 37 % 101) as f64 - 50.0) / 50.0)
            .collect();
        let mut own = b.clone();
        normal
            .supernodes
            .as_mut()
            .expect("supernodal")
            .solve(&normal.factor, &mut own);
        let mut reference = b;
        let n = normal.n_rows;
        LltRef::new(&normal.structure.symbolic, &normal.factor).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut reference, n, 1),
            Par::Seq,
            MemStack::new(&mut normal.buffer),
        );
        let scale = norm_inf(&reference);
        let difference = own
            .iter()
            .zip(&reference)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(
            difference <= 1e-12 * scale,
            "own solve differs by {difference:e} of {scale:e}"
        );
    }
}
