//! The Newton system of the step's interior point (`ipm.rs`), reduced to the
//! net's node graph.
//!
//! With `D` the barrier weights `λ/s` of the inequality rows, the system in
//! `(δz, δy)` is `[H + GᵀDG, Eᵀ; E, 0]`. Its parts:
//!
//! * `p` (one per cable): the box rows and the set rows of cable `k` give
//!   the diagonal `h_k = d_k + D_k` (`d_k` the box's weight and the
//!   model's curvature `c_k`, `D_k` the set rows'), and couple `p_k` to `ξ`
//!   of its ends through `φ_k = ∂δs_k/∂z`;
//! * `ξ` and `y` (three each per free node): the surface terms and `D_k φ_k
//!   φ_kᵀ` on `ξ`, the linearised equilibrium `E` between them;
//! * a border of a few dense columns: the bounds `u_g`, `l_g` of each set
//!   (coupled to every cable of the set) and the level term's rank-one
//!   `2κ a aᵀ`, written as one more unknown `ω = 2κ aᵀz` with the row
//!   `aᵀz − ω/(2κ) = 0`.
//!
//! `p` is eliminated cable by cable (its block is diagonal); what is left on
//! `(ξ, y)` is quasi-definite with the pattern of the node graph in 6×6
//! blocks, `R = [Hξξ − Hξp h⁻¹ Hpξ, ·; E_ξ − E_p h⁻¹ Hpξ, −E_p h⁻¹ E_pᵀ]`, factored
//! by faer's sparse LDLᵀ (pattern and ordering: `block_pattern.rs`;
//! dynamic regularisation with the signs `+` on `ξ`, `−` on `y`); the border
//! is eliminated through its `nb × nb` Schur complement, factored densely
//! with pivoting (its `nb` columns are solved with the first right-hand
//! side after each factorisation, one solve with `nb + 1` columns). Put in
//! the sparse factor as its last rows, the border is lost near the optimum:
//! the level of all tensions (`u_g + l_g`) is fixed only by the box and the
//! level term, and its pivot is then below the dynamic regularisation's
//! threshold. The `ξξ` part of one cable is `D_k d_k/h_k g gᵀ` — the
//! difference `D_k − D_k²/h_k` formed without cancellation.
//!
//! Near the optimum `h_k` of a cable whose rows are all inactive tends to
//! zero, and eliminating `p_k` through it would amplify rounding by
//! `1/h_k`: the factored system keeps `h_k ≥` the settings' `primal_floor`
//! (in `d_k`), and carries a small static shift (`regularization`) on
//! `(ξ, y)`; `ipm.rs` refines each solve against the exact operator.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::{LdltError, LdltRegularization};
use faer::sparse::linalg::cholesky::{LdltRef, SymbolicCholesky};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};
use nalgebra::{DMatrix, DVector};

use super::model::StepModel;
use crate::fdm::NONE;
use crate::uniformity::block_pattern::{BlockPattern, PatternError};
use crate::uniformity::ipm::IpmSettings;

/// Unknowns per free node in the reduced system: `ξ` (3), then `y` (3).
const B: usize = 6;
/// One thread: a solve with one right-hand side is memory-bound (see the
/// plan LP's `normal.rs`).
const PAR: Par = Par::Seq;

/// The barrier weights `λ/s` of the inequality rows at one iteration.
#[derive(Debug, Clone)]
pub(super) struct RowWeights {
    /// Per cable: the box's two rows, summed.
    pub(super) boxes: Vec<f64>,
    /// Per set, per member: the upper-bound row `s + δs ≤ u`.
    pub(super) high: Vec<Vec<f64>>,
    /// Per set, per member: the lower-bound row `l ≤ s + δs`.
    pub(super) low: Vec<Vec<f64>>,
}

