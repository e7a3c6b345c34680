//! Free-geometry gradient solver (DESIGN §4): forward FDM from `q` with no
//! prescribed positions, a smooth penalty objective, its adjoint gradient
//! (DESIGN §3), and argmin's L-BFGS with a More–Thuente line search,
//! finished on the exact, nonsmooth objective (see *Exact finish*).
//!
//! # Objective
//!
//! Variables `θ` (one per cable) map smoothly onto the box of force densities,
//!
//! $$q_k = q_0 + ([q] − q_0)\,σ(θ_k), \qquad σ(θ) = 1/(1 + e^{−θ}),$$
//!
//! so `q_0 < q < [q]` for every `θ` (`q_0` = 10⁻⁹ of the problem's typical
//! force density, or of `[q]` if lower, keeps `D` numerically positive
//! definite); for `q ≪ [q]`, `θ ≈ ln(q/[q])`. The objective is
//!
//! $$J = \frac{1}{n_s}\Big(\sum_{i\in\text{surf}} \frac{e_i^2}{ε^2} + λ_{\text{lay}}
//!   \sum_i \frac{d_i^2}{ε^2}\Big) + w \sum_g R_g(T)
//!   + κ \Big(\frac{\ln(\bar T_0/t_0)}{10^{-3}}\Big)^2 + ν B(q),$$
//!
//! every term a pure number in the units of its own tolerance, so that the
//! weights mean the same on every scene and at every mesh density:
//!
//! * **surface**: `e_i = z_i − (x_i² + y_i²)/(4F)` at every surface node for a
//!   paraboloid target, `|x_i − x̂_i|` for a prescribed one; `ε` is the surface
//!   tolerance ([`Gradient::surface_tolerance_m`]) and `n_s` the number of
//!   surface nodes: the term is `(RMS/ε)²`;
//! * **layout** (`λ_lay` = [`Gradient::layout_weight`]): `d_i` is the plan drift
//!   of a surface node from its design position (paraboloid target) and the 3-D
//!   drift of every other free node (rear net). Without it the problem is not
//!   the one the fixed-geometry solvers solve: the front net slides in plan to
//!   an equal-tension layout on the paraboloid (on `small-hex`, `Tmax/Tmin` = 1.000
//!   with 0.19 m of plan drift), or the rear nodes move so that tilted ties
//!   balance any front-net tension;
//! * **ratio surrogate** (eq. 5's objective): `R_g = smax_β(s) − smin_β(s)` over
//!   the set's tensions in units of its target, `s_k = ln(T_k/t_g)`, with the
//!   normalised log-sum-exp `smax_β(s) = (1/β) ln((1/n) Σ e^{β s_k})` and
//!   `smin_β(s) = −smax_β(−s)`: smooth, below `ln(Tmax/Tmin)` by at most
//!   `2 ln(n)/β`, equal to it as the sharpness `β → ∞`. So `w` is the price of
//!   the surface in ratio: at `w = 1` an RMS of `ε` costs as much as a factor
//!   `e` in `Tmax/Tmin`;
//! * **level**: a homogeneous network's shape is invariant under `q → c q`, so
//!   without a level term the minimum is a ray, not a point; its unit is a
//!   mean tension 0.1 % off the target `t_0`;
//! * **bound barrier** `B = Σ_k (ln(q̲_k/q_k)/10⁻²)₊³ + (ln(q_k/q̄)/10⁻²)₊³`, C²,
//!   zero inside the box `T_k ≥ f t_0` (at design lengths; `f` the problem's
//!   `min_tension_fraction`) and `q_k ≤ 0.99 [q]`, where the map does not
//!   saturate; its unit is 1 % beyond a bound.
//!
//! `T_k = q_k ℓ_k(x(q))`: the tension terms enter `∂J/∂q` through `q_k` and
//! `∂J/∂x` through `ℓ_k`; one adjoint solve with the factor of the forward solve
//! turns `∂J/∂x` into `dJ/dq` ([`crate::Equilibrium::sensitivities`]).
//!
//! The weight `w` is the accuracy knob: the surface error of the minimiser grows
//! in proportion to `w`.
//!
//! # Solver
//!
//! In `θ` the problem is badly conditioned: about the design geometry the surface
//! term is `‖D⁻¹ A(x̂) δq‖²` (`A(x̂)` the equilibrium matrix of the design
//! geometry), so its curvature spreads like the square of `D`'s spectrum, and
//! the ratio term along the self-stresses is `w` times flatter again; plain
//! L-BFGS on `θ` ([`Gradient::precondition`] `= false`) needs thousands of
//! iterations on the small test scenes. L-BFGS therefore runs in preconditioned
//! variables `φ = (ψ, b)`, linearised around the `q_r` at which a run starts:
//!
//! $$q = q_r ∘ c(1 + Δ), \qquad Δ = ψ + W B^⊤ K^{-1}(D_r b − B ψ),$$
//!
//! with `B = A(x̂) diag(q_r)`, `K = B W Bᵀ` (one sparse Cholesky factorisation per
//! run), `D_r = D(q_r)`, and `W = diag(1 on set cables, 10⁴ elsewhere)`, so that
//! ties, boundary and rear cables absorb residual changes and the set cables
//! stay the design variables. `c` is the identity on `[1/4, ~[q]/q_r]`,
//! continued smoothly towards 0 below and towards `[q]` above: every iterate
//! keeps `0 < q < [q]`. Equilibrium at the design geometry is affine in `q`:
//! `ψ` moves only along its self-stresses, and `b` changes its residual by
//! `D_r b`, which displaces the free nodes by about `−b`; the surface term is
//! then about `‖b‖²`, and the layout of `q` no longer matters. The objective
//! is the same; only L-BFGS's coordinates change.
//!
//! A run ends after [`Gradient::restart_iterations`] iterations, at a line
//! search that cannot go on, or at the gradient test; the next run
//! re-linearises. The sharpness starts at [`Gradient::initial_sharpness`] and
//! grows ×3 per run up to [`Gradient::sharpness`] (a smooth surrogate first, the
//! sharp one at the end). At the final sharpness the solve has converged when
//! the stationarity `‖dJ/dθ‖∞ / J` (checked at every accepted iterate) falls
//! to [`Gradient::gradient_tolerance`], and only then. It ends without that
//! when a whole run lowers `J` by no more than
//! [`Gradient::cost_tolerance`]`·|J|` (at the rounding of `J`: `Stalled`,
//! with the stationarity it reached in a warning). Terminations: `Converged`,
//! `MaxIterations`, `Stalled` (no progress over a run, a line search that
//! failed in the last run, or a design below the tension floor that positive
//! force densities could avoid), `Infeasible` (a shape that needs slack
//! cables: the slack analysis names the nodes), `NumericalError` (a forward
//! solve failed: the best point so far is returned).
//!
//! The start, in order: a neighbouring problem's design
//! ([`super::UniformitySolver::solve_from`]: the previous outer iteration's,
//! the neighbouring weight's); the fixed-geometry optimum (`lp`'s design)
//! where `lp` applies ([`Gradient::optimum_start`]); or the uniform-tension
//! guess (`T = t_g` on the set cables at design lengths, the network's `q`
//! elsewhere) moved onto equilibrium at the design geometry by damped
//! Gauss–Newton steps in `θ` (a handful of sparse solves), then scaled to the
//! target level. The first two begin at the final sharpness, the last at
//! [`Gradient::initial_sharpness`].
//!
//! # Exact finish
//!
//! The soft max's minimiser is not the objective's: it trades the largest
//! tension for the spread of the next ones (on the benches' tied nets its
//! `J` is 6e-5 … 4e-3 above the true minimum), and L-BFGS pays for a
//! sharper surrogate in iterations, about in proportion to `β`, following
//! the cables at the extremes. With [`Gradient::exact_finish`] (the
//! default; the solver `gradient-smooth` goes without) the solve ends with
//! sequential quadratic programs on the objective with the exact
//! `ln(Tmax/Tmin)` ([`finish`]): 2–6 programs from `lp`'s optimum or a
//! neighbour's design on the benches' nets of 428 … 38 876 nodes, to a
//! stationarity certificate of the nonsmooth problem. L-BFGS then runs only
//! from a far start (the uniform-tension guess), to bring it near. Each
//! program is solved by an interior point on the net's structure (one
//! sparse LDLᵀ of the node graph in 6×6 blocks an iteration).

