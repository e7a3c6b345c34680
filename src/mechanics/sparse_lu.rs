//! faer's sparse LU, always supernodal: the factorisation of a frame's
//! tangent (the truss alone, or the Schur complement the net is condensed
//! onto, [`super::condensed`]).
//!
//! faer's `solvers::SymbolicLu::try_new` chooses between its simplicial
//! (column by column, no dense kernels) and supernodal factorisations by a
//! flop ratio, and picks the simplicial one for a ring truss's tangent:
//! rods of a few elements each, joints, and — condensed — the dense block
//! of the net's attachment unknowns. Measured on realistic-26m (30 bays,
//! 180 attachment unknowns) its numeric factorisation was 38 % of a
//! `budget` run's whole time, design included; the supernodal one of the
//! same matrix, with the same fill-reducing column order (COLAMD), is what
//! this module gives.

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::lu::{
    factorize_symbolic_lu, LuRef, LuSymbolicParams, NumericLu, SymbolicLu as Symbolic,
};
use faer::sparse::linalg::{LuError, SupernodalThreshold};
use faer::sparse::{FaerError, SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par};

/// The parallelism of the factorisation and its solves: one thread. A
/// frame's supernodes are small (rods of a few elements, joints, the
/// attachment block), and faer's parallel kernels spent their time waiting
/// on each other: measured on whole designs, two threads against one,
/// the limit margin (a few hundred LUs of the truss) took 4.19 → 1.99 s on
/// realistic-26m, 3.85 → 1.89 s on paper-26m, 2.22 → 1.33 s on super-100m,
/// and super-100m's conventional assembly 5.88 → 5.06 s (its condensed
/// frame's LU). On a larger frame the two balance: super-60m with 120 bays
/// took 56.2 s with two threads and 57.4–58.4 s with one (verification
/// 6.7 s against 7.3–8.3 s, the margin 2.2 s against 1.5–1.8 s).
const PARALLELISM: Par = Par::Seq;

/// The symbolic analysis of a sparse LU: column order and supernodes, once
/// per pattern.
#[derive(Debug, Clone)]
pub(crate) struct SymbolicLu(Arc<Symbolic<usize>>);

/// A numeric sparse LU of one matrix of a [`SymbolicLu`]'s pattern.
pub(crate) struct Lu {
    symbolic: SymbolicLu,
    numeric: NumericLu<usize, f64>,
    /// The factorisation's workspace, kept for [`Lu::refactor`].
    scratch: MemBuffer,
    par: Par,
}

impl SymbolicLu {
    /// Analyse `pattern` (square).
    ///
    /// # Errors
    /// A pattern faer cannot analyse, or out of memory.
    pub(crate) fn try_new(pattern: SymbolicSparseColMatRef<'_, usize>) -> Result<Self, FaerError> {
        let params = LuSymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        Ok(SymbolicLu(Arc::new(factorize_symbolic_lu(
            pattern, params,
        )?)))
    }
}

impl Lu {
    /// Factor `matrix`, of `symbolic`'s pattern, with partial pivoting, in
    /// `previous`'s storage where it is a factor of the same pattern (a
    /// Newton iteration's refactorisation).
    ///
    /// # Errors
    /// A structurally or numerically singular matrix, or out of memory.
    pub(crate) fn refactor(
        symbolic: SymbolicLu,
        matrix: SparseColMatRef<'_, usize, f64>,
        previous: Option<Lu>,
    ) -> Result<Self, LuError> {
        let par = PARALLELISM;
        let (mut numeric, mut scratch) = match previous {
            Some(lu) if Arc::ptr_eq(&lu.symbolic.0, &symbolic.0) => (lu.numeric, lu.scratch),
            _ => {
                let req = symbolic
                    .0
                    .factorize_numeric_lu_scratch::<f64>(par, Default::default());
                let scratch = MemBuffer::try_new(req)
                    .map_err(|_| LuError::Generic(FaerError::OutOfMemory))?;
                (NumericLu::new(), scratch)
            }
        };
        symbolic.0.factorize_numeric_lu(
            &mut numeric,
            matrix,
            par,
            MemStack::new(&mut scratch),
            Default::default(),
        )?;
        Ok(Lu {
            symbolic,
            numeric,
            scratch,
            par,
        })
    }

    /// Solve `A x = rhs` in place.
    ///
    /// # Panics
    /// Out of memory for the solve's scratch (a few columns of the matrix's
    /// size: far below the factor's own).
    pub(crate) fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        let symbolic = &self.symbolic.0;
        let mut buffer =
            MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(rhs.ncols(), self.par));
        LuRef::new_unchecked(symbolic, &self.numeric).solve_in_place_with_conj(
            Conj::No,
            rhs,
            self.par,
            MemStack::new(&mut buffer),
        );
    }
}
