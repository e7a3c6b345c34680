//! A primal–dual interior point (Mehrotra predictor–corrector) for the
//! step's quadratic program, on its structure:
//!
//! ```text
//! min ½ zᵀHz + cᵀz   s.t.   E z = 0,   G z + s = h,  s ≥ 0,
//! ```
//!
//! `E` the linearised equilibrium of the free nodes, `G` the rows of the
//! box `lo ≤ p_k ≤ hi` and of the set bounds `l_g ≤ s_k + δs_k ≤ u_g`. Each
//! Newton system is solved by `kkt.rs` (reduced to the node graph) and
//! refined against the exact operator `[H + GᵀDG, Eᵀ; E, 0]`. It starts
//! from `z = 0` with the bounds at the set's extremes, infeasible in the
//! slacks only, with the previous step's multipliers where given. It stops
//! when the residuals are below [`FEASIBILITY`] (or, once they have stalled,
//! below [`REDUCED_FEASIBILITY`]) and the gap below
//! [`TOLERANCE`]`·max(1, |f|)` — the finish compares the model's optimum
//! with `J` to `10⁻⁹ J` — or below [`COARSE`] times the decrease the
//! program makes.

use super::kkt::{Kkt, KktError, RowWeights};
use super::model::StepModel;
use crate::algebra::norm_inf;

/// Relative residuals at which the program is solved (clarabel's default).
const FEASIBILITY: f64 = 1e-8;
/// Relative residuals at which a program whose residuals have stopped
/// falling is taken as solved: at the edge of the directions' precision
/// they can stall a little above [`FEASIBILITY`] (2–5e-8 on realistic-26m
/// in the design loop) and then drift away. The finish reads the point only
/// after re-solving its equilibrium ([`StepModel::feasible_point`]).
const REDUCED_FEASIBILITY: f64 = 1e-6;
/// Iterations over which the residuals must halve not to have stalled.
const STALL_ITERATIONS: usize = 10;
/// Gap, relative to `max(1, |f|)`, at which the program is solved.
const TOLERANCE: f64 = 1e-10;
/// Most interior-point iterations.
const MAX_ITERATIONS: usize = 80;
/// Most refinement steps of one Newton solve.
const REFINEMENT_STEPS: usize = 30;
/// The backward error at which refinement stops: each block's residual
/// relative to the size of its terms. The interior point asks its residuals
/// for [`FEASIBILITY`]; a direction this accurate leaves them unchanged to
/// a hundredth of that.
const REFINED: f64 = 1e-10;
/// Refinement steps of the predictor, which only sets the centring.
const PREDICTOR_REFINEMENT: usize = 0;
/// A program that lowers the model by `Δ` is solved once its gap is below
/// `COARSE·Δ`: its step is then known to a thousandth of its decrease,
/// which is all the finish reads from it; only a program that predicts
/// (almost) no decrease — the certificate — is solved to [`TOLERANCE`].
const COARSE: f64 = 1e-3;
/// The least first slack of a row (the rows are in units of `ln T` and of
/// relative `δq`): 0.1 took 10 iterations a program where 1 took 13.
const FIRST_SLACK: f64 = 0.1;
/// The least first multiplier of a warm start. The sets' rows keep their
/// activity from one step to the next: on the tied nets a warm program
/// takes 5–7 iterations against 7–11 cold; below 1e-4 it can stall.
const WARM_FLOOR: f64 = 1e-4;
/// Fraction of the step to the boundary taken.
const STEP_FRACTION: f64 = 0.99;

