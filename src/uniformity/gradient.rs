//! Free-geometry gradient solver (DESIGN §4): forward FDM from `q` with no
//! prescribed positions, a smooth penalty objective, its adjoint gradient
//! (DESIGN §3), and argmin's L-BFGS with a More–Thuente line search.
//!
//! # Objective
//!
//! Variables `θ` (one per cable) map smoothly onto the box of force densities,
//!
//! $$q_k = q_0 + ([q] − q_0)\,σ(θ_k), \qquad σ(θ) = 1/(1 + e^{−θ}),$$
//!
//! so `q_0 < q < [q]` for every `θ` (`q_0 = 10⁻⁹ [q]` keeps `D` numerically
//! positive definite); for `q ≪ [q]`, `θ ≈ ln(q/[q])`. The objective is
//!
//! $$J = \frac{1}{n_s L^2}\Big(\sum_{i\in\text{surf}} e_i^2 + λ_{\text{lay}}
//!   \sum_i d_i^2\Big) + w \sum_g R_g(T) + κ \ln^2\frac{\bar T_0}{t_0} + ν B(q)$$
//!
//! * **surface**: `e_i = z_i − (x_i² + y_i²)/(4F)` at every surface node for a
//!   paraboloid target, `|x_i − x̂_i|` for a prescribed one; `L` is the mean
//!   design length of the first set's cables and `n_s` the number of surface
//!   nodes, so the term is a dimensionless mean square;
//! * **layout** (`λ_lay` = [`Gradient::layout_weight`]): `d_i` is the plan drift
//!   of a surface node from its design position (paraboloid target) and the 3-D
//!   drift of every other free node (rear net). Without it the problem is not
//!   the one the fixed-geometry solvers solve: the front net slides in plan to
//!   an equal-tension layout on the paraboloid (on `small-hex`, `Tmax/Tmin` = 1.000
//!   with 0.19 m of plan drift), or the rear nodes move so that tilted ties
//!   balance any front-net tension;
//! * **ratio surrogate**: `R_g = smax_β(s) − smin_β(s)` over the set's
//!   `s_k = ln T_k`, with the normalised log-sum-exp
//!   `smax_β(s) = (1/β) ln((1/n) Σ e^{β s_k})` and `smin_β(s) = −smax_β(−s)`:
//!   smooth, below `ln(Tmax/Tmin)` by at most `2 ln(n)/β`, equal to it as the
//!   sharpness `β → ∞`;
//! * **level**: a homogeneous network's shape is invariant under `q → c q`, so
//!   without a level term the minimum is a ray, not a point;
//! * **bound barrier** `B = Σ_k (ln(q̲_k/q_k))₊³ + (ln(q_k/q̄))₊³`, C², zero inside
//!   the box `T_k ≥ f t_0` (at design lengths; `f` the problem's
//!   `min_tension_fraction`) and `q_k ≤ 0.99 [q]`, where the map does not
//!   saturate.
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
//! `‖dJ/dθ‖` (checked at every accepted iterate) falls below
//! [`Gradient::gradient_tolerance`] times its value at the network's `q`, or when
//! a whole run lowers `J` by no more than [`Gradient::cost_tolerance`]`·|J|`.
//! Terminations: `Converged` (either test), `MaxIterations`, `Stalled` (a line
//! search that failed in the last run), `NumericalError` (a forward solve
//! failed: the best point so far is returned).
//!
//! The start is the uniform-tension guess (`T = t_g` on the set cables at
//! design lengths, the network's `q` elsewhere) moved onto equilibrium at the
//! design geometry by damped Gauss–Newton steps in `θ` (a handful of sparse
//! solves), then scaled to the target level.

use std::cell::RefCell;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{
    CostFunction, Error as ArgminError, Executor, IterState, State, TerminationReason,
    TerminationStatus, KV,
};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::linalg::LltError;
use faer::sparse::{CreationError, FaerError, SparseColMat, Triplet};
use faer::{Mat, Side};

use super::{
    Design, KnobRange, SurfaceTarget, Termination, UniformityError, UniformityProblem,
    UniformitySolver,
};
use crate::algebra::norm2;

/// Lower asymptote of the map, as a fraction of `[q]`.
const FLOOR_FRACTION: f64 = 1e-9;
/// Upper edge of the barrier's free box, as a fraction of `[q]`.
const UPPER_FRACTION: f64 = 0.99;
/// Relative diagonal shift of `K` (dependent rows of `A`: flat nodes,
/// infinitesimal mechanisms).
const SHIFT: f64 = 1e-10;
/// How much more freely than a set cable's the other cables' force densities
/// absorb residual changes (`W`), in the start and the preconditioner.
const OTHER_FREEDOM: f64 = 1e4;
/// Where the positivity clamp `c(t)` leaves the identity.
const CLAMP_LOW: f64 = 0.25;
/// Length of the first step of every L-BFGS run, in the solver's variables
/// (relative change of `q`, or metres of `b`); the line search extends it.
const FIRST_STEP: f64 = 1e-3;
/// How the observer stops a run whose iterate passes the gradient test.
const CONVERGED: &str = "converged: ‖dJ/dθ‖ below tolerance";
/// Growth of the sharpness per restart.
const SHARPNESS_GROWTH: f64 = 3.0;
/// Why an L-BFGS run stopped when its update degenerated.
const NO_PROGRESS: &str = "no further progress (non-finite L-BFGS update)";
/// Most damped Gauss–Newton steps of the projected start.
const START_STEPS: usize = 20;
/// Most step halvings of one of them.
const START_HALVINGS: usize = 12;

/// Adjoint-gradient L-BFGS on the free geometry (see the module documentation).
#[derive(Debug, Clone)]
pub struct Gradient {
    /// Weight `w` of the ratio surrogate against the surface error: larger buys a
    /// lower `Tmax/Tmin` with a larger surface error (the design-front knob).
    pub weight: f64,
    /// Weight of the layout drift against the surface error (0: free layout).
    pub layout_weight: f64,
    /// Sharpness `β` of the soft max/min of `ln T`: larger follows `Tmax/Tmin`
    /// more closely and makes the objective stiffer.
    pub sharpness: f64,
    /// Sharpness of the first L-BFGS run; it grows ×3 per restart up to
    /// `sharpness` (continuation: smooth first, sharp at the end).
    pub initial_sharpness: f64,
    /// Weight `κ` of the pretension-level term `ln²(T̄₀/t₀)`.
    pub level_weight: f64,
    /// Weight `ν` of the bound barrier.
    pub barrier_weight: f64,
    /// Number of correction pairs L-BFGS keeps.
    pub memory: usize,
    /// Most L-BFGS iterations in all.
    pub max_iterations: usize,
    /// Most iterations of one L-BFGS run; then the preconditioner is
    /// re-linearised around the current point, the sharpness raised, and L-BFGS
    /// restarted.
    pub restart_iterations: usize,
    /// Converged (at the final sharpness) when
    /// `‖dJ/dθ‖ ≤ gradient_tolerance · ‖dJ/dθ‖` at the network's `q`, the
    /// initial guess.
    pub gradient_tolerance: f64,
    /// Converged (at the final sharpness) when a whole L-BFGS run lowers `J` by
    /// no more than `cost_tolerance · |J|`.
    pub cost_tolerance: f64,
    /// Precondition L-BFGS (see the module documentation); `false` runs it on `θ`.
    pub precondition: bool,
    /// Start from the uniform-tension guess projected onto equilibrium at the
    /// design geometry; `false` starts from the network's `q`.
    pub project_start: bool,
}