/// Why the reduced system could not be set up or factored.
#[derive(Debug, thiserror::Error)]
pub(super) enum KktError {
    /// The pattern, its ordering or its symbolic factorisation.
    #[error(transparent)]
    Pattern(#[from] PatternError),
    /// The factorisation's workspace could not be allocated.
    #[error("out of memory for the factorisation")]
    OutOfMemory,
    /// The reduced system's values are not all finite.
    #[error("the reduced system is not finite")]
    NotFinite,
    /// The numeric LDLᵀ factorisation failed.
    #[error("numeric factorisation: {0:?}")]
    Numeric(LdltError),
    /// The Schur complement of the border (the sets' bound columns) is
    /// singular.
    #[error("the border's Schur complement is singular")]
    SingularBorder,
}

/// The reduced Newton system of one step's program: pattern and symbolic
/// factorisation (once per program), values and factor (per iteration).
pub(super) struct Kkt<'a> {
    model: &'a StepModel,
    /// The static shift (`+` on `ξ`, `−` on `y`), the pivots' dynamic
    /// regularisation and the floor of `h_k`.
    settings: IpmSettings,
    /// Per cable with two free ends: the place of its upper end among the
    /// lower end's neighbours.
    neighbour: Vec<usize>,
    col_ptr: Vec<usize>,
    pattern: SymbolicSparseColMat<usize>,
    symbolic: SymbolicCholesky<usize>,
    signs: Vec<i8>,
    values: Vec<f64>,
    scale: Vec<f64>,
    factor: Vec<f64>,
    buffer: MemBuffer,
    /// `h_k` and `D_k` of the current iteration.
    h: Vec<f64>,
    ratio: Vec<f64>,
    /// The border's columns `B` over `(p, ξ, y)` and its corner `C`, `M0⁻¹B`,
    /// and the factored `C − BᵀM0⁻¹B` (`None` until the first solve after a
    /// factorisation).
    border: Vec<Vec<f64>>,
    corner: Vec<f64>,
    border_solved: Vec<Vec<f64>>,
    schur: Option<nalgebra::LU<f64, nalgebra::Dyn, nalgebra::Dyn>>,
    /// `‖E‖∞` of the model, the scale of the equilibrium's residual in
    /// refinement (once per program, not per solve).
    pub(super) equilibrium_norm: f64,
}

