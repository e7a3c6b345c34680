//! The driver: the Mehrotra predictor–corrector iteration from its starting
//! point to a converged, stalled or failed end, the choice of the best iterate,
//! and its final projection onto equilibrium.

use super::data::Program;
use super::data::RatioLp;
use super::direction::Rhs;
use super::error::IpmError;
use super::normal::NormalMatrix;
use super::settings::{IpmSettings, Start};
use super::status::IpmSolution;
use crate::algebra::{dot, norm_inf};
use crate::fdm::NONE;
use crate::status::Termination;

/// Solves the ratio LP with the structured interior-point method and
/// `settings`. The returned `q` is unscaled (smallest set tension ≈ 1); the
/// caller rescales it.
///
/// # Errors
/// A setting out of range, an LP the method does not take (a tension floor
/// that is not positive, an empty set), or a normal system that cannot be set
/// up. How the iteration itself ended is the solution's status.
///
/// # Panics
/// If the per-cable vectors of `lp` differ in length.
pub(crate) fn solve<const D: usize>(
    lp: &RatioLp<D>,
    settings: &IpmSettings,
) -> Result<IpmSolution, IpmError> {
    settings.validate()?;
    let program = Program::new(lp, *settings)?;
    let mut normal = NormalMatrix::new(lp, settings)?;
    Ok(program.run(&mut normal))
}

/// The best iterate so far, by its largest residual relative to its tolerance.
struct Best {
    score: f64,
    x: Vec<f64>,
    iteration: usize,
    residuals: [f64; 3],
    max_tension: f64,
}

impl Program {
    /// Projects `q` onto `A q = 0` in the metric of relative changes:
    /// `q ← q − W Aᵀ (A W Aᵀ)⁻¹ A q`, `W = diag(q²)`, so every cable moves by
    /// about the residual relative to its own force density (cables at a bound
    /// stay there to that order). Returns `q` and its relative residual.
    fn polish<const D: usize>(
        &self,
        normal: &mut NormalMatrix<D>,
        mut q: Vec<f64>,
        max_tension: f64,
    ) -> (Vec<f64>, f64) {
        let n = normal.n_rows;
        let mut residual = vec![0.0; n];
        let mut correction = vec![0.0; self.m];
        let weights: Vec<f64> = q.iter().map(|v| v * v).collect();
        if normal.factorize(&weights).is_err() {
            return (q, f64::INFINITY);
        }
        for _ in 0..2 {
            normal.a_mul(&q, &mut residual);
            if norm_inf(&residual) <= 0.1 * self.settings.polished * max_tension {
                break;
            }
            let v = normal.solve(&weights, &residual);
            normal.at_mul(&v, &mut correction);
            for ((qk, ck), wk) in q.iter_mut().zip(&correction).zip(&weights) {
                *qk -= wk * ck;
            }
        }
        normal.a_mul(&q, &mut residual);
        (q, norm_inf(&residual) / max_tension)
    }