impl Default for Gradient {
    fn default() -> Self {
        Gradient {
            weight: 1e-6,
            layout_weight: 1.0,
            sharpness: 100.0,
            initial_sharpness: 10.0,
            level_weight: 1.0,
            barrier_weight: 1.0,
            memory: 20,
            max_iterations: 5000,
            restart_iterations: 300,
            gradient_tolerance: 1e-8,
            cost_tolerance: 1e-12,
            precondition: true,
            project_start: true,
        }
    }
}

impl Gradient {
    /// Checks the settings.
    pub fn validate(&self) -> Result<(), UniformityError> {
        let bad = |name: &'static str, value: f64, range: &'static str| {
            Err(UniformityError::Setting {
                solver: "gradient",
                name,
                value,
                range,
            })
        };
        let non_negative = [
            ("weight", self.weight),
            ("layout_weight", self.layout_weight),
            ("barrier_weight", self.barrier_weight),
            ("gradient_tolerance", self.gradient_tolerance),
            ("cost_tolerance", self.cost_tolerance),
        ];
        for (what, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return bad(what, v, "finite and ≥ 0");
            }
        }
        for (what, v) in [
            ("sharpness", self.sharpness),
            ("initial_sharpness", self.initial_sharpness),
            ("level_weight", self.level_weight),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(what, v, "finite and > 0");
            }
        }
        if self.memory == 0 {
            return bad("memory", 0.0, "≥ 1");
        }
        if self.restart_iterations == 0 {
            return bad("restart_iterations", 0.0, "≥ 1");
        }
        Ok(())
    }

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
        let start = Instant::now();
        self.validate()?;
        let objective = Objective::new(self, problem);
        let mut warnings = Vec::new();
        let mut q = if self.project_start {
            projected_start(problem, &objective.map).unwrap_or_else(|e| {
                warnings.push(format!(
                    "projected start failed ({e}); starting from the network's q"
                ));
                problem.network().q.clone()
            })
        } else {
            problem.network().q.clone()
        };
        // Into the map's range, as the solver's iterates are.
        q = self.q_of_theta(problem, &self.theta_of_q(problem, &q));

        // The gradient test is relative to the gradient at the network's q.
        let reference = {
            let q0 = self.q_of_theta(problem, &self.theta_of_q(problem, &problem.network().q));
            let (_, g) = objective.evaluate_q(&q0)?;
            objective.theta_gradient_norm(&q0, &g)
        };
        let tolerance = self.gradient_tolerance * reference;
        let (j, g) = objective.evaluate_q(&q)?;
        let gradient_norm = objective.theta_gradient_norm(&q, &g);
        let mut history = History {
            objective: vec![j],
            gradient_norm: vec![gradient_norm],
            evaluations: 1,
            runs: 0,
        };
        let mut termination = if gradient_norm <= tolerance {
            Termination::Converged
        } else {
            Termination::MaxIterations
        };
        let mut iterations = 0;
        while termination != Termination::Converged && iterations < self.max_iterations {
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
            let budget = self
                .restart_iterations
                .min(self.max_iterations - iterations);
            let sharpness = (self.initial_sharpness.min(self.sharpness)
                * SHARPNESS_GROWTH.powi(history.runs as i32))
            .min(self.sharpness);
            let objective = Objective {
                sharpness,
                ..objective.clone()
            };
            let before = objective.evaluate_q(&q)?.0;
            history.evaluations += 1;
            let variables = Variables::new(&objective, preconditioner.as_ref(), &q);
            let run = minimise(&variables, self.memory, budget, tolerance, &mut history)?;
            history.runs += 1;
            iterations += run.iterations;
            warnings.extend(run.warnings);
            q = run.q;
            termination = run.termination;
            let after = objective.evaluate_q(&q)?.0;
            history.evaluations += 1;
            if matches!(termination, Termination::NumericalError) {
                break;
            }
            if sharpness < self.sharpness {
                termination = Termination::MaxIterations;
                continue;
            }
            // Objective change over a whole run (restart_iterations iterations, or
            // up to a line search that could not go on).
            if before - after <= self.cost_tolerance * after.abs() {
                termination = Termination::Converged;
            }
        }
        let design = Design::evaluate(
            problem,
            self.name(),
            q,
            termination,
            iterations,
            start.elapsed(),
            warnings,
        )?;
        Ok((design, history))
    }
}

/// Objective value and gradient norm of every accepted iterate.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct History {
    /// `J` at the start and after every iteration (each run at its own
    /// sharpness, the start at the final one).
    pub objective: Vec<f64>,
    /// `‖dJ/dθ‖` at the same points.
    pub gradient_norm: Vec<f64>,
    /// Evaluations of `J` and its gradient (forward + adjoint solves).
    pub evaluations: usize,
    /// L-BFGS runs (the preconditioner is re-linearised for each).
    pub runs: usize,
}

impl UniformitySolver for Gradient {
    fn name(&self) -> &'static str {
        "gradient"
    }

    /// The ratio weight from 1e-8 to 1: the surface term is normalised, so
    /// 1e-6 is already near the exact-equilibrium design.
    fn knob_range(&self, _problem: &UniformityProblem) -> Option<KnobRange> {
        Some(KnobRange {
            name: "weight",
            exact: None,
            low: 1e-8,
            high: 1.0,
        })
    }

    fn solve(&self, problem: &UniformityProblem) -> Result<Design, UniformityError> {
        self.solve_with_history(problem).map(|(design, _)| design)
    }
}

