//! Least-squares tension uniformity (DESIGN §4): the tensions closest to their
//! targets, `min ‖L q − T̄‖²`, either in exact equilibrium (`A q = p`) or traded
//! against it (the Tikhonov family `min ‖A q − p‖² + λ ‖L q − T̄‖²`). Both are one
//! symmetric KKT system, solved through its Schur complement with one sparse
//! Cholesky factorisation (faer) and iterative refinement. Least squares does not
//! enforce `0 < q ≤ [q]`: an optimum that breaks a bound is reported as an error
//! naming the cables, never returned as a design.
//!
//! # Formulation
//!
//! In tension variables `T = L q` (`L = diag(ℓ)`, ℓ the prescribed cable lengths)
//! equilibrium reads `Ã T = p` with `Ã = A L⁻¹`, whose columns hold the cables'
//! unit directions. The uniformity objective is
//!
//! $$ g(T) = \sum_k w_k (T_k - t_k)^2 , $$
//!
//! where for a cable of a uniformity set `w_k = 1` and `t_k` is the set's mean
//! tension `T̄` (a cable in several sets: `w_k` = their number, `t_k` = the mean of
//! their targets), so that `g = ‖L q − T̄‖²` over the sets. With
//! `f(T) = ‖Ã T − p‖² = ‖A q − p‖²`:
//!
//! * **equality-constrained** (`lambda = None`): `min ½ g` s.t. `Ã T = p`, with
//!   KKT conditions `W (T − t) + Ãᵀ μ = 0`, `Ã T = p`;
//! * **Tikhonov** (`lambda = Some(λ)`): `min f + λ g`. With
//!   `μ = (Ã T − p)/λ` its normal equations `(ÃᵀÃ + λW) T = Ãᵀp + λWt` become
//!   the same KKT system with `−λ I` in the (2,2) block:
//!
//! $$ \begin{bmatrix} W & \tilde A^\top \\ \tilde A & -\lambda I \end{bmatrix}
//!    \begin{bmatrix} T \\ \mu \end{bmatrix} =
//!    \begin{bmatrix} W t \\ p \end{bmatrix}, \qquad \lambda \ge 0 . $$
//!
//! `W = diag(w)` is diagonal, so `T = t − W⁻¹Ãᵀμ` and `μ` solves the Schur
//! complement system `S μ = Ã t − p`, `S = Ã W⁻¹ Ãᵀ + λ I` (3·n_free square, the
//! sparsity of `D` with 3 × 3 blocks), symmetric positive definite for `λ > 0`.
//! For `λ = 0`, `A` may have dependent rows (a flat node's vertical row, an
//! infinitesimal mechanism), so `S` is factored with the shift
//! `max(λ, 1e-12 · max diag S)` and the solution is refined against the unshifted
//! system until its componentwise backward error is below
//! [`LeastSquares::tolerance`]. When `A` has dependent rows the multipliers'
//! component in the null space of `Aᵀ` is undetermined; it does not reach `q`.
//! Loads outside the range of `A` make refinement stall with a material
//! equilibrium residual: reported as [`Termination::Infeasible`].
//!
//! # Cables outside every set
//!
//! They are not in `g`, so `W` would be singular and, where the sets leave a
//! self-stress undetermined, so would the KKT system. They get the weight
//! `w_k = δ` ([`LeastSquares::other_weight`]) and first the target
//! `t_k = τ` ([`UniformityProblem::min_other_tension_n`]); then *proximal steps*
//! replace their targets by their current tensions and solve again (same factor,
//! warm start) until those stop moving. At that fixed point the regularisation's
//! gradient is zero: `T` is stationary for the unregularised objective, so the
//! result does not depend on δ (δ = 10⁻⁶ and 10⁻⁸ agree to ~10⁻¹²). δ only
//! keeps the system nonsingular and, where the sets do not determine some
//! cables, picks the solution the proximal path reaches from τ. Rounding in
//! `T_k` of such cables grows like `ε/δ`, so δ much below 10⁻⁸ costs accuracy
//! and buys nothing.
//!
//! # The λ family
//!
//! For `λ₁ < λ₂` with optima `T₁, T₂`, optimality gives
//! `f₁ + λ₁g₁ ≤ f₂ + λ₁g₂` and `f₂ + λ₂g₂ ≤ f₁ + λ₂g₁`; adding,
//! `(λ₂ − λ₁)(g₂ − g₁) ≤ 0`, so the deviation `g = ‖L q − T̄‖²` is non-increasing
//! in λ, and then `f₁ − f₂ ≤ λ₁(g₂ − g₁) ≤ 0`, so the equilibrium residual
//! `f = ‖A q − p‖²` is non-decreasing. As `λ → 0` the optimum tends to the
//! equality-constrained one (when `A q = p` is solvable); as `λ → ∞`, the set
//! cables' tensions tend to their targets.
//!
//! # Pretension level
//!
//! For an unloaded net (`p = 0`) the equality-constrained optimum is the
//! orthogonal projection of the targets onto the self-stresses, which shortens
//! them: a set's mean tension comes out *below* its target whenever the targets
//! are not themselves in equilibrium. Tension ratios are scale-free; rescale `q`
//! if the level matters.

