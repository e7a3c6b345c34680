//! The tangent of a frame carrying a cable net, factored by condensing the
//! net onto the frame (DESIGN §7: the assembly of a design).
//!
//! The unknowns split into the net's *points* — nodes that only cables hold —
//! and the rest (frame nodes, joint multipliers):
//!
//! ```text
//! J = ⎡ A  B ⎤     A: the cables' stiffness among the points,
//!     ⎣ C  D ⎦     B, C: points ↔ the m attachment unknowns, C = Bᵀ.
//! ```
//!
//! Only cables touch the points, and every cable's tangent is symmetric
//! ([`super::cable`]), so `A` is symmetric and `C = Bᵀ`; `A` is positive
//! definite while the net is taut (a slack cable's negative geometric
//! stiffness is 1e-9 of the axial one it keeps). The Schur complement
//! `S = D − G`, `G = C A⁻¹ B`, differs from `D` on the `m × m` attachment
//! block only, so `S` keeps the frame's sparsity and is factored by sparse LU.
//!
//! `G` comes out of one sparse LDLᵀ: the quasi-definite matrix
//!
//! ```text
//! M = ⎡ A   Cᵀ ⎤     (attachment unknowns last, τ > 0 the scale of A's diagonal)
//!     ⎣ C  −τI ⎦
//! ```
//!
//! factored `M = L Λ Lᵀ` without pivoting (quasi-definite matrices factor
//! stably in any symmetric order, Vanderbei 1995) has the Schur complement
//! `Σ = −τI − G` of its last `m` rows in its last block, `Σ = L₂₂ Λ₂ L₂₂ᵀ`.
//! A solve `J (δp, δr) = (r_p, r_r)` is then two solves with `M`:
//!
//! 1. `M (u, v) = (r_p, 0)` gives `q = C A⁻¹ r_p = −Σ v`;
//! 2. `S δr = r_r − q`;
//! 3. `M (δp, w) = (r_p, q + Σ δr)`, whose first block is
//!    `δp = A⁻¹ (r_p − B δr)` (and `w = δr`).
//!
//! Measured per Newton iteration on the assemblies of super-60m (87 486
//! point unknowns, 7 554 others, 210 attachment unknowns) and super-100m
//! (265 320 unknowns): faer's sparse LU of the whole tangent took 1.1 s
//! and 11 s; `G` by `m` solves with an LDLᵀ of `A` took 1.0 s on top of the
//! LDLᵀ's 0.25 s at 60 m; this factor takes 0.29 s and 1.0 s, and the peak
//! memory of `ringmesh design problems/super-100m.toml` fell from 5.2 GB to
//! 1.7 GB.

use std::sync::Arc;

use super::sparse_lu::{Lu, SymbolicLu};
use crate::algebra::Plain;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::{LdltError, LdltRegularization};
use faer::linalg::{matmul, triangular_solve};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, supernodal::SupernodalLdltRef, CholeskySymbolicParams,
    SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{Pair, SparseColMatRef, SymbolicSparseColMat};
use faer::{Accum, Mat, MatMut, Par, Side};

/// The parallelism of the net's LDLᵀ and its solves: one thread, as the
/// frame's LU ([`super::sparse_lu`]). Two threads spent a third of the
/// CPU in the scheduler (faer's supernodes waiting on each other), and
/// were slower: super-100m's design tangent 1.52 → 0.86 s, its whole
/// `ringmesh design` 30.9–31.9 → 28.7–29.5 s (verification and the
/// conventional assembly); its tolerance samples, each on its own thread
/// already, unchanged (four in 42.1 s against 42.6 s).
const PARALLELISM: Par = Par::Seq;

/// Why a condensed factor could not be computed.
#[derive(Debug, Clone, thiserror::Error)]
pub(crate) enum CondensedError {
    /// A zero pivot of `M`'s LDLᵀ.
    #[error("LDLᵀ of the net: {0:?}")]
    Ldlt(LdltError),
    /// faer's sparse LU of `S` failed (the frame is a mechanism, or memory).
    #[error("LU of the frame: {0:?}")]
    SparseLu(faer::sparse::linalg::LuError),
    /// A workspace could not be allocated.
    #[error("out of memory for the factorisation")]
    OutOfMemory,
}

