//! The force density method (paper §2, DESIGN §3): forward equilibrium, reactions,
//! the equilibrium matrix `A(x)` of the inverse form, and adjoint sensitivities.
//!
//! Layers, as in jax_fdm: a [`Network`] (the user's data) → an [`FdmStructure`]
//! (index maps, the sparsity of `D = C_fᵀ Q C_f` and its symbolic Cholesky
//! factorisation; built once per topology) → an [`Equilibrium`] (positions,
//! lengths, forces, reactions, residuals, and the numeric factor, kept for
//! sensitivities). Changing `q` only refills `D`'s values and refactors
//! numerically.

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, LltRef, SymbolicCholesky};
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMat, Triplet};
use faer::{Conj, Mat, MatMut, Par, Side};

use crate::algebra::{norm3, Plain};
use crate::network::{edges_vectors, Network, NetworkError};

/// Marks "no such index" in the dense index maps below.
pub(crate) const NONE: usize = usize::MAX;

/// Parallelism of the numeric factorisation and solves. Sequential: on the
/// 2-core reference machine faer's parallel supernodal factorisation of a
/// 10⁵-node `D` took 0.6–0.7 s against 0.24 s sequentially (rayon's workers
/// spin in the kernel), and callers that sweep designs parallelise outside.
const PAR: Par = Par::Seq;

/// A forward solve is refined while some free node's componentwise backward
/// error `|r| / (Σ_k |q_k u_k| + |p|)` exceeds this: well above the ~100 ε a
/// well-conditioned solve leaves (coordinates larger than cables), far below
/// any error that matters.
const REFINE_ABOVE: f64 = 1e-12;

/// Most refinement steps of one forward solve.
const MAX_REFINEMENTS: usize = 40;

/// The force density method failed.
#[derive(Debug, thiserror::Error)]
pub enum FdmError {
    /// The network itself is invalid.
    #[error(transparent)]
    InvalidNetwork(#[from] NetworkError),
    /// An argument's shape does not match the structure.
    #[error("`{field}` has {found} entries, expected {expected}")]
    Shape {
        /// The argument.
        field: &'static str,
        /// Its length.
        found: usize,
        /// The expected length.
        expected: usize,
    },
    /// A force density is not finite and positive.
    #[error(
        "`q[{edge}]` = {value:e}: force densities must be finite and at least {:e} N/m \
         (the smallest normal double)",
        f64::MIN_POSITIVE
    )]
    InvalidQ {
        /// The cable.
        edge: usize,
        /// The value found.
        value: f64,
    },
    /// The numeric Cholesky factorisation of `D` failed: with valid `q` this means
    /// the force densities span more than double precision can resolve.
    #[error("D = C_fᵀ Q C_f is not numerically positive definite ({n_free} free nodes): {reason}")]
    NotPositiveDefinite {
        /// Number of free nodes.
        n_free: usize,
        /// faer's message.
        reason: String,
    },
    /// An allocation of the factorisation of `D` failed: the net is larger
    /// than the memory this machine gives the run (not a numerical fault).
    #[error(
        "out of memory factorising D = C_fᵀ Q C_f ({n_free} free nodes, {during}){note}: \
         the net is too large for this machine; lower the net, or run where more memory is free"
    )]
    OutOfMemory {
        /// Number of free nodes.
        n_free: usize,
        /// Which step ran out (`symbolic factorisation`, …).
        during: &'static str,
        /// The memory guard's estimate against its limit
        /// ([`crate::resources::memory_note`]).
        note: String,
    },
    /// The solve produced non-finite positions.
    #[error("the forward solve produced non-finite positions (node {node})")]
    NonFinite {
        /// The first node with a non-finite coordinate.
        node: usize,
    },
    /// Positions are finite but a force is not: `q` times the geometry
    /// overflows double precision.
    #[error(
        "the forward solve's {what} is not finite: force densities up to {max_q:e} N/m \
         on this geometry overflow double precision"
    )]
    Overflow {
        /// The first non-finite quantity (a cable's tension, a reaction, a
        /// node's residual).
        what: String,
        /// The largest force density.
        max_q: f64,
    },
}