use std::time::Instant;

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, Side};

use super::{Design, KnobRange, Termination, UniformityError, UniformityProblem, UniformitySolver};
use crate::algebra::Plain;

const SOLVER: &str = "least-squares";

/// Relative shift of the Schur complement when the (2,2) block is (nearly)
/// zero: `shift = SHIFT_FLOOR · max diag S`.
const SHIFT_FLOOR: f64 = 1e-12;

/// A relative equilibrium residual above this cannot be rounding: when
/// refinement stalls there, `A q = p` is inconsistent.
const EQUILIBRIUM_MATERIAL: f64 = 1e-6;

/// How many offending cables an error message names.
const SHOWN: usize = 6;

/// `min ‖L q − T̄‖²` s.t. `A q = p`, or the Tikhonov family
/// `min ‖A q − p‖² + λ ‖L q − T̄‖²` (see the module documentation).
///
/// The design's `iterations` counts the solves with the one factorisation
/// (refinement and proximal steps together).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LeastSquares {
    /// Tikhonov weight λ (dimensionless: both terms are in N²), the design
    /// front's knob; `None` (or `Some(0.0)`, the λ → 0 limit) for the
    /// equality-constrained problem.
    pub lambda: Option<f64>,
    /// Weight δ of the regularisation `(T_k − t_k)²` of the cables outside
    /// every uniformity set, relative to the set cables' unit weight: keeps the
    /// KKT system nonsingular; the proximal steps remove its bias.
    pub other_weight: f64,
    /// Refinement stops when the KKT residual, relative to the size of the terms
    /// it sums, is below this; the proximal steps stop when no tension outside
    /// the sets moves by more than this × the largest tension.
    pub tolerance: f64,
    /// Most refinement steps per solve (each one solve with the factor).
    pub max_refinements: usize,
    /// Most proximal steps (0: keep the δ-regularised optimum with targets τ).
    pub max_proximal_steps: usize,
}

impl Default for LeastSquares {
    fn default() -> Self {
        LeastSquares {
            lambda: None,
            other_weight: 1e-6,
            tolerance: 1e-12,
            max_refinements: 30,
            max_proximal_steps: 100,
        }
    }
}

impl LeastSquares {
    /// Checks the settings: `λ ≥ 0`, `δ > 0`, `0 < tolerance < 1`, all finite, and
    /// at least one solve.
    pub fn validate(&self) -> Result<(), UniformityError> {
        if let Some(lambda) = self.lambda {
            if !(lambda.is_finite() && lambda >= 0.0) {
                return Err(UniformityError::Setting {
                    solver: SOLVER,
                    name: "lambda",
                    value: lambda,
                    range: "finite and ≥ 0",
                });
            }
        }
        if !(self.other_weight.is_finite() && self.other_weight > 0.0) {
            return Err(UniformityError::Setting {
                solver: SOLVER,
                name: "other_weight",
                value: self.other_weight,
                range: "finite and > 0",
            });
        }
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return Err(UniformityError::Setting {
                solver: SOLVER,
                name: "tolerance",
                value: self.tolerance,
                range: "in (0, 1)",
            });
        }
        if self.max_refinements == 0 {
            return Err(UniformityError::Setting {
                solver: SOLVER,
                name: "max_refinements",
                value: 0.0,
                range: "≥ 1 (the first solve counts)",
            });
        }
        Ok(())
    }
}

