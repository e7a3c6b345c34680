//! Stability of an equilibrium (DESIGN §5, §9): whether the tangent
//! stiffness is positive definite on the joints' constraints.
//!
//! Load control alone cannot see a bifurcation: a symmetric ring under a
//! symmetric pull stays on its fundamental branch past the buckling load,
//! Newton converging there as well as anywhere. The test here is on the state
//! itself. At equilibrium the tangent is the saddle-point matrix
//! `J = [[H, Aᵀ], [A, 0]]` (`H` the stiffness, `A` the constraint Jacobian),
//! and the frame is stable when `H` is positive definite on `ker A`.
//! Inverse iteration with `J`'s factor finds the reduced eigenvalue of least
//! magnitude: solving `J [z; y] = [W² x; 0]` gives `z ∈ ker A` with
//! `zᵀ H z = zᵀ W² x` — the curvature along `z` comes from the solve itself,
//! without a product with `H`. `W` weights rotations by the mean element
//! length, so eigenvalues are stiffnesses in N/m. The eigenvalue crossing zero
//! first along a path is the least in magnitude just before it does, whatever
//! its multiplicity (a ring's buckling modes come in pairs), and a negative
//! curvature `zᵀ H z < 0` is a certificate of instability.
//!
//! How many eigenvalues are negative is the tangent's inertia
//! ([`negative_eigenvalues`]): by Sylvester's law and the saddle point's
//! structure, `J` has exactly `m` more negative eigenvalues than `H` has on
//! `ker A` (`m` the multipliers, `A` of full rank), and the count is the
//! number of negative pivots of a symmetric indefinite (Bunch–Kaufman)
//! factorisation `P J Pᵀ = L B Lᵀ` — dense up to [`INERTIA_ROWS`] rows, of
//! the congruent augmented tangent by a sparse supernodal one above
//! ([`InertiaStructure`]), so that every symmetric tangent has its count.
//! It changes where, and only where, an eigenvalue crosses zero: a critical
//! point, whichever mode is the least in magnitude on either side.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{Argsort, Pair, SparseColMat, SymbolicSparseColMat};
use faer::{Mat, Side};
use serde::Serialize;

use super::assembly::{State, System};
use super::model::MechanicsError;
use super::solver::{wdot, StaticSolver};
use crate::algebra::Plain;

/// Inverse iterations at most.
const MAX_ITERATIONS: usize = 60;

/// Relative change of the eigenvalue estimate at which inverse iteration stops.
const EIGENVALUE_TOLERANCE: f64 = 1e-4;

/// A curvature counts as negative below this fraction of its roundoff scale
/// `‖z‖_W ‖x‖_W` (as the Newton solver's curvature test).
const CURVATURE_NOISE: f64 = 1e-8;

/// The stability of one equilibrium state.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Stability {
    /// The least-magnitude eigenvalue of the stiffness on the constraints
    /// (rotations weighted by the mean element length), N/m: the estimate
    /// inverse iteration reached, or the curvature of the first direction
    /// found negative.
    pub lowest_stiffness_n_per_m: f64,
    /// True when no direction of negative curvature was found.
    pub stable: bool,
    /// Inverse iterations.
    pub iterations: usize,
    /// The direction the estimate belongs to: the lowest mode when stable,
    /// the direction of negative curvature otherwise.
    #[serde(skip)]
    pub mode: Mode,
}

/// A mode shape: every node's translation, scaled so that the largest is 1 m
/// (its sign is arbitrary).
#[derive(Clone, PartialEq, Default)]
pub struct Mode(Vec<[f64; 3]>);

impl Mode {
    /// Every node's translation, m.
    pub fn translations_m(&self) -> &[[f64; 3]] {
        &self.0
    }
}

impl std::fmt::Debug for Mode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Mode({} nodes)", self.0.len())
    }
}

