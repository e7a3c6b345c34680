//! Sparse assembly of the residual and the consistent tangent of a [`Model`],
//! joints by Lagrange multipliers, and their solution: dense LU for small
//! systems, the cable net condensed onto the frame when the model has one
//! ([`super::condensed`]), faer's sparse LU otherwise.
//!
//! Unknowns: the free components of every node's increment `(δx, δθ)` (fixed
//! components are eliminated), then one multiplier per joint equation. The
//! equations are scaled by a stiffness `s` so that the saddle-point matrix
//!
//! ```text
//! ⎡ K + s Σ μ ∂²g   s Gᵀ ⎤
//! ⎣ s G              0   ⎦
//! ```
//!
//! stays balanced for thin tubes (EA·L²/EI up to 1e8). The sparsity pattern and
//! the symbolic factorisation are computed once; each Newton iteration refills values in
//! the same order and refactors numerically.

use std::sync::Arc;

use super::sparse_lu::{Lu, SymbolicLu};
use faer::linalg::solvers::PartialPivLu;
use faer::sparse::{Argsort, Pair, SparseColMat, SymbolicSparseColMat};
use faer::{Mat, MatMut};
use rayon::prelude::*;

use super::cable::SLACK_STIFFNESS_RATIO;
pub(crate) use super::condensed::Precision;
use super::condensed::{Condensation, CondensedError, CondensedFactor};
use super::joint::ConstraintRow;
use super::model::{MechanicsError, Model};
use super::node::Frame;
use crate::algebra::{norm_inf, Plain};

/// Index of a fixed component.
const FIXED: usize = usize::MAX;

/// Elements below which they are evaluated on one thread: an element costs a
/// few microseconds, a parallel fork-join about as much as ten of them.
const PARALLEL_ELEMENTS: usize = 64;

/// Unknowns up to which the tangent is factored dense: at a cantilever of 10
/// elements (60 unknowns) the dense LU takes a fraction of the per-column
/// overhead of the sparse one; at 96 unknowns they cost the same.
const DENSE_ROWS: usize = 64;

/// A factorisation of the tangent: dense for small systems, sparse otherwise.
pub(crate) enum Factor {
    Dense(PartialPivLu<f64>),
    Sparse(Lu),
    /// The cable net's points condensed onto the frame.
    Condensed(CondensedFactor),
}