mod finish;
mod history;
mod lbfgs;
mod map;
mod objective;
mod preconditioner;
mod settings;
mod start;

use std::time::Instant;

use super::{Design, KnobRange, Termination, UniformityError, UniformityProblem, UniformitySolver};
use lbfgs::{minimise, Variables};
use map::Map;
use objective::Objective;
use preconditioner::Preconditioner;
use start::{optimum_start, projected_start};

pub use history::History;
pub use settings::{FinishSettings, Gradient};

/// Growth of the sharpness per restart.
const SHARPNESS_GROWTH: f64 = 3.0;

impl Gradient {
    /// The objective `J(θ)` and its gradient `dJ/dθ` (adjoint, through the map).
    ///
    /// `theta`: n_edges.
    pub fn objective_and_gradient(
        &self,
        problem: &UniformityProblem,
        theta: &[f64],
    ) -> Result<(f64, Vec<f64>), UniformityError> {
        self.validate()?;
        let m = problem.network().n_edges();
        if theta.len() != m {
            return Err(UniformityError::invalid(
                "theta",
                format!("{} entries, expected {m}", theta.len()),
            ));
        }
        Objective::new(self, problem).evaluate_theta(theta)
    }

    /// The objective with the exact `ln(Tmax/Tmin)` of every set in place of
    /// its soft form (what the exact finish minimises), at the force
    /// densities `q` (n_edges, N/m): the criterion by which two designs for
    /// the same weight compare.
    pub fn exact_objective(
        &self,
        problem: &UniformityProblem,
        q: &[f64],
    ) -> Result<f64, UniformityError> {
        self.validate()?;
        let m = problem.network().n_edges();
        if q.len() != m || q.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
            return Err(UniformityError::invalid(
                "q",
                format!("{} entries, expected {m} finite and positive", q.len()),
            ));
        }
        Ok(Objective::new(self, problem).exact().evaluate_q(q)?.0)
    }

    /// The force densities of `theta` (n_edges), N/m.
    pub fn q_of_theta(&self, problem: &UniformityProblem, theta: &[f64]) -> Vec<f64> {
        let map = Map::new(problem);
        theta.iter().map(|&t| map.q(t)).collect()
    }

    /// The variables of `q` (n_edges, N/m), each clamped into the map's range.
    pub fn theta_of_q(&self, problem: &UniformityProblem, q: &[f64]) -> Vec<f64> {
        let map = Map::new(problem);
        q.iter().map(|&v| map.theta(v)).collect()
    }

    /// Solves, and returns the design with the objective and gradient norm of
    /// every accepted iterate.
    pub fn solve_with_history(
        &self,
        problem: &UniformityProblem,
    ) -> Result<(Design, History), UniformityError> {
        self.solve_history_from(problem, None)
    }

    /// [`Gradient::solve_with_history`] from the force densities `start`
    /// (a neighbouring problem's design: the previous outer iteration's, the
    /// neighbouring weight's), or from the starts of the module documentation.
    pub fn solve_history_from(
        &self,
        problem: &UniformityProblem,
        start: Option<&[f64]>,
    ) -> Result<(Design, History), UniformityError> {
        let clock = Instant::now();
        self.validate()?;
        let objective = Objective::new(self, problem);
        let mut warnings = Vec::new();
        let m = problem.network().n_edges();
        let warm = start.filter(|q| q.len() == m && q.iter().all(|v| v.is_finite() && *v > 0.0));
        let optimum = if warm.is_none() && self.optimum_start {
            optimum_start(problem)
        } else {
            None
        };
        let near_optimum = warm.is_some() || optimum.is_some();
        let mut q = match warm.map(<[f64]>::to_vec).or(optimum) {
            Some(q) => q,
            None if self.project_start => {
                projected_start(problem, &objective.map).unwrap_or_else(|e| {
                    warnings.push(format!(
                        "projected start failed ({e}); starting from the network's q"
                    ));
                    problem.network().q.clone()
                })
            }
            None => problem.network().q.clone(),
        };
        // Into the map's range, as the solver's iterates are.
        let map = objective.map;
        q = q.iter().map(|&v| map.q(map.theta(v))).collect();

        let (j, g) = objective.evaluate_q(&q)?;
        let stationarity = objective.stationarity(&q, j, &g);
        // `J` at the current `q` and the sharpness it was evaluated at: a
        // run at that sharpness starts from it instead of evaluating again.
        let mut current = (self.sharpness, j);
        let mut history = History {
            objective: vec![j],
            gradient_norm: vec![objective.theta_gradient_norm(&q, &g)],
            stationarity,
            evaluations: 1,
            runs: 0,
            finish_steps: 0,
            finish_corrections: 0,
            finish_interior_iterations: 0,
            exact_objective: None,
        };
        // A start near the optimum begins at the final sharpness: its point
        // is already near the sharp problem's minimiser, and a smooth stage
        // would pull it away first.
        let first_sharpness = if near_optimum {
            self.sharpness
        } else {
            self.initial_sharpness.min(self.sharpness)
        };
        let mut termination = if stationarity <= self.gradient_tolerance {
            Termination::Converged
        } else {
            Termination::MaxIterations
        };
        // With the exact finish, L-BFGS only brings a far start near: from a
        // start near the optimum the programs go straight there.
        let lbfgs_budget = if self.exact_finish && near_optimum {
            0
        } else {
            self.max_iterations
        };
        let mut iterations = 0;
        while termination != Termination::Converged && iterations < lbfgs_budget {
            let preconditioner = if self.precondition {
                match Preconditioner::new(problem, &q) {
                    Ok(p) => Some(p),
                    Err(e) => {
                        warnings.push(format!("no preconditioner ({e}); plain θ variables"));
                        None
                    }
                }
            } else {
                None
            };
            let budget = self.restart_iterations.min(lbfgs_budget - iterations);
            let sharpness =
                (first_sharpness * SHARPNESS_GROWTH.powi(history.runs as i32)).min(self.sharpness);
            let objective = objective.with_sharpness(sharpness);
            let before = if current.0 == sharpness {
                current.1
            } else {
                history.evaluations += 1;
                objective.evaluate_q(&q)?.0
            };
            let variables = Variables::new(&objective, preconditioner.as_ref(), &q);
            let run = minimise(
                &variables,
                self.memory,
                budget,
                self.gradient_tolerance,
                &mut history,
            )?;
            history.runs += 1;
            iterations += run.iterations;
            warnings.extend(run.warnings);
            q = run.q;
            termination = run.termination;
            let (after, g) = objective.evaluate_q(&q)?;
            history.stationarity = objective.stationarity(&q, after, &g);
            history.evaluations += 1;
            current = (sharpness, after);
            if matches!(termination, Termination::NumericalError) {
                break;
            }
            if sharpness < self.sharpness {
                termination = Termination::MaxIterations;
                continue;
            }
            // Objective change over a whole run (restart_iterations iterations, or
            // up to a line search that could not go on).
            if termination != Termination::Converged
                && before - after <= self.cost_tolerance * after.abs()
            {
                termination = if history.stationarity <= self.gradient_tolerance {
                    Termination::Converged
                } else {
                    warnings.push(format!(
                        "J stopped decreasing (by at most {:.0e} of J over a run) at \
                         stationarity {:.2e}, above the tolerance {:.0e}",
                        self.cost_tolerance, history.stationarity, self.gradient_tolerance
                    ));
                    Termination::Stalled
                };
                break;
            }
        }
        if self.exact_finish && termination != Termination::NumericalError {
            let program = crate::uniformity::ipm::IpmSettings::finish();
            let finished = finish::finish(&objective, &q, &self.finish, &program)?;
            history.finish_steps = finished.steps;
            history.finish_corrections = finished.corrections;
            history.finish_interior_iterations = finished.interior_iterations;
            history.exact_objective = Some(finished.objective);
            warnings.extend(finished.warnings);
            q = finished.q;
            termination = finished.termination;
            iterations += finished.steps;
        }
        let design = Design::evaluate(
            problem,
            self.name(),
            q,
            termination,
            iterations,
            clock.elapsed(),
            warnings,
        )?;
        Ok((self.certified(problem, design, clock)?, history))
    }

    /// `design`, or [`Termination::Infeasible`] when it holds the shape only
    /// by letting a cable go slack (a tension below the barrier's floor,
    /// `min_tension_fraction` of the target) and the geometry has no strictly
    /// positive equilibrium (the slack analysis names the nodes; when it has
    /// one, the design stays, with a warning).
    fn certified(
        &self,
        problem: &UniformityProblem,
        mut design: Design,
        clock: Instant,
    ) -> Result<Design, UniformityError> {
        let floor = problem.min_other_tension_n();
        let Some(k) = (0..design.q.len()).find(|&k| design.tensions_n[k] < floor) else {
            return Ok(design);
        };
        let slack = super::conic::slack_nodes(problem)?;
        if slack.count > 0 {
            let mut warnings = std::mem::take(&mut design.warnings);
            warnings.push(format!(
                "cable {k} holds {:.3e} N, below the floor {floor:.3e} N: the shape needs slack cables",
                design.tensions_n[k]
            ));
            return super::conic::infeasible_design_with(
                problem,
                self.name(),
                design.iterations,
                clock,
                warnings,
                Ok(slack),
            );
        }
        design.warnings.push(format!(
            "cable {k} holds {:.3e} N, below the floor {floor:.3e} N, though strictly positive \
             force densities balance the geometry: the solve did not find them",
            design.tensions_n[k]
        ));
        design.termination = Termination::Stalled;
        Ok(design)
    }
}