impl FdmError {
    /// True when the cause is the caller's input rather than a numerical failure.
    pub fn is_bad_input(&self) -> bool {
        matches!(
            self,
            FdmError::InvalidNetwork(_) | FdmError::Shape { .. } | FdmError::InvalidQ { .. }
        )
    }
}

/// Where cable `k = (i, j)` adds its force density into the values of `D`:
/// the diagonal slots of `i` and `j` (if free) and the off-diagonal slot (if both
/// are free).
#[derive(Debug, Clone, Copy)]
pub(crate) struct EdgeSlots {
    pub(crate) diagonal: [usize; 2],
    pub(crate) off_diagonal: usize,
}

/// The topology of a network as the force density method needs it: free/fixed
/// index maps, the lower-triangular sparsity of `D = C_fᵀ Q C_f` (eq. 3–4) and
/// its symbolic Cholesky factorisation (fill-reducing ordering included).
///
/// Build it once per topology; [`FdmStructure::solve`] then costs one value
/// fill, one numeric factorisation and three triangular solve pairs.
#[derive(Debug, Clone)]
pub struct FdmStructure {
    n_nodes: usize,
    edges: Vec<[usize; 2]>,
    free: Vec<usize>,
    fixed: Vec<usize>,
    free_index: Vec<usize>,
    d_pattern: SymbolicSparseColMat<usize>,
    edge_slots: Vec<EdgeSlots>,
    symbolic: Option<Arc<SymbolicCholesky<usize>>>,
}

impl FdmStructure {
    /// Validates `network` and builds its structure.
    pub fn new(network: &Network) -> Result<Self, FdmError> {
        network.validate()?;
        let n_nodes = network.n_nodes();
        let is_fixed = network.fixed_mask();
        let free: Vec<usize> = (0..n_nodes).filter(|&i| !is_fixed[i]).collect();
        let mut free_index = vec![NONE; n_nodes];
        for (f, &i) in free.iter().enumerate() {
            free_index[i] = f;
        }
        let edges = network.edges.clone();
        let (d_pattern, edge_slots) = d_sparsity(&edges, &free_index, free.len());
        let symbolic = if free.is_empty() {
            None
        } else {
            let symbolic = factorize_symbolic_cholesky(
                d_pattern.as_ref(),
                Side::Lower,
                Default::default(),
                Default::default(),
            )
            .map_err(|e| match e {
                faer::sparse::FaerError::OutOfMemory => FdmError::OutOfMemory {
                    n_free: free.len(),
                    during: "symbolic factorisation",
                    note: crate::resources::memory_note(),
                },
                e => FdmError::NotPositiveDefinite {
                    n_free: free.len(),
                    reason: format!("symbolic factorisation: {}", e.plain()),
                },
            })?;
            Some(Arc::new(symbolic))
        };
        Ok(FdmStructure {
            n_nodes,
            edges,
            free,
            fixed: network.fixed.clone(),
            free_index,
            d_pattern,
            edge_slots,
            symbolic,
        })
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.n_nodes
    }

    /// Number of cables.
    pub fn n_edges(&self) -> usize {
        self.edges.len()
    }

    /// The cables, as pairs of node indices.
    pub fn edges(&self) -> &[[usize; 2]] {
        &self.edges
    }

    /// Free nodes, ascending; free index `f` is node `free_nodes()[f]`.
    pub fn free_nodes(&self) -> &[usize] {
        &self.free
    }

    /// Fixed nodes, in the order of the network's `fixed` (the order of reactions).
    pub fn fixed_nodes(&self) -> &[usize] {
        &self.fixed
    }

    /// The free index of `node`, or `None` for a fixed node.
    pub fn free_index(&self, node: usize) -> Option<usize> {
        Some(self.free_index[node]).filter(|&f| f != NONE)
    }

    /// Number of nonzeros in the lower triangle of `D`.
    pub fn d_nonzeros(&self) -> usize {
        self.d_pattern.row_idx().len()
    }

    /// The values of the lower triangle of `D = C_fᵀ Q C_f` (eq. 4), in the order of
    /// `d_pattern`.
    fn d_values(&self, q: &[f64]) -> Vec<f64> {
        let mut values = vec![0.0; self.d_nonzeros()];
        for (slots, &qk) in self.edge_slots.iter().zip(q) {
            for s in slots.diagonal {
                if s != NONE {
                    values[s] += qk;
                }
            }
            if slots.off_diagonal != NONE {
                values[slots.off_diagonal] -= qk;
            }
        }
        values
    }