/// Why the tangent could not be factored.
#[derive(Debug, Clone, thiserror::Error)]
pub(crate) enum FactorError {
    /// A pivot of the dense LU at or below the roundoff of a zero pivot,
    /// `n ε ‖J‖max`, or not a number: a mechanism.
    #[error("singular tangent: pivot {pivot} is {value:e}, below the roundoff {roundoff:e}")]
    SingularPivot {
        /// The pivot's index.
        pivot: usize,
        /// Its value.
        value: f64,
        /// The roundoff of a zero pivot.
        roundoff: f64,
    },
    /// faer could not build the sparse matrix from the pattern's values.
    #[error("{}", .0.plain())]
    SparseMatrix(faer::sparse::FaerError),
    /// faer's sparse LU failed (a structurally singular matrix, or memory).
    #[error("{}", .0.plain())]
    SparseLu(faer::sparse::linalg::LuError),
    /// The tangent has entries that are not finite: a modulus, a section or
    /// a displacement beyond double precision.
    #[error("{count} entries of the tangent are not finite")]
    NotFinite {
        /// How many.
        count: usize,
    },
    /// The cable net could not be condensed onto the frame.
    #[error(transparent)]
    Condensed(#[from] CondensedError),
}

impl From<FactorError> for MechanicsError {
    /// A tangent that cannot be factored: not finite, out of memory, or
    /// singular (a mechanism), each said as such.
    fn from(e: FactorError) -> Self {
        let out_of_memory = matches!(
            e,
            FactorError::SparseMatrix(faer::sparse::FaerError::OutOfMemory)
                | FactorError::SparseLu(faer::sparse::linalg::LuError::Generic(
                    faer::sparse::FaerError::OutOfMemory
                ))
        );
        match e {
            FactorError::NotFinite { .. } => MechanicsError::NotFinite {
                detail: e.to_string(),
            },
            _ if out_of_memory => MechanicsError::OutOfMemory {
                detail: e.to_string(),
            },
            _ => MechanicsError::Mechanism {
                detail: e.to_string(),
            },
        }
    }
}

/// The assembled problem's structure: dof numbering, pattern, symbolic factorisation.
pub(crate) struct System {
    /// Global unknown of node n's component c (or `FIXED`).
    dof: Vec<[usize; 6]>,
    pub n_free: usize,
    /// First multiplier row of each joint.
    joint_row: Vec<usize>,
    pub n_rows: usize,
    /// Constraint scaling `s`, N/m.
    pub scale: f64,
    pattern: Vec<Pair<usize, usize>>,
    symbolic: SymbolicSparseColMat<usize>,
    argsort: Argsort<usize>,
    /// How the tangent is factored above [`DENSE_ROWS`].
    sparse: SparseFactorisation,
    /// The structure of the sparse inertia count, analysed at its first
    /// use ([`super::stability::negative_eigenvalues`]); `None` inside when
    /// it could not be.
    pub(crate) inertia: std::sync::OnceLock<Option<super::inertia::InertiaStructure>>,
}

/// The symbolic factorisation of a sparse tangent.
enum SparseFactorisation {
    /// The cable net's points condensed onto the rest (a model with points).
    Condensed(Arc<Condensation>),
    /// faer's sparse LU of the whole tangent.
    Lu(SymbolicLu),
}

/// The state of the unknowns: node frames and scaled multipliers.
#[derive(Debug, Clone)]
pub struct State {
    /// Every node's position and rotation.
    pub frames: Vec<Frame>,
    /// Joint multipliers (scaled by the system's stiffness scale).
    pub(crate) multipliers: Vec<f64>,
}

/// The constraint scale `s` of a model: the stiffest element's or cable's
/// axial stiffness EA/L, N/m (it also sets the roundoff floor of the forces).
pub(crate) fn constraint_scale(model: &Model) -> f64 {
    model
        .elements
        .iter()
        .map(|e| e.axial_stiffness())
        .chain(
            model
                .cables
                .iter()
                .map(|c| c.axial_n() / c.rest_length_m(0.0).min(c.rest_length_m(1.0))),
        )
        .fold(0.0, f64::max)
        .max(1.0)
}

impl State {
    /// Multiply every multiplier by `factor`: a state of a model of
    /// constraint scale `s₁` starts a model of scale `s₂` with
    /// `factor = s₁/s₂` (the joint forces `s μ` are what carries over).
    pub(crate) fn rescale_multipliers(&mut self, factor: f64) {
        self.multipliers.iter_mut().for_each(|m| *m *= factor);
    }