impl UniformitySolver for Gradient {
    fn name(&self) -> &'static str {
        if self.exact_finish {
            "gradient"
        } else {
            "gradient-smooth"
        }
    }

    /// The ratio weight from 10⁻² to 10⁶: the surface term is in units of the
    /// tolerance (1 mm by default), so the range means the same on every
    /// scene (on paper-26m: RMS 5e-6 mm at 10⁻², 33 mm at 10⁶).
    fn knob_range(&self, _problem: &UniformityProblem) -> Option<KnobRange> {
        Some(KnobRange {
            name: "weight",
            exact: None,
            low: 1e-2,
            high: 1e6,
        })
    }

    fn solve(&self, problem: &UniformityProblem) -> Result<Design, UniformityError> {
        self.solve_with_history(problem).map(|(design, _)| design)
    }

    fn solve_from(
        &self,
        problem: &UniformityProblem,
        start: &Design,
    ) -> Result<Design, UniformityError> {
        self.solve_history_from(problem, Some(&start.q))
            .map(|(design, _)| design)
    }
}

/// Problems the unit tests of the solver's parts share.
#[cfg(test)]
mod fixtures {
    use std::path::Path;

    use crate::geometry::build_mesh;
    use crate::scene::Scene;
    use crate::uniformity::UniformityProblem;
    use crate::CableGroup;