impl UniformitySolver for LeastSquares {
    fn name(&self) -> &'static str {
        SOLVER
    }

    /// λ from 1e-6 to 1e2 (the equality-constrained limit λ → 0 is the
    /// `lp`-like exact point, run separately).
    fn knob_range(&self, _problem: &UniformityProblem) -> Option<KnobRange> {
        Some(KnobRange {
            name: "lambda",
            exact: None,
            low: 1e-6,
            high: 1e2,
        })
    }

    fn solve(&self, problem: &UniformityProblem) -> Result<Design, UniformityError> {
        let start = Instant::now();
        self.validate()?;
        let lambda = self.lambda.unwrap_or(0.0);
        let mut kkt = Kkt::new(problem, self.other_weight, lambda);
        let factor = kkt.factor()?;
        let mut t = kkt.targets_n.clone();
        let mut mu = vec![0.0; kkt.n_rows];
        let refine = |kkt: &Kkt, t: &mut [f64], mu: &mut [f64]| {
            kkt.refine(factor.as_ref(), t, mu, self.tolerance, self.max_refinements)
        };
        let mut refinement = refine(&kkt, &mut t, &mut mu);
        let mut solves = refinement.solves;

        // Proximal steps: the others' targets follow their tensions.
        let others = problem.other_edges();
        let mut proximal_steps = 0;
        let mut moved = 0.0;
        while refinement.backward_error <= self.tolerance {
            let largest = t.iter().map(|v| v.abs()).fold(0.0, f64::max);
            moved = others
                .iter()
                .map(|&k| (t[k] - kkt.targets_n[k]).abs())
                .fold(0.0, f64::max);
            if moved <= self.tolerance * largest || proximal_steps >= self.max_proximal_steps {
                moved /= largest.max(f64::MIN_POSITIVE);
                break;
            }
            for &k in &others {
                kkt.targets_n[k] = t[k];
            }
            refinement = refine(&kkt, &mut t, &mut mu);
            solves += refinement.solves;
            proximal_steps += 1;
        }

        let mut warnings = Vec::new();
        let termination = if refinement.backward_error > self.tolerance {
            if lambda == 0.0 && refinement.equilibrium_error > EQUILIBRIUM_MATERIAL {
                warnings.push(format!(
                    "A q = p has no solution: refinement stalls at an equilibrium residual \
                     of {:.3e} N ({:.1e} of the terms it sums); the loads are not in the \
                     range of the equilibrium matrix",
                    refinement.max_equilibrium_residual_n, refinement.equilibrium_error
                ));
                Termination::Infeasible
            } else {
                warnings.push(format!(
                    "iterative refinement stopped after {} steps at a relative KKT \
                     residual of {:.3e} (tolerance {:.1e})",
                    refinement.solves, refinement.backward_error, self.tolerance
                ));
                Termination::NumericalError
            }
        } else if self.max_proximal_steps > 0 && moved > self.tolerance {
            warnings.push(format!(
                "{proximal_steps} proximal steps: tensions outside the sets still move by \
                 {moved:.3e} of the largest; the result is optimal for the regularised \
                 problem (other_weight {:.1e}), not yet for the sets alone",
                self.other_weight
            ));
            Termination::MaxIterations
        } else {
            Termination::Converged
        };

        let lengths = problem.lengths_m();
        let q: Vec<f64> = t.iter().zip(lengths).map(|(t, l)| t / l).collect();
        check_bounds(problem, &q, self.lambda)?;
        Design::evaluate(
            problem,
            SOLVER,
            q,
            termination,
            solves,
            start.elapsed(),
            warnings,
        )
    }
}

