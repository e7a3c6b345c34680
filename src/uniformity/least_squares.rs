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
//! their targets), so that `g = ‖L q − T̄‖²`. Cables outside every set are not in
//! the uniformity objective; they get the regularisation weight
//! `w_k = δ` ([`LeastSquares::other_weight`]) and the target
//! `t_k = τ` ([`UniformityProblem::min_other_tension_n`]), which makes `W = diag(w)`
//! positive definite and picks one solution when the sets alone leave a
//! self-stress undetermined. With `f(T) = ‖Ã T − p‖²`:
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
//! `W` is diagonal, so `T = t − W⁻¹Ãᵀμ` and `μ` solves the Schur complement
//! system `S μ = Ã t − p`, `S = Ã W⁻¹ Ãᵀ + λ I` (3·n_free square, the sparsity
//! of `D` with 3 × 3 blocks), symmetric positive definite for `λ > 0`. For
//! `λ = 0`, `A` may have dependent rows (a flat node's vertical row, an
//! infinitesimal mechanism), so `S` is factored with the shift
//! `max(λ, 1e-12 · max diag S)` and the solution is refined against the unshifted
//! system until its residual is at rounding level ([`LeastSquares::tolerance`]).
//! Refinement changes only the multipliers' component in the null space of
//! `Aᵀ`, which does not reach `q`.
//!
//! # The λ family
//!
//! For `λ₁ < λ₂` with optima `T₁, T₂`, optimality gives
//! `f₁ + λ₁g₁ ≤ f₂ + λ₁g₂` and `f₂ + λ₂g₂ ≤ f₁ + λ₂g₁`; adding,
//! `(λ₂ − λ₁)(g₂ − g₁) ≤ 0`, so `g` is non-increasing in λ, and then
//! `f₁ − f₂ ≤ λ₁(g₂ − g₁) ≤ 0`, so the equilibrium residual `f = ‖A q − p‖²` is
//! non-decreasing. As `λ → 0` the optimum tends to the equality-constrained one
//! (when `A q = p` is solvable); as `λ → ∞`, to the targets `T = t`.

use std::time::Instant;

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, Side};

use super::{Design, Termination, UniformityError, UniformityProblem, UniformitySolver};

const SOLVER: &str = "least-squares";

/// Relative shift of the Schur complement when the (2,2) block is (nearly)
/// zero: `shift = SHIFT_FLOOR · max diag S`.
const SHIFT_FLOOR: f64 = 1e-12;

/// How many offending cables an error message names.
const SHOWN: usize = 6;

/// `min ‖L q − T̄‖²` s.t. `A q = p`, or the Tikhonov family
/// `min ‖A q − p‖² + λ ‖L q − T̄‖²` (see the module documentation).
#[derive(Debug, Clone)]
pub struct LeastSquares {
    /// Tikhonov weight λ (dimensionless: both terms are in N²), the design
    /// front's knob; `None` (or `Some(0.0)`, the λ → 0 limit) for the
    /// equality-constrained problem.
    pub lambda: Option<f64>,
    /// Weight δ of `(T_k − τ)²` for the cables outside every uniformity set,
    /// relative to the set cables' unit weight. Small, so that the sets decide;
    /// positive, so that the KKT system is nonsingular.
    pub other_weight: f64,
    /// Refinement stops when the KKT residual, relative to the size of the terms
    /// it sums, is below this.
    pub tolerance: f64,
    /// Most refinement steps (each one solve with the factor).
    pub max_refinements: usize,
}

impl Default for LeastSquares {
    fn default() -> Self {
        LeastSquares {
            lambda: None,
            other_weight: 1e-6,
            tolerance: 1e-12,
            max_refinements: 30,
        }
    }
}

impl LeastSquares {
    /// Checks the settings: `λ ≥ 0`, `δ > 0`, `0 < tolerance < 1`, all finite.
    pub fn validate(&self) -> Result<(), UniformityError> {
        if let Some(lambda) = self.lambda {
            if !(lambda.is_finite() && lambda >= 0.0) {
                return Err(UniformityError::Invalid(format!(
                    "least-squares: lambda {lambda} must be finite and ≥ 0"
                )));
            }
        }
        if !(self.other_weight.is_finite() && self.other_weight > 0.0) {
            return Err(UniformityError::Invalid(format!(
                "least-squares: other_weight {} must be finite and > 0",
                self.other_weight
            )));
        }
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return Err(UniformityError::Invalid(format!(
                "least-squares: tolerance {} must be in (0, 1)",
                self.tolerance
            )));
        }
        Ok(())
    }
}