/// Where an entry of `M` or `S` takes its value from.
#[derive(Debug, Clone, Copy)]
enum Source {
    /// The tangent's value at this position of its pattern.
    Tangent(usize),
    /// `−τ` (a diagonal entry of `M`'s attachment block).
    Shift,
    /// `−G` at this position of the column-major attachment block.
    Coupling(usize),
}

/// A matrix whose entries are gathered from the tangent's values.
struct Block {
    symbolic: SymbolicSparseColMat<usize>,
    /// The sources of the entries, in the pattern's (compressed column)
    /// order: entry `k` sums `source[group[k]..group[k + 1]]`.
    source: Vec<Source>,
    group: Vec<usize>,
}

impl Block {
    fn new(n: usize, mut entries: Vec<(Pair<usize, usize>, Source)>) -> Self {
        // Stable: duplicates sum in the tangent's order.
        entries.sort_by_key(|(at, _)| (at.col, at.row));
        let mut col_ptr = vec![0usize; n + 1];
        let (mut row_idx, mut group) = (Vec::new(), Vec::new());
        for (k, (at, _)) in entries.iter().enumerate() {
            if k == 0 || entries[k - 1].0 != *at {
                group.push(k);
                row_idx.push(at.row);
                col_ptr[at.col + 1] += 1;
            }
        }
        group.push(entries.len());
        for j in 0..n {
            col_ptr[j + 1] += col_ptr[j];
        }
        Block {
            symbolic: SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx),
            source: entries.into_iter().map(|(_, source)| source).collect(),
            group,
        }
    }

    /// The matrix's values (its pattern's order) at the tangent's `values`,
    /// the shift `τ` and the coupling block `−G` (column-major), into `out`.
    fn values_into<T: Real>(&self, values: &[f64], tau: f64, minus_g: &[f64], out: &mut Vec<T>) {
        let value = |s: &Source| match *s {
            Source::Tangent(p) => values[p],
            Source::Shift => -tau,
            Source::Coupling(k) => minus_g[k],
        };
        out.clear();
        out.extend(
            self.group
                .windows(2)
                .map(|g| T::of(self.source[g[0]..g[1]].iter().map(value).sum())),
        );
    }
}

/// The split of a tangent's unknowns into points and the rest, the patterns
/// of `M` and `S`, and their symbolic factorisations: once per model.
pub(crate) struct Condensation {
    /// Unknown of each point, in the points' order (`M`'s first rows).
    points: Vec<usize>,
    /// Unknown of each other row, in their order (`S`'s rows).
    rest: Vec<usize>,
    /// Index in `rest` of each attachment unknown (`M`'s last rows).
    coupled: Vec<usize>,
    /// Tangent positions of the contributions to `A`'s diagonal: `τ` is the
    /// largest (any `τ > 0` gives the same `G`; `A`'s scale keeps `Σ` as
    /// well conditioned as `G + τI` can be).
    diagonal: Vec<usize>,
    m: Block,
    s: Block,
    ldlt: SymbolicCholesky<usize>,
    lu: Option<SymbolicLu>,
    par: Par,
}

/// The arithmetic of a factor of `M`: double, or single precision where
/// the factor only has to be near `M`'s (the iteration matrix of
/// [`super::statics::Linearisation::solve`], whose residuals are double).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Precision {
    /// `f64`.
    Double,
    /// `f32`.
    Single,
}

/// A factor's numeric storage in one precision, which a refactorisation
/// in it reuses: at 10⁵ nodes the first touch of a fresh buffer's pages
/// cost a third of the LDLᵀ.
struct Storage<T> {
    /// `M`'s values (its pattern's order).
    matrix: Vec<T>,
    /// `M`'s LDLᵀ values.
    l: Vec<T>,
    /// The LDLᵀ's workspace.
    scratch: MemBuffer,
}

/// `M`'s LDLᵀ, in the precision it was computed in.
enum Values {
    Double(Storage<f64>),
    Single(Storage<f32>),
}

/// A real type the net's LDLᵀ can be computed in.
trait Real: faer::traits::RealField + Copy {
    fn of(x: f64) -> Self;
    fn to(self) -> f64;
    /// `values`' storage, where it is in this type.
    fn stored(values: Values) -> Option<Storage<Self>>;
    /// `storage` as a factor's values.
    fn store(storage: Storage<Self>) -> Values;
}