/// The stability of `state`, an equilibrium at load factor `lambda`.
pub(super) fn stability(
    solver: &StaticSolver,
    state: &State,
    lambda: f64,
) -> Result<Stability, MechanicsError> {
    let run = inverse_iteration(solver, state, lambda, true)?;
    Ok(Stability {
        lowest_stiffness_n_per_m: run.eigenvalue,
        stable: !run.negative,
        iterations: run.iterations,
        mode: translations(solver, &run.vector),
    })
}

/// The least-magnitude eigenvalue of the stiffness on the joints'
/// constraints at `state`, signed, and its eigenvector in unknown order
/// (multipliers zero, weighted norm 1): inverse iteration run to
/// convergence (not stopped at the first negative curvature, as
/// [`stability`] is), so that the value is a continuous function along a
/// path and crosses zero where the path meets a critical point.
pub(super) fn lowest_eigenpair(
    solver: &StaticSolver,
    state: &State,
    lambda: f64,
) -> Result<EigenPair, MechanicsError> {
    inverse_iteration(solver, state, lambda, false)
}

/// The outcome of inverse iteration.
pub(super) struct EigenPair {
    /// The Rayleigh quotient `zᵀHz / zᵀW²z` of the last iterate, N/m.
    pub eigenvalue: f64,
    /// Some iterate had a curvature below the noise: negative.
    pub negative: bool,
    /// Inverse iterations.
    pub iterations: usize,
    /// The last iterate (unknown order, multipliers zero), weighted norm 1.
    pub vector: Vec<f64>,
}

/// Inverse iteration with the tangent's factor (module doc), stopped at the
/// first direction of negative curvature when `stop_on_negative`.
fn inverse_iteration(
    solver: &StaticSolver,
    state: &State,
    lambda: f64,
    stop_on_negative: bool,
) -> Result<EigenPair, MechanicsError> {
    let system = solver.system();
    let ev = system.evaluate(solver.model(), state, lambda);
    let lu = system.factor(&ev.values)?;
    let w = solver.weights();
    let n_free = system.n_free;
    // A start with every component: a fixed pseudo-random sequence.
    let mut x: Vec<f64> = (0..system.n_rows)
        .map(|i| {
            if i < n_free {
                (0.754_877_666 * (i + 1) as f64).fract() - 0.5
            } else {
                0.0
            }
        })
        .collect();
    let mut estimate = f64::NAN;
    let mut negative = false;
    for iteration in 1..=MAX_ITERATIONS {
        let mut rhs = Mat::from_fn(system.n_rows, 1, |i, _| {
            if i < n_free {
                w[i] * w[i] * x[i]
            } else {
                0.0
            }
        });
        System::solve_in_place(&lu, rhs.as_mut());
        let z: Vec<f64> = (0..system.n_rows)
            .map(|i| if i < n_free { rhs[(i, 0)] } else { 0.0 })
            .collect();
        let curvature = wdot(&w, &z, &x);
        let (z_norm, x_norm) = (wdot(&w, &z, &z).sqrt(), wdot(&w, &x, &x).sqrt());
        if !(z_norm.is_finite() && z_norm > 0.0) {
            return Err(MechanicsError::Mechanism {
                detail: "inverse iteration on the tangent gave no finite direction".into(),
            });
        }
        let previous = estimate;
        estimate = curvature / (z_norm * z_norm);
        negative |= curvature < -CURVATURE_NOISE * z_norm * x_norm;
        let settled = (estimate - previous).abs() <= EIGENVALUE_TOLERANCE * estimate.abs();
        x = z.iter().map(|v| v / z_norm).collect();
        if (negative && stop_on_negative) || settled || iteration == MAX_ITERATIONS {
            return Ok(EigenPair {
                eigenvalue: estimate,
                negative,
                iterations: iteration,
                vector: x,
            });
        }
    }
    unreachable!("the last iteration returns")
}