    /// `D = C_fᵀ Q C_f` as a lower-triangular sparse matrix (n_free × n_free).
    pub fn d_matrix(&self, q: &[f64]) -> SparseColMat<usize, f64> {
        SparseColMat::new(self.d_pattern.clone(), self.d_values(q))
    }

    fn check_len(field: &'static str, found: usize, expected: usize) -> Result<(), FdmError> {
        if found == expected {
            Ok(())
        } else {
            Err(FdmError::Shape {
                field,
                found,
                expected,
            })
        }
    }

    /// Forward equilibrium (eq. 3–4): solves `D x_f = p_f − C_fᵀ Q C_g x_g` for x, y
    /// and z as three right-hand sides of one factorisation of `D`.
    ///
    /// `q`: n_edges force densities (N/m). `nodes`: n_nodes × 3, of which only the
    /// fixed nodes' positions are read. `loads`: n_nodes × 3 (N), or `None`.
    pub fn solve(
        &self,
        q: &[f64],
        nodes: &[[f64; 3]],
        loads: Option<&[[f64; 3]]>,
    ) -> Result<Equilibrium, FdmError> {
        Self::check_len("q", q.len(), self.n_edges())?;
        Self::check_len("nodes", nodes.len(), self.n_nodes)?;
        if let Some(loads) = loads {
            Self::check_len("loads", loads.len(), self.n_nodes)?;
        }
        if let Some((edge, &value)) = q
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && **v >= f64::MIN_POSITIVE))
        {
            return Err(FdmError::InvalidQ { edge, value });
        }

        let n_free = self.free.len();
        let mut rhs =
            Mat::<f64>::from_fn(n_free, 3, |f, c| loads.map_or(0.0, |p| p[self.free[f]][c]));
        for (&[i, j], &qk) in self.edges.iter().zip(q) {
            let (fi, fj) = (self.free_index[i], self.free_index[j]);
            if fi != NONE && fj == NONE {
                for c in 0..3 {
                    rhs[(fi, c)] += qk * nodes[j][c];
                }
            } else if fj != NONE && fi == NONE {
                for c in 0..3 {
                    rhs[(fj, c)] += qk * nodes[i][c];
                }
            }
        }

        let factor = match &self.symbolic {
            None => None,
            Some(symbolic) => {
                let values = self.d_values(q);
                if values.iter().any(|v| !v.is_finite()) {
                    return Err(FdmError::Overflow {
                        what: "matrix D = C_fᵀ Q C_f".to_string(),
                        max_q: q.iter().copied().fold(0.0, f64::max),
                    });
                }
                let d = SparseColMatRef::new(self.d_pattern.as_ref(), &values);
                // Allocations that fail are the machine's memory, said as
                // such (not a factorisation that found D indefinite).
                let out_of_memory = |during| FdmError::OutOfMemory {
                    n_free,
                    during,
                    note: crate::resources::memory_note(),
                };
                let mut l_values = Vec::new();
                l_values
                    .try_reserve_exact(symbolic.len_val())
                    .map_err(|_| out_of_memory("the factor"))?;
                l_values.resize(symbolic.len_val(), 0.0);
                let scratch = symbolic
                    .factorize_numeric_llt_scratch::<f64>(PAR, Default::default())
                    .or(symbolic.solve_in_place_scratch::<f64>(3, PAR));
                let mut buffer =
                    MemBuffer::try_new(scratch).map_err(|_| out_of_memory("the workspace"))?;
                let stack = MemStack::new(&mut buffer);
                symbolic
                    .factorize_numeric_llt(
                        &mut l_values,
                        d,
                        Side::Lower,
                        Default::default(),
                        PAR,
                        stack,
                        Default::default(),
                    )
                    .map_err(|e| FdmError::NotPositiveDefinite {
                        n_free,
                        reason: e.plain(),
                    })?;
                let factor = Factor {
                    symbolic: Arc::clone(symbolic),
                    l_values,
                };
                factor.solve_in_place(rhs.as_mut(), stack);
                Some(factor)
            }
        };

        let mut xyz = nodes.to_vec();
        let place = |xyz: &mut [[f64; 3]], x: &Mat<f64>| -> Result<(), FdmError> {
            for (f, &i) in self.free.iter().enumerate() {
                xyz[i] = [x[(f, 0)], x[(f, 1)], x[(f, 2)]];
                if xyz[i].iter().any(|v| !v.is_finite()) {
                    return Err(FdmError::NonFinite { node: i });
                }
            }
            Ok(())
        };
        place(&mut xyz, &rhs)?;
        if let Some(factor) = &factor {
            self.refine(factor, q, &mut xyz, loads, rhs);
        }
        let equilibrium = Equilibrium::new(self, q, xyz, loads, factor);
        let overflow = |what: String| FdmError::Overflow {
            what,
            max_q: q.iter().copied().fold(0.0, f64::max),
        };
        if let Some(k) = equilibrium
            .edges_forces_n
            .iter()
            .position(|t| !t.is_finite())
        {
            return Err(overflow(format!("tension of cable {k}")));
        }
        let finite = |v: &[f64; 3]| v.iter().all(|c| c.is_finite());
        if let Some(g) = equilibrium.reactions_n.iter().position(|r| !finite(r)) {
            return Err(overflow(format!(
                "reaction at fixed node {}",
                self.fixed[g]
            )));
        }
        if let Some(i) = equilibrium.residuals_n.iter().position(|r| !finite(r)) {
            return Err(overflow(format!("residual at node {}", self.free[i])));
        }
        Ok(equilibrium)
    }

    /// The out-of-balance force at every free node in *edge form*,
    /// `r_f = p_f − Σ_k C_fk q_k u_k` with `u_k = x_i − x_j` (n_free × 3), and
    /// the largest componentwise backward error `max |r| / (Σ_k |q_k u_k| + |p|)`.
    ///
    /// Edge form matters: `u_k` is a difference of nearby coordinates, exact or
    /// nearly so, so the residual is accurate relative to the forces meeting
    /// at each node, where `p − D x` would carry the roundoff of `q·|x|`.
    fn edge_residual(
        &self,
        q: &[f64],
        xyz: &[[f64; 3]],
        loads: Option<&[[f64; 3]]>,
    ) -> (Mat<f64>, f64) {
        let n_free = self.free.len();
        let mut r =
            Mat::<f64>::from_fn(n_free, 3, |f, c| loads.map_or(0.0, |p| p[self.free[f]][c]));
        let mut scale = Mat::<f64>::from_fn(n_free, 3, |f, c| r[(f, c)].abs());
        for (&[i, j], &qk) in self.edges.iter().zip(q) {
            for c in 0..3 {
                let force = qk * (xyz[i][c] - xyz[j][c]);
                for (node, sign) in [(i, -1.0), (j, 1.0)] {
                    let f = self.free_index[node];
                    if f != NONE {
                        r[(f, c)] += sign * force;
                        scale[(f, c)] += force.abs();
                    }
                }
            }
        }
        let mut worst = 0.0f64;
        for f in 0..n_free {
            for c in 0..3 {
                if scale[(f, c)] > 0.0 {
                    worst = worst.max(r[(f, c)].abs() / scale[(f, c)]);
                }
            }
        }
        (r, worst)
    }

    /// Iterative refinement with the edge-form residual: while some node's
    /// backward error exceeds [`REFINE_ABOVE`], solve `D δ = r` with the factor
    /// at hand and move the free nodes by `δ`, keeping the best iterate.
    ///
    /// Force densities spanning many decades make `D` ill-conditioned
    /// (cond ~ q_max/q_min · n²); Cholesky stays backward stable in `D`'s
    /// entries, but a stiff cable's `q (x_i − x_j)` then hides the weak cables'
    /// forces in its roundoff. The edge-form residual resolves them, and
    /// refinement against it converges while `ε · cond(D) < 1` (a chain of
    /// cables with q alternating between 1e-6 and 1e6: node errors from 1e-3 m
    /// to roundoff in three steps). Well-conditioned nets pass the test at
    /// once and cost one residual evaluation.
    fn refine(
        &self,
        factor: &Factor,
        q: &[f64],
        xyz: &mut [[f64; 3]],
        loads: Option<&[[f64; 3]]>,
        mut x: Mat<f64>,
    ) {
        let (mut r, mut error) = self.edge_residual(q, xyz, loads);
        if error <= REFINE_ABOVE {
            return;
        }
        let mut best = (error, xyz.to_vec());
        let mut buffer = MemBuffer::new(factor.symbolic.solve_in_place_scratch::<f64>(3, PAR));
        let mut worse = 0;
        for _ in 0..MAX_REFINEMENTS {
            if best.0 <= REFINE_ABOVE || worse >= 3 || !error.is_finite() {
                break;
            }
            factor.solve_in_place(r.as_mut(), MemStack::new(&mut buffer));
            x = &x + &r;
            let mut trial = xyz.to_vec();
            for (f, &i) in self.free.iter().enumerate() {
                trial[i] = [x[(f, 0)], x[(f, 1)], x[(f, 2)]];
            }
            (r, error) = self.edge_residual(q, &trial, loads);
            if error < best.0 {
                best = (error, trial);
                worse = 0;
            } else {
                worse += 1;
            }
        }
        xyz.copy_from_slice(&best.1);
    }

    /// The equilibrium matrix of the inverse form, `A(x)` (3·n_free × n_edges):
    /// `A[(f, c), k] = C[k, i] u[k, c]` for free node `i` with free index `f`, row
    /// `3f + c`. With every position prescribed, equilibrium is linear in q:
    /// `A(x) q = p_f`.
    ///
    /// # Panics
    /// If `nodes` is not n_nodes × 3.
    #[track_caller]
    pub fn equilibrium_matrix(&self, nodes: &[[f64; 3]]) -> SparseColMat<usize, f64> {
        assert_eq!(nodes.len(), self.n_nodes, "nodes: one row per node");
        let u = edges_vectors(&self.edges, nodes);
        let mut triplets = Vec::with_capacity(6 * self.n_edges());
        for (k, (&[i, j], uk)) in self.edges.iter().zip(&u).enumerate() {
            for (node, sign) in [(i, 1.0), (j, -1.0)] {
                let f = self.free_index[node];
                if f != NONE {
                    for (c, &uc) in uk.iter().enumerate() {
                        triplets.push(Triplet::new(3 * f + c, k, sign * uc));
                    }
                }
            }
        }
        SparseColMat::try_new_from_triplets(3 * self.free.len(), self.n_edges(), &triplets)
            .expect("indices are in range by construction")
    }
}