/// Why the interior point did not reach the program's optimum (the finish
/// then asks clarabel).
#[derive(Debug, thiserror::Error)]
pub(super) enum ProgramError {
    /// The reduced Newton system could not be set up, factored or solved.
    #[error(transparent)]
    Kkt(#[from] KktError),
    /// The residuals or the gap stopped being finite numbers.
    #[error("non-finite iterate at iteration {iteration}")]
    NonFinite {
        /// The interior-point iteration.
        iteration: usize,
    },
    /// The iteration limit came first.
    #[error("the step's program did not converge in {iterations} interior-point iterations")]
    MaxIterations {
        /// The limit, [`MAX_ITERATIONS`].
        iterations: usize,
    },
}

/// The program's optimum `z` and the multipliers `λ` of its rows, or why it
/// was not reached. `warm`: the multipliers of the previous program of the
/// same rows (the step before), the first `λ` where given; `coarse`: stop
/// at [`COARSE`] times the decrease from the start (the step-free point)
/// where that comes first, else always at [`TOLERANCE`].
pub(super) fn solve(
    model: &StepModel,
    warm: Option<&[f64]>,
    coarse: bool,
) -> Result<(Vec<f64>, Vec<f64>), ProgramError> {
    let rows = Rows::new(model);
    let mut kkt = Kkt::new(model)?;
    let n = model.n();
    let n_rows = rows.len();
    let n_eq = 3 * model.n_free;

    // Start: z = 0 with each set's bounds at its extremes.
    let mut z = vec![0.0; n];
    let at = model.at_bounds();
    for (g, set) in model.sets.iter().enumerate() {
        let s = set.iter().map(|&(_, s)| s);
        z[at + 2 * g] = s.clone().fold(f64::NEG_INFINITY, f64::max);
        z[at + 2 * g + 1] = s.fold(f64::INFINITY, f64::min);
    }
    // The start is the step-free point, feasible but for the slacks.
    let reference = if coarse {
        model.value(&z)
    } else {
        f64::NEG_INFINITY
    };
    let gz = rows.mul(&z);
    let mut s: Vec<f64> = rows
        .h
        .iter()
        .zip(&gz)
        .map(|(h, g)| (h - g).max(FIRST_SLACK))
        .collect();
    let mut lambda = match warm {
        Some(w) if w.len() == n_rows => w.iter().map(|&l| l.max(WARM_FLOOR)).collect(),
        _ => rows.cold_multipliers(),
    };
    let mut y = vec![0.0; n_eq];
    let c_norm = norm_inf(&model.gradient(&vec![0.0; n])).max(1.0);
    let h_norm = norm_inf(&rows.h).max(1.0);
    // max(primal, dual) residual per iteration.
    let mut residuals = Vec::with_capacity(MAX_ITERATIONS);

    for iteration in 0..MAX_ITERATIONS {
        // Residuals.
        let mut r_dual = model.gradient(&z);
        model.equilibrium_transpose_mul(&y, &mut r_dual);
        rows.add_transpose_mul(&lambda, &mut r_dual);
        let mut r_eq = vec![0.0; n_eq];
        model.equilibrium_mul(&z, &mut r_eq);
        let gz = rows.mul(&z);
        let r_rows: Vec<f64> = (0..n_rows).map(|i| gz[i] + s[i] - rows.h[i]).collect();
        let gap: f64 = s.iter().zip(&lambda).map(|(s, l)| s * l).sum();
        let f = model.value(&z);
        let primal = norm_inf(&r_eq).max(norm_inf(&r_rows)) / h_norm;
        let dual = norm_inf(&r_dual) / c_norm;
        if !(primal.is_finite() && dual.is_finite() && gap.is_finite()) {
            return Err(ProgramError::NonFinite { iteration });
        }
        let decrease = reference - f;
        let closed = gap <= TOLERANCE * f.abs().max(1.0) || gap <= COARSE * decrease;
        let residual = primal.max(dual);
        let stalled = iteration >= STALL_ITERATIONS
            && residual > 0.5 * residuals[iteration - STALL_ITERATIONS];
        residuals.push(residual);
        if closed && (residual <= FEASIBILITY || (stalled && residual <= REDUCED_FEASIBILITY)) {
            return Ok((z, lambda));
        }
        let mu = gap / n_rows as f64;

        let weights = rows.weights(&s, &lambda);
        kkt.factorize(&weights)?;
        let d: Vec<f64> = s.iter().zip(&lambda).map(|(s, l)| l / s).collect();
        // The Newton direction for the complementarity target `r_c`
        // (`s∘λ` minus what it should become).
        let mut direction = |r_c: &[f64], refinement: usize| {
            // δλ = (−r_c + λ∘(r_rows + G δz))/s; the system in (δz, δy):
            // (H + GᵀDG) δz + Eᵀδy = −r_dual − Gᵀ((−r_c + λ∘r_rows)/s),
            // E δz = −r_eq.
            let shifted: Vec<f64> = (0..n_rows)
                .map(|i| (-r_c[i] + lambda[i] * r_rows[i]) / s[i])
                .collect();
            let mut bz: Vec<f64> = r_dual.iter().map(|v| -v).collect();
            let mut gts = vec![0.0; n];
            rows.add_transpose_mul(&shifted, &mut gts);
            bz.iter_mut().zip(&gts).for_each(|(b, g)| *b -= g);
            let by: Vec<f64> = r_eq.iter().map(|v| -v).collect();
            let (dz, dy) = refined_solve(model, &rows, &d, &mut kkt, &bz, &by, refinement)?;
            let gdz = rows.mul(&dz);
            let ds: Vec<f64> = (0..n_rows).map(|i| -r_rows[i] - gdz[i]).collect();
            let dl: Vec<f64> = (0..n_rows)
                .map(|i| (-r_c[i] - lambda[i] * ds[i]) / s[i])
                .collect();
            Ok::<_, KktError>((dz, dy, ds, dl))
        };

        // Predictor.
        let r_c: Vec<f64> = s.iter().zip(&lambda).map(|(s, l)| s * l).collect();
        let (_, _, ds, dl) = direction(&r_c, PREDICTOR_REFINEMENT)?;
        let alpha = step_to_boundary(&s, &ds).min(step_to_boundary(&lambda, &dl));
        let gap_affine: f64 = (0..n_rows)
            .map(|i| (s[i] + alpha * ds[i]) * (lambda[i] + alpha * dl[i]))
            .sum();
        let sigma = (gap_affine / gap).powi(3).clamp(0.0, 1.0);

        // Corrector.
        let r_c: Vec<f64> = (0..n_rows)
            .map(|i| s[i] * lambda[i] + ds[i] * dl[i] - sigma * mu)
            .collect();
        let (dz, dy, ds, dl) = direction(&r_c, REFINEMENT_STEPS)?;
        let alpha = (STEP_FRACTION * step_to_boundary(&s, &ds).min(step_to_boundary(&lambda, &dl)))
            .min(1.0);
        for (v, d) in z.iter_mut().zip(&dz) {
            *v += alpha * d;
        }
        for (v, d) in y.iter_mut().zip(&dy) {
            *v += alpha * d;
        }
        for (v, d) in s.iter_mut().zip(&ds) {
            *v += alpha * d;
        }
        for (v, d) in lambda.iter_mut().zip(&dl) {
            *v += alpha * d;
        }
    }
    Err(ProgramError::MaxIterations {
        iterations: MAX_ITERATIONS,
    })
}

/// Adds to `model` the curvature its linearised `δ ln T_k = p_k + …` leaves
/// out, weighted by the multipliers `lambda` of the previous step's rows
/// (the Lagrangian's Hessian of sequential quadratic programming): `ln(1 +
/// p) = p − p²/2`, so the lower row of cable `k` curves by `+λ_low` and
/// the upper by `−λ_high`; the sum, where positive (the program stays
/// convex). Without it the model is linear along the sets' extremes, its
/// step ends at the trust radius, and the concave `ln` costs the lowest
/// tensions `≈ p²/2` that no step sees.
pub(super) fn add_log_curvature(model: &mut StepModel, lambda: &[f64]) {
    let m = model.m();
    let set_rows: usize = model.sets.iter().map(|set| 2 * set.len()).sum();
    if lambda.len() != 2 * m + set_rows {
        return;
    }
    let mut curvature = vec![0.0; m];
    let mut i = 2 * m;
    for set in &model.sets {
        for &(k, _) in set {
            curvature[k] += lambda[i + 1] - lambda[i];
            i += 2;
        }
    }
    for (cable, c) in model.cables.iter_mut().zip(curvature) {
        cable.curvature = c.max(0.0);
    }
}

/// The largest `α ≤ 1/STEP_FRACTION` with `v + α dv ≥ 0`.
fn step_to_boundary(v: &[f64], dv: &[f64]) -> f64 {
    v.iter()
        .zip(dv)
        .filter(|(_, &d)| d < 0.0)
        .map(|(&v, &d)| -v / d)
        .fold(1.0 / STEP_FRACTION, f64::min)
}

/// Solves `[H + GᵀDG, Eᵀ; E, 0] (δz, δy) = (bz, by)` with the factor, refined
/// against the exact operator while the residual keeps halving.
fn refined_solve(
    model: &StepModel,
    rows: &Rows,
    d: &[f64],
    kkt: &mut Kkt,
    bz: &[f64],
    by: &[f64],
    max_steps: usize,
) -> Result<(Vec<f64>, Vec<f64>), KktError> {
    let (mut dz, mut dy) = kkt.solve(bz, by)?;
    // Each block's residual relative to the size of its own terms (a
    // backward error). A joint norm would hide the equilibrium's, and its
    // right-hand side is tiny near the optimum (zero at the start): it is
    // measured against `‖E‖ ‖δz‖` where that is larger.
    let (bz_norm, by_norm) = (norm_inf(bz), norm_inf(by));
    let e_norm = kkt.equilibrium_norm;
    let mut previous = f64::INFINITY;
    for _ in 0..max_steps {
        // r = b − K (δz, δy).
        let mut kz = model.hessian_mul(&dz);
        model.equilibrium_transpose_mul(&dy, &mut kz);
        let weighted: Vec<f64> = rows.mul(&dz).iter().zip(d).map(|(g, d)| g * d).collect();
        rows.add_transpose_mul(&weighted, &mut kz);
        let mut ky = vec![0.0; by.len()];
        model.equilibrium_mul(&dz, &mut ky);
        let rz: Vec<f64> = bz.iter().zip(&kz).map(|(b, k)| b - k).collect();
        let ry: Vec<f64> = by.iter().zip(&ky).map(|(b, k)| b - k).collect();
        let z_size = bz_norm.max(norm_inf(&kz)).max(f64::MIN_POSITIVE);
        let y_size = by_norm.max(e_norm * norm_inf(&dz)).max(f64::MIN_POSITIVE);
        let norm = (norm_inf(&rz) / z_size).max(norm_inf(&ry) / y_size);
        if norm <= REFINED || norm > 0.5 * previous {
            break;
        }
        previous = norm;
        let (cz, cy) = kkt.solve(&rz, &ry)?;
        dz.iter_mut().zip(&cz).for_each(|(v, c)| *v += c);
        dy.iter_mut().zip(&cy).for_each(|(v, c)| *v += c);
    }
    Ok((dz, dy))
}

/// The inequality rows `G z ≤ h`: per cable the box's upper and lower row,
/// then per set and member the upper and lower bound row.
struct Rows<'a> {
    model: &'a StepModel,
    h: Vec<f64>,
}