impl Real for f64 {
    fn of(x: f64) -> Self {
        x
    }
    fn to(self) -> f64 {
        self
    }
    fn stored(values: Values) -> Option<Storage<Self>> {
        match values {
            Values::Double(storage) => Some(storage),
            Values::Single(_) => None,
        }
    }
    fn store(storage: Storage<Self>) -> Values {
        Values::Double(storage)
    }
}

impl Real for f32 {
    #[allow(clippy::cast_possible_truncation)]
    fn of(x: f64) -> Self {
        x as f32
    }
    fn to(self) -> f64 {
        f64::from(self)
    }
    fn stored(values: Values) -> Option<Storage<Self>> {
        match values {
            Values::Single(storage) => Some(storage),
            Values::Double(_) => None,
        }
    }
    fn store(storage: Storage<Self>) -> Values {
        Values::Single(storage)
    }
}

/// `L₂₂` (unit lower triangular) and `Λ₂`, the factors of `M`'s Schur
/// complement on its last `m` rows, `Σ = L₂₂ Λ₂ L₂₂ᵀ`.
type Trailing = (Mat<f64>, Vec<f64>);

/// A condensed factor of one tangent.
pub(crate) struct CondensedFactor {
    structure: Arc<Condensation>,
    /// `M`'s LDLᵀ values.
    l: Values,
    /// `L₂₂`, unit lower triangular, and `Λ₂`: the factors of `M`'s Schur
    /// complement on its last `m` rows, `Σ = L₂₂ Λ₂ L₂₂ᵀ`.
    l22: Mat<f64>,
    lambda2: Vec<f64>,
    s: Option<Lu>,
}