/// The smooth bijection `θ ↦ q = q_0 + ([q] − q_0) σ(θ)` onto `(q_0, [q])`, or
/// `θ ↦ e^θ` onto `(0, ∞)` when there is no bound.
#[derive(Debug, Clone, Copy)]
enum Map {
    /// `q = q_0 + ([q] − q_0) σ(θ)` for a finite bound `[q]`.
    Bounded { floor: f64, span: f64 },
    /// `q = e^θ` when there is no bound.
    Log,
}

impl Map {
    fn new(problem: &UniformityProblem) -> Self {
        let q_max = problem.max_force_density_n_per_m;
        if q_max.is_finite() {
            let floor = FLOOR_FRACTION * q_max;
            Map::Bounded {
                floor,
                span: q_max - floor,
            }
        } else {
            Map::Log
        }
    }

    /// The smallest `q` the map reaches, `q_0` (or the smallest positive float).
    fn floor(&self) -> f64 {
        match *self {
            Map::Bounded { floor, .. } => floor,
            Map::Log => f64::MIN_POSITIVE,
        }
    }

    /// `q(θ)`.
    fn q(&self, theta: f64) -> f64 {
        match *self {
            Map::Bounded { floor, span } => floor + span * sigmoid(theta),
            Map::Log => theta.exp(),
        }
    }

    /// `dq/dθ`: `([q] − q_0) σ (1 − σ)`, or `e^θ`.
    fn dq(&self, theta: f64) -> f64 {
        match *self {
            Map::Bounded { span, .. } => {
                let s = sigmoid(theta);
                span * s * (1.0 - s)
            }
            Map::Log => theta.exp(),
        }
    }

    /// `θ(q)`, with `q` clamped a hair inside `(q_0, [q])` (or above 0).
    fn theta(&self, q: f64) -> f64 {
        match *self {
            Map::Bounded { floor, span } => {
                let s = ((q - floor) / span).clamp(1e-300, 1.0 - 1e-12);
                s.ln() - (-s).ln_1p()
            }
            Map::Log => q.max(f64::MIN_POSITIVE).ln(),
        }
    }
}

/// `1/(1 + e^{−θ})`, without overflow.
fn sigmoid(theta: f64) -> f64 {
    if theta >= 0.0 {
        1.0 / (1.0 + (-theta).exp())
    } else {
        let e = theta.exp();
        e / (1.0 + e)
    }
}

/// Normalised log-sum-exp `(1/β) ln((1/n) Σ e^{β s_k})`, and its weights
/// `softmax(β s)` written into `weights`.
fn soft_max(s: &[f64], beta: f64, weights: &mut [f64]) -> f64 {
    let top = s.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut sum = 0.0;
    for (w, &v) in weights.iter_mut().zip(s) {
        *w = (beta * (v - top)).exp();
        sum += *w;
    }
    for w in weights.iter_mut() {
        *w /= sum;
    }
    top + (sum / s.len() as f64).ln() / beta
}

/// The objective of one problem with one set of settings.
#[derive(Clone)]
struct Objective<'a> {
    problem: &'a UniformityProblem,
    map: Map,
    weight: f64,
    layout_weight: f64,
    sharpness: f64,
    level_weight: f64,
    barrier_weight: f64,
    /// `1/(n_s L²)`.
    surface_scale: f64,
    /// Free nodes that are not surface nodes.
    other_free: Vec<usize>,
    /// Lower edge `q̲_k` of the barrier's box.
    q_low: Vec<f64>,
    /// Upper edge `q̄` of the barrier's box.
    q_high: f64,
}

impl<'a> Objective<'a> {
    fn new(settings: &Gradient, problem: &'a UniformityProblem) -> Self {
        let lengths = problem.lengths_m();
        let first = &problem.sets()[0];
        let length_scale =
            first.edges.iter().map(|&k| lengths[k]).sum::<f64>() / first.edges.len() as f64;
        let n_surface = problem.surface_nodes().len().max(1) as f64;
        let mut is_surface = vec![false; problem.network().n_nodes()];
        for &i in problem.surface_nodes() {
            is_surface[i] = true;
        }
        let min_tension = problem.min_other_tension_n();
        Objective {
            problem,
            map: Map::new(problem),
            weight: settings.weight,
            layout_weight: settings.layout_weight,
            sharpness: settings.sharpness,
            level_weight: settings.level_weight,
            barrier_weight: settings.barrier_weight,
            surface_scale: 1.0 / (n_surface * length_scale * length_scale),
            other_free: problem
                .structure()
                .free_nodes()
                .iter()
                .copied()
                .filter(|&i| !is_surface[i])
                .collect(),
            q_low: lengths.iter().map(|&l| min_tension / l).collect(),
            q_high: UPPER_FRACTION * problem.max_force_density_n_per_m,
        }
    }

    /// `J(θ)` and `dJ/dθ`.
    fn evaluate_theta(&self, theta: &[f64]) -> Result<(f64, Vec<f64>), UniformityError> {
        let q: Vec<f64> = theta.iter().map(|&t| self.map.q(t)).collect();
        let (value, mut gradient) = self.evaluate_q(&q)?;
        for (g, &t) in gradient.iter_mut().zip(theta) {
            *g *= self.map.dq(t);
        }
        Ok((value, gradient))
    }

    /// `‖dJ/dθ‖` from `dJ/dq`.
    fn theta_gradient_norm(&self, q: &[f64], dj_dq: &[f64]) -> f64 {
        q.iter()
            .zip(dj_dq)
            .map(|(&q, g)| (g * self.map.dq(self.map.theta(q))).powi(2))
            .sum::<f64>()
            .sqrt()
    }