/// Builds the lower-triangular sparsity of `D` (diagonal first in each column,
/// rows ascending) and each cable's value slots in it.
pub(crate) fn d_sparsity(
    edges: &[[usize; 2]],
    free_index: &[usize],
    n_free: usize,
) -> (SymbolicSparseColMat<usize>, Vec<EdgeSlots>) {
    // Column c holds row c (the diagonal) and every free neighbour r > c.
    let mut col_ptr = vec![0usize; n_free + 1];
    for c in 0..n_free {
        col_ptr[c + 1] = 1;
    }
    let free_pair = |&[i, j]: &[usize; 2]| {
        let (a, b) = (free_index[i], free_index[j]);
        (a != NONE && b != NONE).then(|| (a.min(b), a.max(b)))
    };
    for (c, _) in edges.iter().filter_map(free_pair) {
        col_ptr[c + 1] += 1;
    }
    for c in 0..n_free {
        col_ptr[c + 1] += col_ptr[c];
    }
    let mut row_idx = vec![0usize; col_ptr[n_free]];
    let mut fill = col_ptr.clone();
    for c in 0..n_free {
        row_idx[fill[c]] = c;
        fill[c] += 1;
    }
    for (c, r) in edges.iter().filter_map(free_pair) {
        row_idx[fill[c]] = r;
        fill[c] += 1;
    }
    // Sort and deduplicate each column (parallel cables share a slot).
    let mut compact_ptr = vec![0usize; n_free + 1];
    let mut write = 0;
    for c in 0..n_free {
        let column = &mut row_idx[col_ptr[c]..col_ptr[c + 1]];
        column.sort_unstable();
        let mut previous = NONE;
        for read in col_ptr[c]..col_ptr[c + 1] {
            let r = row_idx[read];
            if r != previous {
                row_idx[write] = r;
                write += 1;
                previous = r;
            }
        }
        compact_ptr[c + 1] = write;
    }
    row_idx.truncate(write);

    let slot = |c: usize, r: usize| {
        let column = &row_idx[compact_ptr[c]..compact_ptr[c + 1]];
        compact_ptr[c] + column.binary_search(&r).expect("entry is in the pattern")
    };
    let edge_slots = edges
        .iter()
        .map(|&[i, j]| {
            let (a, b) = (free_index[i], free_index[j]);
            let diagonal = [a, b].map(|f| if f == NONE { NONE } else { compact_ptr[f] });
            let off_diagonal = if a != NONE && b != NONE {
                slot(a.min(b), a.max(b))
            } else {
                NONE
            };
            EdgeSlots {
                diagonal,
                off_diagonal,
            }
        })
        .collect();
    let pattern = SymbolicSparseColMat::new_checked(n_free, n_free, compact_ptr, None, row_idx);
    (pattern, edge_slots)
}