impl Condensation {
    /// The condensation of a tangent of `n_rows` unknowns with `pattern`
    /// (entries in value order, duplicates allowed, every diagonal present),
    /// whose unknowns with `point[i]` have symmetric entries only. `None`
    /// when there is no point.
    ///
    /// # Errors
    /// A pattern faer cannot analyse (named).
    pub(crate) fn new(
        n_rows: usize,
        pattern: &[Pair<usize, usize>],
        point: &[bool],
    ) -> Result<Option<Self>, String> {
        const NONE: usize = usize::MAX;
        let mut local = vec![NONE; n_rows];
        let (mut points, mut rest) = (Vec::new(), Vec::new());
        for i in 0..n_rows {
            let list = if point[i] { &mut points } else { &mut rest };
            local[i] = list.len();
            list.push(i);
        }
        if points.is_empty() {
            return Ok(None);
        }
        let n_p = points.len();
        // Attachment unknowns: the rest's rows of C.
        let mut coupled_index = vec![NONE; rest.len()];
        let mut coupled = Vec::new();
        for e in pattern.iter().filter(|e| !point[e.row] && point[e.col]) {
            let r = local[e.row];
            if coupled_index[r] == NONE {
                coupled_index[r] = coupled.len();
                coupled.push(r);
            }
        }
        let m = coupled.len();
        let (mut m_entries, mut s_entries, mut diagonal) = (Vec::new(), Vec::new(), Vec::new());
        for (p, e) in pattern.iter().enumerate() {
            let (row, col) = (local[e.row], local[e.col]);
            match (point[e.row], point[e.col]) {
                (true, true) if row >= col => {
                    m_entries.push((Pair { row, col }, Source::Tangent(p)));
                    if row == col {
                        diagonal.push(p);
                    }
                }
                (false, true) => {
                    let row = n_p + coupled_index[row];
                    m_entries.push((Pair { row, col }, Source::Tangent(p)));
                }
                (false, false) => s_entries.push((Pair { row, col }, Source::Tangent(p))),
                // A's upper triangle and B = Cᵀ.
                _ => {}
            }
        }
        for k in 0..m {
            let at = Pair {
                row: n_p + k,
                col: n_p + k,
            };
            m_entries.push((at, Source::Shift));
            for (i, &row) in coupled.iter().enumerate() {
                let at = Pair {
                    row,
                    col: coupled[k],
                };
                s_entries.push((at, Source::Coupling(k * m + i)));
            }
        }
        let m_block = Block::new(n_p + m, m_entries);
        let ldlt = factorize_symbolic_cholesky(
            m_block.symbolic.as_ref(),
            Side::Lower,
            SymmetricOrdering::Custom(ordering(&m_block.symbolic, n_p)?.as_ref()),
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                ..Default::default()
            },
        )
        .map_err(|e| format!("symbolic LDLᵀ of the net: {}", e.plain()))?;
        let s = Block::new(rest.len(), s_entries);
        let lu = if rest.is_empty() {
            None
        } else {
            Some(
                SymbolicLu::try_new(s.symbolic.as_ref())
                    .map_err(|e| format!("symbolic LU of the frame: {}", e.plain()))?,
            )
        };
        Ok(Some(Condensation {
            points,
            rest,
            coupled,
            diagonal,
            m: m_block,
            s,
            ldlt,
            lu,
            par: PARALLELISM,
        }))
    }

    /// Factor the tangent with `values` (pattern order), in `previous`'s
    /// storage where it has `precision`.
    ///
    /// # Errors
    /// A zero pivot of `M` (a point no taut cable holds) or a singular `S`.
    pub(crate) fn factor(
        self: &Arc<Self>,
        values: &[f64],
        precision: Precision,
        previous: Option<CondensedFactor>,
    ) -> Result<CondensedFactor, CondensedError> {
        let (storage, previous_s) = match previous {
            Some(f) => (Some(f.l), f.s),
            None => (None, None),
        };
        let m = self.coupled.len();
        let tau = self
            .diagonal
            .iter()
            .map(|&p| values[p].abs())
            .fold(f64::MIN_POSITIVE, f64::max);
        let (l, (l22, lambda2)) = match precision {
            Precision::Double => self.numeric::<f64>(values, tau, storage)?,
            Precision::Single => self.numeric::<f32>(values, tau, storage)?,
        };
        let s = match &self.lu {
            None => None,
            Some(lu) => {
                // −G = Σ + τI, Σ = L₂₂ Λ₂ L₂₂ᵀ
                let sigma = &Mat::from_fn(m, m, |i, j| l22[(i, j)] * lambda2[j]) * l22.transpose();
                let mut minus_g: Vec<f64> = (0..m * m).map(|k| sigma[(k % m, k / m)]).collect();
                for k in 0..m {
                    minus_g[k * m + k] += tau;
                }
                let mut s_values = Vec::new();
                self.s.values_into(values, tau, &minus_g, &mut s_values);
                let s = SparseColMatRef::new(self.s.symbolic.as_ref(), &s_values);
                Some(Lu::refactor(lu.clone(), s, previous_s).map_err(CondensedError::SparseLu)?)
            }
        };
        Ok(CondensedFactor {
            structure: self.clone(),
            l,
            l22,
            lambda2,
            s,
        })
    }

    /// `M`'s LDLᵀ in `T` at the tangent's `values` and the shift `tau` (in
    /// `previous`'s storage where it is in `T`), and the factors `L₂₂`, `Λ₂`
    /// of its trailing Schur complement.
    fn numeric<T: Real>(
        &self,
        values: &[f64],
        tau: f64,
        previous: Option<Values>,
    ) -> Result<(Values, Trailing), CondensedError> {
        let par = self.par;
        let mut storage = match previous.and_then(T::stored) {
            Some(storage) => storage,
            None => Storage {
                matrix: Vec::new(),
                l: Vec::new(),
                scratch: MemBuffer::try_new(
                    self.ldlt
                        .factorize_numeric_ldlt_scratch::<T>(par, Default::default()),
                )
                .map_err(|_| CondensedError::OutOfMemory)?,
            },
        };
        self.m.values_into(values, tau, &[], &mut storage.matrix);
        // faer zeroes the values itself.
        storage.l.resize(self.ldlt.len_val(), T::zero());
        self.ldlt
            .factorize_numeric_ldlt(
                &mut storage.l,
                SparseColMatRef::new(self.m.symbolic.as_ref(), &storage.matrix),
                Side::Lower,
                LdltRegularization::default(),
                par,
                MemStack::new(&mut storage.scratch),
                Default::default(),
            )
            .map_err(CondensedError::Ldlt)?;
        let trailing = trailing_factor(
            &self.ldlt,
            &storage.l,
            self.points.len(),
            self.coupled.len(),
        );
        Ok((T::store(storage), trailing))
    }
}

