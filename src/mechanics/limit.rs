//! The limit load of a frame (DESIGN §9): the largest multiple of its dead
//! loads at which the equilibrium path from the unstressed frame stays
//! stable, bracketed by solving along the path ([`StaticSolver::solve_from`])
//! and testing each equilibrium ([`StaticSolver::stability`]).

use std::time::Instant;

use serde::Serialize;

use super::assembly::State;
use super::model::{MechanicsError, NodalLoad};
use super::settings::StaticSettings;
use super::solver::StaticSolver;

/// The limit load of a frame under a multiple of its dead loads.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LimitSearch {
    /// The largest load factor whose equilibrium (on the path from the
    /// unstressed frame) was found stable.
    pub stable_to: f64,
    /// The least load factor with an unstable equilibrium or none at all; `None`
    /// when the frame is stable up to `searched_to`. The limit load lies in
    /// `[stable_to, unstable_from]`.
    pub unstable_from: Option<f64>,
    /// The load factor the search went up to.
    pub searched_to: f64,
    /// The stable states found, `[load factor, lowest stiffness N/m]`, from
    /// the unstressed frame on: the lowest stiffness falls to zero at the
    /// limit load.
    pub path: Vec<[f64; 2]>,
    /// Static solves.
    pub solves: usize,
    /// Newton iterations of all solves.
    pub newton_iterations: usize,
    /// Wall time, s.
    pub time_s: f64,
}

impl std::fmt::Display for LimitSearch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.unstable_from {
            Some(hi) => write!(
                f,
                "stable up to {:.3} × the load, unstable (or lost) at {hi:.3} ×",
                self.stable_to
            ),
            None => write!(
                f,
                "stable up to {} × the load, the end of the search",
                self.stable_to
            ),
        }
    }
}

impl LimitSearch {
    /// The margin to the limit load: the load factor certified stable.
    pub fn margin(&self) -> f64 {
        self.stable_to
    }
}

/// The first load factor tried: small, so that the trend of the lowest
/// stiffness is known before the path goes far.
const FIRST_TRIAL: f64 = 0.05;

/// Static solves a search may take.
const MAX_SOLVES: usize = 64;

/// Largest growth of the load factor from one trial to the next.
const MAX_GROWTH: f64 = 4.0;

/// The limit load of `solver`'s frame as a multiple of its dead loads,
/// searched up to `search_to`, to a bracket of relative width `precision`.
///
/// The path from the unstressed frame is followed in steps sized by the
/// lowest stiffness `μ(λ)` of the stable states found so far: each step goes
/// at most half-way to where the line through the last two `(λ, μ)` crosses
/// zero (and at most ×4, `MAX_GROWTH`), so that an eigenvalue turns negative
/// within a short step, while it is still the least in magnitude and inverse
/// iteration finds it. The first unstable state (or a load with no
/// equilibrium) brackets the limit, and bisection narrows the bracket. Each
/// solve starts from the last stable state. The model's loads are restored
/// before returning.
///
/// # Errors
/// Invalid arguments or settings, or a tangent that cannot be factored at a
/// converged state.
pub fn limit_load_factor(
    solver: &mut StaticSolver,
    search_to: f64,
    precision: f64,
    settings: &StaticSettings,
) -> Result<LimitSearch, MechanicsError> {
    if !(search_to > 0.0 && search_to.is_finite()) {
        return Err(MechanicsError::invalid(
            "limit search",
            "search_to must be positive",
        ));
    }
    if !(precision > 0.0 && precision < 1.0) {
        return Err(MechanicsError::invalid(
            "limit search",
            "precision must be in (0, 1)",
        ));
    }
    let clock = Instant::now();
    let loads = solver.model().loads().to_vec();
    let mut stable_state = solver.reference_state();
    let mut search = LimitSearch {
        stable_to: 0.0,
        unstable_from: None,
        searched_to: search_to,
        path: vec![[
            0.0,
            solver
                .stability(&stable_state, 0.0)?
                .lowest_stiffness_n_per_m,
        ]],
        solves: 0,
        newton_iterations: 0,
        time_s: 0.0,
    };
    // The least load factor a solve could not reach: no certificate, but the
    // next try stays below it.
    let mut failed_at = f64::INFINITY;
    let result = loop {
        let ceiling = search.unstable_from.unwrap_or(f64::INFINITY).min(failed_at);
        let halfway = 0.5 * (search.stable_to + ceiling);
        let lambda = match search.unstable_from {
            Some(_) => halfway,
            None => next_trial(&search.path, search_to, precision).min(halfway),
        };
        let reached = match equilibrium_at(
            solver,
            &loads,
            lambda,
            &stable_state,
            search.stable_to,
            settings,
        ) {
            Ok(reached) => reached,
            Err(e) => break Err(e),
        };
        search.solves += 1;
        search.newton_iterations += reached.newton_iterations;
        // The last converged state, if the solve moved at all.
        if reached.load_factor > search.stable_to {
            match solver.stability(&reached.state, reached.load_factor / lambda) {
                Ok(s) if s.stable => {
                    if reached.converged {
                        // The path goes on: the failure was the step's.
                        failed_at = f64::INFINITY;
                    }
                    search.stable_to = reached.load_factor;
                    search
                        .path
                        .push([reached.load_factor, s.lowest_stiffness_n_per_m]);
                    stable_state = reached.state;
                }
                Ok(_) => search.unstable_from = Some(reached.load_factor),
                Err(e) => break Err(e),
            }
        }
        if !reached.converged {
            if lambda - search.stable_to <= precision * lambda {
                // No equilibrium within `precision` beyond a stable one.
                search.unstable_from = Some(lambda);
            } else {
                failed_at = lambda;
            }
        }
        if search.solves >= MAX_SOLVES && search.unstable_from.is_none() {
            // Out of budget: the least load not reached bounds the limit.
            search.unstable_from = Some(failed_at.min(search_to)).filter(|f| *f < search_to);
            break Ok(());
        }
        match search.unstable_from {
            None if search.stable_to >= search_to => break Ok(()),
            Some(hi) if hi - search.stable_to <= precision * hi => break Ok(()),
            _ => {}
        }
    };
    solver.model_mut().set_loads(loads)?;
    result?;
    search.time_s = clock.elapsed().as_secs_f64();
    Ok(search)
}