/// The numeric Cholesky factor `D = L Lᵀ` of one `q`, sharing the symbolic part.
#[derive(Debug, Clone)]
struct Factor {
    symbolic: Arc<SymbolicCholesky<usize>>,
    l_values: Vec<f64>,
}

impl Factor {
    /// Solves `D x = rhs` in place, using `stack` as scratch.
    fn solve_in_place(&self, rhs: MatMut<'_, f64>, stack: &mut MemStack) {
        LltRef::new(&self.symbolic, &self.l_values).solve_in_place_with_conj(
            Conj::No,
            rhs,
            PAR,
            stack,
        );
    }
}

/// An equilibrium state of the network for one `q`: what the forward solve
/// returns, plus the numeric factor of `D` for adjoint sensitivities.
#[derive(Debug, Clone)]
pub struct Equilibrium {
    /// Node positions (m): n_nodes × 3; fixed nodes as given.
    pub nodes_xyz_m: Vec<[f64; 3]>,
    /// Edge vectors `u = C x` (m): n_edges × 3.
    pub edges_vectors_m: Vec<[f64; 3]>,
    /// Cable lengths `ℓ_k = |u_k|` (m): n_edges.
    pub edges_lengths_m: Vec<f64>,
    /// Cable tensions `T_k = q_k ℓ_k` (N): n_edges.
    pub edges_forces_n: Vec<f64>,
    /// Support reactions `F_g = C_gᵀ Q C x − p_g` (N), one per fixed node in the
    /// order of [`FdmStructure::fixed_nodes`]: the force the support applies to
    /// the node. The net pulls on its supports with `−F_g − p_g`.
    pub reactions_n: Vec<[f64; 3]>,
    /// Out-of-balance force `p_f − C_fᵀ Q u` at every free node (N): n_free × 3.
    pub residuals_n: Vec<[f64; 3]>,
    factor: Option<Factor>,
}