/// A fill-reducing order of `M` (pattern `symbolic`, lower triangle): the
/// first `n_p` rows by approximate minimum degree, the rest last in their
/// order, so that their Schur complement is the factor's last block.
fn ordering(
    symbolic: &SymbolicSparseColMat<usize>,
    n_p: usize,
) -> Result<faer::perm::Perm<usize>, String> {
    let n = symbolic.nrows();
    // A's pattern: M's columns and rows below n_p.
    let (col_ptr, row_idx) = (symbolic.col_ptr(), symbolic.row_idx());
    let mut a_ptr = vec![0usize; n_p + 1];
    let mut a_idx = Vec::new();
    for j in 0..n_p {
        a_idx.extend(
            row_idx[col_ptr[j]..col_ptr[j + 1]]
                .iter()
                .filter(|&&i| i < n_p),
        );
        a_ptr[j + 1] = a_idx.len();
    }
    let a = SymbolicSparseColMat::new_checked(n_p, n_p, a_ptr, None, a_idx);
    let (mut fwd, mut inv) = (vec![0usize; n_p], vec![0usize; n_p]);
    let mut mem = MemBuffer::try_new(amd::order_scratch::<usize>(n_p, a.compute_nnz()))
        .map_err(|_| "out of memory for the AMD ordering of the net".to_string())?;
    amd::order(
        &mut fwd,
        &mut inv,
        a.as_ref(),
        amd::Control::default(),
        MemStack::new(&mut mem),
    )
    .map_err(|e| format!("AMD ordering of the net: {}", e.plain()))?;
    fwd.extend(n_p..n);
    inv.extend(n_p..n);
    Ok(faer::perm::Perm::new_checked(
        fwd.into_boxed_slice(),
        inv.into_boxed_slice(),
        n,
    ))
}

/// `L₂₂` and `Λ₂` of `Σ = L₂₂ Λ₂ L₂₂ᵀ`, the Schur complement of the last
/// `m` of `n_p + m` rows, from the supernodal LDLᵀ values `l` (the last `m`
/// rows are the last `m` of the ordering: [`ordering`]).
fn trailing_factor<T: Real>(
    symbolic: &SymbolicCholesky<usize>,
    l: &[T],
    n_p: usize,
    m: usize,
) -> Trailing {
    let mut l22 = Mat::<f64>::zeros(m, m);
    let mut lambda = vec![0.0; m];
    let factor = supernodal(symbolic, l);
    for s in 0..factor.symbolic().n_supernodes() {
        let node = factor.supernode(s);
        let (start, val) = (node.start(), node.val());
        let n_cols = val.ncols();
        for jj in 0..n_cols {
            let j = start + jj;
            if j < n_p {
                continue;
            }
            let c = j - n_p;
            lambda[c] = val[(jj, jj)].to();
            l22[(c, c)] = 1.0;
            for ii in jj + 1..n_cols {
                l22[(start + ii - n_p, c)] = val[(ii, jj)].to();
            }
            for (k, &row) in node.pattern().iter().enumerate() {
                l22[(row - n_p, c)] = val[(n_cols + k, jj)].to();
            }
        }
    }
    (l22, lambda)
}

/// The supernodal LDLᵀ of `M`.
fn supernodal<'a, T: Real>(
    symbolic: &'a SymbolicCholesky<usize>,
    l: &'a [T],
) -> SupernodalLdltRef<'a, usize, T> {
    let SymbolicCholeskyRaw::Supernodal(supernodal) = symbolic.raw() else {
        unreachable!("the condensation's factor is supernodal by its parameters")
    };
    SupernodalLdltRef::new(supernodal, l)
}

/// A scratch block of as many rows as the longest pattern below a
/// supernode of `factor`, `k` columns.
fn scratch<T: Real>(factor: SupernodalLdltRef<'_, usize, T>, k: usize) -> Mat<T> {
    let rows = (0..factor.symbolic().n_supernodes())
        .map(|s| factor.supernode(s).pattern().len())
        .max()
        .unwrap_or(0);
    Mat::zeros(rows, k)
}

