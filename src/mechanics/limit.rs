//! The limit load of a frame (DESIGN §9): the largest multiple of its dead
//! loads at which the equilibrium path from the unstressed frame stays
//! stable, bracketed by solving along the path ([`StaticSolver::solve_from`])
//! and testing each equilibrium ([`StaticSolver::stability`]).

use std::time::Instant;

use serde::Serialize;

use super::assembly::State;
use super::model::{MechanicsError, NodalLoad};
use super::settings::{PathControl, StaticSettings, StaticTermination};
use super::solver::StaticSolver;
use super::stability::{Mode, Stability};

/// What bounds the limit load from above.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum LimitBound {
    /// Stable up to the end of the search: no bound below it.
    SearchEnd,
    /// Certified: the equilibrium on the path at `load_factor` has a
    /// direction of negative curvature on the joints' constraints.
    Unstable {
        /// Its load factor.
        load_factor: f64,
    },
    /// The path's load maximum (a limit point), passed by arc length: the
    /// path turns back there and the state it reaches beyond is certified
    /// unstable, so there is no equilibrium above it on this path. The
    /// maximum is the vertex of the parabola through the highest arc-length
    /// step and its two neighbours (load factor against arc length),
    /// resampled with shorter steps until it is within the search's
    /// precision of the highest stable step.
    LoadMaximum {
        /// The largest load factor on the path.
        load_factor: f64,
    },
    /// Not certified: no equilibrium was found at `load_factor`, though the
    /// solves started from a stable one within the search's precision below
    /// it, and arc length from there neither passed a load maximum nor got
    /// beyond it.
    NotReached {
        /// The least load factor no solve reached.
        load_factor: f64,
    },
    /// The search's budget of solves ran out before a bound was found.
    Budget,
}

/// The limit load of a frame under a multiple of its dead loads.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LimitSearch {
    /// The largest load factor whose equilibrium (on the path from the
    /// unstressed frame) was found stable.
    pub stable_to: f64,
    /// What bounds the limit load from above: the limit lies between
    /// `stable_to` and the bound's load factor.
    pub bound: LimitBound,
    /// The load factor the search went up to.
    pub searched_to: f64,
    /// The stable states found, `[load factor, lowest stiffness N/m]`, from
    /// the unstressed frame on: the lowest stiffness falls to zero at the
    /// limit load.
    pub path: Vec<[f64; 2]>,
    /// The lowest mode of the last stable state: the buckling mode, near
    /// the limit.
    #[serde(skip)]
    pub mode: Mode,
    /// Static solves.
    pub solves: usize,
    /// Newton iterations of all solves.
    pub newton_iterations: usize,
    /// Wall time, s.
    pub time_s: f64,
}

impl std::fmt::Display for LimitBound {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LimitBound::SearchEnd => write!(f, "the end of the search"),
            LimitBound::Unstable { load_factor } => {
                write!(f, "unstable at {load_factor:.3} × (negative curvature)")
            }
            LimitBound::LoadMaximum { load_factor } => write!(
                f,
                "a load maximum at {load_factor:.3} × (the path turns back to unstable states)"
            ),
            LimitBound::NotReached { load_factor } => write!(
                f,
                "no equilibrium found at {load_factor:.3} × (not certified unstable)"
            ),
            LimitBound::Budget => write!(f, "out of solves before an upper bound"),
        }
    }
}

impl std::fmt::Display for LimitSearch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let precision = if self.stable_to >= 10.0 { 1 } else { 3 };
        write!(
            f,
            "stable up to {:.precision$} × the load, {}",
            self.stable_to, self.bound
        )
    }
}

impl LimitBound {
    /// The bound's kind, as `design.json` names it.
    pub fn kind(&self) -> &'static str {
        match self {
            LimitBound::SearchEnd => "search_end",
            LimitBound::Unstable { .. } => "unstable",
            LimitBound::LoadMaximum { .. } => "load_maximum",
            LimitBound::NotReached { .. } => "not_reached",
            LimitBound::Budget => "budget",
        }
    }
}

