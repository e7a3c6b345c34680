//! The paper's relaxation rule as written (paper §4): the full step
//! `x_{k+1} = G(x_k)` while `ξ` decreases, else the half step
//! `x_k + (G(x_k) − x_k)/2`.

use super::{relaxed_step, Relaxation, Step};

/// The paper's step rule: the full step (1) at the first iteration and
/// whenever `ξ` decreased, else the half step (½).
pub fn paper_step(xi: f64, previous_xi: Option<f64>) -> f64 {
    match previous_xi {
        Some(previous) if xi >= previous => 0.5,
        _ => 1.0,
    }
}

/// The paper's policy; its state is the last `ξ`.
#[derive(Debug, Clone, Default)]
pub struct Paper {
    previous_xi: Option<f64>,
}

impl Relaxation for Paper {
    fn name(&self) -> &str {
        "paper"
    }

    fn next(&mut self, x: &[f64], _image: &[f64], residual: &[f64], xi: f64) -> Step {
        let factor = paper_step(xi, self.previous_xi.replace(xi));
        Step {
            x: relaxed_step(x, residual, factor),
            factor,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_rule_takes_the_full_step_while_xi_decreases() {
        assert_eq!(paper_step(3.0, None), 1.0);
        assert_eq!(paper_step(2.0, Some(3.0)), 1.0);
        assert_eq!(paper_step(3.0, Some(3.0)), 0.5);
        assert_eq!(paper_step(4.0, Some(3.0)), 0.5);
    }

    #[test]
    fn paper_policy_halves_the_step_after_an_increase() {
        let mut p = Paper::default();
        assert_eq!(p.next(&[0.0], &[2.0], &[2.0], 2.0).factor, 1.0);
        let step = p.next(&[2.0], &[5.0], &[3.0], 3.0);
        assert_eq!((step.factor, step.x[0]), (0.5, 3.5));
    }
}