impl UniformitySolver for LeastSquares {
    fn name(&self) -> &'static str {
        SOLVER
    }

    fn knob(&self) -> Option<f64> {
        self.lambda
    }

    fn solve(&self, problem: &UniformityProblem) -> Result<Design, UniformityError> {
        let start = Instant::now();
        self.validate()?;
        let lambda = self.lambda.unwrap_or(0.0);
        let kkt = Kkt::new(problem, self.other_weight, lambda);
        let solution = kkt.solve(self.tolerance, self.max_refinements)?;

        let mut warnings = Vec::new();
        let termination = if solution.backward_error <= self.tolerance {
            Termination::Converged
        } else if lambda == 0.0 && solution.equilibrium_error > EQUILIBRIUM_MATERIAL {
            warnings.push(format!(
                "A q = p has no solution: after {} refinement steps the equilibrium \
                 residual is {:.3e} N ({:.1e} of the terms it sums); the loads are \
                 not in the range of the equilibrium matrix",
                solution.solves, solution.max_equilibrium_residual_n, solution.equilibrium_error
            ));
            Termination::Infeasible
        } else {
            warnings.push(format!(
                "iterative refinement stopped after {} steps at a relative KKT \
                 residual of {:.3e} (tolerance {:.1e})",
                solution.solves, solution.backward_error, self.tolerance
            ));
            Termination::NumericalError
        };

        let lengths = problem.lengths_m();
        let q: Vec<f64> = solution
            .tensions_n
            .iter()
            .zip(lengths)
            .map(|(t, l)| t / l)
            .collect();
        check_bounds(problem, &q, self.lambda)?;
        Design::evaluate(
            problem,
            SOLVER,
            q,
            termination,
            solution.solves,
            start.elapsed(),
            warnings,
        )
    }
}

/// A relative equilibrium residual above this cannot be rounding: when
/// refinement stalls there, `A q = p` is inconsistent.
const EQUILIBRIUM_MATERIAL: f64 = 1e-6;

/// What the KKT solve returns.
#[derive(Debug, Clone)]
struct KktSolution {
    /// `T`, N: n_edges.
    tensions_n: Vec<f64>,
    /// Largest relative residual of either block (0 is exact).
    backward_error: f64,
    /// Relative residual of the equilibrium block.
    equilibrium_error: f64,
    /// `‖Ã T − p + λμ‖∞`, N.
    max_equilibrium_residual_n: f64,
    /// Solves with the factor.
    solves: usize,
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

    /// The lower triangle of `S = Ã W⁻¹ Ãᵀ + shift·I` and the largest diagonal
    /// entry of `Ã W⁻¹ Ãᵀ`.
    fn schur(&self, shift: impl Fn(f64) -> f64) -> (SparseColMat<usize, f64>, f64) {
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
        let matrix = SparseColMat::try_new_from_triplets(self.n_rows, self.n_rows, &triplets)
            .expect("indices are in range by construction");
        (matrix, max_diagonal)
    }

    /// Solves the system: factor `S` (shifted by at least `SHIFT_FLOOR · max diag`),
    /// then refine against the unshifted system from `T = t`, `μ = 0`.
    fn solve(
        &self,
        tolerance: f64,
        max_refinements: usize,
    ) -> Result<KktSolution, UniformityError> {
        let m = self.weights.len();
        let mut t = self.targets_n.clone();
        let mut mu = vec![0.0; self.n_rows];
        let factor = if self.n_rows == 0 {
            None
        } else {
            let lambda = self.lambda;
            let (s, _) = self.schur(|max_diagonal| lambda.max(SHIFT_FLOOR * max_diagonal));
            let failed = |what: &str, e: String| UniformityError::SolverFailed {
                solver: SOLVER,
                status: format!("{what} Cholesky factorisation of the Schur complement: {e}"),
            };
            let symbolic = SymbolicLlt::try_new(s.symbolic(), Side::Lower)
                .map_err(|e| failed("symbolic", format!("{e:?}")))?;
            Some(
                Llt::try_new_with_symbolic(symbolic, s.as_ref(), Side::Lower)
                    .map_err(|e| failed("numeric", format!("{e:?}")))?,
            )
        };

        let mut solves = 0;
        let mut previous = f64::INFINITY;
        loop {
            let residuals = self.residuals(&t, &mu);
            let error = residuals.error1.max(residuals.error2);
            let stalled = solves >= 2 && error > 0.5 * previous;
            eprintln!("DBG solves {solves} e1 {:.3e} e2 {:.3e}", residuals.error1, residuals.error2);
            let Some(factor) = factor
                .as_ref()
                .filter(|_| error > tolerance && !stalled && solves < max_refinements.max(1))
            else {
                return Ok(KktSolution {
                    tensions_n: t,
                    backward_error: error,
                    equilibrium_error: residuals.error2,
                    max_equilibrium_residual_n: residuals.max2,
                    solves,
                });
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