/// The KKT system `[W Ãᵀ; Ã −λI] [T; μ] = [W t; p]` of a problem.
#[derive(Debug, Clone)]
struct Kkt {
    /// `Ã = A L⁻¹` by columns: cable `k` has rows `row_idx[col_ptr[k]..col_ptr[k + 1]]`
    /// (ascending) with the values alongside.
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
    /// 3·n_free.
    n_rows: usize,
    /// `w`: n_edges.
    weights: Vec<f64>,
    /// `t`, N: n_edges.
    targets_n: Vec<f64>,
    /// `p`, N: 3·n_free.
    loads_n: Vec<f64>,
    lambda: f64,
}

impl Kkt {
    fn new(problem: &UniformityProblem, other_weight: f64, lambda: f64) -> Self {
        let a = problem
            .structure()
            .equilibrium_matrix(&problem.network().nodes);
        let lengths = problem.lengths_m();
        let m = a.ncols();
        let (symbolic, values) = a.parts();
        let mut col_ptr = Vec::with_capacity(m + 1);
        col_ptr.push(0);
        let mut row_idx = Vec::with_capacity(values.len());
        let mut scaled = Vec::with_capacity(values.len());
        for (k, &length) in lengths.iter().enumerate().take(m) {
            let range = symbolic.col_range(k);
            row_idx.extend_from_slice(&symbolic.row_idx()[range.clone()]);
            scaled.extend(values[range].iter().map(|v| v / length));
            col_ptr.push(row_idx.len());
        }

        let mut weights = vec![0.0; m];
        let mut weighted_targets = vec![0.0; m];
        for set in problem.sets() {
            for &k in &set.edges {
                weights[k] += 1.0;
                weighted_targets[k] += set.mean_tension_n;
            }
        }
        let tau = problem.min_other_tension_n();
        let targets_n = (0..m)
            .map(|k| {
                if weights[k] > 0.0 {
                    weighted_targets[k] / weights[k]
                } else {
                    weights[k] = other_weight;
                    tau
                }
            })
            .collect();
        Kkt {
            col_ptr,
            row_idx,
            values: scaled,
            n_rows: a.nrows(),
            weights,
            targets_n,
            loads_n: problem.free_loads(),
            lambda,
        }
    }

    fn column(&self, k: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let range = self.col_ptr[k]..self.col_ptr[k + 1];
        self.row_idx[range.clone()]
            .iter()
            .copied()
            .zip(self.values[range].iter().copied())
    }

