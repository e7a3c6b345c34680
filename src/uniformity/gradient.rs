//! Free-geometry gradient solver (placeholder until implemented).

use super::{Design, UniformityError, UniformityProblem, UniformitySolver};

/// Adjoint-gradient L-BFGS on the free geometry.
#[derive(Debug, Clone)]
pub struct Gradient {
    /// Weight of the ratio surrogate against the surface error.
    pub weight: f64,
}

impl Default for Gradient {
    fn default() -> Self {
        Gradient { weight: 1e-3 }
    }
}

impl UniformitySolver for Gradient {
    fn name(&self) -> &'static str {
        "gradient"
    }

    fn knob(&self) -> Option<f64> {
        Some(self.weight)
    }

    fn solve(&self, _problem: &UniformityProblem) -> Result<Design, UniformityError> {
        Err(UniformityError::Unsupported {
            solver: "gradient",
            reason: "not implemented yet".into(),
        })
    }
}