    /// Take the multipliers of the first joints from `other`, a state of a
    /// model whose joints are the first joints of this one (a sub-model).
    ///
    /// # Panics
    /// If `other` has more multipliers than this state.
    #[track_caller]
    pub fn set_multipliers(&mut self, other: &State) {
        let n = other.multipliers.len();
        self.multipliers[..n].copy_from_slice(&other.multipliers);
    }
}

/// Residual and support reactions at a state, without the tangent: what a
/// step's line search and convergence tests read.
pub(crate) struct Forces {
    /// Residual of every unknown (forces, moments, joint equations).
    pub residual: Vec<f64>,
    /// Residual of every fixed component: the support reactions, per node.
    pub reactions: Vec<[f64; 6]>,
    /// Largest internal nodal force component of any element or cable
    /// (roundoff scale).
    pub internal_scale: f64,
    /// Largest force component of any cable: the force scale of a prestressed
    /// structure with no external load.
    pub prestress_scale: f64,
}

/// Residual and tangent values at a state.
pub(crate) struct Evaluation {
    /// The residual and reactions.
    pub forces: Forces,
    /// Tangent values in pattern order.
    pub values: Vec<f64>,
}

impl System {
    /// The structure of `model`.
    pub fn new(model: &Model) -> Result<Self, MechanicsError> {
        let mut dof = vec![[FIXED; 6]; model.node_count()];
        let mut n_free = 0;
        for (n, d) in dof.iter_mut().enumerate() {
            for (c, slot) in d.iter_mut().enumerate().take(model.node_dofs[n]) {
                if !model.fixed[n][c] {
                    *slot = n_free;
                    n_free += 1;
                }
            }
        }
        let mut joint_row = Vec::with_capacity(model.joints.len());
        let mut n_rows = n_free;
        for j in &model.joints {
            joint_row.push(n_rows);
            n_rows += j.rows();
        }
        let scale = constraint_scale(model);

        let mut pattern = Vec::new();
        let block = |a: usize, b: usize, pattern: &mut Vec<Pair<usize, usize>>| {
            for &i in dof[a].iter().filter(|&&i| i != FIXED) {
                for &j in dof[b].iter().filter(|&&j| j != FIXED) {
                    pattern.push(Pair { row: i, col: j });
                }
            }
        };
        for e in &model.elements {
            for a in e.nodes {
                for b in e.nodes {
                    block(a, b, &mut pattern);
                }
            }
        }
        for c in &model.cables {
            for a in c.nodes {
                for b in c.nodes {
                    for &i in dof[a][..3].iter().filter(|&&i| i != FIXED) {
                        for &j in dof[b][..3].iter().filter(|&&j| j != FIXED) {
                            pattern.push(Pair { row: i, col: j });
                        }
                    }
                }
            }
        }
        for (k, j) in model.joints.iter().enumerate() {
            for a in j.nodes {
                for b in j.nodes {
                    block(a, b, &mut pattern);
                }
            }
            for r in 0..j.rows() {
                let row = joint_row[k] + r;
                for n in j.nodes {
                    for &i in dof[n].iter().filter(|&&i| i != FIXED) {
                        pattern.push(Pair { row, col: i });
                        pattern.push(Pair { row: i, col: row });
                    }
                }
            }
        }
        // Every diagonal entry, so that the pattern is structurally square.
        pattern.extend((0..n_rows).map(|i| Pair { row: i, col: i }));

        let (symbolic, argsort) =
            SymbolicSparseColMat::try_new_from_indices(n_rows, n_rows, &pattern).map_err(|e| {
                MechanicsError::Mechanism {
                    detail: format!("sparsity pattern: {}", e.plain()),
                }
            })?;
        // The net's points: translations of nodes that only cables hold.
        let mut held_otherwise = vec![false; model.node_count()];
        for n in model.elements.iter().flat_map(|e| e.nodes) {
            held_otherwise[n] = true;
        }
        for n in model.joints.iter().flat_map(|j| j.nodes) {
            held_otherwise[n] = true;
        }
        let mut point = vec![false; n_rows];
        for (n, d) in dof.iter().enumerate() {
            if model.node_dofs[n] == 3 && !held_otherwise[n] {
                for &i in d[..3].iter().filter(|&&i| i != FIXED) {
                    point[i] = true;
                }
            }
        }
        let condensation = if n_rows > DENSE_ROWS {
            Condensation::new(n_rows, &pattern, &point)
                .map_err(|detail| MechanicsError::Mechanism { detail })?
        } else {
            None
        };
        let sparse =
            match condensation {
                Some(condensation) => SparseFactorisation::Condensed(Arc::new(condensation)),
                None => SparseFactorisation::Lu(SymbolicLu::try_new(symbolic.as_ref()).map_err(
                    |e| MechanicsError::Mechanism {
                        detail: format!("symbolic LU: {}", e.plain()),
                    },
                )?),
            };
        Ok(System {
            dof,
            n_free,
            joint_row,
            n_rows,
            scale,
            pattern,
            symbolic,
            argsort,
            sparse,
            inertia: std::sync::OnceLock::new(),
        })
    }

    /// The reference state: reference frames, zero multipliers.
    pub fn reference_state(&self, model: &Model) -> State {
        State {
            frames: model.reference.clone(),
            multipliers: vec![0.0; self.n_rows - self.n_free],
        }
    }

    /// Residual `F = f_int + s Gᵀμ − λ f_ext` (free components), `s g` (joint
    /// rows), and the tangent values, at `state` and load factor `lambda`.
    pub fn evaluate(&self, model: &Model, state: &State, lambda: f64) -> Evaluation {
        self.evaluate_with(model, state, lambda, SLACK_STIFFNESS_RATIO)
    }

