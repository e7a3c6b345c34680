//! The ratio LP as a [`NewtonSystem`] of the driver: its starting point
//! (Mehrotra's, optionally in tensions), its residuals, the factor and
//! directions of its reduced normal system (`direction.rs`, `normal.rs`),
//! and the final projection of the driver's best iterate onto equilibrium.

use super::data::{Program, RatioLp};
use super::direction::{Rhs as LpRhs, Scaling};
use super::driver;
use super::error::{IpmError, NormalError};
use super::normal::NormalMatrix;
use super::settings::{IpmSettings, Start};
use super::status::{IpmSolution, WarmStart};
use super::system::{Measures, NewtonSystem, Point, Rhs};
use crate::algebra::{dot, norm_inf};
use crate::fdm::NONE;
use crate::status::Termination;
use crate::uniformity::problem::ratio_over;

/// Solves the ratio LP with the structured interior-point method and
/// `settings`, from `start`'s iterate when it has one of an LP of the same
/// sizes (else from Mehrotra's point), with `start`'s analysis of the
/// normal matrix where it fits this LP's net. The returned `q` is unscaled
/// (smallest set tension ≈ 1); the caller rescales it.
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
    start: Option<&WarmStart>,
) -> Result<IpmSolution, IpmError> {
    settings.validate()?;
    let program = Program::new(lp, *settings)?;
    let normal = NormalMatrix::new(lp, settings, start.map(|w| &w.pattern))?;
    let mut b = vec![0.0; normal.n_rows];
    // b = −A lb.
    normal.a_mul(&program.lower, &mut b);
    b.iter_mut().for_each(|v| *v = -*v);
    let (m, p, n) = (program.m, program.set.len(), normal.n_rows);
    let mut system = LpSystem {
        program: &program,
        normal,
        b,
        rp: vec![0.0; n],
        rd: vec![0.0; m],
        rw: vec![0.0; p],
        rs: 0.0,
        scaling: None,
        corrector_residual: 0.0,
        warm: start.and_then(|w| w.point.clone()),
    };
    let outcome = driver::run(&mut system, settings);
    let kept = WarmStart {
        point: outcome.kept,
        pattern: system.normal.pattern(),
    };
    let Some(point) = outcome.point else {
        return Ok(IpmSolution {
            q: program.lower.clone(),
            iterations: 0,
            termination: Termination::NumericalError,
            residuals: [f64::NAN; 3],
            kept,
        });
    };
    let measures = outcome.measures;
    let q: Vec<f64> = point.primal[..m]
        .iter()
        .zip(&program.lower)
        .map(|(a, l)| a + l)
        .collect();
    let residuals = [measures.primal, measures.dual, measures.gap];
    if !matches!(
        outcome.termination,
        Termination::Converged | Termination::Stalled
    ) {
        return Ok(IpmSolution {
            q,
            iterations: outcome.iterations,
            termination: outcome.termination,
            residuals,
            kept,
        });
    }
    let (q, primal) = program.polish(&mut system.normal, q);
    Ok(IpmSolution {
        q,
        iterations: outcome.iterations,
        termination: if primal > settings.polished {
            Termination::NumericalError
        } else {
            outcome.termination
        },
        residuals: [primal, measures.dual, measures.gap],
        kept,
    })
}

impl Program {
    /// The largest tension of `x` (`ℓ_k (x_k + lb_k)`), the scale of the
    /// primal residual.
    fn max_tension(&self, x: &[f64]) -> f64 {
        (0..self.m)
            .map(|k| self.lengths[k] * (x[k] + self.lower[k]))
            .fold(0.0, f64::max)
    }