    /// `J(q)` and `dJ/dq`.
    fn evaluate_q(&self, q: &[f64]) -> Result<(f64, Vec<f64>), UniformityError> {
        let problem = self.problem;
        let structure = problem.structure();
        let design = &problem.network().nodes;
        let eq = problem.forward(q)?;
        let x = &eq.nodes_xyz_m;
        let mut dj_dx = vec![[0.0; 3]; x.len()];
        let mut value = 0.0;

        // Surface error, and the plan drift of the surface nodes.
        let layout = self.layout_weight * self.surface_scale;
        for &i in problem.surface_nodes() {
            let p = x[i];
            match problem.surface() {
                SurfaceTarget::Paraboloid(parab) => {
                    let e = parab.axial_deviation(p);
                    value += self.surface_scale * e * e;
                    let c = 2.0 * self.surface_scale * e;
                    let two_f = 2.0 * parab.focal_length_m;
                    dj_dx[i][0] -= c * p[0] / two_f;
                    dj_dx[i][1] -= c * p[1] / two_f;
                    dj_dx[i][2] += c;
                    for d in 0..2 {
                        let drift = p[d] - design[i][d];
                        value += layout * drift * drift;
                        dj_dx[i][d] += 2.0 * layout * drift;
                    }
                }
                SurfaceTarget::Prescribed => {
                    for d in 0..3 {
                        let e = p[d] - design[i][d];
                        value += self.surface_scale * e * e;
                        dj_dx[i][d] += 2.0 * self.surface_scale * e;
                    }
                }
            }
        }
        // Layout: the other free nodes near their design positions.
        if layout > 0.0 {
            for &i in &self.other_free {
                for d in 0..3 {
                    let drift = x[i][d] - design[i][d];
                    value += layout * drift * drift;
                    dj_dx[i][d] += 2.0 * layout * drift;
                }
            }
        }

        // Ratio surrogate and level: dJ/dT per cable.
        let tensions = &eq.edges_forces_n;
        let mut dj_dt = vec![0.0; q.len()];
        let mut s = Vec::new();
        let mut up = Vec::new();
        let mut down = Vec::new();
        for set in problem.sets() {
            s.clear();
            s.extend(set.edges.iter().map(|&k| tensions[k].ln()));
            up.resize(s.len(), 0.0);
            down.resize(s.len(), 0.0);
            let high = soft_max(&s, self.sharpness, &mut up);
            for v in s.iter_mut() {
                *v = -*v;
            }
            let low = -soft_max(&s, self.sharpness, &mut down);
            value += self.weight * (high - low);
            for (n, &k) in set.edges.iter().enumerate() {
                dj_dt[k] += self.weight * (up[n] - down[n]) / tensions[k];
            }
        }
        let first = &problem.sets()[0];
        let n0 = first.edges.len() as f64;
        let mean = first.edges.iter().map(|&k| tensions[k]).sum::<f64>() / n0;
        let level = (mean / first.mean_tension_n).ln();
        value += self.level_weight * level * level;
        for &k in &first.edges {
            dj_dt[k] += 2.0 * self.level_weight * level / (n0 * mean);
        }

        // T_k = q_k ℓ_k(x): explicit in q, and through the positions.
        let mut dj_dq = vec![0.0; q.len()];
        for (k, (&g, &[i, j])) in dj_dt.iter().zip(structure.edges()).enumerate() {
            if g == 0.0 {
                continue;
            }
            let l = eq.edges_lengths_m[k];
            dj_dq[k] += g * l;
            let u = eq.edges_vectors_m[k];
            for c in 0..3 {
                let d = g * q[k] * u[c] / l;
                dj_dx[i][c] += d;
                dj_dx[j][c] -= d;
            }
        }
        let mut gradient = eq.sensitivities(structure, &dj_dx, Some(&dj_dq));

        // Bound barrier, in ln q.
        if self.barrier_weight > 0.0 {
            for (k, g) in gradient.iter_mut().enumerate() {
                let below = (self.q_low[k] / q[k]).ln();
                if below > 0.0 {
                    value += self.barrier_weight * below.powi(3);
                    *g -= 3.0 * self.barrier_weight * below * below / q[k];
                }
                let above = (q[k] / self.q_high).ln();
                if above > 0.0 {
                    value += self.barrier_weight * above.powi(3);
                    *g += 3.0 * self.barrier_weight * above * above / q[k];
                }
            }
        }
        Ok((value, gradient))
    }
}

/// The positivity clamp `c(t)` of the preconditioned variables and `c'(t)`:
/// the identity on `[a, u_b]`, `a e^{(t−a)/a}` below `a` (→ 0), and
/// `u − (u − u_b) e^{−(t−u_b)/(u−u_b)}` above `u_b` (→ `u`, the bound); C¹.
fn clamp(t: f64, upper: f64) -> (f64, f64) {
    let a = CLAMP_LOW;
    let start = a + 0.9 * (upper - a);
    if t < a {
        let e = ((t - a) / a).exp();
        (a * e, e)
    } else if t > start {
        let gap = upper - start;
        let e = (-(t - start) / gap).exp();
        (upper - gap * e, e)
    } else {
        (t, 1.0)
    }
}

/// Why `K = B W Bᵀ` of the linearised equilibrium could not be factored (the
/// preconditioner and the projected start fall back without it).
#[derive(Debug, thiserror::Error)]
enum LinearisationError {
    /// The network has no free node, so `K` is empty.
    #[error("no free node")]
    NoFreeNode,
    /// Assembling `K` failed.
    #[error("{0:?}")]
    Assembly(CreationError),
    /// Its symbolic factorisation failed.
    #[error("{0:?}")]
    Symbolic(FaerError),
    /// Its numeric factorisation failed.
    #[error("{0:?}")]
    Numeric(LltError),
}

/// The linearised equilibrium of the design geometry around `q_r` (see the
/// module documentation): `B = A(x̂) diag(q_r)`, `K = B W Bᵀ` factored once,
/// `D_r = D(q_r)`.
struct Preconditioner {
    q_ref: Vec<f64>,
    /// The map's floor `q_0`: `q` never goes below it.
    floor: f64,
    /// `c`'s upper asymptote `u_k = [q] / q_r,k` (times a hair below 1).
    upper: Vec<f64>,
    /// `W`.
    freedom: Vec<f64>,
    edges_vectors: Vec<[f64; 3]>,
    /// Free indices of every cable's end nodes.
    edges: Vec<[Option<usize>; 2]>,
    n_rows: usize,
    factor: Llt<usize, f64>,
    /// The last `(φ, Δ(φ))`: `Δ` of a nearby point is computed from it, so that
    /// the solve's rounding error scales with the step, not with `φ`.
    base: RefCell<(Vec<f64>, Vec<f64>)>,
}

impl Preconditioner {
    fn new(problem: &UniformityProblem, q_ref: &[f64]) -> Result<Self, LinearisationError> {
        Self::with_weights(problem, q_ref.to_vec(), q_ref)
    }

    /// `B = A(x̂) diag(g)` (g = q_r here; `dq/dθ` for the projected start).
    fn with_weights(
        problem: &UniformityProblem,
        q_ref: Vec<f64>,
        g: &[f64],
    ) -> Result<Self, LinearisationError> {
        let structure = problem.structure();
        let edges: Vec<[Option<usize>; 2]> = structure
            .edges()
            .iter()
            .map(|&[i, j]| [structure.free_index(i), structure.free_index(j)])
            .collect();
        let n_rows = 3 * structure.free_nodes().len();
        if n_rows == 0 {
            return Err(LinearisationError::NoFreeNode);
        }
        let mut freedom = vec![OTHER_FREEDOM; edges.len()];
        for set in problem.sets() {
            for &k in &set.edges {
                freedom[k] = 1.0;
            }
        }
        let edges_vectors = problem.network().edges_vectors();
        let q_max = problem.max_force_density_n_per_m * (1.0 - 1e-6);
        let upper = q_ref.iter().map(|&q| q_max / q).collect();
        let factor = factor_k(&edges, &edges_vectors, &freedom, n_rows, g)?;
        Ok(Preconditioner {
            q_ref,
            floor: Map::new(problem).floor(),
            upper,
            freedom,
            edges_vectors,
            edges,
            n_rows,
            factor,
            base: RefCell::new((Vec::new(), Vec::new())),
        })
    }