    pub fn small_hex() -> UniformityProblem {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/small-hex.toml");
        let scene = Scene::read(&path).unwrap();
        let mesh = build_mesh(&scene).unwrap();
        UniformityProblem::from_mesh(
            &mesh,
            &[(CableGroup::Front, scene.front_net.mean_tension_n)],
            scene.cables.max_force_density_n_per_m,
        )
        .unwrap()
    }

    /// A deterministic spread of values in `[-1, 1]`.
    pub fn pattern(n: usize, seed: usize) -> Vec<f64> {
        (0..n)
            .map(|i| (((i * 7919 + seed * 104_729) % 201) as f64 - 100.0) / 100.0)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uniformity::gradient::fixtures::small_hex;

    #[test]
    fn invalid_settings_are_rejected() {
        let problem = small_hex();
        for bad in [
            Gradient {
                weight: -1.0,
                ..Gradient::default()
            },
            Gradient {
                sharpness: 0.0,
                ..Gradient::default()
            },
            Gradient {
                memory: 0,
                ..Gradient::default()
            },
        ] {
            assert!(matches!(
                bad.solve(&problem),
                Err(UniformityError::Setting {
                    solver: "gradient",
                    ..
                })
            ));
        }
        let theta = vec![0.0; 3];
        assert!(Gradient::default()
            .objective_and_gradient(&problem, &theta)
            .is_err());
    }
}