impl Equilibrium {
    fn new(
        structure: &FdmStructure,
        q: &[f64],
        nodes_xyz_m: Vec<[f64; 3]>,
        loads: Option<&[[f64; 3]]>,
        factor: Option<Factor>,
    ) -> Self {
        let u = edges_vectors(&structure.edges, &nodes_xyz_m);
        let lengths: Vec<f64> = u.iter().map(|&v| norm3(v)).collect();
        let forces = lengths.iter().zip(q).map(|(l, qk)| l * qk).collect();
        // Internal force C^T Q u at every node.
        let mut internal = vec![[0.0; 3]; structure.n_nodes];
        for ((&[i, j], uk), &qk) in structure.edges.iter().zip(&u).zip(q) {
            for c in 0..3 {
                internal[i][c] += qk * uk[c];
                internal[j][c] -= qk * uk[c];
            }
        }
        let load = |i: usize| loads.map_or([0.0; 3], |p| p[i]);
        let residuals_n = structure
            .free
            .iter()
            .map(|&i| std::array::from_fn(|c| load(i)[c] - internal[i][c]))
            .collect();
        let reactions_n = structure
            .fixed
            .iter()
            .map(|&i| std::array::from_fn(|c| internal[i][c] - load(i)[c]))
            .collect();
        Equilibrium {
            nodes_xyz_m,
            edges_vectors_m: u,
            edges_lengths_m: lengths,
            edges_forces_n: forces,
            reactions_n,
            residuals_n,
            factor,
        }
    }