/// The next load factor to try beyond the last stable point of `path`
/// (`[λ, μ]`, increasing λ): half-way to the predicted zero of `μ`, at least
/// `precision` × λ further, at most ×[`MAX_GROWTH`] and `search_to`.
fn next_trial(path: &[[f64; 2]], search_to: f64, precision: f64) -> f64 {
    let [l1, m1] = path[path.len() - 1];
    if l1 == 0.0 {
        return FIRST_TRIAL * search_to.min(1.0);
    }
    let mut trial = MAX_GROWTH * l1;
    if let [.., [l0, m0], _] = path {
        if m1 < *m0 {
            let zero = l1 + m1 * (l1 - l0) / (m0 - m1);
            trial = trial.min(l1 + (0.5 * (zero - l1)).max(precision * l1));
        }
    }
    trial.min(search_to)
}

/// How far a solve towards a load factor got.
struct Reached {
    /// The last converged state.
    state: State,
    /// Its load factor (× the reference loads).
    load_factor: f64,
    /// True when it is the one asked for.
    converged: bool,
    /// Newton iterations.
    newton_iterations: usize,
}

/// Equilibrium under `lambda` × `loads`, from `start` (an equilibrium at
/// `start_lambda` × `loads`), with the new loads set on the model.
fn equilibrium_at(
    solver: &mut StaticSolver,
    loads: &[NodalLoad],
    lambda: f64,
    start: &State,
    start_lambda: f64,
    settings: &StaticSettings,
) -> Result<Reached, MechanicsError> {
    let scaled = loads
        .iter()
        .map(|l| NodalLoad {
            force_n: lambda * l.force_n,
            moment_nm: lambda * l.moment_nm,
            ..*l
        })
        .collect();
    solver.model_mut().set_loads(scaled)?;
    let solution = solver.solve_from(start.clone(), start_lambda / lambda, settings)?;
    Ok(Reached {
        converged: solution.converged(),
        load_factor: lambda * solution.load_factor,
        state: solution.state,
        newton_iterations: solution.newton_iterations,
    })
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;

    use super::*;
    use crate::mechanics::{ElementKind, ModelBuilder, RodSpec, Section};

    /// Length of the column, m.
    const LENGTH_M: f64 = 10.0;

    /// The column's section: EA = GA = 10⁴ N, GJ = EI = 100 N·m² (the
    /// cantilever benchmark's).
    fn section() -> Section {
        Section {
            axial_n: 1e4,
            shear_n: [1e4, 1e4],
            torsion_nm2: 100.0,
            bending_nm2: [100.0, 100.0],
        }
    }

    /// A column clamped at its foot, free at its head, under an axial
    /// compression `p_n` at the head (Euler's case 1). Its section has equal
    /// bending stiffness both ways: every buckling load is a double one.
    fn column(elements: usize, p_n: f64) -> StaticSolver {
        let mut b = ModelBuilder::new();
        let rod = b.add_rod(
            Vector3::zeros(),
            Vector3::new(0.0, 0.0, LENGTH_M),
            Vector3::x(),
            &RodSpec {
                section: section(),
                elements,
                kind: ElementKind::Se3,
            },
        );
        b.fix(rod.start(), [true; 6]);
        b.add_load(rod.end(), Vector3::new(0.0, 0.0, -p_n), Vector3::zeros());
        StaticSolver::new(b.build().unwrap()).unwrap()
    }

    /// Euler's load of the clamped–free column with shear flexibility,
    /// `P = P_E / (1 + P_E/GA)`, `P_E = π²EI/(4L²)`.
    fn critical_load_n() -> f64 {
        let s = section();
        let euler = std::f64::consts::PI.powi(2) * s.bending_nm2[0] / (4.0 * LENGTH_M.powi(2));
        euler / (1.0 + euler / s.shear_n[0])
    }

    #[test]
    fn column_below_euler_load_is_stable_and_above_it_is_not() {
        let p_cr = critical_load_n();
        for (fraction, expected) in [(0.9, true), (1.1, false)] {
            let solver = column(16, fraction * p_cr);
            // The straight column is an equilibrium at every load.
            let solution = solver.solve(&StaticSettings::default()).unwrap();
            assert!(solution.converged(), "{:?}", solution.termination);
            let s = solver.stability(&solution.state, 1.0).unwrap();
            assert_eq!(s.stable, expected, "{fraction} × P_cr: {s:?}");
        }
    }

    #[test]
    fn column_limit_search_finds_euler_load() {
        let p_cr = critical_load_n();
        // Loaded at half the critical load: the margin is 2.
        let mut solver = column(16, 0.5 * p_cr);
        let search = limit_load_factor(&mut solver, 8.0, 1e-6, &StaticSettings::default()).unwrap();
        let hi = search
            .unstable_from
            .expect("the column buckles below 8 × the load");
        let found = 0.5 * search.stable_to;
        // The discrete column's error: 16 elements of constant curvature on a
        // quarter sine wave, (π/32)²/12 = 8.0e-4 relative (measured at 4…64
        // elements: the h² law), and the shortening under the load, P/EA =
        // 2.5e-4, which the inextensible formula leaves out.
        let expected =
            1.0 + (std::f64::consts::PI / 32.0).powi(2) / 12.0 + p_cr / section().axial_n;
        assert!(
            (found - expected).abs() <= 2e-5,
            "found {found} × Euler, expected {expected}: {search:?}"
        );
        assert!(hi - search.stable_to <= 1e-6 * hi);
        // The loads are restored.
        assert_eq!(solver.model().loads()[0].force_n.z, -0.5 * p_cr);
    }

    #[test]
    fn column_loaded_past_its_limit_has_a_margin_below_one() {
        let p_cr = critical_load_n();
        let mut solver = column(16, 3.0 * p_cr);
        let search = limit_load_factor(&mut solver, 4.0, 1e-6, &StaticSettings::default()).unwrap();
        let expected =
            (1.0 + (std::f64::consts::PI / 32.0).powi(2) / 12.0 + p_cr / section().axial_n) / 3.0;
        assert!(search.unstable_from.is_some());
        assert!(
            (search.margin() - expected).abs() <= 2e-5,
            "margin {}, expected {expected}: {search:?}",
            search.margin()
        );
    }

    #[test]
    fn column_in_tension_is_stable_up_to_the_search_end() {
        let mut solver = column(8, -10.0 * critical_load_n());
        let search = limit_load_factor(&mut solver, 4.0, 1e-3, &StaticSettings::default()).unwrap();
        assert_eq!(search.unstable_from, None);
        assert_eq!(search.stable_to, 4.0);
    }
}
