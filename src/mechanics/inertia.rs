//! The sparse inertia count of a symmetric tangent: how many eigenvalues
//! the stiffness has below zero on the joints' constraints, from the
//! pivots of a supernodal `LBLᵀ` ([`InertiaStructure`]), for tangents too
//! large for the dense count of [`super::stability`]. Its own file, below
//! both the assembly (which caches the structure per model) and the
//! stability test (which counts with it).

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{Argsort, Pair, SparseColMat, SymbolicSparseColMat};
use faer::Side;

use crate::algebra::Plain;

/// An equilibrium's tangent counts as symmetric when no entry differs from
/// its transpose's by more than this fraction of the largest entry: under
/// conservative loads it is, to the residual's roundoff; a moment fixed in
/// space (not conservative under finite rotations) makes it unsymmetric by
/// the moment's size.
pub(super) const SYMMETRY: f64 = 1e-8;

/// The negative eigenvalues of a block-diagonal `B` of 1×1 and 2×2 blocks,
/// given as each row's diagonal entry and the entry below it (nonzero: a
/// 2×2 block starts there). `None` when an entry is not finite (a zero
/// pivot met on the way).
pub(super) fn negative_pivots(mut rows: impl Iterator<Item = (f64, f64)>) -> Option<usize> {
    let mut negative = 0;
    while let Some((a, b)) = rows.next() {
        if !(a.is_finite() && b.is_finite()) {
            return None;
        }
        if b == 0.0 {
            negative += usize::from(a < 0.0);
            continue;
        }
        // A 2×2 block: its eigenvalues' signs from its determinant and
        // trace.
        let (c, _) = rows.next()?;
        if !c.is_finite() {
            return None;
        }
        let det = a * c - b * b;
        negative += match (det < 0.0, a + c < 0.0) {
            (true, _) => 1,
            (false, true) => 2,
            (false, false) => 0,
        };
    }
    Some(negative)
}

/// Where an entry of `J_ρ`'s lower triangle ([`InertiaStructure`]) takes
/// its value from: positions in the tangent's compressed columns.
#[derive(Debug, Clone, Copy)]
enum Source {
    /// The tangent's symmetric part at this position.
    Tangent(usize),
    /// `ρ aᵢ aⱼ`, the constraint row's entries at these two positions.
    Penalty(usize, usize),
}

/// The sparse inertia count of a model's tangents: the structure, analysed
/// once per model.
///
/// Without pivoting, an `LDLᵀ` of the saddle-point tangent
/// `J = [[H, Aᵀ], [A, 0]]` breaks on the zero block wherever a multiplier
/// comes before its joint's unknowns, and on `H` itself where a body or a
/// rod is held only by its joints (`H` is singular there: the rigid motions
/// the joints alone stop). The matrix factored is instead
///
/// ```text
/// J_ρ = ⎡ H + ρ AᵀA   Aᵀ ⎤  = Tᵀ J T,   T = ⎡ I      0 ⎤
///       ⎣ A           0  ⎦                  ⎣ ρA/2   I ⎦
/// ```
///
/// congruent to `J`, so of exactly its inertia (Sylvester) for any `ρ`
/// (the augmented Lagrangian: `H + ρAᵀA` is `H` on `ker A`). With
/// `ρ = 1/s` (`s` the constraint scale, [`super::assembly`]) the penalty
/// `s GᵀG` is as stiff as the stiffest element: enough, in practice, for
/// `H + ρAᵀA` to be positive definite wherever the frame is stable (it is
/// for `ρ` large enough, Finsler; a rod or body that only joints hold has
/// its rigid motions stiffened by it). The joint nodes' blocks it fills
/// are in the tangent's pattern already. The order eliminates `H`'s
/// unknowns by approximate minimum degree, each multiplier right after the
/// last of its joint's unknowns: every leading block is then the saddle
/// point of a part of the frame with the later unknowns clamped, which is
/// nonsingular when `H + ρAᵀA` is definite (its principal blocks are, and
/// `A`'s rows stay independent), so that no pivot is zero on a stable
/// state. Past a critical point the count stays exact while no pivot is;
/// faer's supernodal `LBLᵀ` pivots by Bunch–Kaufman inside each supernode,
/// against small pivots there. A pivot that is not finite (a zero one
/// met) leaves the count out (`None`), not wrong.
///
/// Measured against the dense count ([`super::stability::dense_negative_eigenvalues`], the
/// tests below): the same count at every point of load sweeps through the
/// column's two Euler loads, the Argyris frame's two bifurcations and the
/// ring truss's double one (bodies held by revolute and fixed joints only).
/// At 1 038 rows (the ring truss) it takes 4 ms where the dense count takes
/// 30–55 ms and the inverse iteration of [`super::stability::lowest_eigenpair`] 5 ms: one
/// symbolic analysis per model, one numeric factorisation per count.
///
/// Rejected: a penalty form `H + ρAᵀA` alone (no multipliers) counts
/// `H`'s negative eigenvalues on `ker A` only for `ρ` large against
/// `‖H‖²/μ` (`μ` the eigenvalue crossing zero, ~1e-8 of `‖H‖` for slender
/// rods), where roundoff in `ρAᵀA` swamps `H`; and a shift `−δI` on the
/// zero block, whose count is `J`'s only for `δ` below the least
/// eigenvalue, unknown near a crossing, and whose pivots grow as `1/δ`.
pub(crate) struct InertiaStructure {
    /// Position of each tangent entry's transpose.
    mirror: Vec<usize>,
    /// Free unknowns: the multipliers follow.
    n_free: usize,
    /// `ρ = 1/s`, m/N.
    rho: f64,
    /// `J_ρ`'s lower triangle: its pattern and each entry's source.
    symbolic: SymbolicSparseColMat<usize>,
    argsort: Argsort<usize>,
    source: Vec<Source>,
    /// Its symbolic supernodal factorisation in the order above.
    cholesky: SymbolicCholesky<usize>,
}

