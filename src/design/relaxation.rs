//! Relaxation policies of the outer loop (DESIGN §6): how the next iterate is
//! chosen from the last ones.
//!
//! * `paper` — the paper's rule as written: the full step `x_{k+1} = G(x_k)`
//!   while `ξ` decreases, else the half step `x_k + (G(x_k) − x_k)/2`;
//! * `aitken` — Aitken's dynamic relaxation `x_{k+1} = x_k + ω_k r_k`,
//!   `ω_k = −ω_{k−1} r_{k−1}ᵀ(r_k − r_{k−1}) / ‖r_k − r_{k−1}‖²`;
//! * `anderson` — Anderson mixing of depth m (type II, Walker–Ni 2011):
//!   `x_{k+1} = G(x_k) − ΔG γ`, `γ = argmin ‖r_k − ΔR γ‖₂` over the last m
//!   differences of residuals `ΔR` and of images `ΔG`.

use std::collections::VecDeque;

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// How the next boundary is chosen from the last ones.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Relaxation {
    /// The paper's rule: full step while ξ decreases, else the half step.
    Paper,
    /// Aitken's dynamic scalar relaxation.
    Aitken,
    /// Anderson mixing (depth [`LoopSettings::anderson_depth`]).
    #[default]
    Anderson,
}

impl Relaxation {
    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Relaxation::Paper => "paper",
            Relaxation::Aitken => "aitken",
            Relaxation::Anderson => "anderson",
        }
    }
}

/// The paper's step rule: the full step (1) at the first iteration and
/// whenever `ξ` decreased, else the half step (½).
pub fn paper_step(xi: f64, previous_xi: Option<f64>) -> f64 {
    match previous_xi {
        Some(previous) if xi >= previous => 0.5,
        _ => 1.0,
    }
}

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

/// Anderson mixing state: the last differences of residuals and images.
pub(crate) struct Anderson {
    depth: usize,
    previous: Option<(Vec<f64>, Vec<f64>)>,
    delta_r: VecDeque<Vec<f64>>,
    delta_g: VecDeque<Vec<f64>>,
}

impl Anderson {
    pub(crate) fn new(depth: usize) -> Self {
        Anderson {
            depth,
            previous: None,
            delta_r: VecDeque::new(),
            delta_g: VecDeque::new(),
        }
    }

    /// The next iterate from the image `g = G(x)` and residual `r = g − x`.
    pub(crate) fn next(&mut self, g: &[f64], r: &[f64]) -> Vec<f64> {
        if let Some((pg, pr)) = self.previous.take() {
            self.delta_g
                .push_back(g.iter().zip(&pg).map(|(a, b)| a - b).collect());
            self.delta_r
                .push_back(r.iter().zip(&pr).map(|(a, b)| a - b).collect());
            if self.delta_r.len() > self.depth {
                self.delta_r.pop_front();
                self.delta_g.pop_front();
            }
        }
        self.previous = Some((g.to_vec(), r.to_vec()));
        let m = self.delta_r.len();
        if m == 0 {
            return g.to_vec();
        }
        let n = r.len();
        let dr = DMatrix::from_fn(n, m, |i, j| self.delta_r[j][i]);
        let rhs = DVector::from_column_slice(r);
        // γ = argmin ‖r − ΔR γ‖₂, by SVD with a relative cut of tiny singular
        // values (nearly dependent differences near convergence).
        let svd = dr.svd(true, true);
        let cut = 1e-12 * svd.singular_values.max();
        let Ok(gamma) = svd.solve(&rhs, cut) else {
            return g.to_vec();
        };
        (0..n)
            .map(|i| g[i] - (0..m).map(|j| self.delta_g[j][i] * gamma[j]).sum::<f64>())
            .collect()
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

    /// Anderson mixing solves a linear fixed point in n + 1 iterations.
    #[test]
    fn anderson_solves_a_linear_map_in_few_steps() {
        let a = DMatrix::from_row_slice(3, 3, &[0.5, 0.2, 0.0, -0.3, 0.4, 0.1, 0.0, 0.2, -0.6]);
        let b = DVector::from_column_slice(&[1.0, -2.0, 0.5]);
        let exact = (DMatrix::identity(3, 3) - &a).lu().solve(&b).unwrap();
        let mut x = DVector::zeros(3);
        let mut anderson = Anderson::new(5);
        for _ in 0..5 {
            let g = &a * &x + &b;
            let r = &g - &x;
            x = DVector::from_vec(anderson.next(g.as_slice(), r.as_slice()));
        }
        assert!((x - exact).amax() < 1e-12);
    }
}