    /// Refactors `K` for new column weights `g`.
    fn refactor(&mut self, g: &[f64]) -> Result<(), LinearisationError> {
        self.factor = factor_k(
            &self.edges,
            &self.edges_vectors,
            &self.freedom,
            self.n_rows,
            g,
        )?;
        Ok(())
    }

    /// Number of variables `φ = (ψ, b)`.
    fn dim(&self) -> usize {
        self.q_ref.len() + self.n_rows
    }

    /// `A(x̂) diag(g) v`.
    fn b_times(&self, g: &[f64], v: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.n_rows];
        for (k, ends) in self.edges.iter().enumerate() {
            let value = g[k] * v[k];
            for (end, sign) in ends.iter().zip([1.0, -1.0]) {
                if let Some(f) = end {
                    for c in 0..3 {
                        out[3 * f + c] += sign * self.edges_vectors[k][c] * value;
                    }
                }
            }
        }
        out
    }

    /// `W diag(g) A(x̂)ᵀ μ`.
    fn w_bt_times(&self, g: &[f64], mu: &[f64]) -> Vec<f64> {
        self.edges
            .iter()
            .enumerate()
            .map(|(k, ends)| {
                let mut sum = 0.0;
                for (end, sign) in ends.iter().zip([1.0, -1.0]) {
                    if let Some(f) = end {
                        for c in 0..3 {
                            sum += sign * self.edges_vectors[k][c] * mu[3 * f + c];
                        }
                    }
                }
                self.freedom[k] * g[k] * sum
            })
            .collect()
    }

    /// `D_r b`, per coordinate.
    fn d_times(&self, b: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.n_rows];
        for (k, &[fi, fj]) in self.edges.iter().enumerate() {
            for c in 0..3 {
                let bi = fi.map_or(0.0, |f| b[3 * f + c]);
                let bj = fj.map_or(0.0, |f| b[3 * f + c]);
                let d = self.q_ref[k] * (bi - bj);
                if let Some(f) = fi {
                    out[3 * f + c] += d;
                }
                if let Some(f) = fj {
                    out[3 * f + c] -= d;
                }
            }
        }
        out
    }

    /// `K⁻¹ v`.
    fn k_solve(&self, v: &[f64]) -> Vec<f64> {
        let mut rhs = Mat::<f64>::from_fn(self.n_rows, 1, |r, _| v[r]);
        self.factor.solve_in_place(rhs.as_mut());
        (0..self.n_rows).map(|r| rhs[(r, 0)]).collect()
    }

    /// `Δ(φ)`, from the last point evaluated: `Δ(φ₀) + Δ(φ − φ₀)` (linear).
    fn delta(&self, phi: &[f64]) -> Vec<f64> {
        let mut base = self.base.borrow_mut();
        let delta = if base.0.len() == phi.len() {
            let step: Vec<f64> = phi.iter().zip(&base.0).map(|(a, b)| a - b).collect();
            let change = self.delta_linear(&step);
            base.1.iter().zip(&change).map(|(a, b)| a + b).collect()
        } else {
            self.delta_linear(phi)
        };
        *base = (phi.to_vec(), delta.clone());
        delta
    }

    /// `Δ(φ) = ψ + W Bᵀ K⁻¹ (D_r b − B ψ)`.
    fn delta_linear(&self, phi: &[f64]) -> Vec<f64> {
        let m = self.q_ref.len();
        let (psi, b) = phi.split_at(m);
        let mut rhs = self.d_times(b);
        for (r, v) in rhs.iter_mut().zip(self.b_times(&self.q_ref, psi)) {
            *r -= v;
        }
        let back = self.w_bt_times(&self.q_ref, &self.k_solve(&rhs));
        psi.iter().zip(&back).map(|(p, b)| p + b).collect()
    }

    /// `q(φ)`, with `Δ(φ)` computed afresh.
    fn q_exact(&self, phi: &[f64]) -> Vec<f64> {
        self.q_of_delta(&self.delta_linear(phi)).0
    }

    /// `q(φ) = max(q_r ∘ c(1 + Δ), q_0)` and `dq/dΔ`.
    fn q(&self, phi: &[f64]) -> (Vec<f64>, Vec<f64>) {
        self.q_of_delta(&self.delta(phi))
    }

    fn q_of_delta(&self, delta: &[f64]) -> (Vec<f64>, Vec<f64>) {
        delta
            .iter()
            .enumerate()
            .map(|(k, d)| {
                let (c, dc) = clamp(1.0 + d, self.upper[k]);
                let q = self.q_ref[k] * c;
                if q > self.floor {
                    (q, self.q_ref[k] * dc)
                } else {
                    (self.floor, 0.0)
                }
            })
            .unzip()
    }

    /// `dJ/dφ` from `dJ/dΔ`: `(g − Bᵀ K⁻¹ B W g, D_r K⁻¹ B W g)`.
    fn pull_back(&self, gradient: &[f64]) -> Vec<f64> {
        let weighted: Vec<f64> = gradient
            .iter()
            .zip(&self.freedom)
            .map(|(g, f)| g * f)
            .collect();
        let y = self.k_solve(&self.b_times(&self.q_ref, &weighted));
        let mut back = self.w_bt_times(&self.q_ref, &y);
        for (b, f) in back.iter_mut().zip(&self.freedom) {
            *b /= f;
        }
        let mut out: Vec<f64> = gradient.iter().zip(&back).map(|(g, b)| g - b).collect();
        out.extend(self.d_times(&y));
        out
    }

    /// The equilibrium residual `A(x̂) q − p` of the design geometry.
    fn residual(&self, q: &[f64], loads: &[f64]) -> Vec<f64> {
        let ones = vec![1.0; q.len()];
        let mut r = self.b_times(q, &ones);
        for (r, p) in r.iter_mut().zip(loads) {
            *r -= p;
        }
        r
    }
}