    /// [`System::evaluate`] with an iteration matrix in place of the
    /// tangent: slack cables keep `slack_tangent_ratio × EA` of axial
    /// stiffness in it (the residual is the same).
    pub(crate) fn evaluate_with(
        &self,
        model: &Model,
        state: &State,
        lambda: f64,
        slack_tangent_ratio: f64,
    ) -> Evaluation {
        let mut values = Vec::new();
        let forces = self.assemble(
            model,
            state,
            lambda,
            Some((slack_tangent_ratio, &mut values)),
        );
        Evaluation { forces, values }
    }

    /// The residual and reactions at `state` and load factor `lambda`
    /// alone: [`System::evaluate`] without assembling the tangent.
    pub(crate) fn forces(&self, model: &Model, state: &State, lambda: f64) -> Forces {
        self.assemble(model, state, lambda, None)
    }

    /// The tangent values of [`System::evaluate_with`] into `values`
    /// (cleared first, its allocation reused: at 10⁵ nodes the values are
    /// ≈ 80 MB, and a fresh buffer's first touch of each page cost as much
    /// as filling it).
    pub(crate) fn tangent_into(
        &self,
        model: &Model,
        state: &State,
        lambda: f64,
        slack_tangent_ratio: f64,
        values: &mut Vec<f64>,
    ) {
        self.assemble(model, state, lambda, Some((slack_tangent_ratio, values)));
    }

