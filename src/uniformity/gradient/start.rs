//! The start point: the uniform-tension guess moved onto equilibrium at the
//! design geometry.

use super::map::Map;
use super::preconditioner::{LinearisationError, Preconditioner};
use crate::algebra::norm2;
use crate::uniformity::{Lp, Termination, UniformityProblem, UniformitySolver};

/// Most damped Gauss–Newton steps of the projected start.
const START_STEPS: usize = 20;
/// Most step halvings of one of them.
const START_HALVINGS: usize = 12;

/// The uniform-tension guess (`T = t_g` on every set cable at its design
/// length, the network's `q` elsewhere) moved onto equilibrium at the design
/// geometry by damped Gauss–Newton steps `θ ← θ − α W Bᵀ K⁻¹ (A q(θ) − p)`
/// (`B = A diag(dq/dθ)`): the least weighted change in `θ`, positive by
/// construction; then scaled to the first set's level when there are no loads.
pub(super) fn projected_start(
    problem: &UniformityProblem,
    map: &Map,
) -> Result<Vec<f64>, LinearisationError> {
    let mut q = problem.network().q.clone();
    let lengths = problem.lengths_m();
    for set in problem.sets().iter().rev() {
        for &k in &set.edges {
            q[k] = set.mean_tension_n / lengths[k];
        }
    }
    let mut theta: Vec<f64> = q.iter().map(|&v| map.theta(v)).collect();
    q = theta.iter().map(|&t| map.q(t)).collect();
    let loads = problem.free_loads();
    let slope = |theta: &[f64]| theta.iter().map(|&t| map.dq(t)).collect::<Vec<f64>>();
    let mut linear = Preconditioner::with_weights(problem, q.clone(), &slope(&theta))?;
    let mut residual = linear.residual(&q, &loads);
    for _ in 0..START_STEPS {
        let g = slope(&theta);
        let step = linear.w_bt_times(&g, &linear.k_solve(&residual));
        let mut accepted = None;
        let mut alpha = 1.0;
        for _ in 0..START_HALVINGS {
            let trial: Vec<f64> = theta
                .iter()
                .zip(&step)
                .map(|(t, s)| t - alpha * s)
                .collect();
            let trial_q: Vec<f64> = trial.iter().map(|&t| map.q(t)).collect();
            let trial_residual = linear.residual(&trial_q, &loads);
            if norm2(&trial_residual) < norm2(&residual) {
                accepted = Some((trial, trial_q, trial_residual));
                break;
            }
            alpha *= 0.5;
        }
        let Some((trial, trial_q, trial_residual)) = accepted else {
            break;
        };
        theta = trial;
        q = trial_q;
        residual = trial_residual;
        linear.refactor(&slope(&theta))?;
    }
    // A homogeneous network keeps its equilibrium under q → c q: meet the level.
    if !problem.has_loads() {
        let first = &problem.sets()[0];
        let mean =
            first.edges.iter().map(|&k| q[k] * lengths[k]).sum::<f64>() / first.edges.len() as f64;
        let c = first.mean_tension_n / mean;
        for v in q.iter_mut() {
            *v *= c;
        }
    }
    Ok(q)
}

/// The fixed-geometry optimum (`lp`'s design, a few ms even on 10⁴ nodes)
/// where `lp` applies — one set, no loads — and converges with every `q`
/// positive: the end of the front where the geometry is held, from which
/// the free-geometry minimiser is a short way off.
pub(super) fn optimum_start(problem: &UniformityProblem) -> Option<Vec<f64>> {
    if problem.sets().len() != 1 || problem.has_loads() {
        return None;
    }
    let design = Lp.solve(problem).ok()?;
    (design.termination == Termination::Converged && design.q.iter().all(|&q| q > 0.0))
        .then_some(design.q)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uniformity::gradient::fixtures::small_hex;

    #[test]
    fn projected_start_is_in_equilibrium_at_the_level() {
        let problem = small_hex();
        let q = projected_start(&problem, &Map::new(&problem)).unwrap();
        assert!(q.iter().all(|&v| v > 0.0));
        let max_force = problem
            .lengths_m()
            .iter()
            .zip(&q)
            .map(|(l, q)| l * q)
            .fold(0.0, f64::max);
        assert!(problem.prescribed_residual_n(&q) <= 1e-9 * max_force);
        let set = &problem.sets()[0];
        let mean = set
            .edges
            .iter()
            .map(|&k| q[k] * problem.lengths_m()[k])
            .sum::<f64>()
            / set.edges.len() as f64;
        assert!((mean / set.mean_tension_n - 1.0).abs() < 1e-12);
    }
}