/// Factors `K = A G W G Aᵀ` (`G = diag(g)`, `W = diag(freedom)`), its diagonal
/// raised by [`SHIFT`].
fn factor_k(
    edges: &[[Option<usize>; 2]],
    edges_vectors: &[[f64; 3]],
    freedom: &[f64],
    n_rows: usize,
    g: &[f64],
) -> Result<Llt<usize, f64>, LinearisationError> {
    let mut diagonal = vec![0.0; n_rows];
    let mut triplets = Vec::with_capacity(n_rows + 15 * g.len());
    let mut column: Vec<(usize, f64)> = Vec::with_capacity(6);
    for (k, (ends, u)) in edges.iter().zip(edges_vectors).enumerate() {
        column.clear();
        for (end, sign) in ends.iter().zip([1.0, -1.0]) {
            if let Some(f) = end {
                for (c, &uc) in u.iter().enumerate() {
                    column.push((3 * f + c, sign * uc));
                }
            }
        }
        // Rows ascending: (ra, rb) with b < a is in the lower triangle.
        column.sort_by_key(|&(r, _)| r);
        let scale = g[k] * g[k] * freedom[k];
        for (a, &(ra, va)) in column.iter().enumerate() {
            diagonal[ra] += va * va * scale;
            for &(rb, vb) in &column[..a] {
                triplets.push(Triplet::new(ra, rb, va * vb * scale));
            }
        }
    }
    triplets.extend(
        diagonal
            .iter()
            .enumerate()
            .map(|(r, &d)| Triplet::new(r, r, d * (1.0 + SHIFT))),
    );
    let k = SparseColMat::try_new_from_triplets(n_rows, n_rows, &triplets)
        .map_err(LinearisationError::Assembly)?;
    let symbolic =
        SymbolicLlt::try_new(k.symbolic(), Side::Lower).map_err(LinearisationError::Symbolic)?;
    Llt::try_new_with_symbolic(symbolic, k.as_ref(), Side::Lower)
        .map_err(LinearisationError::Numeric)
}

/// The solver's variables: `θ`, or the preconditioned `φ`.
struct Variables<'a, 'p> {
    objective: &'a Objective<'p>,
    preconditioner: Option<&'a Preconditioner>,
    start: Vec<f64>,
}

impl<'a, 'p> Variables<'a, 'p> {
    fn new(
        objective: &'a Objective<'p>,
        preconditioner: Option<&'a Preconditioner>,
        q: &[f64],
    ) -> Self {
        let start = match preconditioner {
            Some(p) => vec![0.0; p.dim()],
            None => q.iter().map(|&v| objective.map.theta(v)).collect(),
        };
        Variables {
            objective,
            preconditioner,
            start,
        }
    }

    fn q(&self, phi: &[f64]) -> Vec<f64> {
        match self.preconditioner {
            Some(p) => p.q_exact(phi),
            None => phi.iter().map(|&t| self.objective.map.q(t)).collect(),
        }
    }

    /// `J`, `dJ/dφ` and `‖dJ/dθ‖`.
    fn evaluate(&self, phi: &[f64]) -> Result<(f64, Vec<f64>, f64), UniformityError> {
        match self.preconditioner {
            Some(p) => {
                let (q, dq) = p.q(phi);
                let (j, mut g) = self.objective.evaluate_q(&q)?;
                let theta_norm = self.objective.theta_gradient_norm(&q, &g);
                for (g, d) in g.iter_mut().zip(&dq) {
                    *g *= d;
                }
                Ok((j, p.pull_back(&g), theta_norm))
            }
            None => {
                let (j, g) = self.objective.evaluate_theta(phi)?;
                let theta_norm = norm2(&g);
                Ok((j, g, theta_norm))
            }
        }
    }
}

/// What one L-BFGS run returns.
struct Run {
    q: Vec<f64>,
    termination: Termination,
    iterations: usize,
    warnings: Vec<String>,
}

/// One L-BFGS run of at most `budget` iterations from the variables' start,
/// converged when `‖dJ/dθ‖ ≤ tolerance` at an accepted iterate. Appends the
/// accepted iterates to `history`.
fn minimise(
    variables: &Variables,
    memory: usize,
    budget: usize,
    tolerance: f64,
    history: &mut History,
) -> Result<Run, UniformityError> {
    let phi0 = variables.start.clone();
    let (j0, g0, _) = variables.evaluate(&phi0)?;
    history.evaluations += 1;
    let g0_norm = norm2(&g0);
    if !(j0.is_finite() && g0_norm.is_finite()) {
        return Err(UniformityError::SolverFailed {
            solver: "gradient",
            status: format!("non-finite objective {j0} or gradient"),
        });
    }
    let q0 = variables.q(&phi0);
    if g0_norm == 0.0 {
        return Ok(Run {
            q: q0,
            termination: Termination::Converged,
            iterations: 0,
            warnings: Vec::new(),
        });
    }
    // argmin sees `scale · J`, scaled so that this run's first step, −∇, has
    // length FIRST_STEP. Its own tests are off (tolerances 0): the gradient
    // test is on `dJ/dθ`, made by the observer.
    let scale = FIRST_STEP / g0_norm;
    let shared = Arc::new(Mutex::new(Shared::default()));
    let cost = Scaled {
        variables,
        scale,
        shared: Arc::clone(&shared),
    };
    let solver = LBFGS::new(MoreThuenteLineSearch::new(), memory)
        .with_tolerance_grad(0.0)
        .and_then(|s| s.with_tolerance_cost(0.0))
        .map_err(|e| UniformityError::SolverFailed {
            solver: "gradient",
            status: format!("L-BFGS settings: {e}"),
        })?;
    let recorder = Recorder {
        shared: Arc::clone(&shared),
        tolerance,
    };
    let result = Executor::new(cost, solver)
        .configure(|state| state.param(phi0.clone()).max_iters(budget as u64))
        .add_observer(recorder, ObserverMode::Always)
        .ctrlc(false)
        .run();
    let shared =
        std::mem::take(
            &mut *shared.lock().map_err(|_| UniformityError::SolverFailed {
                solver: "gradient",
                status: "poisoned lock".into(),
            })?,
        );
    history.evaluations += shared.evaluations;
    for &(j, g) in &shared.records {
        history.objective.push(j / scale);
        history.gradient_norm.push(g);
    }
    let mut warnings = Vec::new();
    let iterations = shared.records.len();
    let (phi, termination) = match result {
        Ok(mut result) => {
            let termination = match result.state.get_termination_status() {
                TerminationStatus::Terminated(TerminationReason::MaxItersReached) => {
                    Termination::MaxIterations
                }
                TerminationStatus::Terminated(TerminationReason::SolverConverged) => {
                    Termination::Converged
                }
                TerminationStatus::Terminated(TerminationReason::SolverExit(text)) => {
                    warnings.push(format!("L-BFGS stopped: {text}"));
                    Termination::Stalled
                }
                TerminationStatus::Terminated(reason) => {
                    warnings.push(format!("L-BFGS stopped: {}", reason.text()));
                    Termination::Stalled
                }
                TerminationStatus::NotTerminated => Termination::Stalled,
            };
            let phi = result
                .state
                .take_best_param()
                .or_else(|| result.state.take_param())
                .unwrap_or(phi0);
            (phi, termination)
        }
        Err(e) => {
            let text = e.to_string();
            let phi = shared.best.map_or(phi0, |(_, p)| p);
            if text == CONVERGED {
                (phi, Termination::Converged)
            } else if text == NO_PROGRESS {
                warnings.push(format!("L-BFGS stopped: {NO_PROGRESS}"));
                (phi, Termination::Stalled)
            } else {
                warnings.push(format!("L-BFGS failed: {text}"));
                (phi, Termination::NumericalError)
            }
        }
    };
    Ok(Run {
        q: variables.q(&phi),
        termination,
        iterations,
        warnings,
    })
}

