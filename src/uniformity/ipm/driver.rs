//! The driver: the Mehrotra predictor–corrector iteration of any
//! [`NewtonSystem`] from its starting point to a converged, stalled or
//! failed end — centring, Gondzio's centrality correctors, the step to the
//! boundary, the stopping tests and the choice of the best iterate.

use super::settings::{IpmSettings, StepLength};
use super::system::{Measures, NewtonSystem, Point, Rhs};
use crate::status::Termination;

/// How the iteration ended.
#[derive(Debug)]
pub(crate) struct Outcome<E> {
    /// The best iterate when it was accepted (converged or stalled at
    /// reduced accuracy), else the last one; `None` when there was no
    /// starting point.
    pub point: Option<Point>,
    /// Iterations.
    pub iterations: usize,
    /// How the iteration stopped:
    /// * `Converged`: residuals and gap below their tolerances;
    /// * `Stalled`: the iterate stopped improving with residuals and gap
    ///   below the reduced tolerances (clarabel's `AlmostSolved`): its best
    ///   iterate, usable at reduced accuracy;
    /// * `MaxIterations`: the iteration limit came first;
    /// * `NumericalError`: a factorisation or solve failed, or the iterate
    ///   stopped being finite.
    pub termination: Termination,
    /// The measures of `point`.
    pub measures: Measures,
    /// The failure behind a `NumericalError`, when the system reported one.
    pub error: Option<E>,
    /// The last iterate whose gap was at least
    /// [`IpmSettings::keep_at_gap`]: near the central path at that gap (not
    /// closer to the optimal face, from which a neighbouring problem's
    /// iterates could not follow their own path), the start of a
    /// neighbouring problem.
    pub kept: Option<Point>,
}

/// The best iterate so far, by its largest measure relative to its
/// tolerance.
struct Best {
    score: f64,
    point: Point,
    iteration: usize,
    measures: Measures,
}

/// `Σ_i f(i)` over the pairs, block by block (`ends` from
/// [`NewtonSystem::pair_blocks`]).
fn pair_sum(ends: &[usize], f: impl Fn(usize) -> f64) -> f64 {
    let mut start = 0;
    let mut sum = 0.0;
    for (b, &end) in ends.iter().enumerate() {
        let block: f64 = (start..end).map(&f).sum();
        sum = if b == 0 { block } else { sum + block };
        start = end;
    }
    sum
}

/// Largest step in `[0, cap]` keeping `v + α dv ≥ 0`.
fn step_to_boundary(v: &[f64], dv: &[f64], cap: f64) -> f64 {
    v.iter()
        .zip(dv)
        .filter(|(_, &d)| d < 0.0)
        .fold(cap, |alpha, (&v, &d)| alpha.min(-v / d))
}

