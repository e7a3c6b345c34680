//! The record of one gradient solve ([`History`]): what L-BFGS (`lbfgs.rs`)
//! and the exact finish add to as they go, and what
//! [`super::Gradient::solve_with_history`] returns beside the design.

/// Objective value and gradient norm of every accepted iterate.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct History {
    /// The stationarity `‖dJ/dθ‖∞ / J` at the end (the convergence test).
    pub stationarity: f64,
    /// `J` at the start and after every iteration (each run at its own
    /// sharpness, the start at the final one).
    pub objective: Vec<f64>,
    /// `‖dJ/dθ‖` at the same points.
    pub gradient_norm: Vec<f64>,
    /// Evaluations of `J` and its gradient (forward + adjoint solves).
    pub evaluations: usize,
    /// L-BFGS runs (the preconditioner is re-linearised for each).
    pub runs: usize,
    /// Quadratic programs of the exact finish (0 without it), one a step.
    pub finish_steps: usize,
    /// Programs the finish solved again as second-order corrections.
    pub finish_corrections: usize,
    /// Interior-point iterations of all programs, corrections included.
    pub finish_interior_iterations: usize,
    /// With the exact finish, `J` with the exact `ln(Tmax/Tmin)` at the end.
    pub exact_objective: Option<f64>,
}
