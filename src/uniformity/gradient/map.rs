//! The map `θ ↦ q` of the unpreconditioned variables onto the box of force
//! densities (see the module documentation of [`super`]).

use super::super::UniformityProblem;

/// Lower asymptote of the map, as a fraction of the problem's typical force
/// density (or of `[q]`, if lower): `D` stays numerically positive definite,
/// and no design's `q` is cut off however far the bound is lifted.
const FLOOR_FRACTION: f64 = 1e-9;

/// The smooth bijection `θ ↦ q = q_0 + ([q] − q_0) σ(θ)` onto `(q_0, [q])`, or
/// `θ ↦ e^θ` onto `(0, ∞)` when there is no bound.
#[derive(Debug, Clone, Copy)]
pub(super) enum Map {
    /// `q = q_0 + ([q] − q_0) σ(θ)` for a finite bound `[q]`.
    Bounded { floor: f64, span: f64 },
    /// `q = e^θ` when there is no bound.
    Log,
}

impl Map {
    pub(super) fn new(problem: &UniformityProblem) -> Self {
        let q_max = problem.max_force_density_n_per_m;
        if q_max.is_finite() {
            let set = &problem.sets()[0];
            let lengths = problem.lengths_m();
            let mean_length =
                set.edges.iter().map(|&k| lengths[k]).sum::<f64>() / set.edges.len() as f64;
            let typical = set.mean_tension_n / mean_length;
            let floor = FLOOR_FRACTION * q_max.min(typical);
            Map::Bounded {
                floor,
                span: q_max - floor,
            }
        } else {
            Map::Log
        }
    }

    /// The smallest `q` the map reaches, `q_0` (or the smallest positive float).
    pub(super) fn floor(&self) -> f64 {
        match *self {
            Map::Bounded { floor, .. } => floor,
            Map::Log => f64::MIN_POSITIVE,
        }
    }

    /// `q(θ)`.
    pub(super) fn q(&self, theta: f64) -> f64 {
        match *self {
            Map::Bounded { floor, span } => floor + span * sigmoid(theta),
            Map::Log => theta.exp(),
        }
    }

    /// `dq/dθ`: `([q] − q_0) σ (1 − σ)`, or `e^θ`.
    pub(super) fn dq(&self, theta: f64) -> f64 {
        match *self {
            Map::Bounded { span, .. } => {
                let s = sigmoid(theta);
                span * s * (1.0 - s)
            }
            Map::Log => theta.exp(),
        }
    }

    /// `θ(q)`, with `q` clamped a hair inside `(q_0, [q])` (or above 0).
    pub(super) fn theta(&self, q: f64) -> f64 {
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
pub(super) fn sigmoid(theta: f64) -> f64 {
    if theta >= 0.0 {
        1.0 / (1.0 + (-theta).exp())
    } else {
        let e = theta.exp();
        e / (1.0 + e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uniformity::gradient::fixtures::small_hex;

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
}