/// Rows up to which the tangent's inertia is counted dense
/// ([`dense_negative_eigenvalues`]): a Bunch–Kaufman factorisation with
/// pivoting over the whole matrix, `n³/3` operations (≈ 0.3 G at 1 000 rows,
/// tens of ms). Above, the sparse count ([`InertiaStructure`]).
pub(super) const INERTIA_ROWS: usize = 1_000;

/// An equilibrium's tangent counts as symmetric when no entry differs from
/// its transpose's by more than this fraction of the largest entry: under
/// conservative loads it is, to the residual's roundoff; a moment fixed in
/// space (not conservative under finite rotations) makes it unsymmetric by
/// the moment's size.
const SYMMETRY: f64 = 1e-8;

/// The number of negative eigenvalues of the stiffness on the joints'
/// constraints at `state` (module doc): the negative pivots of a symmetric
/// indefinite factorisation of the tangent, less one per multiplier —
/// dense up to [`INERTIA_ROWS`] rows ([`dense_negative_eigenvalues`]),
/// sparse above ([`InertiaStructure`]). `None` for a tangent with entries
/// that are not finite, or unsymmetric ([`SYMMETRY`]: loads that are not
/// conservative have no energy whose second variation the inertia would
/// count), or whose sparse factorisation could not be analysed or met a
/// pivot that is not finite.
pub(super) fn negative_eigenvalues(
    solver: &StaticSolver,
    state: &State,
    lambda: f64,
) -> Option<usize> {
    if solver.system().n_rows <= INERTIA_ROWS {
        dense_negative_eigenvalues(solver, state, lambda)
    } else {
        sparse_negative_eigenvalues(solver, state, lambda)
    }
}

/// [`negative_eigenvalues`] by faer's dense Bunch–Kaufman `LBLᵀ` of the
/// whole tangent, whatever its size.
pub(super) fn dense_negative_eigenvalues(
    solver: &StaticSolver,
    state: &State,
    lambda: f64,
) -> Option<usize> {
    let system = solver.system();
    let ev = system.evaluate(solver.model(), state, lambda);
    if ev.values.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let j = system.dense_tangent(&ev.values);
    let n = system.n_rows;
    let mut largest: f64 = 0.0;
    let mut asymmetry: f64 = 0.0;
    for c in 0..n {
        for r in 0..n {
            largest = largest.max(j[(r, c)].abs());
            asymmetry = asymmetry.max((j[(r, c)] - j[(c, r)]).abs());
        }
    }
    if asymmetry > SYMMETRY * largest {
        return None;
    }
    let symmetric = Mat::from_fn(n, n, |r, c| 0.5 * (j[(r, c)] + j[(c, r)]));
    let lblt = symmetric.lblt(faer::Side::Lower);
    let (diag, sub) = (lblt.B_diag(), lblt.B_subdiag());
    let (diag, sub) = (diag.column_vector(), sub.column_vector());
    let negative = negative_pivots((0..n).map(|i| (diag[i], sub[i])))?;
    Some(negative.saturating_sub(n - system.n_free))
}

/// [`negative_eigenvalues`] by the sparse count ([`InertiaStructure`]),
/// whatever the tangent's size.
pub(super) fn sparse_negative_eigenvalues(
    solver: &StaticSolver,
    state: &State,
    lambda: f64,
) -> Option<usize> {
    let system = solver.system();
    let ev = system.evaluate(solver.model(), state, lambda);
    if ev.values.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let j = system.sparse_tangent(&ev.values).ok()?;
    let structure = system
        .inertia
        .get_or_init(|| InertiaStructure::new(&j, system.n_free, system.scale).ok())
        .as_ref()?;
    structure.negative_eigenvalues(&j)
}