/// `x ← L⁻¹ x` (the factor's order), supernode by supernode.
fn forward_sweep<T: Real>(factor: SupernodalLdltRef<'_, usize, T>, mut x: MatMut<'_, T>, par: Par) {
    let k = x.ncols();
    let mut product = scratch(factor, k);
    for s in 0..factor.symbolic().n_supernodes() {
        let node = factor.supernode(s);
        let (size, pattern) = (node.val().ncols(), node.pattern());
        let (top, bottom) = node.val().split_at_row(size);
        let mut x_top = x.rb_mut().subrows_mut(node.start(), size);
        triangular_solve::solve_unit_lower_triangular_in_place(top, x_top.rb_mut(), par);
        let mut product = product.rb_mut().subrows_mut(0, pattern.len());
        matmul::matmul(
            product.rb_mut(),
            Accum::Replace,
            bottom,
            x_top.rb(),
            T::one(),
            par,
        );
        for j in 0..k {
            for (idx, &i) in pattern.iter().enumerate() {
                x[(i, j)] -= product[(idx, j)];
            }
        }
    }
}

/// `x ← L⁻ᵀ Λ⁻¹ x` (the factor's order), supernode by supernode.
fn backward_sweep<T: Real>(
    factor: SupernodalLdltRef<'_, usize, T>,
    mut x: MatMut<'_, T>,
    par: Par,
) {
    let k = x.ncols();
    let mut below = scratch(factor, k);
    for s in (0..factor.symbolic().n_supernodes()).rev() {
        let node = factor.supernode(s);
        let (size, pattern) = (node.val().ncols(), node.pattern());
        let (top, bottom) = node.val().split_at_row(size);
        let d = top.diagonal().column_vector();
        let mut below = below.rb_mut().subrows_mut(0, pattern.len());
        for j in 0..k {
            for (idx, &i) in pattern.iter().enumerate() {
                below[(idx, j)] = x[(i, j)];
            }
            for idx in 0..size {
                x[(node.start() + idx, j)] /= d[idx];
            }
        }
        let mut x_top = x.rb_mut().subrows_mut(node.start(), size);
        matmul::matmul(
            x_top.rb_mut(),
            Accum::Add,
            bottom.transpose(),
            below.rb(),
            -T::one(),
            par,
        );
        triangular_solve::solve_unit_upper_triangular_in_place(top.transpose(), x_top, par);
    }
}