    /// Projects `q` onto `A q = 0` twice — moving every cable, and holding
    /// the cables at a bound (within [`POLISH_BOUND`] of their floor or, on
    /// the set, of the largest set tension; their weights scaled by
    /// [`POLISH_HELD`]) — and returns the projection with the lower ratio
    /// among those that reach [`IpmSettings::polished`] (both are feasible
    /// points of the LP, the ratio its objective), else the one with the
    /// smaller residual; with its relative residual.
    ///
    /// The cables at the bounds carry the ratio: moved by the residual, they
    /// move it by as much. On the hexagonal net at 99 913 free nodes the
    /// iterate's primal residual ends at 6.9e-9 of the largest tension (776,
    /// so 5e-6 of the floor's) and its ratio 8e-9 from clarabel's; moving
    /// every cable put the ratio 1.2e-6 above clarabel's, holding the bounds
    /// (residual 2.1e-10 after six steps, then every cable for the rest)
    /// 5.2e-7. On the jittered net at that size, where 72 577 cables lie
    /// within 1e-4 of a bound, holding them moved the others across (the
    /// ratio 6.7e-4 above the iterate's), and moving every cable gave 3.7e-6
    /// above clarabel's (the iterate 1.1e-8).
    ///
    /// [`IpmSettings::polished`]: super::settings::IpmSettings::polished
    fn polish<const D: usize>(&self, normal: &mut NormalMatrix<D>, q: Vec<f64>) -> (Vec<f64>, f64) {
        let max_tension = q
            .iter()
            .zip(&self.lengths)
            .map(|(q, l)| l * q)
            .fold(0.0, f64::max);
        // Already in equilibrium (the iterate's residual at 10⁴ free nodes
        // is 1e-15 of the largest tension): no projection, no factorisation.
        let mut residual = vec![0.0; normal.n_rows];
        normal.a_mul(&q, &mut residual);
        let r = norm_inf(&residual);
        if r <= 0.1 * self.settings.polished * max_tension {
            return (q, r / max_tension);
        }
        let max_set_tension = self
            .set
            .iter()
            .map(|&k| self.lengths[k] * q[k])
            .fold(0.0, f64::max);
        let held: Vec<bool> = (0..self.m)
            .map(|k| {
                let above_floor = q[k] - self.lower[k];
                let below_top = match self.in_set[k] {
                    NONE => f64::INFINITY,
                    _ => max_set_tension - self.lengths[k] * q[k],
                };
                above_floor <= POLISH_BOUND * q[k] || below_top <= POLISH_BOUND * max_set_tension
            })
            .collect();
        let every = vec![false; self.m];
        let moving_all = self.polish_with(normal, q.clone(), max_tension, &every, 2);
        let (held_q, held_primal) = self.polish_with(normal, q, max_tension, &held, 6);
        let holding = if held_primal <= self.settings.polished {
            (held_q, held_primal)
        } else {
            self.polish_with(normal, held_q, max_tension, &every, 2)
        };
        let polished = |p: &(Vec<f64>, f64)| p.1 <= self.settings.polished;
        let better = match (polished(&moving_all), polished(&holding)) {
            (true, true) => {
                let ratio = |q: &[f64]| ratio_over(&self.set, |k| self.lengths[k] * q[k]);
                ratio(&holding.0) < ratio(&moving_all.0)
            }
            (false, true) => true,
            (true, false) => false,
            (false, false) => holding.1 < moving_all.1,
        };
        if better {
            holding
        } else {
            moving_all
        }
    }

    /// `q ← q − W Aᵀ (A W Aᵀ)⁻¹ A q` (`steps` times at most), `W = diag(q²)` scaled
    /// by [`POLISH_HELD`] where `held`: every other cable moves by about the
    /// residual relative to its own force density. Returns `q` and its
    /// residual relative to `max_tension`.
    fn polish_with<const D: usize>(
        &self,
        normal: &mut NormalMatrix<D>,
        mut q: Vec<f64>,
        max_tension: f64,
        held: &[bool],
        steps: usize,
    ) -> (Vec<f64>, f64) {
        let n = normal.n_rows;
        let mut residual = vec![0.0; n];
        let mut correction = vec![0.0; self.m];
        let weights: Vec<f64> = q
            .iter()
            .zip(held)
            .map(|(v, &h)| if h { POLISH_HELD * v * v } else { v * v })
            .collect();
        if normal.factorize(&weights).is_err() {
            return (q, f64::INFINITY);
        }
        for _ in 0..steps {
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
}

/// A cable within this fraction of a bound is held by the final projection
/// ([`Program::polish`]).
const POLISH_BOUND: f64 = 1e-4;

/// The factor of a held cable's weight in the final projection.
const POLISH_HELD: f64 = 1e-8;

/// The ratio LP in the driver's form: pairs `(x, z)` per cable, then
/// `(w, λ)` per set cable; the ratio `s` takes the primal step, `y` the
/// dual one.
struct LpSystem<'a, const D: usize> {
    program: &'a Program,
    normal: NormalMatrix<D>,
    /// `b = −A lb`.
    b: Vec<f64>,
    /// The residuals of the current iterate (see `direction::Rhs`).
    rp: Vec<f64>,
    rd: Vec<f64>,
    rw: Vec<f64>,
    rs: f64,
    /// The scaling of the last factorisation.
    scaling: Option<Scaling>,
    /// The 2-norm of the last corrector's residual in the rows FGMRES
    /// completes: the tolerance of the centrality corrections that follow.
    corrector_residual: f64,
    /// A neighbouring LP's kept iterate to start from.
    warm: Option<Point>,
}

/// The LP's parts of a point: `(x, w | z, λ)`, the ratio `s` and `y`.
struct Parts<'p> {
    x: &'p [f64],
    w: &'p [f64],
    z: &'p [f64],
    lam: &'p [f64],
    s: f64,
    y: &'p [f64],
}