/// The negative eigenvalues of a block-diagonal `B` of 1×1 and 2×2 blocks,
/// given as each row's diagonal entry and the entry below it (nonzero: a
/// 2×2 block starts there). `None` when an entry is not finite (a zero
/// pivot met on the way).
fn negative_pivots(mut rows: impl Iterator<Item = (f64, f64)>) -> Option<usize> {
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
/// Measured against the dense count ([`dense_negative_eigenvalues`], the
/// tests below): the same count at every point of load sweeps through the
/// column's two Euler loads, the Argyris frame's two bifurcations and the
/// ring truss's double one (bodies held by revolute and fixed joints only).
/// At 1 038 rows (the ring truss) it takes 4 ms where the dense count takes
/// 30–55 ms and the inverse iteration of [`lowest_eigenpair`] 5 ms: one
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
    fn new(j: &SparseColMat<usize, f64>, n_free: usize, scale: f64) -> Result<Self, String> {
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
    fn negative_eigenvalues(&self, j: &SparseColMat<usize, f64>) -> Option<usize> {
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
        let par = faer::get_global_parallelism();
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

/// Every node's translation in the unknowns `z` (0 where fixed), scaled so
/// that the largest is 1 m.
pub(super) fn translations(solver: &StaticSolver, z: &[f64]) -> Mode {
    let system = solver.system();
    let mut t: Vec<[f64; 3]> = (0..solver.model().node_count())
        .map(|n| std::array::from_fn(|c| system.unknown(n, c).map_or(0.0, |i| z[i])))
        .collect();
    let largest = t
        .iter()
        .map(|v| crate::algebra::norm3(*v))
        .fold(0.0, f64::max);
    if largest > 0.0 {
        t.iter_mut().flatten().for_each(|v| *v /= largest);
    }
    Mode(t)
}

#[cfg(test)]
mod tests {
    use nalgebra::{DMatrix, Vector3};

    use super::*;
    use crate::mechanics::{ElementKind, JointKind, ModelBuilder, RodSpec, Section};
    use crate::mechanics::{StaticSettings, StaticTermination};

    /// A clamped-free column of length 1 m along x in two rods joined by a
    /// fixed joint (so that the tangent has multipliers), bending
    /// stiffnesses 1 and 2 N·m², under an axial tip force `p` (N).
    fn column(p: f64) -> StaticSolver {
        let spec = RodSpec {
            section: Section {
                axial_n: 1e4,
                shear_n: [1e4, 1e4],
                torsion_nm2: 1.0,
                bending_nm2: [1.0, 2.0],
            },
            elements: 4,
            kind: ElementKind::Se3,
        };
        let mut b = ModelBuilder::new();
        let mid = Vector3::new(0.5, 0.0, 0.0);
        let first = b.add_rod(Vector3::zeros(), mid, Vector3::z(), &spec);
        let second = b.add_rod(mid, Vector3::x(), Vector3::z(), &spec);
        b.add_joint(JointKind::Fixed, first.end(), second.start(), mid);
        b.fix(first.start(), [true; 6]);
        b.add_load(second.end(), Vector3::new(-p, 0.0, 0.0), Vector3::zeros());
        StaticSolver::new(b.build().unwrap()).unwrap()
    }

    /// The negative eigenvalues of the stiffness on `ker A`, counted
    /// independently of the factorisation: `ker A` from the eigenvectors
    /// of `AᵀA` with zero eigenvalue, then the eigenvalues of `ZᵀHZ`.
    fn negative_by_eigenvalues(solver: &StaticSolver, state: &State, lambda: f64) -> usize {
        let system = solver.system();
        let ev = system.evaluate(solver.model(), state, lambda);
        let j = system.dense_tangent(&ev.values);
        let (n, m) = (system.n_free, system.n_rows - system.n_free);
        let h = DMatrix::from_fn(n, n, |r, c| 0.5 * (j[(r, c)] + j[(c, r)]));
        let a = DMatrix::from_fn(m, n, |r, c| j[(n + r, c)]);
        let ata = (a.transpose() * &a).symmetric_eigen();
        let top = ata.eigenvalues.amax();
        let kernel: Vec<usize> = (0..n)
            .filter(|&i| ata.eigenvalues[i] <= 1e-10 * top)
            .collect();
        assert_eq!(kernel.len(), n - m, "A has full rank");
        let z = DMatrix::from_fn(n, kernel.len(), |r, c| ata.eigenvectors[(r, kernel[c])]);
        let reduced = (z.transpose() * h * &z).symmetric_eigen();
        let scale = reduced.eigenvalues.amax();
        reduced
            .eigenvalues
            .iter()
            .filter(|&&e| e < -1e-10 * scale)
            .count()
    }

    #[test]
    fn the_inertia_counts_the_negative_eigenvalues_on_the_constraints() {
        // Euler's clamped-free loads π²EI/(4L²): 2.467 N and 4.935 N.
        let first = std::f64::consts::PI.powi(2) / 4.0;
        for (p, expected) in [(0.5 * first, 0), (1.5 * first, 1), (3.0 * first, 2)] {
            let solver = column(p);
            let solution = solver.solve(&StaticSettings::default()).unwrap();
            assert_eq!(solution.termination, StaticTermination::Converged, "{p}");
            let counted = negative_eigenvalues(&solver, &solution.state, 1.0);
            let independent = negative_by_eigenvalues(&solver, &solution.state, 1.0);
            assert_eq!(independent, expected, "P = {p} N");
            assert_eq!(counted, Some(expected), "P = {p} N");
            let sparse = sparse_negative_eigenvalues(&solver, &solution.state, 1.0);
            assert_eq!(sparse, Some(expected), "P = {p} N");
        }
    }

    /// The dense and sparse counts at equilibria of `file` under its loads
    /// times each of `factors` (increasing), each solved by load control
    /// from the last: the fundamental path, through and past its
    /// bifurcations. Returns the counts.
    fn counts_along(file: &crate::frame::FrameFile, factors: &[f64]) -> Vec<usize> {
        let mut solver = StaticSolver::new(file.model.clone()).unwrap();
        let base = file.model.loads().to_vec();
        let settings = StaticSettings {
            max_step: 0.25,
            ..StaticSettings::default()
        };
        let (mut state, mut last) = (solver.reference_state(), 0.0);
        let mut counts = Vec::new();
        for &t in factors {
            let scaled = base
                .iter()
                .map(|l| crate::mechanics::NodalLoad {
                    force_n: l.force_n * t,
                    moment_nm: l.moment_nm * t,
                    ..*l
                })
                .collect();
            solver.model_mut().set_loads(scaled).unwrap();
            let solution = solver.solve_from(state, last / t, &settings).unwrap();
            assert_eq!(solution.termination, StaticTermination::Converged, "× {t}");
            let dense = dense_negative_eigenvalues(&solver, &solution.state, 1.0);
            let sparse = sparse_negative_eigenvalues(&solver, &solution.state, 1.0);
            assert!(dense.is_some(), "× {t}");
            assert_eq!(sparse, dense, "× {t}");
            counts.push(dense.unwrap());
            (state, last) = (solution.state, t);
        }
        counts
    }

    /// The Argyris frame (`tests/critical_points.rs`): 2 × 10 elements, a
    /// fixed joint at the corner, so the second leg is held by the joint
    /// alone; bending stiffnesses `[in-plane, out-of-plane]`, tip force
    /// 1 N across the second leg.
    fn argyris(bending: [f64; 2]) -> crate::frame::FrameFile {
        let text = format!(
            r#"
nodes = [
  {{ name = "root", position_m = [0.0, 0.0, 0.0] }},
  {{ name = "corner", position_m = [240.0, 0.0, 0.0] }},
  {{ name = "tip", position_m = [240.0, 240.0, 0.0] }},
]
[sections.s]
axial_n = 1.28232e6
shear_n = [4.8942e5, 4.8942e5]
torsion_nm2 = 58730.4
bending_nm2 = {bending:?}
[[rods]]
name = "leg1"
start = "root"
end = "corner"
section = "s"
elements = 10
up = [0.0, 0.0, 1.0]
[[rods]]
name = "leg2"
start = "corner"
end = "tip"
section = "s"
elements = 10
up = [0.0, 0.0, 1.0]
[[joints]]
kind = "fixed"
a = {{ rod = "leg1", end = "end" }}
b = {{ rod = "leg2", end = "start" }}
[[supports]]
on = {{ rod = "leg1", end = "start" }}
fixed = ["all"]
[[loads]]
on = {{ rod = "leg2", end = "end" }}
force_n = [-1.0, 0.0, 0.0]
"#
        );
        crate::frame::FrameFile::from_toml(&text).unwrap()
    }

    #[test]
    fn the_sparse_count_is_the_dense_one_through_the_argyris_frames_buckling() {
        // Deep section: lateral buckling between 0.6 and 0.7 N, a second
        // mode between 2.4 and 2.5 N on the (unstable) fundamental path.
        let file = argyris([9.6174e7, 38470.0]);
        let factors: Vec<f64> = (1..=30).map(|k| 0.1 * k as f64).collect();
        let counts = counts_along(&file, &factors);
        assert_eq!((counts[0], counts[9], counts[29]), (0, 1, 2), "{counts:?}");
    }

    #[test]
    fn the_sparse_count_is_the_dense_one_through_the_ring_trusss_buckling() {
        // 1 038 rows (above INERTIA_ROWS: the sparse count is the one
        // paths use here). Hinge bodies held by revolute and fixed joints only; the file's
        // radial loads turned down (−z), so that battens and diagonals
        // carry the compression.
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("problems/frames/ring-truss-frame.toml");
        let mut file = crate::frame::FrameFile::read(&path).unwrap();
        let down = file
            .model
            .loads()
            .iter()
            .map(|l| crate::mechanics::NodalLoad {
                force_n: nalgebra::Vector3::new(0.0, 0.0, -l.force_n.norm()),
                ..*l
            })
            .collect();
        file.model.set_loads(down).unwrap();
        // A pair of modes crosses between 5.39 and 5.41 × the loads: the
        // count jumps from 0 to 2 there (load control stops near 5.68).
        let factors: Vec<f64> = (1..=10)
            .map(|k| 0.5 * k as f64)
            .chain((1..=20).map(|k| 5.0 + 0.034 * k as f64))
            .collect();
        let counts = counts_along(&file, &factors);
        assert_eq!(counts[0], 0, "{counts:?}");
        assert_eq!(*counts.last().unwrap(), 2, "{counts:?}");
        assert!(counts.windows(2).all(|w| w[0] <= w[1]), "{counts:?}");
    }

    #[test]
    fn a_moment_fixed_in_space_leaves_the_inertia_uncounted_dense_or_sparse() {
        // Not conservative under finite rotations: the tangent is
        // unsymmetric by the moment's size, and no energy's second
        // variation is there to count.
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("problems/frames/cantilever-moment.toml");
        let file = crate::frame::FrameFile::read(&path).unwrap();
        let solver = StaticSolver::new(file.model.clone()).unwrap();
        let solution = solver.solve(&file.settings).unwrap();
        assert_eq!(solution.termination, StaticTermination::Converged);
        let state = &solution.state;
        assert_eq!(dense_negative_eigenvalues(&solver, state, 1.0), None);
        assert_eq!(sparse_negative_eigenvalues(&solver, state, 1.0), None);
        // The unloaded reference is symmetric: counted, both ways.
        let reference = solver.reference_state();
        assert_eq!(
            dense_negative_eigenvalues(&solver, &reference, 0.0),
            Some(0)
        );
        assert_eq!(
            sparse_negative_eigenvalues(&solver, &reference, 0.0),
            Some(0)
        );
    }
}
