//! The pattern of a symmetric matrix on a net's free nodes in `b × b`
//! blocks — the pattern of the FDM matrix `D = C_fᵀ Q C_f` (eq. 3–4) with
//! each entry a dense block — with its fill-reducing ordering (AMD or nested
//! dissection on the node graph, whichever fills less: `ordering.rs`,
//! expanded blockwise) and its symbolic Cholesky factorisation.
//! The interior points of `ipm/` (normal matrix, `b = D`) and of the
//! gradient's exact finish (reduced Newton system, `b = 6`) share it.

use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{FaerError, SymbolicSparseColMat};
use faer::Side;

use super::ordering::{self, OrderingError};
use crate::fdm::{d_sparsity, NONE};

/// Why the pattern could not be set up.
#[derive(Debug, thiserror::Error)]
pub(crate) enum PatternError {
    /// The fill-reducing ordering of the node graph failed.
    #[error(transparent)]
    Ordering(#[from] OrderingError),
    /// The symbolic Cholesky factorisation failed.
    #[error("symbolic factorisation: {0:?}")]
    Symbolic(FaerError),
}

/// The lower triangle in `b × b` blocks: column `b f + c` holds rows
/// `b f + c .. b f + b` of the diagonal block, then the `b` rows of each
/// neighbour block, neighbours ascending.
pub(crate) struct BlockPattern {
    /// Per cable with two different free ends: the place of its upper end
    /// among the lower end's neighbours (`NONE` otherwise).
    pub(crate) neighbour: Vec<usize>,
    pub(crate) col_ptr: Vec<usize>,
    pub(crate) pattern: SymbolicSparseColMat<usize>,
    pub(crate) symbolic: SymbolicCholesky<usize>,
    /// What it was made for: the cables' ends (free indices, `NONE` for a
    /// fixed end), the free nodes, the block.
    pub(crate) ends: Vec<[usize; 2]>,
    n_free: usize,
    b: usize,
}

impl BlockPattern {
    /// The pattern of the cables `ends` (free indices, `NONE` for a fixed
    /// end) on `n_free` free nodes in `b × b` blocks.
    pub(crate) fn new(ends: &[[usize; 2]], n_free: usize, b: usize) -> Result<Self, PatternError> {
        let n_rows = b * n_free;
        // The node graph, a fixed end mapped to an extra node that is not free.
        let free_index: Vec<usize> = (0..n_free).chain([NONE]).collect();
        let node_edges: Vec<[usize; 2]> = ends
            .iter()
            .map(|e| e.map(|f| if f == NONE { n_free } else { f }))
            .collect();
        let (graph, slots) = d_sparsity(&node_edges, &free_index, n_free);
        let (graph_ptr, graph_idx) = (graph.col_ptr(), graph.row_idx());
        let neighbour = ends
            .iter()
            .zip(&slots)
            .map(|(&[a, c], slot)| {
                if a == NONE || c == NONE || a == c {
                    NONE
                } else {
                    slot.off_diagonal - graph_ptr[a.min(c)] - 1
                }
            })
            .collect();
        let neighbours = |f: usize| &graph_idx[graph_ptr[f] + 1..graph_ptr[f + 1]];

        let ordering::Ordering { perm, perm_inv, .. } = ordering::fill_reducing(graph.as_ref())?;
        let block_perm: Vec<usize> = (0..n_rows).map(|r| b * perm[r / b] + r % b).collect();
        let block_perm_inv: Vec<usize> = (0..n_rows).map(|r| b * perm_inv[r / b] + r % b).collect();

        let mut col_ptr = vec![0usize; n_rows + 1];
        for f in 0..n_free {
            let n_nb = neighbours(f).len();
            for c in 0..b {
                col_ptr[b * f + c + 1] = col_ptr[b * f + c] + (b - c) + b * n_nb;
            }
        }
        let mut row_idx = Vec::with_capacity(col_ptr[n_rows]);
        for f in 0..n_free {
            for c in 0..b {
                row_idx.extend(b * f + c..b * f + b);
                for &r in neighbours(f) {
                    row_idx.extend(b * r..b * r + b);
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
        .map_err(PatternError::Symbolic)?;
        Ok(BlockPattern {
            neighbour,
            col_ptr,
            pattern,
            symbolic,
            ends: ends.to_vec(),
            n_free,
            b,
        })
    }

    /// Whether this is the pattern [`BlockPattern::new`] makes of `ends`,
    /// `n_free` and `b`: a net of the same cables, ends and fixed nodes
    /// (its geometry may differ), whose matrices it factors as they are.
    pub(crate) fn fits(&self, ends: &[[usize; 2]], n_free: usize, b: usize) -> bool {
        self.n_free == n_free && self.b == b && self.ends == ends
    }
}
