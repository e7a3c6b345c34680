//! The corrector of path following: Newton on the extended system
//! `F(u) − λ f̂ = 0`, `c(Δu, Δλ) = 0`, the load factor an unknown beside the
//! displacements and one scalar constraint `c` fixing how far the step goes
//! ([`Constraint`]: the load factor, an arc length, or one displacement
//! component). Each iteration solves the tangent for two right-hand sides,
//! `J [δu_R, δu_f] = [−R, f̂]`, and takes `δu = δu_R + δλ δu_f` with the
//! `δλ` the constraint asks for (Crisfield 1981; Batoz & Dhatt 1979 for
//! displacement control).
//!
//! Distances use the weighted norm of [`StaticSolver::weights`] (rotations
//! × the mean element length), the load factor scaled by `ψ` to a length.

use faer::Mat;

use super::assembly::{State, System};
use super::settings::StaticSettings;
use super::solver::{wdot, StaticSolver};

/// How far a step goes: the scalar equation beside equilibrium.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Constraint {
    /// The load factor is `lambda` (load control).
    Load {
        /// The step's load factor.
        lambda: f64,
    },
    /// `‖Δu‖² + ψ² Δλ² = length²` (the spherical arc length; `ψ = 0` is
    /// Crisfield's cylindrical one), `Δ` measured from the step's start; of
    /// the two roots, the one that keeps the step's direction.
    Arc {
        /// The arc length, m.
        length: f64,
        /// The scale of the load factor, m per unit λ.
        psi: f64,
    },
    /// The unknown `dof` (a translation) moves by `increment` over the step.
    Displacement {
        /// The controlled unknown.
        dof: usize,
        /// Its increment over the step, m.
        increment: f64,
    },
}

/// A converged corrector step.
#[derive(Debug, Clone)]
pub(super) struct Corrected {
    /// The equilibrium reached.
    pub state: State,
    /// Its load factor.
    pub lambda: f64,
    /// The increment from the step's start, unknown order (rotations as
    /// the sum of their spatial increments).
    pub increment: Vec<f64>,
    /// The load factor's increment.
    pub d_lambda: f64,
    /// Newton iterations.
    pub iterations: usize,
    /// `‖F‖∞` before each iteration.
    pub residuals: Vec<f64>,
    /// Support reactions per node.
    pub reactions: Vec<[f64; 6]>,
}

/// The corrector of one solver: its weights and reference load.
pub(super) struct Corrector<'a> {
    pub solver: &'a StaticSolver,
    pub settings: &'a StaticSettings,
    /// Weights of the norm.
    pub w: Vec<f64>,
    /// The reference load `f̂`, unknown order (zero on joint rows).
    pub f_hat: Vec<f64>,
    /// The last failed correction met a residual, tangent or increment
    /// that is not finite.
    pub non_finite: std::cell::Cell<bool>,
}

impl<'a> Corrector<'a> {
    /// The corrector of `solver` with `settings`.
    pub fn new(solver: &'a StaticSolver, settings: &'a StaticSettings) -> Self {
        Corrector {
            solver,
            settings,
            w: solver.weights(),
            f_hat: reference_load(solver),
            non_finite: std::cell::Cell::new(false),
        }
    }

    /// The tangent `t = J⁻¹ f̂` at an equilibrium `(state, lambda)`: the
    /// path's direction per unit load factor. `None` when the tangent
    /// cannot be factored (exactly critical, or a mechanism) or `t` is not
    /// finite.
    pub fn tangent(&self, state: &State, lambda: f64) -> Option<Vec<f64>> {
        let system = self.solver.system();
        let ev = system.evaluate(self.solver.model(), state, lambda);
        let lu = system.factor(&ev.values).ok()?;
        let mut t = system.column(&self.f_hat);
        System::solve_in_place(&lu, t.as_mut());
        let t: Vec<f64> = (0..system.n_rows).map(|i| t[(i, 0)]).collect();
        t.iter().all(|v| v.is_finite()).then_some(t)
    }

    /// The weighted dot product.
    pub fn dot(&self, a: &[f64], b: &[f64]) -> f64 {
        wdot(&self.w, a, b)
    }