impl<'a> Rows<'a> {
    fn new(model: &'a StepModel) -> Self {
        let mut h: Vec<f64> = model.cables.iter().map(|c| c.hi).collect();
        h.extend(model.cables.iter().map(|c| -c.lo));
        for set in &model.sets {
            for &(_, s) in set {
                h.extend([-s, s]);
            }
        }
        Rows { model, h }
    }

    fn len(&self) -> usize {
        self.h.len()
    }

    /// `G z`.
    fn mul(&self, z: &[f64]) -> Vec<f64> {
        let model = self.model;
        let m = model.m();
        let mut out: Vec<f64> = z[..m].to_vec();
        out.extend(z[..m].iter().map(|v| -v));
        let at = model.at_bounds();
        for (g, set) in model.sets.iter().enumerate() {
            for &(k, _) in set {
                let ds = model.delta_s(k, z);
                out.extend([ds - z[at + 2 * g], -ds + z[at + 2 * g + 1]]);
            }
        }
        out
    }

    /// `out += Gᵀ v`.
    fn add_transpose_mul(&self, v: &[f64], out: &mut [f64]) {
        let model = self.model;
        let m = model.m();
        for k in 0..m {
            out[k] += v[k] - v[m + k];
        }
        let at = model.at_bounds();
        let mut i = 2 * m;
        for (g, set) in model.sets.iter().enumerate() {
            for &(k, _) in set {
                let (high, low) = (v[i], v[i + 1]);
                model.add_delta_s_gradient(k, high - low, out);
                out[at + 2 * g] -= high;
                out[at + 2 * g + 1] += low;
                i += 2;
            }
        }
    }