    /// Largest out-of-balance force at a free node (N, Euclidean norm per node).
    pub fn max_residual_n(&self) -> f64 {
        self.residuals_n
            .iter()
            .map(|&r| norm3(r))
            .fold(0.0, f64::max)
    }

    /// Largest cable tension (N).
    pub fn max_force_n(&self) -> f64 {
        self.edges_forces_n.iter().copied().fold(0.0, f64::max)
    }

    /// Solves `D x = rhs` in place for the three columns of `rhs` (one row
    /// per free node, in free order) with this equilibrium's factor of `D`
    /// (eq. 3–4); `rhs` is left as it is when no node is free.
    ///
    /// # Panics
    /// If `rhs` has not one row per free node of the factored `D`.
    #[track_caller]
    pub fn solve_d(&self, rhs: &mut [[f64; 3]]) {
        let Some(factor) = &self.factor else {
            return;
        };
        let n_free = rhs.len();
        let mut x = Mat::<f64>::from_fn(n_free, 3, |f, c| rhs[f][c]);
        let mut buffer = MemBuffer::new(factor.symbolic.solve_in_place_scratch::<f64>(3, PAR));
        factor.solve_in_place(x.as_mut(), MemStack::new(&mut buffer));
        for (f, row) in rhs.iter_mut().enumerate() {
            *row = [x[(f, 0)], x[(f, 1)], x[(f, 2)]];
        }
    }

    /// Adjoint sensitivities of an objective `J(x_f, q)` (DESIGN §3): solves
    /// `D λ = ∂J/∂x_f` with the factor already at hand, then
    /// `dJ/dq_k = ∂J/∂q_k − Σ_c (C_f λ_c)_k u_{k,c}`.
    ///
    /// `dj_dx`: n_nodes × 3 (entries of fixed nodes are ignored); `dj_dq`: n_edges,
    /// or `None` when `J` depends on `q` only through the positions.
    ///
    /// # Panics
    /// If the shapes do not match `structure`, or `structure` is not the one
    /// this equilibrium was solved with.
    #[track_caller]
    pub fn sensitivities(
        &self,
        structure: &FdmStructure,
        dj_dx: &[[f64; 3]],
        dj_dq: Option<&[f64]>,
    ) -> Vec<f64> {
        assert_eq!(dj_dx.len(), structure.n_nodes, "dj_dx: one row per node");
        assert_eq!(
            self.edges_vectors_m.len(),
            structure.n_edges(),
            "structure mismatch"
        );
        let mut gradient = match dj_dq {
            Some(g) => {
                assert_eq!(g.len(), structure.n_edges(), "dj_dq: one entry per edge");
                g.to_vec()
            }
            None => vec![0.0; structure.n_edges()],
        };
        let mut lambda: Vec<[f64; 3]> = structure.free.iter().map(|&i| dj_dx[i]).collect();
        self.solve_d(&mut lambda);
        let lambda_of = |node: usize, c: usize| {
            let f = structure.free_index[node];
            if f == NONE {
                0.0
            } else {
                lambda[f][c]
            }
        };
        for (k, (&[i, j], uk)) in structure
            .edges
            .iter()
            .zip(&self.edges_vectors_m)
            .enumerate()
        {
            let projected: f64 = (0..3)
                .map(|c| (lambda_of(i, c) - lambda_of(j, c)) * uk[c])
                .sum();
            gradient[k] -= projected;
        }
        gradient
    }
}

/// Forward equilibrium of a network with its own `q`, positions and loads.
pub fn solve_network(network: &Network) -> Result<(FdmStructure, Equilibrium), FdmError> {
    let structure = FdmStructure::new(network)?;
    let equilibrium = structure.solve(&network.q, &network.nodes, network.loads.as_deref())?;
    Ok((structure, equilibrium))
}