    /// Newton from `start` (an equilibrium at `lambda0`) moved by the
    /// predictor `(du, d_lambda)` onto the path, subject to `constraint`.
    /// `None` when it does not converge within the iteration budget;
    /// [`Corrector::non_finite`] then says whether it met a number that is
    /// not finite.
    pub fn correct(
        &self,
        start: &State,
        lambda0: f64,
        du: &[f64],
        d_lambda: f64,
        constraint: Constraint,
    ) -> Option<Corrected> {
        self.non_finite.set(false);
        let system = self.solver.system();
        let n = system.n_rows;
        let mut state = start.clone();
        system.apply(&mut state, du, 1.0);
        let mut increment = du.to_vec();
        let mut dl = match constraint {
            Constraint::Load { lambda } => lambda - lambda0,
            _ => d_lambda,
        };
        let mut residuals = Vec::new();
        // The last increment passed the increment test.
        let mut small = false;
        for it in 0..=self.settings.max_iterations {
            let lambda = lambda0 + dl;
            let ev = system.evaluate(self.solver.model(), &state, lambda);
            let (force, converged) = self.solver.converged(&ev.forces, lambda, self.settings);
            residuals.push(force);
            if !force.is_finite() {
                self.non_finite.set(true);
                return None;
            }
            if converged || small {
                return Some(Corrected {
                    state,
                    lambda,
                    increment,
                    d_lambda: dl,
                    iterations: it,
                    residuals,
                    reactions: ev.forces.reactions,
                });
            }
            if it == self.settings.max_iterations {
                return None;
            }
            let lu = match system.factor(&ev.values) {
                Ok(lu) => lu,
                Err(e) => {
                    self.non_finite
                        .set(matches!(e, super::assembly::FactorError::NotFinite { .. }));
                    return None;
                }
            };
            let mut rhs = Mat::from_fn(n, 2, |i, j| {
                if j == 0 {
                    -ev.forces.residual[i]
                } else {
                    self.f_hat[i]
                }
            });
            System::solve_in_place(&lu, rhs.as_mut());
            let du_r: Vec<f64> = (0..n).map(|i| rhs[(i, 0)]).collect();
            let du_f: Vec<f64> = (0..n).map(|i| rhs[(i, 1)]).collect();
            let d_lambda = match constraint {
                Constraint::Load { .. } => 0.0,
                Constraint::Displacement {
                    dof,
                    increment: target,
                } => (target - increment[dof] - du_r[dof]) / du_f[dof],
                Constraint::Arc { length, psi } => {
                    self.arc_root(&increment, dl, &du_r, &du_f, length, psi)?
                }
            };
            let delta: Vec<f64> = du_r
                .iter()
                .zip(&du_f)
                .map(|(r, f)| r + d_lambda * f)
                .collect();
            if !(d_lambda.is_finite() && delta.iter().all(|d| d.is_finite())) {
                self.non_finite.set(true);
                return None;
            }
            small = self
                .solver
                .increment_converged(&delta, &self.w, self.settings)
                && d_lambda.abs() <= self.settings.tolerance * (lambda0 + dl).abs().max(1.0);
            system.apply(&mut state, &delta, 1.0);
            for (a, d) in increment.iter_mut().zip(&delta) {
                *a += d;
            }
            dl += d_lambda;
        }
        None
    }

    /// The `δλ` that puts `a + δu_R + δλ δu_f` (`a` the step's increment so
    /// far, `dl` its load increment) on the sphere `‖·‖² + ψ²(dl + δλ)² =
    /// length²`: of the two roots, the one whose increment is closest in
    /// direction to the step's so far (Crisfield's angle criterion). `None`
    /// when the sphere is not reached (a complex pair).
    fn arc_root(
        &self,
        a: &[f64],
        dl: f64,
        du_r: &[f64],
        du_f: &[f64],
        length: f64,
        psi: f64,
    ) -> Option<f64> {
        let b: Vec<f64> = a.iter().zip(du_r).map(|(a, r)| a + r).collect();
        let psi2 = psi * psi;
        let a1 = self.dot(du_f, du_f) + psi2;
        let a2 = 2.0 * (self.dot(&b, du_f) + psi2 * dl);
        let a3 = self.dot(&b, &b) + psi2 * dl * dl - length * length;
        let disc = a2 * a2 - 4.0 * a1 * a3;
        if !(disc >= 0.0 && a1 > 0.0) {
            return None;
        }
        let roots = [
            (-a2 + disc.sqrt()) / (2.0 * a1),
            (-a2 - disc.sqrt()) / (2.0 * a1),
        ];
        let score = |r: f64| {
            let along: f64 = self
                .w
                .iter()
                .zip(&b)
                .zip(du_f)
                .zip(a)
                .map(|(((w, b), f), a)| w * w * (b + r * f) * a)
                .sum();
            along + psi2 * (dl + r) * dl
        };
        Some(if score(roots[0]) >= score(roots[1]) {
            roots[0]
        } else {
            roots[1]
        })
    }
}

/// The reference load `f̂` in unknown order (zero on joint rows).
pub(super) fn reference_load(solver: &StaticSolver) -> Vec<f64> {
    let system = solver.system();
    let mut f = vec![0.0; system.n_rows];
    for l in solver.model().loads() {
        for c in 0..3 {
            if let Some(i) = system.unknown(l.node, c) {
                f[i] += l.force_n[c];
            }
            if let Some(i) = system.unknown(l.node, 3 + c) {
                f[i] += l.moment_nm[c];
            }
        }
    }
    f
}