impl CondensedFactor {
    /// Solve `J Δ = rhs` in place (every column of `rhs`).
    ///
    /// The two solves with `M` share their forward sweep `y = L⁻¹ P b`: its
    /// first `n_p` rows see `r_p` only. The first needs only the last `m`
    /// rows of its solution, `v = L₂₂⁻ᵀ Λ₂⁻¹ y₂`, whence `q = −Σ v = −L₂₂ y₂`;
    /// the second's last `m` rows sweep to `y₂ + L₂₂⁻¹ (q + Σ δr) = Λ₂ L₂₂ᵀ
    /// δr`. One forward and one backward sweep through `L` then, not two of
    /// each (the solve reads the factor, 390 MB at super-100m, once a
    /// sweep).
    pub(crate) fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        match &self.l {
            Values::Double(storage) => self.solve_with(&storage.l, rhs),
            Values::Single(storage) => self.solve_with(&storage.l, rhs),
        }
    }

    /// [`CondensedFactor::solve_in_place`] with `M`'s factor `l`, the
    /// sweeps through it in its precision.
    fn solve_with<T: Real>(&self, l: &[T], mut rhs: MatMut<'_, f64>) {
        let structure = &*self.structure;
        let (par, k) = (structure.par, rhs.ncols());
        let (points, rest, coupled) = (&structure.points, &structure.rest, &structure.coupled);
        let (n_p, m) = (points.len(), coupled.len());
        let factor = supernodal(&structure.ldlt, l);
        let perm = structure
            .ldlt
            .perm()
            .expect("the condensation's ordering is its own");
        let (order, _) = perm.arrays();
        // 1. y = L⁻¹ P (r_p, 0); q = −Σ v = −L₂₂ y₂
        let mut y = Mat::from_fn(n_p + m, k, |i, j| {
            let row = order[i];
            if row < n_p {
                T::of(rhs[(points[row], j)])
            } else {
                T::zero()
            }
        });
        forward_sweep(factor, y.as_mut(), par);
        let y2 = Mat::from_fn(m, k, |c, j| y[(n_p + c, j)].to());
        let q = -(&self.l22 * &y2);
        // 2. δr = S⁻¹ (r_r − q)
        let mut r = Mat::from_fn(rest.len(), k, |i, j| rhs[(rest[i], j)]);
        for (c, &i) in coupled.iter().enumerate() {
            for j in 0..k {
                r[(i, j)] -= q[(c, j)];
            }
        }
        if let Some(s) = &self.s {
            s.solve_in_place(r.as_mut());
        }
        // 3. M (δp, w) = (r_p, q + Σ δr): its forward sweep is y₁ and
        // y₂ + L₂₂⁻¹ (q + Σ δr) = Λ₂ L₂₂ᵀ δr; then the backward sweep
        let dr = Mat::from_fn(m, k, |c, j| r[(coupled[c], j)]);
        let y2 = self.l22.transpose() * &dr;
        y.subrows_mut(n_p, m).copy_from(Mat::from_fn(m, k, |c, j| {
            T::of(self.lambda2[c] * y2[(c, j)])
        }));
        backward_sweep(factor, y.as_mut(), par);
        for j in 0..k {
            for (i, &row) in order.iter().enumerate() {
                if row < n_p {
                    rhs[(points[row], j)] = y[(i, j)].to();
                }
            }
            for (i, &q) in rest.iter().enumerate() {
                rhs[(q, j)] = r[(i, j)];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use faer::prelude::Solve;
    use nalgebra::{UnitQuaternion, Vector3};

    use super::super::assembly::{Factor, System};
    use super::super::{JointKind, ModelBuilder, RodSpec, Section};

    /// A pseudo-random number in [−½, ½) (golden-ratio sequence).
    fn noise(k: usize) -> f64 {
        (0.618_033_988_749_895 * (k + 1) as f64).fract() - 0.5
    }

    /// An L-shaped frame of two rods hinged together, its first end clamped,
    /// carrying a 6 × 6 net of points on cables: the net's edge hangs from
    /// the frame's nodes (`flexible`) or from fixed points, and some cables
    /// are slack. Returns the system's tangent and residual at a perturbed
    /// state with nonzero multipliers.
    fn tangent(flexible: bool) -> (System, Vec<f64>, Vec<f64>) {
        let mut b = ModelBuilder::new();
        let spec = RodSpec {
            section: Section::tube(0.05, 0.046, 70e9, 26e9),
            elements: 4,
            kind: Default::default(),
        };
        let up = Vector3::z();
        let first = b.add_rod(Vector3::zeros(), Vector3::new(5.0, 0.0, 0.0), up, &spec);
        let second = b.add_rod(
            Vector3::new(5.0, 0.0, 0.0),
            Vector3::new(5.0, 5.0, 0.0),
            up,
            &spec,
        );
        b.fix(first.start(), [true; 6]);
        let corner = Vector3::new(5.0, 0.0, 0.0);
        b.add_joint(
            JointKind::Revolute { axis: up },
            first.end(),
            second.start(),
            corner,
        );
        let frame_nodes: Vec<usize> = first
            .nodes
            .iter()
            .chain(&second.nodes[1..])
            .copied()
            .collect();
        let n = 6;
        let points: Vec<usize> = (0..n * n)
            .map(|k| {
                let (i, j) = ((k % n) as f64, (k / n) as f64);
                b.add_point(Vector3::new(0.5 + 0.8 * i, 0.5 + 0.8 * j, -0.3))
            })
            .collect();
        let at = |i: usize, j: usize| points[j * n + i];
        let mut k = 0;
        let mut cable = |b: &mut ModelBuilder, p: usize, q: usize| {
            let d = (b.frame(q).unwrap().position_m - b.frame(p).unwrap().position_m).norm();
            // Every seventh cable slack at the reference state.
            let rest = d * if k % 7 == 3 { 1.02 } else { 0.98 };
            b.add_cable(p, q, 1e5, [rest, rest]);
            k += 1;
        };
        for j in 0..n {
            for i in 0..n {
                if i + 1 < n {
                    cable(&mut b, at(i, j), at(i + 1, j));
                }
                if j + 1 < n {
                    cable(&mut b, at(i, j), at(i, j + 1));
                }
            }
        }
        for (e, &node) in frame_nodes.iter().enumerate() {
            let p = if e < 5 {
                at(e.min(n - 1), 0)
            } else {
                at(n - 1, (e - 4).min(n - 1))
            };
            let anchor = if flexible {
                node
            } else {
                let fixed = b.add_point(b.frame(node).unwrap().position_m);
                b.fix(fixed, [true; 6]);
                fixed
            };
            cable(&mut b, p, anchor);
        }
        for j in 0..n {
            let anchor = b.add_point(Vector3::new(0.0, 0.5 + 0.8 * j as f64, 0.0));
            b.fix(anchor, [true; 6]);
            cable(&mut b, at(0, j), anchor);
        }
        b.add_load(at(3, 3), Vector3::new(0.0, 0.0, -50.0), Vector3::zeros());
        let model = b.build().unwrap();
        let system = System::new(&model).unwrap();
        let mut state = system.reference_state(&model);
        for (f, frame) in state.frames.iter_mut().enumerate() {
            frame.position_m +=
                0.01 * Vector3::new(noise(3 * f), noise(3 * f + 1), noise(3 * f + 2));
            let theta = 0.02 * Vector3::new(noise(5 * f), noise(7 * f), noise(11 * f));
            frame.rotation = UnitQuaternion::from_scaled_axis(theta) * frame.rotation;
        }
        for (k, mu) in state.multipliers.iter_mut().enumerate() {
            *mu = noise(13 * k);
        }
        let ev = system.evaluate(&model, &state, 0.7);
        (system, ev.values, ev.forces.residual)
    }

    /// The condensed solve agrees with a dense LU of the whole tangent, on
    /// two right-hand sides at once, with the net on a flexible frame (a
    /// nonsymmetric frame block, joint multipliers) and on fixed anchors
    /// (nothing but the net).
    #[test]
    fn condensed_solve_matches_the_dense_lu() {
        for flexible in [true, false] {
            let (system, values, residual) = tangent(flexible);
            let factor = system.factor(&values).unwrap();
            assert!(
                matches!(factor, Factor::Condensed(_)),
                "flexible {flexible}: not condensed"
            );
            let dense = system.dense_tangent(&values);
            if flexible {
                let skew = (&dense - dense.transpose()).norm_max();
                assert!(
                    skew > 1e-6 * dense.norm_max(),
                    "the frame block is symmetric: {skew:e}"
                );
            }
            let n = system.n_rows;
            let rhs = faer::Mat::from_fn(n, 2, |i, j| if j == 0 { residual[i] } else { noise(i) });
            let mut condensed = rhs.clone();
            System::solve_in_place(&factor, condensed.as_mut());
            let exact = dense.partial_piv_lu().solve(&rhs);
            let error = (&condensed - &exact).norm_max() / exact.norm_max();
            assert!(
                error < 1e-9,
                "flexible {flexible}: relative difference {error:e}"
            );
            // And the residual of the condensed solution itself.
            let r = (&dense * &condensed - &rhs).norm_max() / rhs.norm_max();
            assert!(r < 1e-9, "flexible {flexible}: relative residual {r:e}");
        }
    }

    /// The single-precision factor is the double one to f32's roundoff
    /// (measured: 5.6e-6 relative on the flexible frame), far better than
    /// the chord iterations need, and refining with it (the residual in
    /// double, as the iterations compute it) reaches double's agreement,
    /// 1.1e-11 after two refinements (the double factor's own condition).
    #[test]
    fn single_precision_factor_refines_to_the_double_solution() {
        use super::Precision;
        for flexible in [true, false] {
            let (system, values, residual) = tangent(flexible);
            let single = system.refactor(&values, Precision::Single, None).unwrap();
            let dense = system.dense_tangent(&values);
            let n = system.n_rows;
            let rhs = faer::Mat::from_fn(n, 1, |i, _| residual[i]);
            let exact = dense.partial_piv_lu().solve(&rhs);
            let mut x = rhs.clone();
            System::solve_in_place(&single, x.as_mut());
            let error = (&x - &exact).norm_max() / exact.norm_max();
            assert!(
                error > 1e-9 && error < 1e-4,
                "flexible {flexible}: single precision's difference {error:e}"
            );
            for _ in 0..3 {
                let mut correction = &rhs - &dense * &x;
                System::solve_in_place(&single, correction.as_mut());
                x += &correction;
            }
            let error = (&x - &exact).norm_max() / exact.norm_max();
            assert!(error < 1e-10, "flexible {flexible}: refined {error:e}");
        }
    }
}