    /// `Ã t`: 3·n_free.
    fn a_times(&self, t: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.n_rows];
        for (k, &tk) in t.iter().enumerate() {
            for (r, v) in self.column(k) {
                y[r] += v * tk;
            }
        }
        y
    }

    /// `Ãᵀ μ`: n_edges.
    fn at_times(&self, mu: &[f64]) -> Vec<f64> {
        (0..self.weights.len())
            .map(|k| self.column(k).map(|(r, v)| v * mu[r]).sum())
            .collect()
    }

    /// `|Ã|ᵀ |μ|`: n_edges, the size of the terms `Ãᵀ μ` sums.
    fn at_times_abs(&self, mu: &[f64]) -> Vec<f64> {
        (0..self.weights.len())
            .map(|k| self.column(k).map(|(r, v)| (v * mu[r]).abs()).sum())
            .collect()
    }

    /// The residuals `r₁ = W(t − T) − Ãᵀμ`, `r₂ = p − ÃT + λμ` and their relative
    /// sizes: each row's residual over the sum of its terms' magnitudes (a
    /// componentwise backward error, which rounding keeps at a few ε whatever the
    /// weights).
    fn residuals(&self, t: &[f64], mu: &[f64]) -> Residuals {
        let at_mu = self.at_times(mu);
        let at_mu_size = self.at_times_abs(mu);
        let mut r1 = vec![0.0; t.len()];
        let mut error1 = 0.0f64;
        for k in 0..t.len() {
            let (w, target) = (self.weights[k], self.targets_n[k]);
            r1[k] = w * (target - t[k]) - at_mu[k];
            let size = w * (target.abs() + t[k].abs()) + at_mu_size[k];
            error1 = error1.max(relative(r1[k], size));
        }
        let mut r2: Vec<f64> = self
            .loads_n
            .iter()
            .zip(mu)
            .map(|(p, m)| p + self.lambda * m)
            .collect();
        let mut size2: Vec<f64> = self
            .loads_n
            .iter()
            .zip(mu)
            .map(|(p, m)| p.abs() + (self.lambda * m).abs())
            .collect();
        for (k, &tk) in t.iter().enumerate() {
            for (r, v) in self.column(k) {
                r2[r] -= v * tk;
                size2[r] += (v * tk).abs();
            }
        }
        let error2 = r2
            .iter()
            .zip(&size2)
            .map(|(&r, &s)| relative(r, s))
            .fold(0.0, f64::max);
        let max2 = r2.iter().map(|r| r.abs()).fold(0.0, f64::max);
        Residuals {
            r1,
            r2,
            error1,
            error2,
            max2,
        }
    }

    /// The lower triangle of `S = Ã W⁻¹ Ãᵀ + shift·I`, the shift a function of
    /// the largest diagonal entry of `Ã W⁻¹ Ãᵀ`.
    fn schur(&self, shift: impl Fn(f64) -> f64) -> SparseColMat<usize, f64> {
        let mut diagonal = vec![0.0; self.n_rows];
        let mut triplets = Vec::with_capacity(self.n_rows + 21 * self.weights.len());
        for (k, &w) in self.weights.iter().enumerate() {
            let entries: Vec<(usize, f64)> = self.column(k).collect();
            for (a, &(ra, va)) in entries.iter().enumerate() {
                diagonal[ra] += va * va / w;
                // Rows ascend within a column: (ra, rb) with b < a is below the diagonal.
                for &(rb, vb) in &entries[..a] {
                    triplets.push(Triplet::new(ra, rb, va * vb / w));
                }
            }
        }
        let max_diagonal = diagonal.iter().copied().fold(0.0, f64::max);
        let s = shift(max_diagonal);
        triplets.extend(
            diagonal
                .iter()
                .enumerate()
                .map(|(r, &d)| Triplet::new(r, r, d + s)),
        );
        SparseColMat::try_new_from_triplets(self.n_rows, self.n_rows, &triplets)
            .expect("indices are in range by construction")
    }

    /// Factors `S = Ã W⁻¹ Ãᵀ + shift·I` with `shift = max(λ, SHIFT_FLOOR · max diag)`
    /// (`None` when there is no free node).
    fn factor(&self) -> Result<Option<Llt<usize, f64>>, UniformityError> {
        if self.n_rows == 0 {
            return Ok(None);
        }
        let lambda = self.lambda;
        let s = self.schur(|max_diagonal| lambda.max(SHIFT_FLOOR * max_diagonal));
        let failed = |what: &str, e: String| UniformityError::SolverFailed {
            solver: SOLVER,
            status: format!("{what} Cholesky factorisation of the Schur complement: {e}"),
        };
        let symbolic = SymbolicLlt::try_new(s.symbolic(), Side::Lower)
            .map_err(|e| failed("symbolic", e.plain()))?;
        Llt::try_new_with_symbolic(symbolic, s.as_ref(), Side::Lower)
            .map(Some)
            .map_err(|e| failed("numeric", e.plain()))
    }

    /// Iterative refinement of `(T, μ)` against the unshifted system, with the
    /// shifted factor: stops at `tolerance`, after `max_solves`, or when a step
    /// no longer halves the residual.
    fn refine(
        &self,
        factor: Option<&Llt<usize, f64>>,
        t: &mut [f64],
        mu: &mut [f64],
        tolerance: f64,
        max_solves: usize,
    ) -> Refinement {
        let m = self.weights.len();
        let mut solves = 0;
        let mut previous = f64::INFINITY;
        loop {
            let residuals = self.residuals(t, mu);
            let error = residuals.error1.max(residuals.error2);
            let stalled = solves >= 2 && error > 0.5 * previous;
            let Some(factor) =
                factor.filter(|_| error > tolerance && !stalled && solves < max_solves)
            else {
                return Refinement {
                    backward_error: error,
                    equilibrium_error: residuals.error2,
                    max_equilibrium_residual_n: residuals.max2,
                    solves,
                };
            };
            previous = error;
            // [W Ãᵀ; Ã −shift·I] [ΔT; Δμ] = [r₁; r₂]:
            // S Δμ = Ã W⁻¹ r₁ − r₂, ΔT = W⁻¹ (r₁ − Ãᵀ Δμ).
            let w_inv_r1: Vec<f64> = (0..m).map(|k| residuals.r1[k] / self.weights[k]).collect();
            let a_w_inv_r1 = self.a_times(&w_inv_r1);
            let mut rhs =
                Mat::<f64>::from_fn(self.n_rows, 1, |r, _| a_w_inv_r1[r] - residuals.r2[r]);
            factor.solve_in_place(rhs.as_mut());
            let d_mu: Vec<f64> = (0..self.n_rows).map(|r| rhs[(r, 0)]).collect();
            let at_d_mu = self.at_times(&d_mu);
            for k in 0..m {
                t[k] += (residuals.r1[k] - at_d_mu[k]) / self.weights[k];
            }
            for (mu_r, d) in mu.iter_mut().zip(&d_mu) {
                *mu_r += d;
            }
            solves += 1;
        }
    }
}

