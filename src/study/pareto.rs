//! Pareto optimality of (cost, error) pairs: the points no other point beats
//! in both.

/// For each `(cost, error)`, whether it is Pareto-optimal among `points`: no
/// other point has a cost and an error both at most its own, one of them
/// smaller. Points with a non-finite coordinate are never optimal and never
/// dominate. Equal points are all optimal.
pub fn pareto_optimal(points: &[(f64, f64)]) -> Vec<bool> {
    let finite = |p: &(f64, f64)| p.0.is_finite() && p.1.is_finite();
    points
        .iter()
        .map(|p| {
            finite(p)
                && !points
                    .iter()
                    .any(|q| finite(q) && q.0 <= p.0 && q.1 <= p.1 && (q.0 < p.0 || q.1 < p.1))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dominated_and_non_finite_points_are_not_optimal() {
        let points = [
            (1.0, 5.0),      // optimal: cheapest
            (2.0, 3.0),      // optimal
            (2.0, 4.0),      // dominated by (2, 3)
            (3.0, 3.0),      // dominated by (2, 3)
            (4.0, 1.0),      // optimal: most accurate
            (f64::NAN, 0.0), // not finite
            (0.5, f64::NAN), // not finite
            (2.0, 3.0),      // equal to an optimal point
        ];
        assert_eq!(
            pareto_optimal(&points),
            vec![true, true, false, false, true, false, false, true]
        );
        assert!(pareto_optimal(&[]).is_empty());
    }
}