impl<'a> Kkt<'a> {
    /// The pattern and symbolic factorisation of `model`'s reduced system.
    pub(super) fn new(model: &'a StepModel, settings: &IpmSettings) -> Result<Self, KktError> {
        let n_free = model.n_free;
        let n_rows = B * n_free;
        let ends: Vec<[usize; 2]> = model.cables.iter().map(|c| c.ends).collect();
        let BlockPattern {
            neighbour,
            col_ptr,
            pattern,
            symbolic,
            ..
        } = BlockPattern::new(&ends, n_free, B)?;
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_ldlt_scratch::<f64>(PAR, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(2 * model.sets.len() + 2, PAR),
        ]);
        let buffer = MemBuffer::try_new(req).map_err(|_| KktError::OutOfMemory)?;
        let m = model.m();
        Ok(Kkt {
            model,
            settings: *settings,
            neighbour,
            values: vec![0.0; col_ptr[n_rows]],
            col_ptr,
            pattern,
            signs: (0..n_rows)
                .map(|r| if r % B < 3 { 1 } else { -1 })
                .collect(),
            scale: vec![1.0; n_rows],
            factor: vec![0.0; symbolic.len_val()],
            symbolic,
            buffer,
            h: vec![0.0; m],
            ratio: vec![0.0; m],
            border: Vec::new(),
            corner: Vec::new(),
            border_solved: Vec::new(),
            schur: None,
            equilibrium_norm: model.equilibrium_norm(),
        })
    }

    /// Length of `(p, ξ, y)`.
    fn n_sparse(&self) -> usize {
        self.model.m() + 6 * self.model.n_free
    }

    /// Fills and factors the system for the row weights `d`.
    pub(super) fn factorize(&mut self, d: &RowWeights) -> Result<(), KktError> {
        let model = self.model;
        let m = model.m();
        self.ratio.fill(0.0);
        for (g, set) in model.sets.iter().enumerate() {
            for (i, &(k, _)) in set.iter().enumerate() {
                self.ratio[k] += d.high[g][i] + d.low[g][i];
            }
        }
        // h_k = D_k + rest_k, the rest the box's weight and the curvature,
        // raised to keep h_k at least the floor.
        let floor = self.settings.primal_floor;
        let rest: Vec<f64> = (0..m)
            .map(|k| (d.boxes[k] + model.cables[k].curvature).max(floor - self.ratio[k]))
            .collect();
        for ((h, ratio), rest) in self.h.iter_mut().zip(&self.ratio).zip(&rest) {
            *h = ratio + rest;
        }
        self.fill_reduced(&rest);
        self.factor_reduced()?;

        // The border: u_g, l_g of each set, then ω for the level term.
        let n_sparse = self.n_sparse();
        let mut border = Vec::new();
        let mut corner = Vec::new();
        for (g, set) in model.sets.iter().enumerate() {
            for weights in [&d.high[g], &d.low[g]] {
                let mut column = vec![0.0; n_sparse];
                for (&(k, _), &w) in set.iter().zip(weights.iter()) {
                    model.add_delta_s_gradient(k, -w, &mut column);
                }
                border.push(column);
                corner.push(weights.iter().sum::<f64>());
            }
        }
        if model.level_weight > 0.0 {
            let mut column = vec![0.0; n_sparse];
            for &(k, w) in &model.level_terms {
                model.add_delta_s_gradient(k, w, &mut column);
            }
            border.push(column);
            corner.push(-0.5 / model.level_weight);
        }
        self.border = border;
        self.corner = corner;
        self.schur = None;
        Ok(())
    }

    /// Solves with `M0` the border's columns together with `w` (one solve
    /// with several columns costs less than two), and factors the border's
    /// Schur complement `C − BᵀM0⁻¹B`.
    fn solve_with_border(&mut self, w: &mut Vec<f64>) -> Result<(), KktError> {
        let n_sparse = self.n_sparse();
        let mut columns: Vec<f64> = self.border.concat();
        columns.extend_from_slice(w);
        self.solve_sparse(&mut columns);
        *w = columns.split_off(self.border.len() * n_sparse);
        let solved: Vec<Vec<f64>> = columns.chunks(n_sparse).map(<[f64]>::to_vec).collect();
        let nb = self.border.len();
        let schur = DMatrix::from_fn(nb, nb, |i, j| {
            let product: f64 = self.border[i]
                .iter()
                .zip(&solved[j])
                .map(|(a, b)| a * b)
                .sum();
            if i == j {
                self.corner[i] - product
            } else {
                -product
            }
        });
        self.border_solved = solved;
        let schur = schur.lu();
        if !schur.is_invertible() {
            return Err(KktError::SingularBorder);
        }
        self.schur = Some(schur);
        Ok(())
    }

    /// The reduced matrix `R` on `(ξ, y)` (see the module documentation).
    fn fill_reduced(&mut self, rest: &[f64]) {
        let model = self.model;
        let values = &mut self.values;
        values.fill(0.0);
        let col_ptr = &self.col_ptr;
        let neighbour = &self.neighbour;
        // Adds the local 12×12 matrix of one cable (rows and columns: ξ, y of
        // end a, then of end b) into the lower triangle.
        let mut scatter = |ends: [usize; 2], k: usize, local: &[[f64; 2 * B]; 2 * B]| {
            for (ea, &fa) in ends.iter().enumerate() {
                if fa == NONE {
                    continue;
                }
                for (eb, &fb) in ends.iter().enumerate() {
                    if fb == NONE || (ea != eb && fa == fb) {
                        continue;
                    }
                    if ea == eb {
                        for j in 0..B {
                            for i in j..B {
                                values[col_ptr[B * fa + j] + i - j] +=
                                    local[B * ea + i][B * ea + j];
                            }
                        }
                    } else if fa > fb {
                        // Rows of fa, columns of fb: stored in fb's columns.
                        for j in 0..B {
                            let base = col_ptr[B * fb + j] + (B - j) + B * neighbour[k];
                            for i in 0..B {
                                values[base + i] += local[B * ea + i][B * eb + j];
                            }
                        }
                    }
                }
            }
        };
        for (k, cable) in model.cables.iter().enumerate() {
            let h = self.h[k];
            let ratio = self.ratio[k];
            let xi_xi = ratio * rest[k] / h;
            let sign = [1.0, -1.0];
            let rho = cable
                .ends
                .map(|f| if f == NONE { 0.0 } else { model.row_scale[f] });
            let mut local = [[0.0; 2 * B]; 2 * B];
            for e in 0..2 {
                for f in 0..2 {
                    let s = sign[e] * sign[f];
                    for i in 0..3 {
                        for j in 0..3 {
                            // ξ_e ξ_f
                            local[B * e + i][B * f + j] = s * xi_xi * cable.g[i] * cable.g[j];
                            // y_e ξ_f and its transpose ξ_f y_e
                            let identity = if i == j { 1.0 } else { 0.0 };
                            let y_xi = s
                                * rho[e]
                                * cable.q
                                * (identity - ratio / h * cable.u[i] * cable.g[j]);
                            local[B * e + 3 + i][B * f + j] = y_xi;
                            local[B * f + j][B * e + 3 + i] = y_xi;
                            // y_e y_f
                            local[B * e + 3 + i][B * f + 3 + j] =
                                -s * rho[e] * rho[f] * cable.q * cable.q * cable.u[i] * cable.u[j]
                                    / h;
                        }
                    }
                }
            }
            scatter(cable.ends, k, &local);
        }
        let diagonal = |f: usize, i: usize, j: usize| col_ptr[B * f + j] + i - j;
        for row in &model.errors {
            if row.node == NONE {
                continue;
            }
            for j in 0..3 {
                for i in j..3 {
                    values[diagonal(row.node, i, j)] +=
                        2.0 * model.error_weight * row.gradient[i] * row.gradient[j];
                }
            }
        }
        for &(column, _) in &model.drifts {
            let (f, d) = (column / 3, column % 3);
            values[diagonal(f, d, d)] += 2.0 * model.drift_weight;
        }
    }

    /// Scales `R` to unit diagonal magnitude, shifts it, and factors it.
    fn factor_reduced(&mut self) -> Result<(), KktError> {
        let n_rows = self.scale.len();
        let col_ptr = &self.col_ptr;
        let values = &mut self.values;
        for (i, s) in self.scale.iter_mut().enumerate() {
            let d = values[col_ptr[i]].abs();
            *s = if d > 0.0 && d.is_finite() {
                1.0 / d.sqrt()
            } else {
                1.0
            };
        }
        let row_idx = self.pattern.row_idx();
        for j in 0..n_rows {
            let sj = self.scale[j];
            for p in col_ptr[j]..col_ptr[j + 1] {
                values[p] *= sj * self.scale[row_idx[p]];
            }
            values[col_ptr[j]] += self.settings.regularization * f64::from(self.signs[j]);
        }
        if values.iter().any(|v| !v.is_finite()) {
            return Err(KktError::NotFinite);
        }
        self.symbolic
            .factorize_numeric_ldlt(
                &mut self.factor,
                SparseColMatRef::new(self.pattern.as_ref(), values),
                Side::Lower,
                LdltRegularization {
                    dynamic_regularization_signs: Some(&self.signs),
                    dynamic_regularization_delta: self.settings.pivot_delta,
                    dynamic_regularization_epsilon: self.settings.pivot_epsilon,
                },
                PAR,
                MemStack::new(&mut self.buffer),
                Default::default(),
            )
            .map_err(KktError::Numeric)?;
        Ok(())
    }

    /// `x ← M0⁻¹ x` on `(p, ξ, y)` for the columns of `x` (column-major, each
    /// of length `m + 6 n_free`): `p` eliminated, the reduced system solved
    /// with the factor, `p` recovered.
    fn solve_sparse(&mut self, x: &mut [f64]) {
        let model = self.model;
        let m = model.m();
        let n_free = model.n_free;
        let n_sparse = self.n_sparse();
        let n_cols = x.len() / n_sparse;
        // r_ξ −= Hξp h⁻¹ r_p, r_y −= E_p h⁻¹ r_p, in the node-interleaved order.
        let mut v = vec![0.0; B * n_free * n_cols];
        for (column, v) in x.chunks(n_sparse).zip(v.chunks_mut(B * n_free)) {
            let (p, rest) = column.split_at(m);
            let (xi, y) = rest.split_at(3 * n_free);
            for f in 0..n_free {
                v[B * f..B * f + 3].copy_from_slice(&xi[3 * f..3 * f + 3]);
                v[B * f + 3..B * f + 6].copy_from_slice(&y[3 * f..3 * f + 3]);
            }
            for (k, cable) in model.cables.iter().enumerate() {
                let t = p[k] / self.h[k];
                for (&f, sign) in cable.ends.iter().zip([1.0, -1.0]) {
                    if f == NONE {
                        continue;
                    }
                    for d in 0..3 {
                        v[B * f + d] -= sign * self.ratio[k] * cable.g[d] * t;
                        v[B * f + 3 + d] -= sign * model.row_scale[f] * cable.q * cable.u[d] * t;
                    }
                }
            }
            for (vi, s) in v.iter_mut().zip(&self.scale) {
                *vi *= s;
            }
        }
        LdltRef::new(&self.symbolic, &self.factor).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut v, B * n_free, n_cols),
            PAR,
            MemStack::new(&mut self.buffer),
        );
        for (column, v) in x.chunks_mut(n_sparse).zip(v.chunks_mut(B * n_free)) {
            for (vi, s) in v.iter_mut().zip(&self.scale) {
                *vi *= s;
            }
            let (p, rest) = column.split_at_mut(m);
            let (xi, y) = rest.split_at_mut(3 * n_free);
            for f in 0..n_free {
                xi[3 * f..3 * f + 3].copy_from_slice(&v[B * f..B * f + 3]);
                y[3 * f..3 * f + 3].copy_from_slice(&v[B * f + 3..B * f + 6]);
            }
            // p = h⁻¹ (r_p − Hpξ ξ − E_pᵀ y).
            for (k, cable) in model.cables.iter().enumerate() {
                let mut r = p[k];
                for (&f, sign) in cable.ends.iter().zip([1.0, -1.0]) {
                    if f == NONE {
                        continue;
                    }
                    for d in 0..3 {
                        r -= sign * self.ratio[k] * cable.g[d] * xi[3 * f + d];
                        r -= sign * model.row_scale[f] * cable.q * cable.u[d] * y[3 * f + d];
                    }
                }
                p[k] = r / self.h[k];
            }
        }
    }

    /// Solves the Newton system for the right-hand side `(rz, ry)` with the
    /// current factor: returns `(δz, δy)`. The first solve after a
    /// factorisation also solves for the border.
    pub(super) fn solve(
        &mut self,
        rz: &[f64],
        ry: &[f64],
    ) -> Result<(Vec<f64>, Vec<f64>), KktError> {
        let model = self.model;
        let (m, at_bounds) = (model.m(), model.at_bounds());
        let mut w: Vec<f64> = rz[..at_bounds].iter().chain(ry).copied().collect();
        if self.schur.is_none() {
            self.solve_with_border(&mut w)?;
        } else {
            self.solve_sparse(&mut w);
        }
        let n_bounds = rz.len() - at_bounds;
        let nb = self.border.len();
        let rhs = DVector::from_fn(nb, |i, _| {
            let given = if i < n_bounds { rz[at_bounds + i] } else { 0.0 };
            given
                - self.border[i]
                    .iter()
                    .zip(&w)
                    .map(|(a, b)| a * b)
                    .sum::<f64>()
        });
        let t = self
            .schur
            .as_ref()
            .and_then(|lu| lu.solve(&rhs))
            .ok_or(KktError::SingularBorder)?;
        for (column, &tj) in self.border_solved.iter().zip(t.iter()) {
            for (wi, ci) in w.iter_mut().zip(column) {
                *wi -= ci * tj;
            }
        }
        let y = w.split_off(at_bounds);
        debug_assert_eq!(w.len(), m + 3 * model.n_free);
        w.extend(t.iter().take(n_bounds));
        Ok((w, y))
    }
}
