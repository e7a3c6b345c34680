//! Anderson mixing of depth m (type II, Walker–Ni 2011):
//! `x_{k+1} = G(x_k) − ΔG γ`, `γ = argmin ‖r_k − ΔR γ‖₂` over the last m
//! differences of residuals `ΔR` and of images `ΔG`.

use std::collections::VecDeque;

use nalgebra::{DMatrix, DVector};

use super::{Relaxation, Step};

/// Anderson mixing; its state is the last differences of residuals and images.
#[derive(Debug, Clone)]
pub struct Anderson {
    depth: usize,
    previous: Option<(Vec<f64>, Vec<f64>)>,
    delta_r: VecDeque<Vec<f64>>,
    delta_g: VecDeque<Vec<f64>>,
}

impl Anderson {
    /// Mixing that keeps the last `depth` differences.
    pub fn new(depth: usize) -> Self {
        Anderson {
            depth,
            previous: None,
            delta_r: VecDeque::new(),
            delta_g: VecDeque::new(),
        }
    }

    /// The next iterate from the image `g = G(x)` and residual `r = g − x`.
    fn mix(&mut self, g: &[f64], r: &[f64]) -> Vec<f64> {
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

impl Relaxation for Anderson {
    fn name(&self) -> &str {
        "anderson"
    }

    fn next(&mut self, _x: &[f64], image: &[f64], residual: &[f64], _xi: f64) -> Step {
        Step {
            x: self.mix(image, residual),
            factor: 1.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
            x = DVector::from_vec(anderson.mix(g.as_slice(), r.as_slice()));
        }
        assert!((x - exact).amax() < 1e-12);
    }
}
