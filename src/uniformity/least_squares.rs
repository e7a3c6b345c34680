//! Least-squares solvers (placeholder until implemented).

use super::{Design, UniformityError, UniformityProblem, UniformitySolver};

/// `min ‖L q − T̄‖²` s.t. `A q = p`, or the Tikhonov family with `lambda`.
#[derive(Debug, Clone, Default)]
pub struct LeastSquares {
    /// Tikhonov weight λ; `None` for the equality-constrained problem.
    pub lambda: Option<f64>,
}

impl UniformitySolver for LeastSquares {
    fn name(&self) -> &'static str {
        "least-squares"
    }

    fn knob(&self) -> Option<f64> {
        self.lambda
    }

    fn solve(&self, _problem: &UniformityProblem) -> Result<Design, UniformityError> {
        Err(UniformityError::Unsupported {
            solver: "least-squares",
            reason: "not implemented yet".into(),
        })
    }
}