impl<'p> Parts<'p> {
    fn of(point: &'p Point, m: usize) -> Self {
        let (x, w) = point.primal.split_at(m);
        let (z, lam) = point.dual.split_at(m);
        Parts {
            x,
            w,
            z,
            lam,
            s: point.free_primal[0],
            y: &point.free_dual,
        }
    }
}

impl<const D: usize> NewtonSystem for LpSystem<'_, D> {
    type Error = NormalError;

    fn pair_blocks(&self) -> Vec<usize> {
        vec![self.program.m, self.program.m + self.program.set.len()]
    }

    /// A neighbouring LP's kept iterate when its sizes match and its pairs
    /// are interior (the new LP's residuals are then those of the geometry's
    /// change); else Mehrotra's starting point: least-norm primal point with
    /// `Θ = I`, `Ω = I`, then shifted into the interior together with the
    /// dual; with `Start::TensionScaled` all of it in tensions above the
    /// floor (`ℓ x`, `z/ℓ`): least norm with `Θ = diag(1/ℓ²)`, one shift for
    /// every tension.
    fn start(&mut self) -> Result<Point, NormalError> {
        let program = self.program;
        let (m, p, n) = (program.m, program.set.len(), self.normal.n_rows);
        if let Some(warm) = self.warm.take() {
            let interior = |v: &[f64]| v.len() == m + p && v.iter().all(|&v| v > 0.0);
            if interior(&warm.primal)
                && interior(&warm.dual)
                && warm.free_primal.len() == 1
                && warm.free_dual.len() == n
                && warm.is_finite()
            {
                return Ok(warm);
            }
        }
        let lengths = &program.lengths;
        let tension_scaled = program.settings.start == Start::TensionScaled;
        let theta0: Vec<f64> = if tension_scaled {
            lengths.iter().map(|l| 1.0 / (l * l)).collect()
        } else {
            vec![1.0; m]
        };
        let (mut x, mut w, s) = {
            let sc = program.scaling(&mut self.normal, theta0, &vec![1.0; p])?;
            let (dx, dlam, _, ds) = program.solve_reduced(
                &mut self.normal,
                &sc,
                &vec![0.0; m],
                &vec![1.0; p],
                &self.b,
                0.0,
            );
            let w: Vec<f64> = dlam.iter().map(|v| -v).collect();
            (dx, w, ds)
        };
        let mut lam = vec![1.0 / p as f64; p];
        let mut z: Vec<f64> = (0..m)
            .map(|k| match program.in_set[k] {
                NONE => 0.0,
                j => lengths[k] * lam[j],
            })
            .collect();
        if tension_scaled {
            x.iter_mut().zip(lengths).for_each(|(v, l)| *v *= l);
            z.iter_mut().zip(lengths).for_each(|(v, l)| *v /= l);
        }
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
            x.iter_mut().zip(lengths).for_each(|(v, l)| *v /= l);
            z.iter_mut().zip(lengths).for_each(|(v, l)| *v *= l);
        }
        x.extend(w);
        z.extend(lam);
        Ok(Point {
            primal: x,
            dual: z,
            free_primal: vec![s],
            free_dual: vec![0.0; n],
        })
    }

    /// The residuals `b − A x`, `Eᵀλ − Aᵀy − z`, `w + 1 + E x − s e` and
    /// `1 − eᵀλ`: the primal ones relative to the largest tension (and to
    /// `max(1, |s|)`), the dual one to the largest of its terms, the gap
    /// `xᵀz + wᵀλ` to `max(1, |s|)`.
    fn residuals(&mut self, point: &Point) -> Measures {
        let program = self.program;
        let m = program.m;
        let Parts { x, w, z, lam, s, y } = Parts::of(point, m);
        let normal = &self.normal;
        normal.a_mul(x, &mut self.rp);
        for (r, bi) in self.rp.iter_mut().zip(&self.b) {
            *r = bi - *r;
        }
        let mut aty = vec![0.0; m];
        normal.at_mul(y, &mut aty);
        let mut et_lam_norm = 0.0f64;
        for k in 0..m {
            let et = match program.in_set[k] {
                NONE => 0.0,
                j => program.lengths[k] * lam[j],
            };
            et_lam_norm = et_lam_norm.max(et.abs());
            self.rd[k] = et - aty[k] - z[k];
        }
        for (j, &k) in program.set.iter().enumerate() {
            self.rw[j] = w[j] + 1.0 + program.lengths[k] * x[k] - s;
        }
        self.rs = 1.0 - lam.iter().sum::<f64>();
        let max_tension = program.max_tension(x);
        let primal = (norm_inf(&self.rp) / max_tension).max(norm_inf(&self.rw) / s.abs().max(1.0));
        let dual_scale = et_lam_norm.max(norm_inf(&aty)).max(norm_inf(z));
        let dual = (norm_inf(&self.rd) / dual_scale).max(self.rs.abs());
        let complementarity = dot(x, z) + dot(w, lam);
        Measures {
            primal,
            dual,
            gap: complementarity / s.abs().max(1.0),
        }
    }

    fn factor(&mut self, point: &Point) -> Result<(), NormalError> {
        let Parts { x, w, z, lam, .. } = Parts::of(point, self.program.m);
        let theta: Vec<f64> = x.iter().zip(z).map(|(a, b)| a / b).collect();
        let omega: Vec<f64> = w.iter().zip(lam).map(|(a, b)| a / b).collect();
        self.scaling = Some(self.program.scaling(&mut self.normal, theta, &omega)?);
        Ok(())
    }

    fn direction(
        &mut self,
        point: &Point,
        complementarity: &[f64],
        rhs: Rhs,
    ) -> Result<Point, NormalError> {
        let program = self.program;
        let (m, p, n) = (program.m, program.set.len(), self.normal.n_rows);
        let Parts { x, w, z, lam, .. } = Parts::of(point, m);
        let (rxz, rwl) = complementarity.split_at(m);
        let sc = self
            .scaling
            .as_ref()
            .expect("the driver factors before it asks for a direction");
        let (zero_n, zero_m, zero_p);
        let (rp, rw, rd, rs) = if rhs == Rhs::Centrality {
            (zero_n, zero_m, zero_p) = (vec![0.0; n], vec![0.0; m], vec![0.0; p]);
            (&zero_n[..], &zero_p[..], &zero_m[..], 0.0)
        } else {
            (&self.rp[..], &self.rw[..], &self.rd[..], self.rs)
        };
        // A centrality correction `c` has zero residual rows, so a tolerance
        // relative to them is zero and FGMRES would always run all its steps.
        // It is added to the corrector `d`, whose residual in those rows is
        // `corrector_residual`: solving `c` beyond that leaves `d + c` no more
        // accurate (its residual is at most twice `d`'s), so FGMRES stops
        // there.
        let floor = if rhs == Rhs::Centrality {
            self.corrector_residual
        } else {
            0.0
        };
        let settings = &program.settings;
        let steps = if rhs == Rhs::Predictor {
            settings.predictor_krylov_steps
        } else {
            settings.krylov_steps
        };
        let (d, residual) = program.direction(
            &mut self.normal,
            sc,
            x,
            z,
            w,
            lam,
            &LpRhs {
                rp,
                rw,
                rd,
                rs,
                rxz,
                rwl,
            },
            floor,
            steps,
        );
        if rhs == Rhs::Corrector {
            self.corrector_residual = residual;
        }
        Ok(d)
    }
}