    /// The first multipliers of a cold start: the rows of each set, and the
    /// box's, each sum to the ratio weight `w`, so that the dual rows of the
    /// bounds `u_g`, `l_g` (gradient `±w`, balanced by their set's `λ`) start
    /// balanced. All ones leaves them off by the set's size: on a
    /// 10⁴-node net 14 iterations against 11.
    fn cold_multipliers(&self) -> Vec<f64> {
        let model = self.model;
        let w = if model.weight > 0.0 {
            model.weight
        } else {
            1.0
        };
        let m = model.m();
        let mut lambda = vec![w / m as f64; 2 * m];
        for set in &model.sets {
            lambda.extend(std::iter::repeat_n(w / set.len() as f64, 2 * set.len()));
        }
        lambda
    }

    /// The weights `λ/s` in the form `kkt.rs` takes.
    fn weights(&self, s: &[f64], lambda: &[f64]) -> RowWeights {
        let m = self.model.m();
        let d = |i: usize| lambda[i] / s[i];
        let mut i = 2 * m;
        let mut high = Vec::new();
        let mut low = Vec::new();
        for set in &self.model.sets {
            high.push((0..set.len()).map(|j| d(i + 2 * j)).collect());
            low.push((0..set.len()).map(|j| d(i + 2 * j + 1)).collect());
            i += 2 * set.len();
        }
        RowWeights {
            boxes: (0..m).map(|k| d(k) + d(m + k)).collect(),
            high,
            low,
        }
    }
}
