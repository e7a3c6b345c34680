//! The step's quadratic program as a [`NewtonSystem`] of the crate's
//! interior point (`uniformity/ipm`, which owns the Mehrotra iteration, its
//! step rule and stopping tests), on the program's structure:
//!
//! ```text
//! min ½ zᵀHz + cᵀz   s.t.   E z = 0,   G z + s = h,  s ≥ 0,
//! ```
//!
//! `E` the linearised equilibrium of the free nodes, `G` the rows of the
//! box `lo ≤ p_k ≤ hi` and of the set bounds `l_g ≤ s_k + δs_k ≤ u_g`. The
//! pairs are the slacks `s` and their multipliers `λ`; `z` takes the primal
//! step, `y` (for `E z = 0`) the dual one. Each Newton system is solved by
//! `kkt.rs` (reduced to the node graph) and refined against the exact
//! operator `[H + GᵀDG, Eᵀ; E, 0]`. It starts from `z = 0` with the bounds
//! at the set's extremes, infeasible in the slacks only, with the previous
//! step's multipliers where given. Its residuals are relative to `‖h‖∞` and
//! `‖c‖∞` (at least 1), its gap to `max(1, |f|)` or, when `coarse`, to the
//! decrease the program makes ([`IpmSettings::coarse_gap`]); the tolerances
//! are [`IpmSettings::finish`]'s.

use super::kkt::{Kkt, KktError, RowWeights};
use super::model::StepModel;
use crate::algebra::norm_inf;
use crate::status::Termination;
use crate::uniformity::ipm::{self, IpmSettings, Measures, NewtonSystem, Point, Rhs};

/// Why the interior point did not reach the program's optimum (the finish
/// then asks clarabel).
#[derive(Debug, thiserror::Error)]
pub(super) enum ProgramError {
    /// A setting is out of its range.
    #[error(transparent)]
    Settings(#[from] ipm::IpmError),
    /// The reduced Newton system could not be set up.
    #[error(transparent)]
    Kkt(#[from] KktError),
    /// The iteration ended without the program's optimum.
    #[error(
        "the step's program ended {termination:?} after {iterations} interior-point iterations{}",
        cause.as_ref().map(|e| format!(" ({e})")).unwrap_or_default()
    )]
    Unsolved {
        /// How the iteration ended.
        termination: Termination,
        /// Its iterations.
        iterations: usize,
        /// The factorisation or solve that failed, if one did.
        cause: Option<KktError>,
    },
}

/// The program's solution.
pub(super) struct Solved {
    /// The optimum `z`.
    pub(super) z: Vec<f64>,
    /// The multipliers `λ` of its rows.
    pub(super) lambda: Vec<f64>,
    /// Interior-point iterations.
    pub(super) iterations: usize,
}

/// The program's optimum `z` and the multipliers `λ` of its rows, or why it
/// was not reached, with `settings` ([`IpmSettings::finish`]'s unless a
/// test says otherwise). `warm`: the multipliers of the previous program of
/// the same rows (the step before), the first `λ` where given; `coarse`:
/// stop at [`IpmSettings::coarse_gap`] times the decrease from the start
/// (the step-free point) where that comes first, else always at the gap
/// tolerance.
pub(super) fn solve(
    model: &StepModel,
    warm: Option<&[f64]>,
    coarse: bool,
    settings: &IpmSettings,
) -> Result<Solved, ProgramError> {
    settings.validate()?;
    let rows = Rows::new(model);
    let kkt = Kkt::new(model, settings)?;
    let n = model.n();
    let n_rows = rows.len();
    let n_eq = 3 * model.n_free;
    let c_norm = norm_inf(&model.gradient(&vec![0.0; n])).max(1.0);
    let h_norm = norm_inf(&rows.h).max(1.0);
    let mut system = QpSystem {
        model,
        rows,
        kkt,
        settings: *settings,
        warm,
        reference: f64::NEG_INFINITY,
        coarse,
        c_norm,
        h_norm,
        r_dual: vec![0.0; n],
        r_eq: vec![0.0; n_eq],
        r_rows: vec![0.0; n_rows],
        d: vec![0.0; n_rows],
    };
    let outcome = ipm::run(&mut system, settings);
    match (outcome.termination, outcome.point) {
        (Termination::Converged | Termination::Stalled, Some(point)) => Ok(Solved {
            z: point.free_primal,
            lambda: point.dual,
            iterations: outcome.iterations,
        }),
        (termination, _) => Err(ProgramError::Unsolved {
            termination,
            iterations: outcome.iterations,
            cause: outcome.error,
        }),
    }
}

/// The program in the driver's form (see the module documentation), with
/// the residuals of the current iterate and the weights `λ/s` of the last
/// factorisation.
struct QpSystem<'a, 'w> {
    model: &'a StepModel,
    rows: Rows<'a>,
    kkt: Kkt<'a>,
    settings: IpmSettings,
    warm: Option<&'w [f64]>,
    /// The model's value at the start when `coarse`, else `−∞`.
    reference: f64,
    coarse: bool,
    c_norm: f64,
    h_norm: f64,
    /// `Hz + c + Eᵀy + Gᵀλ`.
    r_dual: Vec<f64>,
    /// `E z`.
    r_eq: Vec<f64>,
    /// `G z + s − h`.
    r_rows: Vec<f64>,
    /// `λ/s`.
    d: Vec<f64>,
}

impl NewtonSystem for QpSystem<'_, '_> {
    type Error = KktError;

    fn pair_blocks(&self) -> Vec<usize> {
        vec![self.rows.len()]
    }