impl LimitSearch {
    /// The margin to the limit load: the load factor certified stable.
    pub fn margin(&self) -> f64 {
        self.stable_to
    }

    /// The load factor of the upper bound, certified or not (`None` when
    /// there is none).
    pub fn upper(&self) -> Option<f64> {
        match self.bound {
            LimitBound::Unstable { load_factor }
            | LimitBound::LoadMaximum { load_factor }
            | LimitBound::NotReached { load_factor } => Some(load_factor),
            LimitBound::SearchEnd | LimitBound::Budget => None,
        }
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
/// iteration finds it. Each solve starts from the last stable state. An
/// unstable state (negative curvature: a certificate) bounds the limit from
/// above and bisection narrows the bracket. A solve that does not converge
/// certifies nothing: the load is retried half-way from the last stable
/// state, and only when no solve gets within `precision` of it is it the
/// bound, [`LimitBound::NotReached`]. The model's loads are restored before
/// returning.
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
    let unloaded = solver.stability(&stable_state, 0.0)?;
    let mut search = LimitSearch {
        stable_to: 0.0,
        bound: LimitBound::SearchEnd,
        searched_to: search_to,
        path: vec![[0.0, unloaded.lowest_stiffness_n_per_m]],
        mode: unloaded.mode,
        solves: 0,
        newton_iterations: 0,
        time_s: 0.0,
    };
    // The least load factor found unstable (certified), and the least one a
    // solve could not reach (no certificate: the next tries stay below it).
    let mut unstable_from = f64::INFINITY;
    let mut failed_at = f64::INFINITY;
    // The path's load maximum, once arc length has passed it (tried once).
    let mut peak = f64::INFINITY;
    let mut arc_tried = false;
    let result = loop {
        let certified = unstable_from.min(peak);
        let ceiling = certified.min(failed_at);
        let lambda = if certified.is_finite() {
            0.5 * (search.stable_to + ceiling)
        } else {
            next_trial(&search.path, search_to, precision).min(0.5 * (search.stable_to + ceiling))
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
                    search.mode = s.mode;
                    stable_state = reached.state;
                }
                Ok(_) => unstable_from = unstable_from.min(reached.load_factor),
                Err(e) => break Err(e),
            }
        }
        if !reached.converged {
            failed_at = failed_at.min(lambda);
        }
        if search.stable_to >= search_to {
            break Ok(());
        }
        let within = |bound: f64, stable_to: f64| {
            bound.is_finite() && bound - stable_to <= precision * bound
        };
        if !arc_tried && failed_at < certified && within(failed_at, search.stable_to) {
            arc_tried = true;
            // Load control fails just above a stable state: a load maximum,
            // or Newton's failure. Arc length tells which; below a maximum
            // the failures were Newton's, and its highest step, if stable,
            // is the last stable state.
            let found = load_maximum(
                solver,
                &loads,
                failed_at,
                &stable_state,
                search.stable_to,
                precision,
                settings,
            );
            match found {
                Ok(Some(p)) => {
                    peak = p.estimate;
                    failed_at = f64::INFINITY;
                    search.solves += 1;
                    if p.stability.stable && p.load_factor > search.stable_to {
                        search.stable_to = p.load_factor;
                        search
                            .path
                            .push([p.load_factor, p.stability.lowest_stiffness_n_per_m]);
                        search.mode = p.stability.mode;
                        stable_state = p.state;
                    }
                    search.newton_iterations += p.newton_iterations;
                }
                Ok(None) => {}
                Err(e) => break Err(e),
            }
        }
        let certified = unstable_from.min(peak);
        let done = within(certified, search.stable_to)
            || within(failed_at, search.stable_to)
            || search.solves >= MAX_SOLVES;
        if done {
            // The certified bound if there is one, else the failed load.
            search.bound = if unstable_from.is_finite() && unstable_from <= peak {
                LimitBound::Unstable {
                    load_factor: unstable_from,
                }
            } else if peak.is_finite() {
                LimitBound::LoadMaximum { load_factor: peak }
            } else if failed_at.is_finite() {
                LimitBound::NotReached {
                    load_factor: failed_at,
                }
            } else {
                LimitBound::Budget
            };
            break Ok(());
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

/// Loads beyond the first failed load by this fraction are the arc
/// length's target: far enough that it passes a load maximum just above
/// that load before it would land.
const ARC_TARGET_MARGIN: f64 = 0.05;

/// Arc-length runs that resample a load maximum with shorter steps.
const PEAK_REFINEMENTS: usize = 4;

/// Steps before the highest one tested for stability when the highest one
/// has passed the maximum.
const MAX_PAST_MAXIMUM: usize = 3;

/// A load maximum of the path, passed by arc length.
struct Peak {
    /// The converged step of highest load factor that is stable.
    state: State,
    /// Its load factor.
    load_factor: f64,
    /// Its stability.
    stability: Stability,
    /// Newton iterations of the arc-length runs.
    newton_iterations: usize,
    /// The vertex of the parabola through that step and its neighbours
    /// along the path, in load factor against arc length: the maximum's
    /// estimate, at least `load_factor`.
    estimate: f64,
}

/// The path's load maximum above `start` (an equilibrium at `start_lambda` ×
/// `loads`), when arc length towards `beyond` passes one and the state it
/// reaches past it is certified unstable; `None` when it does not (it
/// stalls, or the path goes on, the load-control failure having been
/// Newton's). The maximum is resampled from the step before it with shorter
/// steps until the parabola's vertex is within `precision` of the highest
/// step.
fn load_maximum(
    solver: &mut StaticSolver,
    loads: &[NodalLoad],
    beyond: f64,
    start: &State,
    start_lambda: f64,
    precision: f64,
    settings: &StaticSettings,
) -> Result<Option<Peak>, MechanicsError> {
    let target = beyond * (1.0 + ARC_TARGET_MARGIN);
    set_scaled_loads(solver, loads, target)?;
    // A first step of about a quarter of the gap to the failed load, cut at
    // most to a thousandth of that.
    let mut first = 0.25 * (beyond - start_lambda).max(1e-3 * beyond) / target;
    let mut from = (start.clone(), start_lambda);
    let mut found: Option<Peak> = None;
    let mut newton_iterations = 0;
    for _ in 0..PEAK_REFINEMENTS {
        let arc = StaticSettings {
            path: PathControl::ArcLength,
            initial_step: first,
            min_step: 1e-3 * first,
            ..settings.clone()
        };
        // Every converged step: (arc length so far, load factor, state).
        let mut steps: Vec<(f64, f64, State)> = vec![(0.0, from.1, from.0.clone())];
        let mut travelled = 0.0;
        let solution = super::arc_length::follow_observed(
            solver,
            from.0.clone(),
            from.1 / target,
            &arc,
            &mut |state, lambda, dl| {
                travelled += dl;
                steps.push((travelled, lambda * target, state.clone()));
            },
        );
        newton_iterations += solution.newton_iterations;
        if !matches!(solution.termination, StaticTermination::LimitPoint { .. })
            || solver
                .stability(&solution.state, solution.load_factor)?
                .stable
        {
            break;
        }
        let top = (0..steps.len())
            .max_by(|&a, &b| steps[a].1.total_cmp(&steps[b].1))
            .expect("the start is a step");
        let estimate = match (top.checked_sub(1), steps.get(top + 1)) {
            (Some(before), Some(after)) => {
                parabola_vertex([&steps[before], &steps[top], after].map(|s| [s.0, s.1]))
            }
            _ => steps[top].1,
        }
        .max(steps[top].1);
        // The highest stable step: the top one, or one of the few before
        // it when the top has passed the maximum already.
        let mut highest_stable = None;
        for i in (top.saturating_sub(MAX_PAST_MAXIMUM)..=top).rev() {
            let stability = solver.stability(&steps[i].2, steps[i].1 / target)?;
            if stability.stable {
                highest_stable = Some((i, stability));
                break;
            }
        }
        let Some((i, stability)) = highest_stable else {
            break;
        };
        let (_, load_factor, state) = steps.swap_remove(i);
        // Resample from there, a quarter of the way to the estimate first.
        first = 0.25 * (estimate - load_factor).max(1e-6 * load_factor) / target;
        from = (state.clone(), load_factor);
        found = Some(Peak {
            state,
            load_factor,
            stability,
            newton_iterations: 0,
            estimate,
        });
        if estimate - load_factor <= precision * estimate {
            break;
        }
    }
    Ok(found.map(|p| Peak {
        newton_iterations,
        ..p
    }))
}

/// The largest value of the parabola through three points `[x, y]`, or the
/// largest `y` when they are not concave.
fn parabola_vertex(points: [[f64; 2]; 3]) -> f64 {
    let [[x0, y0], [x1, y1], [x2, y2]] = points;
    let d1 = (y1 - y0) / (x1 - x0);
    let d2 = (y2 - y1) / (x2 - x1);
    let c = (d2 - d1) / (x2 - x0);
    let largest = y0.max(y1).max(y2);
    if c.is_nan() || c >= 0.0 {
        return largest;
    }
    let x = 0.5 * (x0 + x1) - d1 / (2.0 * c);
    let vertex = y0 + d1 * (x - x0) + c * (x - x0) * (x - x1);
    if vertex.is_finite() {
        vertex.max(largest)
    } else {
        largest
    }
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
    set_scaled_loads(solver, loads, lambda)?;
    let solution = solver.solve_from(start.clone(), start_lambda / lambda, settings)?;
    Ok(Reached {
        converged: solution.converged(),
        load_factor: lambda * solution.load_factor,
        state: solution.state,
        newton_iterations: solution.newton_iterations,
    })
}

/// Set `lambda` × `loads` on `solver`'s model.
fn set_scaled_loads(
    solver: &mut StaticSolver,
    loads: &[NodalLoad],
    lambda: f64,
) -> Result<(), MechanicsError> {
    let scaled = loads
        .iter()
        .map(|l| NodalLoad {
            force_n: lambda * l.force_n,
            moment_nm: lambda * l.moment_nm,
            ..*l
        })
        .collect();
    solver.model_mut().set_loads(scaled)
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
        let LimitBound::Unstable { load_factor: hi } = search.bound else {
            panic!("the column buckles below 8 × the load: {search:?}");
        };
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
        assert!(
            matches!(search.bound, LimitBound::Unstable { .. }),
            "{search:?}"
        );
        assert!(
            (search.margin() - expected).abs() <= 2e-5,
            "margin {}, expected {expected}: {search:?}",
            search.margin()
        );
    }

    #[test]
    fn a_bounds_kind_is_its_json_tag() {
        for bound in [
            LimitBound::SearchEnd,
            LimitBound::Unstable { load_factor: 1.0 },
            LimitBound::LoadMaximum { load_factor: 1.0 },
            LimitBound::NotReached { load_factor: 1.0 },
            LimitBound::Budget,
        ] {
            let json = serde_json::to_value(bound).unwrap();
            assert_eq!(json["kind"], bound.kind(), "{bound:?}");
        }
    }

    #[test]
    fn column_in_tension_is_stable_up_to_the_search_end() {
        let mut solver = column(8, -10.0 * critical_load_n());
        let search = limit_load_factor(&mut solver, 4.0, 1e-3, &StaticSettings::default()).unwrap();
        assert_eq!(search.bound, LimitBound::SearchEnd);
        assert_eq!(search.stable_to, 4.0);
    }
}