impl InertiaStructure {
    /// The structure for tangents of `j`'s pattern (structurally symmetric,
    /// every diagonal entry present), `n_free` free unknowns, constraint
    /// scale `scale` (N/m).
    ///
    /// # Errors
    /// A pattern that is not symmetric or that faer cannot analyse
    /// (named).
    pub(super) fn new(
        j: &SparseColMat<usize, f64>,
        n_free: usize,
        scale: f64,
    ) -> Result<Self, String> {
        let n = j.nrows();
        let (col_ptr, row_idx) = (j.symbolic().col_ptr(), j.symbolic().row_idx());
        let mut mirror = vec![0; row_idx.len()];
        let mut entries = Vec::new();
        for c in 0..n {
            for p in col_ptr[c]..col_ptr[c + 1] {
                let r = row_idx[p];
                let column = &row_idx[col_ptr[r]..col_ptr[r + 1]];
                let q = column.binary_search(&c).map_err(|_| {
                    format!("the tangent's pattern has ({r}, {c}) but not ({c}, {r})")
                })?;
                mirror[p] = col_ptr[r] + q;
                if r >= c {
                    entries.push((Pair { row: r, col: c }, Source::Tangent(p)));
                }
            }
        }
        // ρ AᵀA: A's row r is the multiplier column r above the diagonal.
        for r in n_free..n {
            let a: Vec<usize> = (col_ptr[r]..col_ptr[r + 1])
                .filter(|&p| row_idx[p] < n_free)
                .collect();
            for &p in &a {
                for &q in &a {
                    if row_idx[p] >= row_idx[q] {
                        let at = Pair {
                            row: row_idx[p],
                            col: row_idx[q],
                        };
                        entries.push((at, Source::Penalty(p, q)));
                    }
                }
            }
        }
        let (pairs, source): (Vec<_>, Vec<_>) = entries.into_iter().unzip();
        let (symbolic, argsort) = SymbolicSparseColMat::try_new_from_indices(n, n, &pairs)
            .map_err(|e| format!("pattern of the inertia count: {}", e.plain()))?;
        let order = Self::ordering(&symbolic, n_free)?;
        let cholesky = factorize_symbolic_cholesky(
            symbolic.as_ref(),
            Side::Lower,
            SymmetricOrdering::Custom(order.as_ref()),
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                ..Default::default()
            },
        )
        .map_err(|e| format!("symbolic LBLᵀ of the tangent: {}", e.plain()))?;
        Ok(InertiaStructure {
            mirror,
            n_free,
            rho: 1.0 / scale,
            symbolic,
            argsort,
            source,
            cholesky,
        })
    }

    /// The elimination order of `J_ρ` (lower pattern `symbolic`):
    /// the first `n_free` unknowns by approximate minimum degree, each
    /// multiplier right after the last of its unknowns (a multiplier
    /// coupled to none, last).
    fn ordering(
        symbolic: &SymbolicSparseColMat<usize>,
        n_free: usize,
    ) -> Result<faer::perm::Perm<usize>, String> {
        let n = symbolic.nrows();
        let (col_ptr, row_idx) = (symbolic.col_ptr(), symbolic.row_idx());
        let mut h_ptr = vec![0usize; n_free + 1];
        let mut h_idx = Vec::new();
        for c in 0..n_free {
            h_idx.extend(
                row_idx[col_ptr[c]..col_ptr[c + 1]]
                    .iter()
                    .filter(|&&r| r < n_free),
            );
            h_ptr[c + 1] = h_idx.len();
        }
        let h = SymbolicSparseColMat::new_checked(n_free, n_free, h_ptr, None, h_idx);
        let (mut fwd_h, mut inv_h) = (vec![0usize; n_free], vec![0usize; n_free]);
        let mut mem = MemBuffer::try_new(amd::order_scratch::<usize>(n_free, h.compute_nnz()))
            .map_err(|_| "out of memory for the AMD ordering of the tangent".to_string())?;
        amd::order(
            &mut fwd_h,
            &mut inv_h,
            h.as_ref(),
            amd::Control::default(),
            MemStack::new(&mut mem),
        )
        .map_err(|e| format!("AMD ordering of the tangent: {}", e.plain()))?;
        // The position after which each multiplier is eliminated.
        let mut last: Vec<Option<usize>> = vec![None; n - n_free];
        for c in 0..n_free {
            for &r in row_idx[col_ptr[c]..col_ptr[c + 1]]
                .iter()
                .filter(|&&r| r >= n_free)
            {
                let slot = &mut last[r - n_free];
                *slot = Some(slot.map_or(inv_h[c], |k: usize| k.max(inv_h[c])));
            }
        }
        let mut after = vec![Vec::new(); n_free];
        let mut loose = Vec::new();
        for (k, at) in last.iter().enumerate() {
            match at {
                Some(at) => after[*at].push(n_free + k),
                None => loose.push(n_free + k),
            }
        }
        let mut fwd = Vec::with_capacity(n);
        for (k, rows) in after.iter().enumerate() {
            fwd.push(fwd_h[k]);
            fwd.extend(rows);
        }
        fwd.extend(loose);
        let mut inv = vec![0usize; n];
        for (k, &i) in fwd.iter().enumerate() {
            inv[i] = k;
        }
        Ok(faer::perm::Perm::new_checked(
            fwd.into_boxed_slice(),
            inv.into_boxed_slice(),
            n,
        ))
    }

    /// The negative eigenvalues on the constraints of the tangent `j`
    /// (of the pattern analysed): the negative pivots of `J_ρ`'s
    /// supernodal `LBLᵀ`, less one per multiplier. `None` for `j`
    /// unsymmetric ([`SYMMETRY`]), out of memory or with a pivot that is
    /// not finite.
    pub(super) fn negative_eigenvalues(&self, j: &SparseColMat<usize, f64>) -> Option<usize> {
        let v = j.as_ref().val();
        let largest = v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        let asymmetry = v
            .iter()
            .zip(&self.mirror)
            .fold(0.0_f64, |m, (x, &q)| m.max((x - v[q]).abs()));
        if asymmetry > SYMMETRY * largest {
            return None;
        }
        let symmetric = |p: usize| 0.5 * (v[p] + v[self.mirror[p]]);
        let gathered: Vec<f64> = self
            .source
            .iter()
            .map(|s| match *s {
                Source::Tangent(p) => symmetric(p),
                Source::Penalty(p, q) => self.rho * symmetric(p) * symmetric(q),
            })
            .collect();
        let k =
            SparseColMat::new_from_argsort(self.symbolic.clone(), &self.argsort, &gathered).ok()?;
        let n = k.nrows();
        // One thread, as the frame's LU (`sparse_lu.rs`): a truss's
        // supernodes are small (realistic-26m's limit margin 2.01 → 1.86 s).
        let par = faer::Par::Seq;
        let mut l = vec![0.0; self.cholesky.len_val()];
        let mut subdiag = vec![0.0; n];
        let (mut fwd, mut inv) = (vec![0usize; n], vec![0usize; n]);
        let mut buffer = MemBuffer::try_new(
            self.cholesky
                .factorize_numeric_intranode_lblt_scratch::<f64>(par, Default::default()),
        )
        .ok()?;
        self.cholesky.factorize_numeric_intranode_lblt(
            &mut l,
            &mut subdiag,
            &mut fwd,
            &mut inv,
            k.as_ref(),
            Side::Lower,
            par,
            MemStack::new(&mut buffer),
            Default::default(),
        );
        let SymbolicCholeskyRaw::Supernodal(supernodal) = self.cholesky.raw() else {
            unreachable!("the inertia's factor is supernodal by its parameters")
        };
        // Each supernode's values: its columns, column-major, diagonal
        // block on top (B's diagonal on its diagonal).
        let (begin, end) = (supernodal.supernode_begin(), supernodal.supernode_end());
        let at = supernodal.col_ptr_for_val();
        let pivots = (0..supernodal.n_supernodes()).flat_map(|s| {
            let columns = end[s] - begin[s];
            let rows = (at[s + 1] - at[s]) / columns;
            (0..columns).map(move |c| (at[s] + c * rows + c, begin[s] + c))
        });
        let negative = negative_pivots(pivots.map(|(d, i)| (l[d], subdiag[i])))?;
        Some(negative.saturating_sub(n - self.n_free))
    }
}