/// Runs the interior-point method on `system` with `settings` (checked by
/// the caller).
pub(crate) fn run<S: NewtonSystem>(system: &mut S, settings: &IpmSettings) -> Outcome<S::Error> {
    let mut point = match system.start() {
        Ok(point) => point,
        Err(error) => {
            return Outcome {
                point: None,
                iterations: 0,
                termination: Termination::NumericalError,
                measures: Measures::NAN,
                error: Some(error),
                kept: None,
            }
        }
    };
    let ends = system.pair_blocks();
    let n_pairs = ends.last().copied().unwrap_or(0);
    let n_compl = n_pairs as f64;
    let cap = match settings.step_length {
        StepLength::Adaptive => 1.0,
        StepLength::Fixed(fraction) => 1.0 / fraction,
    };
    // The primal and dual steps to the boundary along `d` (equal when the
    // steps are common).
    let steps = |point: &Point, d: &Point| {
        let primal = step_to_boundary(&point.primal, &d.primal, cap);
        let dual = step_to_boundary(&point.dual, &d.dual, cap);
        if settings.separate_steps {
            (primal, dual)
        } else {
            (primal.min(dual), primal.min(dual))
        }
    };
    let (pt, dt, gt) = (
        settings.primal_tolerance,
        settings.dual_tolerance,
        settings.gap_tolerance,
    );

    // Within the reduced tolerances.
    let reduced = |m: &Measures| {
        m.primal.max(m.dual) <= settings.reduced_tolerance
            && m.gap <= settings.reduced_gap_tolerance
    };
    let mut measures = Measures::NAN;
    let mut best: Option<Best> = None;
    let mut failed = false;
    let mut error = None;
    let mut iterations = 0;
    let mut kept = None;
    for iteration in 0..=settings.max_iterations {
        iterations = iteration;
        measures = system.residuals(&point);
        if !measures.is_finite() {
            failed = true;
            break;
        }
        if settings.keep_at_gap.is_some_and(|g| measures.gap >= g) {
            kept = Some(point.clone());
        }
        let converged = measures.primal <= pt && measures.dual <= dt && measures.gap <= gt;
        let score = (measures.primal / pt)
            .max(measures.dual / dt)
            .max(measures.gap / gt);
        // An iterate that could be accepted beats any that could not (the
        // order must agree with the acceptance below, or a best iterate
        // outside the reduced tolerances holds its place against every
        // acceptable one to the iteration limit); then one within the
        // primal tolerance beats any outside it.
        let key = (!reduced(&measures), measures.primal > pt, score);
        let better = |b: &Best| key < (!reduced(&b.measures), b.measures.primal > pt, b.score);
        if converged || best.as_ref().is_none_or(better) {
            best = Some(Best {
                score,
                point: point.clone(),
                iteration,
                measures,
            });
        }
        // Stalled: the best iterate is usable at reduced accuracy and has
        // not been bettered for `stall_iterations`. (An infeasible start can
        // raise the gap for longer than that while its residuals fall: the
        // finish's programs from a step-free point do.)
        let stalled = best.as_ref().is_some_and(|b| {
            reduced(&b.measures) && iteration >= b.iteration + settings.stall_iterations
        });
        if converged || stalled || iteration == settings.max_iterations {
            break;
        }
        let (v, u) = (&point.primal, &point.dual);
        let mu = pair_sum(&ends, |i| v[i] * u[i]) / n_compl;
        if let Err(e) = system.factor(&point) {
            (failed, error) = (true, Some(e));
            break;
        }

        // Predictor.
        let r: Vec<f64> = v.iter().zip(u).map(|(a, b)| -a * b).collect();
        let affine = match system.direction(&point, &r, Rhs::Predictor) {
            Ok(d) => d,
            Err(e) => {
                (failed, error) = (true, Some(e));
                break;
            }
        };
        let (ap, ad) = steps(&point, &affine);
        let (dv, du) = (&affine.primal, &affine.dual);
        let mu_aff = pair_sum(&ends, |i| (v[i] + ap * dv[i]) * (u[i] + ad * du[i])) / n_compl;
        let sigma = (mu_aff / mu).powi(3).clamp(settings.min_centring, 1.0);

        // Corrector.
        let r: Vec<f64> = (0..n_pairs)
            .map(|i| sigma * mu - v[i] * u[i] - dv[i] * du[i])
            .collect();
        let mut d = match system.direction(&point, &r, Rhs::Corrector) {
            Ok(d) => d,
            Err(e) => {
                (failed, error) = (true, Some(e));
                break;
            }
        };
        // Gondzio's multiple centrality correctors: aim a longer step at
        // a point whose complementarity products lie within
        // [β_min, β_max]·σμ, keep the correction while it lengthens the step.
        let (mut bp, mut bd) = steps(&point, &d);
        for _ in 0..settings.centrality_correctors {
            if bp.min(bd) >= 1.0 {
                break;
            }
            let tp = (1.5 * bp + 0.1).min(1.0);
            let td = (1.5 * bd + 0.1).min(1.0);
            let target = sigma * mu;
            let (lo, hi) = (0.1 * target, 10.0 * target);
            let push = |v: f64| {
                if v < lo {
                    lo - v
                } else if v > hi {
                    (hi - v).max(-hi)
                } else {
                    0.0
                }
            };
            let r: Vec<f64> = (0..n_pairs)
                .map(|i| push((v[i] + tp * d.primal[i]) * (u[i] + td * d.dual[i])))
                .collect();
            let Ok(c) = system.direction(&point, &r, Rhs::Centrality) else {
                break;
            };
            let mut trial = d.clone();
            trial.add_scaled(1.0, &c);
            let (np, nd) = steps(&point, &trial);
            if np.min(nd) < 1.01 * bp.min(bd) {
                break;
            }
            d = trial;
            (bp, bd) = (np, nd);
        }
        let fraction = match settings.step_length {
            StepLength::Adaptive => (1.0 - mu.min(0.1)).clamp(0.9, 0.99995),
            StepLength::Fixed(fraction) => fraction,
        };
        let ap = (fraction * bp).min(1.0);
        let ad = (fraction * bd).min(1.0);
        if !(ap.is_finite() && ad.is_finite() && d.is_finite()) {
            failed = true;
            break;
        }
        let add = |x: &mut [f64], dx: &[f64], alpha: f64| {
            x.iter_mut().zip(dx).for_each(|(x, d)| *x += alpha * d);
        };
        add(&mut point.primal, &d.primal, ap);
        add(&mut point.dual, &d.dual, ad);
        add(&mut point.free_primal, &d.free_primal, ap);
        add(&mut point.free_dual, &d.free_dual, ad);
    }
    // The best iterate: converged, or accepted at reduced accuracy.
    let accepted = best.filter(|b| reduced(&b.measures));
    match accepted {
        Some(best) => Outcome {
            point: Some(best.point),
            iterations,
            termination: if best.score <= 1.0 {
                Termination::Converged
            } else {
                Termination::Stalled
            },
            measures: best.measures,
            error,
            kept,
        },
        None => Outcome {
            point: Some(point),
            iterations,
            termination: if failed {
                Termination::NumericalError
            } else {
                Termination::MaxIterations
            },
            measures,
            error,
            kept,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A system whose iterates measure as scripted (the last one repeated),
    /// with zero directions: what the driver makes of the measures alone.
    struct Scripted {
        measures: Vec<Measures>,
        calls: usize,
    }

    impl NewtonSystem for Scripted {
        type Error = std::convert::Infallible;

        fn pair_blocks(&self) -> Vec<usize> {
            vec![1]
        }

        fn start(&mut self) -> Result<Point, Self::Error> {
            Ok(Point {
                primal: vec![1.0],
                dual: vec![1.0],
                free_primal: vec![0.0],
                free_dual: Vec::new(),
            })
        }

        fn residuals(&mut self, _: &Point) -> Measures {
            let m = self.measures[self.calls.min(self.measures.len() - 1)];
            self.calls += 1;
            m
        }

        fn factor(&mut self, _: &Point) -> Result<(), Self::Error> {
            Ok(())
        }

        fn direction(&mut self, point: &Point, _: &[f64], _: Rhs) -> Result<Point, Self::Error> {
            let mut zero = point.clone();
            zero.add_scaled(-1.0, point);
            Ok(zero)
        }
    }

    /// With the exact finish's settings (primal 1e-8, reduced 1e-6, gap
    /// 1e-10 either way): an early iterate inside the primal tolerance but
    /// outside the gap's, then iterates whose primal residual stays at
    /// 1.3e-8 with the gap converged. The acceptable iterate is the best,
    /// the method stalls on it after `stall_iterations`; it does not run to
    /// the iteration limit holding the unacceptable one.
    #[test]
    fn an_acceptable_iterate_beats_one_the_acceptance_refuses() {
        let settings = IpmSettings::finish();
        let measure = |primal, gap| Measures {
            primal,
            dual: 1e-14,
            gap,
        };
        let floor = measure(1.3e-8, 4e-11);
        let mut system = Scripted {
            measures: vec![measure(1e-2, 1.0), measure(5e-9, 1e-9), floor],
            calls: 0,
        };
        let outcome = run(&mut system, &settings);
        assert_eq!(outcome.termination, Termination::Stalled);
        assert_eq!(outcome.measures, floor);
        assert_eq!(outcome.iterations, 2 + settings.stall_iterations);
    }
}
