//! Aitken's dynamic relaxation: `x_{k+1} = x_k + ω_k r_k` with
//! `ω_k = −ω_{k−1} r_{k−1}ᵀ(r_k − r_{k−1}) / ‖r_k − r_{k−1}‖²`.

use super::{relaxed_step, Relaxation, Step};

/// Aitken's factor `ω_k = −ω_{k−1} r_{k−1}ᵀ(r_k − r_{k−1}) / ‖r_k − r_{k−1}‖²`,
/// kept in `[0.05, 20]` (1 when the residual did not change).
pub fn aitken_factor(omega: f64, previous_r: &[f64], r: &[f64]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (p, c) in previous_r.iter().zip(r) {
        let d = c - p;
        num += p * d;
        den += d * d;
    }
    if den > 0.0 && (num / den).is_finite() {
        (-omega * num / den).clamp(0.05, 20.0)
    } else {
        1.0
    }
}

/// Aitken's policy; its state is the last factor and residual.
#[derive(Debug, Clone)]
pub struct Aitken {
    omega: f64,
    previous_residual: Option<Vec<f64>>,
}

impl Default for Aitken {
    /// The first step is the full step.
    fn default() -> Self {
        Aitken {
            omega: 1.0,
            previous_residual: None,
        }
    }
}

impl Relaxation for Aitken {
    fn name(&self) -> &str {
        "aitken"
    }

    fn next(&mut self, x: &[f64], _image: &[f64], residual: &[f64], _xi: f64) -> Step {
        if let Some(previous) = &self.previous_residual {
            self.omega = aitken_factor(self.omega, previous, residual);
        }
        self.previous_residual = Some(residual.to_vec());
        Step {
            x: relaxed_step(x, residual, self.omega),
            factor: self.omega,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a linear map `G(x) = a x + b` the Aitken factor is the exact
    /// relaxation `1/(1 − a)` that lands on the fixed point.
    #[test]
    fn aitken_factor_is_exact_on_a_scalar_linear_map() {
        let (a, b) = (-0.8, 1.0);
        let g = |x: f64| a * x + b;
        let (x0, x1) = (0.0, 0.3);
        let (r0, r1) = (g(x0) - x0, g(x1) - x1);
        // With ω₀ = (x1 − x0)/r0 the update x1 = x0 + ω₀ r0 holds.
        let omega0 = (x1 - x0) / r0;
        let omega = aitken_factor(omega0, &[r0], &[r1]);
        let x2 = x1 + omega * r1;
        assert!((x2 - b / (1.0 - a)).abs() < 1e-14, "{x2}");
    }
}