/// How a refinement ended.
#[derive(Debug, Clone, Copy)]
struct Refinement {
    /// Largest relative residual of either block (0 is exact).
    backward_error: f64,
    /// Relative residual of the equilibrium block.
    equilibrium_error: f64,
    /// `‖p − Ã T + λμ‖∞`, N.
    max_equilibrium_residual_n: f64,
    /// Solves with the factor.
    solves: usize,
}

/// The KKT residuals and their componentwise relative sizes.
#[derive(Debug)]
struct Residuals {
    r1: Vec<f64>,
    r2: Vec<f64>,
    error1: f64,
    error2: f64,
    max2: f64,
}

/// `|r| / size`, 0 when both vanish.
fn relative(r: f64, size: f64) -> f64 {
    if r == 0.0 {
        0.0
    } else {
        r.abs() / size.max(f64::MIN_POSITIVE)
    }
}

/// Reports an optimum outside `0 < q ≤ [q]`, naming the first cables.
fn check_bounds(
    problem: &UniformityProblem,
    q: &[f64],
    lambda: Option<f64>,
) -> Result<(), UniformityError> {
    let network = problem.network();
    let lengths = problem.lengths_m();
    let describe = |k: usize, value: String| {
        let [i, j] = network.edges[k];
        format!(
            "cable {k} ({}, nodes {i}–{j}): {value}",
            network.group_of(k)
        )
    };
    let summary = |offenders: &[usize], value: &dyn Fn(usize) -> String| {
        let shown: Vec<String> = offenders
            .iter()
            .take(SHOWN)
            .map(|&k| describe(k, value(k)))
            .collect();
        let more = if offenders.len() > SHOWN { ", …" } else { "" };
        format!("{}{more}", shown.join("; "))
    };

    let slack: Vec<usize> = (0..q.len())
        .filter(|&k| !(q[k].is_finite() && q[k] > 0.0))
        .collect();
    if !slack.is_empty() {
        let remedy = match lambda {
            Some(l) if l > 0.0 => {
                "a larger λ (the tensions tend to their targets as λ grows)".to_string()
            }
            _ => "the Tikhonov form with a finite λ".to_string(),
        };
        return Err(UniformityError::Unsupported {
            solver: SOLVER,
            reason: format!(
                "positivity fails: the least-squares optimum has T ≤ 0 in {} of {} cables: \
                 {}. Least squares does not enforce q > 0: use `bisection` or `lp`, which \
                 do, or try {remedy}",
                slack.len(),
                q.len(),
                summary(&slack, &|k| format!("T = {:.4e} N", q[k] * lengths[k]))
            ),
        });
    }

    let bound = problem.max_force_density_n_per_m;
    let over: Vec<usize> = (0..q.len()).filter(|&k| q[k] > bound).collect();
    if !over.is_empty() {
        return Err(UniformityError::Unsupported {
            solver: SOLVER,
            reason: format!(
                "the least-squares optimum exceeds the bound [q] = {bound:.4e} N/m in {} \
                 cables: {}. Use `bisection`, which enforces the bound",
                over.len(),
                summary(&over, &|k| format!("q = {:.4e} N/m", q[k]))
            ),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use faer::linalg::solvers::Solve;
    use faer::{Mat, Side};

    use super::*;
    use crate::network::Network;
    use crate::uniformity::{SurfaceTarget, UniformitySet};

    /// A free node at the origin with cables to supports at `ends`.
    fn star(ends: &[[f64; 3]], load: [f64; 3]) -> UniformityProblem {
        let mut nodes = vec![[0.0; 3]];
        nodes.extend_from_slice(ends);
        let mut loads = vec![[0.0; 3]; nodes.len()];
        loads[0] = load;
        let network = Network {
            nodes,
            edges: (1..=ends.len()).map(|j| [0, j]).collect(),
            fixed: (1..=ends.len()).collect(),
            q: vec![1.0; ends.len()],
            loads: Some(loads),
            groups: None,
        };
        let set = UniformitySet {
            name: "star".into(),
            edges: (0..ends.len()).collect(),
            mean_tension_n: 70.0,
        };
        UniformityProblem::new(network, vec![set], vec![0], SurfaceTarget::Prescribed, 1e6).unwrap()
    }

    /// Two loaded free nodes joined by a cable, each held by four supports out
    /// of plane; two overlapping sets and three cables in neither.
    fn two_nodes() -> UniformityProblem {
        let nodes = vec![
            [0.0, 0.0, 0.0],
            [2.0, 0.3, 0.1],
            [-1.0, -0.2, 0.5],
            [0.1, 1.2, 0.4],
            [0.3, -1.1, 0.6],
            [0.2, 0.1, -0.9],
            [3.1, 0.2, 0.6],
            [2.2, 1.5, 0.5],
            [1.8, -0.9, 0.4],
            [2.1, 0.4, -1.2],
        ];
        let edges = vec![
            [0, 1],
            [0, 2],
            [0, 3],
            [0, 4],
            [0, 5],
            [1, 6],
            [1, 7],
            [1, 8],
            [1, 9],
        ];
        let mut loads = vec![[0.0; 3]; nodes.len()];
        loads[0] = [1.0, -2.0, -5.0];
        loads[1] = [-0.5, 0.7, -3.0];
        let network = Network {
            q: vec![1.0; edges.len()],
            nodes,
            edges,
            fixed: (2..10).collect(),
            loads: Some(loads),
            groups: None,
        };
        let sets = vec![
            UniformitySet {
                name: "a".into(),
                edges: vec![0, 1, 2, 3],
                mean_tension_n: 10.0,
            },
            UniformitySet {
                name: "b".into(),
                edges: vec![0, 5, 6],
                mean_tension_n: 20.0,
            },
        ];
        UniformityProblem::new(network, sets, vec![0, 1], SurfaceTarget::Prescribed, 1e6).unwrap()
    }

    #[test]
    fn weights_and_targets_follow_the_sets() {
        let problem = two_nodes();
        let kkt = Kkt::new(&problem, 1e-6, 0.0);
        // Cable 0 is in both sets: weight 2, target the mean of 10 and 20.
        assert_eq!(kkt.weights[0], 2.0);
        assert_eq!(kkt.targets_n[0], 15.0);
        assert_eq!((kkt.weights[1], kkt.targets_n[1]), (1.0, 10.0));
        assert_eq!((kkt.weights[5], kkt.targets_n[5]), (1.0, 20.0));
        for k in [4, 7, 8] {
            assert_eq!(kkt.weights[k], 1e-6);
            assert_eq!(kkt.targets_n[k], problem.min_other_tension_n());
        }
    }

    #[test]
    fn tikhonov_kkt_solve_matches_dense_normal_equations() {
        let problem = two_nodes();
        let (delta, lambda) = (1e-3, 0.5);
        let kkt = Kkt::new(&problem, delta, lambda);
        let factor = kkt.factor().unwrap();
        let mut t = kkt.targets_n.clone();
        let mut mu = vec![0.0; kkt.n_rows];
        let refinement = kkt.refine(factor.as_ref(), &mut t, &mut mu, 1e-14, 10);
        assert!(refinement.backward_error <= 1e-14, "{refinement:?}");

        // (ÃᵀÃ + λW) T = Ãᵀp + λWt, assembled densely from the problem alone.
        let m = problem.network().n_edges();
        let a = problem
            .structure()
            .equilibrium_matrix(&problem.network().nodes)
            .to_dense();
        let lengths = problem.lengths_m();
        let a_tilde = Mat::<f64>::from_fn(a.nrows(), m, |r, k| a[(r, k)] / lengths[k]);
        let mut w = vec![0.0; m];
        let mut wt = vec![0.0; m];
        for set in problem.sets() {
            for &k in &set.edges {
                w[k] += 1.0;
                wt[k] += set.mean_tension_n;
            }
        }
        for k in problem.other_edges() {
            w[k] = delta;
            wt[k] = delta * problem.min_other_tension_n();
        }
        let p = problem.free_loads();
        let mut normal = a_tilde.transpose() * &a_tilde;
        let mut rhs = Mat::<f64>::from_fn(m, 1, |k, _| {
            (0..a.nrows()).map(|r| a_tilde[(r, k)] * p[r]).sum::<f64>() + lambda * wt[k]
        });
        for k in 0..m {
            normal[(k, k)] += lambda * w[k];
        }
        normal
            .llt(Side::Lower)
            .unwrap()
            .solve_in_place(rhs.as_mut());
        for k in 0..m {
            assert!(
                (t[k] - rhs[(k, 0)]).abs() <= 1e-10 * rhs[(k, 0)].abs().max(1.0),
                "cable {k}: {} vs {}",
                t[k],
                rhs[(k, 0)]
            );
        }
    }

    #[test]
    fn flat_node_with_a_zero_row_keeps_symmetric_targets() {
        // A symmetric cross in z = 0: the z row of A is zero (dependent rows),
        // and the targets are already a self-stress.
        let problem = star(
            &[
                [1.0, 0.0, 0.0],
                [0.0, 2.0, 0.0],
                [-3.0, 0.0, 0.0],
                [0.0, -0.5, 0.0],
            ],
            [0.0; 3],
        );
        let design = LeastSquares::default().solve(&problem).unwrap();
        assert_eq!(design.termination, Termination::Converged);
        for (k, t) in design.tensions_n.iter().enumerate() {
            assert!((t - 70.0).abs() <= 1e-12 * 70.0, "cable {k}: {t}");
        }
    }

    #[test]
    fn loads_outside_the_range_of_a_are_infeasible() {
        // The same flat cross cannot carry a vertical load in its plane.
        let problem = star(
            &[
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [-1.0, 0.0, 0.0],
                [0.0, -1.0, 0.0],
            ],
            [0.0, 0.0, -5.0],
        );
        let design = LeastSquares::default().solve(&problem).unwrap();
        assert_eq!(design.termination, Termination::Infeasible);
        assert!(
            design.warnings[0].contains("A q = p has no solution"),
            "{:?}",
            design.warnings
        );
        // The Tikhonov form has a solution for every load.
        let design = LeastSquares {
            lambda: Some(1.0),
            ..LeastSquares::default()
        }
        .solve(&problem)
        .unwrap();
        assert_eq!(design.termination, Termination::Converged);
    }

    #[test]
    fn settings_are_validated() {
        let problem = two_nodes();
        for solver in [
            LeastSquares {
                lambda: Some(-1.0),
                ..LeastSquares::default()
            },
            LeastSquares {
                lambda: Some(f64::NAN),
                ..LeastSquares::default()
            },
            LeastSquares {
                other_weight: 0.0,
                ..LeastSquares::default()
            },
            LeastSquares {
                tolerance: 1.0,
                ..LeastSquares::default()
            },
            LeastSquares {
                max_refinements: 0,
                ..LeastSquares::default()
            },
        ] {
            assert!(matches!(
                solver.solve(&problem),
                Err(UniformityError::Setting { solver: SOLVER, .. })
            ));
        }
    }
}