    /// `z = 0` with each set's bounds at its extremes: the step-free
    /// point, feasible but for the slacks, which are raised to at least
    /// [`IpmSettings::first_slack`]; `λ` warm (at least
    /// [`IpmSettings::warm_floor`]) or cold.
    fn start(&mut self) -> Result<Point, KktError> {
        let model = self.model;
        let mut z = vec![0.0; model.n()];
        let at = model.at_bounds();
        for (g, set) in model.sets.iter().enumerate() {
            let s = set.iter().map(|&(_, s)| s);
            z[at + 2 * g] = s.clone().fold(f64::NEG_INFINITY, f64::max);
            z[at + 2 * g + 1] = s.fold(f64::INFINITY, f64::min);
        }
        if self.coarse {
            self.reference = model.value(&z);
        }
        let gz = self.rows.mul(&z);
        let first_slack = self.settings.first_slack;
        let s: Vec<f64> = self
            .rows
            .h
            .iter()
            .zip(&gz)
            .map(|(h, g)| (h - g).max(first_slack))
            .collect();
        let n_rows = self.rows.len();
        let lambda = match self.warm {
            Some(w) if w.len() == n_rows => {
                w.iter().map(|&l| l.max(self.settings.warm_floor)).collect()
            }
            _ => self.rows.cold_multipliers(),
        };
        Ok(Point {
            primal: s,
            dual: lambda,
            free_primal: z,
            free_dual: vec![0.0; 3 * model.n_free],
        })
    }

    fn residuals(&mut self, point: &Point) -> Measures {
        let model = self.model;
        let (s, lambda, z, y) = (
            &point.primal,
            &point.dual,
            &point.free_primal,
            &point.free_dual,
        );
        self.r_dual = model.gradient(z);
        model.equilibrium_transpose_mul(y, &mut self.r_dual);
        self.rows.add_transpose_mul(lambda, &mut self.r_dual);
        model.equilibrium_mul(z, &mut self.r_eq);
        let gz = self.rows.mul(z);
        for (i, r) in self.r_rows.iter_mut().enumerate() {
            *r = gz[i] + s[i] - self.rows.h[i];
        }
        let gap: f64 = s.iter().zip(lambda).map(|(s, l)| s * l).sum();
        let f = model.value(z);
        let decrease = self.reference - f;
        let coarse = self.settings.coarse_gap / self.settings.gap_tolerance;
        Measures {
            primal: norm_inf(&self.r_eq).max(norm_inf(&self.r_rows)) / self.h_norm,
            dual: norm_inf(&self.r_dual) / self.c_norm,
            gap: gap / f.abs().max(1.0).max(coarse * decrease),
        }
    }

    fn factor(&mut self, point: &Point) -> Result<(), KktError> {
        let weights = self.rows.weights(&point.primal, &point.dual);
        self.kkt.factorize(&weights)?;
        self.d = point
            .primal
            .iter()
            .zip(&point.dual)
            .map(|(s, l)| l / s)
            .collect();
        Ok(())
    }

    /// `δλ = (r − λ∘(r_rows + G δz))/s`, `r` the complementarity rows
    /// (`λ δs + s δλ = r`); the system in `(δz, δy)`:
    /// `(H + GᵀDG) δz + Eᵀδy = −r_dual − Gᵀ((r + λ∘r_rows)/s)`,
    /// `E δz = −r_eq`.
    fn direction(
        &mut self,
        point: &Point,
        complementarity: &[f64],
        rhs: Rhs,
    ) -> Result<Point, KktError> {
        let (s, lambda) = (&point.primal, &point.dual);
        let n_rows = self.rows.len();
        let zero = |v: &[f64]| vec![0.0; v.len()];
        let (r_dual, r_eq, r_rows) = if rhs == Rhs::Centrality {
            (zero(&self.r_dual), zero(&self.r_eq), zero(&self.r_rows))
        } else {
            (self.r_dual.clone(), self.r_eq.clone(), self.r_rows.clone())
        };
        let r = complementarity;
        let shifted: Vec<f64> = (0..n_rows)
            .map(|i| (r[i] + lambda[i] * r_rows[i]) / s[i])
            .collect();
        let mut bz: Vec<f64> = r_dual.iter().map(|v| -v).collect();
        let mut gts = vec![0.0; bz.len()];
        self.rows.add_transpose_mul(&shifted, &mut gts);
        bz.iter_mut().zip(&gts).for_each(|(b, g)| *b -= g);
        let by: Vec<f64> = r_eq.iter().map(|v| -v).collect();
        let refinement = if rhs == Rhs::Predictor {
            self.settings.predictor_refinement_steps
        } else {
            self.settings.refinement_steps
        };
        let (dz, dy) = refined_solve(
            self.model,
            &self.rows,
            &self.d,
            &mut self.kkt,
            &bz,
            &by,
            refinement,
            self.settings.refinement_tolerance,
        )?;
        let gdz = self.rows.mul(&dz);
        let ds: Vec<f64> = (0..n_rows).map(|i| -r_rows[i] - gdz[i]).collect();
        let dl: Vec<f64> = (0..n_rows)
            .map(|i| (r[i] - lambda[i] * ds[i]) / s[i])
            .collect();
        Ok(Point {
            primal: ds,
            dual: dl,
            free_primal: dz,
            free_dual: dy,
        })
    }
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

/// Solves `[H + GᵀDG, Eᵀ; E, 0] (δz, δy) = (bz, by)` with the factor, refined
/// against the exact operator while the residual keeps halving.
#[allow(clippy::too_many_arguments)]
fn refined_solve(
    model: &StepModel,
    rows: &Rows,
    d: &[f64],
    kkt: &mut Kkt,
    bz: &[f64],
    by: &[f64],
    max_steps: usize,
    tolerance: f64,
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
        if norm <= tolerance || norm > 0.5 * previous {
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