    fn run<const D: usize>(&self, normal: &mut NormalMatrix<D>) -> IpmSolution {
        let settings = &self.settings;
        let m = self.m;
        let p = self.set.len();
        let n = normal.n_rows;
        let n_compl = (m + p) as f64;
        // b = −A lb.
        let mut b = vec![0.0; n];
        normal.a_mul(&self.lower, &mut b);
        b.iter_mut().for_each(|v| *v = -*v);

        // Starting point (Mehrotra): least-norm primal point with Θ = I, Ω = I,
        // then shifted into the interior together with the dual; with
        // `Start::TensionScaled` all of it in tensions above the floor
        // (`ℓ x`, `z/ℓ`): least norm with `Θ = diag(1/ℓ²)`, one shift for
        // every tension.
        let tension_scaled = settings.start == Start::TensionScaled;
        let theta0: Vec<f64> = if tension_scaled {
            self.lengths.iter().map(|l| 1.0 / (l * l)).collect()
        } else {
            vec![1.0; m]
        };
        let (mut x, mut w, mut s) = {
            let Ok(sc) = self.scaling(normal, theta0, &vec![1.0; p]) else {
                return IpmSolution {
                    q: self.lower.clone(),
                    iterations: 0,
                    termination: Termination::NumericalError,
                    residuals: [f64::NAN; 3],
                };
            };
            let (dx, dlam, _, ds) =
                self.solve_reduced(normal, &sc, &vec![0.0; m], &vec![1.0; p], &b, 0.0);
            let w: Vec<f64> = dlam.iter().map(|v| -v).collect();
            (dx, w, ds)
        };
        let mut lam = vec![1.0 / p as f64; p];
        let mut y = vec![0.0; n];
        let mut z: Vec<f64> = (0..m)
            .map(|k| match self.in_set[k] {
                NONE => 0.0,
                j => self.lengths[k] * lam[j],
            })
            .collect();
        if tension_scaled {
            x.iter_mut().zip(&self.lengths).for_each(|(v, l)| *v *= l);
            z.iter_mut().zip(&self.lengths).for_each(|(v, l)| *v /= l);
        }
        {
            let min_p = x.iter().chain(&w).fold(f64::INFINITY, |a, &v| a.min(v));
            let min_d = z.iter().chain(&lam).fold(f64::INFINITY, |a, &v| a.min(v));
            let dp = (-1.5 * min_p).max(0.0);
            let dd = (-1.5 * min_d).max(0.0);
            x.iter_mut().chain(w.iter_mut()).for_each(|v| *v += dp);
            z.iter_mut().chain(lam.iter_mut()).for_each(|v| *v += dd);
            let xz = dot(&x, &z) + dot(&w, &lam);
            let sum_p: f64 = x.iter().chain(&w).sum();
            let sum_d: f64 = z.iter().chain(&lam).sum();
            let dp = 0.5 * xz / sum_d;
            let dd = 0.5 * xz / sum_p;
            x.iter_mut().chain(w.iter_mut()).for_each(|v| *v += dp);
            z.iter_mut().chain(lam.iter_mut()).for_each(|v| *v += dd);
            if tension_scaled {
                x.iter_mut().zip(&self.lengths).for_each(|(v, l)| *v /= l);
                z.iter_mut().zip(&self.lengths).for_each(|(v, l)| *v *= l);
            }
        }

        let mut rp = vec![0.0; n];
        let mut rd = vec![0.0; m];
        let mut rw = vec![0.0; p];
        let mut aty = vec![0.0; m];
        let mut residuals = [f64::INFINITY; 3];
        let mut best: Option<Best> = None;
        let mut failed = false;
        let mut iterations = 0;
        for iteration in 0..=settings.max_iterations {
            iterations = iteration;
            // Residuals.
            normal.a_mul(&x, &mut rp);
            for (r, bi) in rp.iter_mut().zip(&b) {
                *r = bi - *r;
            }
            normal.at_mul(&y, &mut aty);
            let mut et_lam_norm = 0.0f64;
            for k in 0..m {
                let et = match self.in_set[k] {
                    NONE => 0.0,
                    j => self.lengths[k] * lam[j],
                };
                et_lam_norm = et_lam_norm.max(et.abs());
                rd[k] = et - aty[k] - z[k];
            }
            for (j, &k) in self.set.iter().enumerate() {
                rw[j] = w[j] + 1.0 + self.lengths[k] * x[k] - s;
            }
            let rs = 1.0 - lam.iter().sum::<f64>();
            let max_tension = (0..m)
                .map(|k| self.lengths[k] * (x[k] + self.lower[k]))
                .fold(0.0, f64::max);
            let primal = (norm_inf(&rp) / max_tension).max(norm_inf(&rw) / s.abs().max(1.0));
            let dual_scale = et_lam_norm.max(norm_inf(&aty)).max(norm_inf(&z));
            let dual = (norm_inf(&rd) / dual_scale).max(rs.abs());
            let complementarity = dot(&x, &z) + dot(&w, &lam);
            let gap = complementarity / s.abs().max(1.0);
            residuals = [primal, dual, gap];
            if !(primal.is_finite() && dual.is_finite() && gap.is_finite()) {
                failed = true;
                break;
            }
            let converged = primal <= settings.primal_tolerance
                && dual <= settings.tolerance
                && gap <= settings.tolerance;
            let score = (primal / settings.primal_tolerance)
                .max(dual / settings.tolerance)
                .max(gap / settings.tolerance);
            // An iterate within the primal tolerance beats any outside it.
            let key = (primal > settings.primal_tolerance, score);
            let better = |b: &Best| key < (b.residuals[0] > settings.primal_tolerance, b.score);
            if converged || best.as_ref().is_none_or(better) {
                best = Some(Best {
                    score,
                    x: x.clone(),
                    iteration,
                    residuals,
                    max_tension,
                });
            }
            let stalled = best
                .as_ref()
                .is_some_and(|b| iteration >= b.iteration + settings.stall_iterations);
            if converged || stalled {
                break;
            }
            if iteration == settings.max_iterations {
                break;
            }
            let mu = complementarity / n_compl;

            // Factor the scaled normal matrix.
            let theta: Vec<f64> = x.iter().zip(&z).map(|(a, b)| a / b).collect();
            let omega: Vec<f64> = w.iter().zip(&lam).map(|(a, b)| a / b).collect();
            let Ok(sc) = self.scaling(normal, theta, &omega) else {
                failed = true;
                break;
            };

            // Predictor.
            let rxz: Vec<f64> = x.iter().zip(&z).map(|(a, b)| -a * b).collect();
            let rwl: Vec<f64> = w.iter().zip(&lam).map(|(a, b)| -a * b).collect();
            // Both directions share the factor and differ in the complementarity rows.
            let zero_n = vec![0.0; n];
            let zero_m = vec![0.0; m];
            let zero_p = vec![0.0; p];
            // `residuals`: the iterate's own residuals, or zero (a corrector).
            let mut direction = |rxz: &[f64], rwl: &[f64], residuals: bool| {
                let (rp, rw, rd, rs) = if residuals {
                    (&rp[..], &rw[..], &rd[..], rs)
                } else {
                    (&zero_n[..], &zero_p[..], &zero_m[..], 0.0)
                };
                self.direction(
                    normal,
                    &sc,
                    &x,
                    &z,
                    &w,
                    &lam,
                    &Rhs {
                        rp,
                        rw,
                        rd,
                        rs,
                        rxz,
                        rwl,
                    },
                )
            };
            let affine = direction(&rxz, &rwl, true);
            let ap = max_step(&x, &affine.dx).min(max_step(&w, &affine.dw));
            let ad = max_step(&z, &affine.dz).min(max_step(&lam, &affine.dlam));
            let mu_aff = ((0..m)
                .map(|k| (x[k] + ap * affine.dx[k]) * (z[k] + ad * affine.dz[k]))
                .sum::<f64>()
                + (0..p)
                    .map(|j| (w[j] + ap * affine.dw[j]) * (lam[j] + ad * affine.dlam[j]))
                    .sum::<f64>())
                / n_compl;
            let sigma = (mu_aff / mu).powi(3).clamp(0.0, 1.0);

            // Corrector.
            let rxz: Vec<f64> = (0..m)
                .map(|k| sigma * mu - x[k] * z[k] - affine.dx[k] * affine.dz[k])
                .collect();
            let rwl: Vec<f64> = (0..p)
                .map(|j| sigma * mu - w[j] * lam[j] - affine.dw[j] * affine.dlam[j])
                .collect();
            let mut d = direction(&rxz, &rwl, true);
            let steps = |d: &super::direction::Direction| {
                (
                    max_step(&x, &d.dx).min(max_step(&w, &d.dw)),
                    max_step(&z, &d.dz).min(max_step(&lam, &d.dlam)),
                )
            };
            // Gondzio's multiple centrality correctors: aim a longer step at
            // a point whose complementarity products lie within
            // [β_min, β_max]·σμ, keep the correction while it lengthens the step.
            let (mut bp, mut bd) = steps(&d);
            for _ in 0..settings.centrality_correctors {
                if bp.min(bd) >= 1.0 {
                    break;
                }
                let tp = (1.5 * bp + 0.1).min(1.0);
                let td = (1.5 * bd + 0.1).min(1.0);
                let target = sigma * mu;
                let (lo, hi) = (0.1 * target, 10.0 * target);
                let push = |v: f64| {
                    if v < lo {
                        lo - v
                    } else if v > hi {
                        (hi - v).max(-hi)
                    } else {
                        0.0
                    }
                };
                let cxz: Vec<f64> = (0..m)
                    .map(|k| push((x[k] + tp * d.dx[k]) * (z[k] + td * d.dz[k])))
                    .collect();
                let cwl: Vec<f64> = (0..p)
                    .map(|j| push((w[j] + tp * d.dw[j]) * (lam[j] + td * d.dlam[j])))
                    .collect();
                let c = direction(&cxz, &cwl, false);
                let mut trial = super::direction::Direction {
                    dx: d.dx.iter().zip(&c.dx).map(|(a, b)| a + b).collect(),
                    dz: d.dz.iter().zip(&c.dz).map(|(a, b)| a + b).collect(),
                    dw: d.dw.iter().zip(&c.dw).map(|(a, b)| a + b).collect(),
                    dlam: d.dlam.iter().zip(&c.dlam).map(|(a, b)| a + b).collect(),
                    dy: d.dy.iter().zip(&c.dy).map(|(a, b)| a + b).collect(),
                    ds: d.ds + c.ds,
                };
                let (np, nd) = steps(&trial);
                if np.min(nd) < 1.01 * bp.min(bd) {
                    break;
                }
                std::mem::swap(&mut d, &mut trial);
                (bp, bd) = (np, nd);
            }
            let eta = (1.0 - mu.min(0.1)).clamp(0.9, 0.99995);
            let ap = (eta * bp).min(1.0);
            let ad = (eta * bd).min(1.0);
            let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
            if !(ap.is_finite()
                && ad.is_finite()
                && d.ds.is_finite()
                && finite(&d.dx)
                && finite(&d.dz)
                && finite(&d.dy))
            {
                failed = true;
                break;
            }
            for k in 0..m {
                x[k] += ap * d.dx[k];
                z[k] += ad * d.dz[k];
            }
            for j in 0..p {
                w[j] += ap * d.dw[j];
                lam[j] += ad * d.dlam[j];
            }
            s += ap * d.ds;
            for (yi, di) in y.iter_mut().zip(&d.dy) {
                *yi += ad * di;
            }
        }
        // The best iterate: converged, or accepted at reduced accuracy.
        // At reduced accuracy the primal residual must still be within its own
        // tolerance: the final projection moves `q` by about that much, and a
        // score scaled by `tolerance` alone let 1e-5 through (measured: the
        // ratio of a 2·10⁵-node net off by 1e-3).
        let Some(best) = best.filter(|b| {
            b.residuals[0] <= settings.primal_tolerance
                && b.residuals[1].max(b.residuals[2]) <= settings.reduced_tolerance
        }) else {
            return IpmSolution {
                q: x.iter().zip(&self.lower).map(|(a, l)| a + l).collect(),
                iterations,
                termination: if failed {
                    Termination::NumericalError
                } else {
                    Termination::MaxIterations
                },
                residuals,
            };
        };
        let q: Vec<f64> = best.x.iter().zip(&self.lower).map(|(a, l)| a + l).collect();
        let (q, primal) = self.polish(normal, q, best.max_tension);
        let mut residuals = best.residuals;
        residuals[0] = primal;
        IpmSolution {
            q,
            iterations,
            termination: if primal > settings.polished {
                Termination::NumericalError
            } else if best.score <= 1.0 {
                Termination::Converged
            } else {
                Termination::Stalled
            },
            residuals,
        }
    }
}

/// Largest step in `[0, 1]` keeping `v + α dv ≥ 0`.
fn max_step(v: &[f64], dv: &[f64]) -> f64 {
    v.iter().zip(dv).fold(
        1.0f64,
        |alpha, (&vi, &di)| {
            if di < 0.0 {
                alpha.min(-vi / di)
            } else {
                alpha
            }
        },
    )
}