    /// The residual and reactions, and the tangent values into `tangent`'s
    /// buffer where asked for (slack cables keeping its ratio of EA).
    fn assemble(
        &self,
        model: &Model,
        state: &State,
        lambda: f64,
        mut tangent: Option<(f64, &mut Vec<f64>)>,
    ) -> Forces {
        let n_nodes = model.node_count();
        let mut full = vec![[0.0f64; 6]; n_nodes];
        if let Some((_, values)) = tangent.as_mut() {
            values.clear();
            values.reserve(self.pattern.len());
        }
        let element = |e: &super::beam::BeamElement| {
            let [a, b] = e.nodes;
            e.residual_tangent([&state.frames[a], &state.frames[b]])
        };
        let element_terms: Vec<_> = if model.elements.len() < PARALLEL_ELEMENTS {
            model.elements.iter().map(element).collect()
        } else {
            model.elements.par_iter().map(element).collect()
        };
        let mut internal_scale = 0.0f64;
        for (e, (r, k)) in model.elements.iter().zip(&element_terms) {
            internal_scale = internal_scale.max(r.amax());
            for (slot, &n) in e.nodes.iter().enumerate() {
                for c in 0..6 {
                    full[n][c] += r[6 * slot + c];
                }
            }
            let Some((_, values)) = tangent.as_mut() else {
                continue;
            };
            for sa in 0..2 {
                for sb in 0..2 {
                    let (a, b) = (e.nodes[sa], e.nodes[sb]);
                    for ca in (0..6).filter(|&c| self.dof[a][c] != FIXED) {
                        for cb in (0..6).filter(|&c| self.dof[b][c] != FIXED) {
                            values.push(k[(6 * sa + ca, 6 * sb + cb)]);
                        }
                    }
                }
            }
        }

        let mut prestress_scale = 0.0f64;
        for c in &model.cables {
            let [a, b] = c.nodes;
            let (pa, pb) = (&state.frames[a].position_m, &state.frames[b].position_m);
            let (f, k) = match tangent.as_mut() {
                Some((ratio, _)) => {
                    let (f, k) = c.force_tangent(pa, pb, lambda, *ratio);
                    (f, Some(k))
                }
                None => (c.force(pa, pb, lambda), None),
            };
            prestress_scale = prestress_scale.max(f.amax());
            for comp in 0..3 {
                full[a][comp] -= f[comp];
                full[b][comp] += f[comp];
            }
            let (Some(k), Some((_, values))) = (k, tangent.as_mut()) else {
                continue;
            };
            for (sa, na) in c.nodes.into_iter().enumerate() {
                for (sb, nb) in c.nodes.into_iter().enumerate() {
                    let sign = if sa == sb { 1.0 } else { -1.0 };
                    for ca in (0..3).filter(|&c| self.dof[na][c] != FIXED) {
                        for cb in (0..3).filter(|&c| self.dof[nb][c] != FIXED) {
                            values.push(sign * k[(ca, cb)]);
                        }
                    }
                }
            }
        }
        internal_scale = internal_scale.max(prestress_scale);

        let mut residual = vec![0.0; self.n_rows];
        let mut rows: Vec<ConstraintRow> = Vec::new();
        let s = self.scale;
        for (k, j) in model.joints.iter().enumerate() {
            let [a, b] = j.nodes;
            j.evaluate([&state.frames[a], &state.frames[b]], &mut rows);
            let first = self.joint_row[k] - self.n_free;
            // Tangent: s Σ μ ∂²g on the rotation blocks.
            if let Some((_, values)) = tangent.as_mut() {
                for sa in 0..2 {
                    for sb in 0..2 {
                        let (na, nb) = (j.nodes[sa], j.nodes[sb]);
                        for ca in (0..6).filter(|&c| self.dof[na][c] != FIXED) {
                            for cb in (0..6).filter(|&c| self.dof[nb][c] != FIXED) {
                                let mut v = 0.0;
                                if ca >= 3 && cb >= 3 {
                                    for (r, row) in rows.iter().enumerate() {
                                        v += state.multipliers[first + r]
                                            * row.curvature[sa][sb][(ca - 3, cb - 3)];
                                    }
                                }
                                values.push(s * v);
                            }
                        }
                    }
                }
            }
            for (r, row) in rows.iter().enumerate() {
                let mu = state.multipliers[first + r];
                residual[self.joint_row[k] + r] = s * row.value;
                for (slot, &n) in j.nodes.iter().enumerate() {
                    for (f, g) in full[n]
                        .iter_mut()
                        .zip(&row.gradient[6 * slot..6 * slot + 6])
                    {
                        *f += s * mu * g;
                    }
                    let Some((_, values)) = tangent.as_mut() else {
                        continue;
                    };
                    for c in (0..6).filter(|&c| self.dof[n][c] != FIXED) {
                        let g = s * row.gradient[6 * slot + c];
                        values.push(g);
                        values.push(g);
                    }
                }
            }
        }
        if let Some((_, values)) = tangent.as_mut() {
            values.extend(std::iter::repeat_n(0.0, self.n_rows));
            debug_assert_eq!(values.len(), self.pattern.len());
        }

        for l in &model.loads {
            for c in 0..3 {
                full[l.node][c] -= lambda * l.force_n[c];
                full[l.node][3 + c] -= lambda * l.moment_nm[c];
            }
        }
        let mut reactions = vec![[0.0; 6]; n_nodes];
        for n in 0..n_nodes {
            for c in 0..model.node_dofs[n] {
                match self.dof[n][c] {
                    FIXED => reactions[n][c] = full[n][c],
                    i => residual[i] = full[n][c],
                }
            }
        }
        Forces {
            residual,
            reactions,
            internal_scale,
            prestress_scale,
        }
    }

    /// Factor the tangent with `values` (pattern order).
    ///
    /// # Errors
    /// A singular tangent: for the dense factor, a pivot below `n ε ‖J‖max`,
    /// the roundoff of a zero pivot (a mechanism).
    pub fn factor(&self, values: &[f64]) -> Result<Factor, FactorError> {
        self.refactor(values, Precision::Double, None)
    }