/// What the cost function and the observer share during one run.
#[derive(Default)]
struct Shared {
    /// The last evaluation (argmin asks for cost and gradient at the same point
    /// separately): `φ`, scaled `J`, scaled `dJ/dφ`, `‖dJ/dθ‖`.
    last: Option<(Vec<f64>, f64, Vec<f64>, f64)>,
    /// The best point seen: scaled `J`, `φ`.
    best: Option<(f64, Vec<f64>)>,
    /// Fresh evaluations.
    evaluations: usize,
    /// Scaled `J` and `‖dJ/dθ‖` of every accepted iterate.
    records: Vec<(f64, f64)>,
}

/// `scale · J` of the solver's variables, as argmin sees it.
struct Scaled<'a, 'v, 'p> {
    variables: &'a Variables<'v, 'p>,
    scale: f64,
    shared: Arc<Mutex<Shared>>,
}

impl Scaled<'_, '_, '_> {
    fn eval(&self, phi: &[f64]) -> Result<(f64, Vec<f64>), ArgminError> {
        if phi.iter().any(|v| !v.is_finite()) {
            // L-BFGS's update degenerates (y = 0) once nothing changes any more.
            return Err(ArgminError::msg(NO_PROGRESS));
        }
        let mut shared = self
            .shared
            .lock()
            .map_err(|_| ArgminError::msg("poisoned lock"))?;
        if let Some((p, j, g, _)) = &shared.last {
            if p.as_slice() == phi {
                return Ok((*j, g.clone()));
            }
        }
        let (j, mut g, theta_norm) = self.variables.evaluate(phi)?;
        shared.evaluations += 1;
        let j = j * self.scale;
        for v in g.iter_mut() {
            *v *= self.scale;
        }
        if !j.is_finite() || g.iter().any(|v| !v.is_finite()) {
            return Err(ArgminError::msg("non-finite objective or gradient"));
        }
        if shared.best.as_ref().is_none_or(|(b, _)| j < *b) {
            shared.best = Some((j, phi.to_vec()));
        }
        shared.last = Some((phi.to_vec(), j, g.clone(), theta_norm));
        Ok((j, g))
    }
}

impl CostFunction for Scaled<'_, '_, '_> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, phi: &Vec<f64>) -> Result<f64, ArgminError> {
        self.eval(phi).map(|(j, _)| j)
    }
}

impl argmin::core::Gradient for Scaled<'_, '_, '_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;

    fn gradient(&self, phi: &Vec<f64>) -> Result<Vec<f64>, ArgminError> {
        self.eval(phi).map(|(_, g)| g)
    }
}

/// Records every accepted iterate and makes the gradient test on `‖dJ/dθ‖`
/// (argmin's own test sees only the solver's variables). The accepted iterate
/// is the last point evaluated: L-BFGS asks for its gradient after the line
/// search.
struct Recorder {
    shared: Arc<Mutex<Shared>>,
    tolerance: f64,
}

type LbfgsState = IterState<Vec<f64>, Vec<f64>, (), (), (), f64>;

impl Observe<LbfgsState> for Recorder {
    fn observe_iter(&mut self, state: &LbfgsState, _kv: &KV) -> Result<(), ArgminError> {
        let mut shared = self
            .shared
            .lock()
            .map_err(|_| ArgminError::msg("poisoned lock"))?;
        let theta_norm = shared.last.as_ref().map_or(f64::NAN, |l| l.3);
        shared.records.push((state.get_cost(), theta_norm));
        if theta_norm <= self.tolerance {
            // Stops the run; `minimise` reads it as convergence.
            return Err(ArgminError::msg(CONVERGED));
        }
        Ok(())
    }
}

