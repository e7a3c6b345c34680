//! Quadrature over a triangle: the collapsed (Duffy) product of two
//! Gauss–Legendre rules, exact for polynomials up to a stated degree.
//!
//! The map `(s, t) ∈ [0, 1]² ↦ (u, v) = (s, (1 − s) t)` takes the square onto
//! the reference triangle with Jacobian `1 − s`. A polynomial of degree `d` in
//! `(u, v)` becomes one of degree `d + 1` in `s` and `d` in `t`; an `n`-point
//! Gauss–Legendre rule is exact to degree `2n − 1`, so the `n × n` product is
//! exact for every polynomial of degree `d ≤ 2n − 2` on the triangle
//! (Stroud, *Approximate calculation of multiple integrals*, 1971, §2.7).

/// A rule for the mean of a function over a triangle: points in barycentric
/// coordinates `(λ₀, λ₁, λ₂)`, weights summing to 1.
#[derive(Debug, Clone)]
pub(crate) struct TriangleRule {
    /// (barycentric coordinates, weight): n².
    pub(crate) points: Vec<([f64; 3], f64)>,
}

impl TriangleRule {
    /// The collapsed product of `n`-point Gauss–Legendre rules: `n²` points,
    /// exact to degree `2n − 2`.
    ///
    /// # Panics
    /// If `n` is 0.
    #[track_caller]
    pub(crate) fn collapsed_gauss(n: usize) -> TriangleRule {
        assert!(n > 0, "a rule needs at least one point");
        let line = gauss_legendre_unit(n);
        let mut points = Vec::with_capacity(n * n);
        for &(s, ws) in &line {
            for &(t, wt) in &line {
                let (u, v) = (s, (1.0 - s) * t);
                // The reference triangle has area 1/2: the mean is twice the integral.
                points.push(([1.0 - u - v, u, v], 2.0 * ws * wt * (1.0 - s)));
            }
        }
        TriangleRule { points }
    }

    /// Highest polynomial degree the rule integrates exactly.
    #[cfg(test)]
    pub(crate) fn degree(&self) -> usize {
        2 * (self.points.len() as f64).sqrt().round() as usize - 2
    }
}

/// Gauss–Legendre rule on [0, 1]: n (node, weight) pairs, weights summing to 1.
fn gauss_legendre_unit(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            // Newton on P_n from the asymptotic estimate of its i-th root.
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            for _ in 0..100 {
                let (p, dp) = legendre(n, x);
                let dx = p / dp;
                x -= dx;
                if dx.abs() <= 4.0 * f64::EPSILON {
                    break;
                }
            }
            let (_, dp) = legendre(n, x);
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            (0.5 * (1.0 - x), 0.5 * w)
        })
        .collect()
}

/// `(P_n(x), P_n'(x))` by the three-term recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    if n == 0 {
        return (1.0, 0.0);
    }
    for k in 2..=n {
        let k = k as f64;
        let p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
    }
    (p1, n as f64 * (x * p1 - p0) / (x * x - 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mean of `u^a v^b` over the reference triangle: `2 a! b! / (a + b + 2)!`.
    fn monomial_mean(a: usize, b: usize) -> f64 {
        let fact = |k: usize| (1..=k).map(|i| i as f64).product::<f64>();
        2.0 * fact(a) * fact(b) / fact(a + b + 2)
    }

    #[test]
    fn collapsed_gauss_is_exact_to_its_degree_and_not_beyond() {
        for n in 1..=7 {
            let rule = TriangleRule::collapsed_gauss(n);
            assert_eq!(rule.degree(), 2 * n - 2);
            let mean = |a: i32, b: i32| -> f64 {
                rule.points
                    .iter()
                    .map(|(l, w)| w * l[1].powi(a) * l[2].powi(b))
                    .sum()
            };
            for d in 0..=rule.degree() {
                for a in 0..=d {
                    let (got, exact) = (mean(a as i32, (d - a) as i32), monomial_mean(a, d - a));
                    assert!(
                        (got - exact).abs() <= 1e-14 * exact.max(1e-3),
                        "n {n}, u^{a} v^{}: {got} vs {exact}",
                        d - a
                    );
                }
            }
            // One degree more: u^(d+1) is integrated wrongly (the rule is no better
            // than stated, so the claim above is the rule's, not luck's).
            let d = rule.degree() + 1;
            let (got, exact) = (mean(d as i32, 0), monomial_mean(d, 0));
            assert!(
                (got - exact).abs() > 1e-9 * exact,
                "n {n}: {got} vs {exact}"
            );
        }
    }
}