    /// [`System::factor`] with the cable net's LDLᵀ in `precision` where
    /// the tangent is condensed (the dense and sparse LU are double), in
    /// `previous`'s storage where it has the same form (a refactorisation:
    /// at 10⁵ nodes a fresh LDLᵀ's first touch of its pages cost as much as
    /// a third of the factorisation).
    ///
    /// # Errors
    /// As [`System::factor`].
    pub(crate) fn refactor(
        &self,
        values: &[f64],
        precision: Precision,
        previous: Option<Factor>,
    ) -> Result<Factor, FactorError> {
        let count = values.iter().filter(|v| !v.is_finite()).count();
        if count > 0 {
            return Err(FactorError::NotFinite { count });
        }
        if self.n_rows <= DENSE_ROWS {
            let dense = self.dense_tangent(values);
            let largest = norm_inf(values);
            let lu = dense.partial_piv_lu();
            let roundoff = self.n_rows as f64 * f64::EPSILON * largest;
            let u = lu.U();
            let singular = |i: &usize| {
                let pivot = u[(*i, *i)].abs();
                pivot.is_nan() || pivot <= roundoff
            };
            if let Some(i) = (0..self.n_rows).find(singular) {
                return Err(FactorError::SingularPivot {
                    pivot: i,
                    value: u[(i, i)],
                    roundoff,
                });
            }
            return Ok(Factor::Dense(lu));
        }
        match (&self.sparse, previous) {
            (SparseFactorisation::Condensed(c), previous) => {
                let previous = match previous {
                    Some(Factor::Condensed(f)) => Some(f),
                    _ => None,
                };
                Ok(Factor::Condensed(c.factor(values, precision, previous)?))
            }
            (SparseFactorisation::Lu(lu), previous) => {
                let previous = match previous {
                    Some(Factor::Sparse(f)) => Some(f),
                    _ => None,
                };
                let matrix = self
                    .sparse_tangent(values)
                    .map_err(FactorError::SparseMatrix)?;
                Lu::refactor(lu.clone(), matrix.as_ref(), previous)
                    .map(Factor::Sparse)
                    .map_err(FactorError::SparseLu)
            }
        }
    }

    /// The tangent with `values` (pattern order) as a dense matrix.
    pub(crate) fn dense_tangent(&self, values: &[f64]) -> Mat<f64> {
        let mut dense = Mat::<f64>::zeros(self.n_rows, self.n_rows);
        for (p, v) in self.pattern.iter().zip(values) {
            dense[(p.row, p.col)] += v;
        }
        dense
    }

    /// The tangent with `values` (pattern order) as a sparse matrix
    /// (duplicates summed; the pattern is structurally symmetric).
    pub(crate) fn sparse_tangent(
        &self,
        values: &[f64],
    ) -> Result<SparseColMat<usize, f64>, faer::sparse::FaerError> {
        SparseColMat::new_from_argsort(self.symbolic.clone(), &self.argsort, values)
    }

    /// Solve `J Δ = rhs` in place with a factor of the tangent.
    pub fn solve_in_place(lu: &Factor, rhs: MatMut<'_, f64>) {
        use faer::linalg::solvers::SolveCore;
        match lu {
            Factor::Dense(lu) => lu.solve_in_place_with_conj(faer::Conj::No, rhs),
            Factor::Sparse(lu) => lu.solve_in_place(rhs),
            Factor::Condensed(factor) => factor.solve_in_place(rhs),
        }
    }

    /// Apply the increment `delta` (unknown order) to `state`:
    /// `x ← x + δx`, `R ← exp(δθ̃) R`, `μ ← μ + δμ`.
    pub fn apply(&self, state: &mut State, delta: &[f64], step: f64) {
        for (n, frame) in state.frames.iter_mut().enumerate() {
            let d = |c: usize| match self.dof[n][c] {
                FIXED => 0.0,
                i => step * delta[i],
            };
            frame.position_m += nalgebra::Vector3::new(d(0), d(1), d(2));
            let theta = nalgebra::Vector3::new(d(3), d(4), d(5));
            if theta != nalgebra::Vector3::zeros() {
                frame.rotation = super::rotation::exp(&theta) * frame.rotation;
                frame.rotation.renormalize();
            }
        }
        for (mu, d) in state.multipliers.iter_mut().zip(&delta[self.n_free..]) {
            *mu += step * d;
        }
    }

    /// The free unknown of node `n`'s component `c`, if not fixed.
    pub fn unknown(&self, n: usize, c: usize) -> Option<usize> {
        (self.dof[n][c] != FIXED).then_some(self.dof[n][c])
    }

    /// A column vector of the unknowns' size.
    pub fn column(&self, values: &[f64]) -> Mat<f64> {
        Mat::from_fn(self.n_rows, 1, |i, _| values[i])
    }
}