/// The uniform-tension guess (`T = t_g` on every set cable at its design
/// length, the network's `q` elsewhere) moved onto equilibrium at the design
/// geometry by damped Gauss–Newton steps `θ ← θ − α W Bᵀ K⁻¹ (A q(θ) − p)`
/// (`B = A diag(dq/dθ)`): the least weighted change in `θ`, positive by
/// construction; then scaled to the first set's level when there are no loads.
fn projected_start(problem: &UniformityProblem, map: &Map) -> Result<Vec<f64>, LinearisationError> {
    let mut q = problem.network().q.clone();
    let lengths = problem.lengths_m();
    for set in problem.sets().iter().rev() {
        for &k in &set.edges {
            q[k] = set.mean_tension_n / lengths[k];
        }
    }
    let mut theta: Vec<f64> = q.iter().map(|&v| map.theta(v)).collect();
    q = theta.iter().map(|&t| map.q(t)).collect();
    let loads = problem.free_loads();
    let slope = |theta: &[f64]| theta.iter().map(|&t| map.dq(t)).collect::<Vec<f64>>();
    let mut linear = Preconditioner::with_weights(problem, q.clone(), &slope(&theta))?;
    let mut residual = linear.residual(&q, &loads);
    for _ in 0..START_STEPS {
        let g = slope(&theta);
        let step = linear.w_bt_times(&g, &linear.k_solve(&residual));
        let mut accepted = None;
        let mut alpha = 1.0;
        for _ in 0..START_HALVINGS {
            let trial: Vec<f64> = theta
                .iter()
                .zip(&step)
                .map(|(t, s)| t - alpha * s)
                .collect();
            let trial_q: Vec<f64> = trial.iter().map(|&t| map.q(t)).collect();
            let trial_residual = linear.residual(&trial_q, &loads);
            if norm2(&trial_residual) < norm2(&residual) {
                accepted = Some((trial, trial_q, trial_residual));
                break;
            }
            alpha *= 0.5;
        }
        let Some((trial, trial_q, trial_residual)) = accepted else {
            break;
        };
        theta = trial;
        q = trial_q;
        residual = trial_residual;
        linear.refactor(&slope(&theta))?;
    }
    // A homogeneous network keeps its equilibrium under q → c q: meet the level.
    if !problem.has_loads() {
        let first = &problem.sets()[0];
        let mean =
            first.edges.iter().map(|&k| q[k] * lengths[k]).sum::<f64>() / first.edges.len() as f64;
        let c = first.mean_tension_n / mean;
        for v in q.iter_mut() {
            *v *= c;
        }
    }
    Ok(q)
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::algebra::dot;
    use crate::geometry::build_mesh;
    use crate::scene::Scene;
    use crate::CableGroup;

    fn small_hex() -> UniformityProblem {
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
    fn pattern(n: usize, seed: usize) -> Vec<f64> {
        (0..n)
            .map(|i| (((i * 7919 + seed * 104_729) % 201) as f64 - 100.0) / 100.0)
            .collect()
    }

    #[test]
    fn map_round_trips_and_stays_in_bounds() {
        let problem = small_hex();
        let map = Map::new(&problem);
        let q_max = problem.max_force_density_n_per_m;
        for q in [1e-3, 0.7, 70.0, 1800.0, 0.98 * q_max] {
            let back = map.q(map.theta(q));
            assert!((back - q).abs() <= 1e-12 * q, "{q} -> {back}");
        }
        for theta in [-800.0, -40.0, 0.0, 40.0, 800.0] {
            let q = map.q(theta);
            assert!(q > 0.0 && q <= q_max, "θ = {theta}: q = {q}");
        }
    }

    #[test]
    fn soft_max_lies_between_mean_and_max() {
        let s = [0.1, 0.5, -0.3, 0.45, 0.2];
        let mut weights = [0.0; 5];
        for beta in [1.0, 10.0, 100.0, 1000.0] {
            let v = soft_max(&s, beta, &mut weights);
            let mean = s.iter().sum::<f64>() / 5.0;
            assert!(v >= mean - 1e-15 && v <= 0.5 + 1e-15, "β = {beta}: {v}");
            assert!((weights.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        }
        let sharp = soft_max(&s, 1e4, &mut weights);
        assert!((sharp - 0.5).abs() < 2.0 * (5f64).ln() / 1e4);
    }

    #[test]
    fn clamp_is_continuously_differentiable_and_bounded() {
        let upper = 40.0;
        let h = 1e-7;
        for t in [-5.0, 0.0, CLAMP_LOW, 1.0, 30.0, 36.0, 50.0] {
            let (c, dc) = clamp(t, upper);
            assert!(c > 0.0 && c < upper, "c({t}) = {c}");
            let fd = (clamp(t + h, upper).0 - clamp(t - h, upper).0) / (2.0 * h);
            assert!((fd - dc).abs() <= 1e-6, "c'({t}) = {dc} vs {fd}");
        }
        assert_eq!(clamp(1.0, upper), (1.0, 1.0));
    }

    #[test]
    fn pull_back_is_the_transpose_of_the_preconditioner() {
        let problem = small_hex();
        let p = Preconditioner::new(&problem, &problem.network().q).unwrap();
        let m = problem.network().n_edges();
        let phi = pattern(p.dim(), 1);
        let g = pattern(m, 2);
        let lhs = dot(&g, &p.delta_linear(&phi));
        let rhs = dot(&p.pull_back(&g), &phi);
        // K's solves are accurate to about ε / SHIFT, its scaled condition.
        let tolerance = f64::EPSILON / SHIFT;
        assert!(
            (lhs - rhs).abs() <= tolerance * lhs.abs().max(rhs.abs()),
            "{lhs} vs {rhs}"
        );
    }

    #[test]
    fn self_stress_directions_keep_the_design_residual() {
        let problem = small_hex();
        let q_ref = &problem.network().q;
        let p = Preconditioner::new(&problem, q_ref).unwrap();
        let m = q_ref.len();
        let mut phi = vec![0.0; p.dim()];
        for (v, w) in phi[..m].iter_mut().zip(pattern(m, 3)) {
            *v = 0.1 * w;
        }
        let loads = problem.free_loads();
        let before = p.residual(q_ref, &loads);
        let after = p.residual(&p.q_exact(&phi), &loads);
        let change = norm2(
            &before
                .iter()
                .zip(&after)
                .map(|(a, b)| a - b)
                .collect::<Vec<_>>(),
        );
        // Without the projection, ψ alone would move it by B ψ.
        let unprojected = norm2(&p.b_times(q_ref, &phi[..m]));
        // The shift of K leaves the near-mechanism modes partly unprojected.
        assert!(
            change <= 1e-3 * unprojected,
            "residual moved by {change:e} of {unprojected:e}"
        );
    }

    #[test]
    fn cached_and_fresh_steps_agree() {
        let problem = small_hex();
        let p = Preconditioner::new(&problem, &problem.network().q).unwrap();
        let a: Vec<f64> = pattern(p.dim(), 4).iter().map(|v| 1e-3 * v).collect();
        let b: Vec<f64> = pattern(p.dim(), 5).iter().map(|v| 1e-3 * v).collect();
        p.delta(&a);
        let cached = p.delta(&b);
        let fresh = p.delta_linear(&b);
        // Both are accurate to about ε / SHIFT (K's scaled condition) of Δ.
        let size = fresh.iter().map(|v| v.abs()).fold(0.0, f64::max);
        let tolerance = 10.0 * f64::EPSILON / SHIFT * size;
        for (c, f) in cached.iter().zip(&fresh) {
            assert!((c - f).abs() <= tolerance, "{c} vs {f}");
        }
    }

    #[test]
    fn projected_start_is_in_equilibrium_at_the_level() {
        let problem = small_hex();
        let q = projected_start(&problem, &Map::new(&problem)).unwrap();
        assert!(q.iter().all(|&v| v > 0.0));
        let max_force = problem
            .lengths_m()
            .iter()
            .zip(&q)
            .map(|(l, q)| l * q)
            .fold(0.0, f64::max);
        assert!(problem.prescribed_residual_n(&q) <= 1e-9 * max_force);
        let set = &problem.sets()[0];
        let mean = set
            .edges
            .iter()
            .map(|&k| q[k] * problem.lengths_m()[k])
            .sum::<f64>()
            / set.edges.len() as f64;
        assert!((mean / set.mean_tension_n - 1.0).abs() < 1e-12);
    }

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
