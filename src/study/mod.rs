//! The cost of accuracy: wall time against achieved accuracy of the whole
//! design (outer loop to a converged net), one knob at a time.
//!
//! Knobs, each swept from the *baseline* — the scene's own settings: its
//! elements per rod, rings and `[effects] truss`, the `design` command's
//! tolerance (1e-6 m) and solver (`lp`):
//!
//! * [`Knob::Tolerance`] — the outer loop's `‖G(C) − C‖∞` tolerance, m;
//! * [`Knob::Elements`] — beam elements per truss rod;
//! * [`Knob::Rings`] — front-net density (rings of the sector grid);
//! * [`Knob::Truss`] — the loop's truss model (rigid, linear, exact);
//! * [`Knob::Solver`] — the uniformity solver.
//!
//! The *reference* run (point 0) has the finest settings: the tightest
//! tolerance and the most elements of the sweep (and of the scene), the exact
//! truss, `lp`, and the scene's net. Every design is judged the same way —
//! cut to length and assembled on the reference truss (exact, the reference's
//! elements per rod; [`crate::verify`]) — so a point's accuracy is what its
//! design would give as built:
//!
//! * `rms_mm` — RMS axial deviation of the assembled front net's free nodes
//!   from the paraboloid, mm;
//! * `built_ratio` — `Tmax/Tmin` of the assembled tensions over the uniformity
//!   sets (the largest), and `ratio_error = |built_ratio − ref|/ref` against
//!   the reference's;
//! * `tension_change_pct` — largest change of an assembled tension from the
//!   point's own design, %;
//! * `cut_length_error_mm` — largest difference of a cable's cut length from
//!   the reference's, mm (same net only);
//! * `facet_rms_mm` — RMS axial distance of the flat facets through the
//!   assembled nodes from the paraboloid ([`crate::geometry::Paraboloid::facet_rms_m`]).
//!
//! A net of other rings is another reflector: it cannot be compared cable by
//! cable (no `cut_length_error_mm`), its `ratio_error` is mostly the change of
//! the optimum with the net, and what its density buys is `facet_rms_mm`.
//!
//! A point that fails (no truss equilibrium, no assembled equilibrium) is a row
//! with its error, not a failed study; only a reference that fails or does not
//! converge stops it.
//! Points run in a deterministic order, so a sweep splits into shards
//! ([`crate::shard`]); every shard runs the reference itself to judge its
//! points.

mod aperture;
mod pareto;

use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

pub use aperture::{
    run_aperture_study, scaled, ApertureResult, ApertureSettings, ModelResult, MAX_APERTURE_M,
};
pub use pareto::pareto_optimal;

use crate::design::{default_solver, LoopSettings, SceneNets};
use crate::scene::{Scene, TrussModel, MAX_ELEMENTS_PER_ROD};
use crate::shard::Shard;
use crate::status::Termination;
use crate::uniformity::SolverKind;
use crate::verify::{verify, AssemblyTruss};

/// A study that cannot run.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// An invalid study setting.
    #[error("study setting `{key}`: {reason}")]
    Setting {
        /// The setting (`tolerances_m`, `elements_per_rod`, `rings`,
        /// `max_iterations`).
        key: &'static str,
        /// Why the value is refused.
        reason: String,
    },
    /// The reference run failed: nothing can be judged.
    #[error("the study's reference run ({settings}) failed: {message}")]
    Reference {
        /// The reference's settings.
        settings: String,
        /// Why.
        message: String,
    },
    /// The worker threads could not be started.
    #[error("starting {jobs} worker threads: {message}")]
    Threads {
        /// Threads asked for.
        jobs: usize,
        /// The cause.
        message: String,
    },
}

impl StudyError {
    /// True when the input is at fault.
    pub fn is_bad_input(&self) -> bool {
        matches!(self, StudyError::Setting { .. })
    }
}

/// What a point of the study varies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Knob {
    /// The finest settings, against which the others are judged.
    #[value(skip)]
    Reference,
    /// The outer loop's tolerance, m.
    Tolerance,
    /// Beam elements per truss rod.
    Elements,
    /// Front-net rings.
    Rings,
    /// The loop's truss model.
    Truss,
    /// The uniformity solver.
    Solver,
}

impl Knob {
    /// The swept knobs, in sweep order.
    pub const SWEPT: [Knob; 5] = [
        Knob::Tolerance,
        Knob::Elements,
        Knob::Rings,
        Knob::Truss,
        Knob::Solver,
    ];

    /// The name in tables.
    pub fn name(self) -> &'static str {
        match self {
            Knob::Reference => "reference",
            Knob::Tolerance => "tolerance",
            Knob::Elements => "elements",
            Knob::Rings => "rings",
            Knob::Truss => "truss",
            Knob::Solver => "solver",
        }
    }

    /// The knob of a table name.
    pub fn from_name(name: &str) -> Option<Knob> {
        std::iter::once(Knob::Reference)
            .chain(Knob::SWEPT)
            .find(|k| k.name() == name)
    }
}

/// The settings of one design run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RunSettings {
    /// Outer-loop tolerance, m.
    pub tolerance_m: f64,
    /// Beam elements per truss rod.
    pub elements_per_rod: usize,
    /// Front-net rings.
    pub rings: usize,
    /// The loop's truss model.
    pub truss: TrussModel,
    /// The uniformity solver.
    pub solver: SolverKind,
}

impl std::fmt::Display for RunSettings {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "tolerance {:e} m, {} elements per rod, {} rings, {} truss, {}",
            self.tolerance_m,
            self.elements_per_rod,
            self.rings,
            value_name(&self.truss),
            value_name(&self.solver)
        )
    }
}

/// The command-line name of an enum value (`least-squares`, `exact`).
pub fn value_name<T: clap::ValueEnum>(value: &T) -> String {
    value
        .to_possible_value()
        .map(|v| v.get_name().to_string())
        .unwrap_or_default()
}

/// The sweeps of a study: plain data; an empty list leaves its knob out.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudySettings {
    /// Outer-loop tolerances, m.
    pub tolerances_m: Vec<f64>,
    /// Beam elements per truss rod.
    pub elements_per_rod: Vec<usize>,
    /// Front-net rings.
    pub rings: Vec<usize>,
    /// Truss models of the loop.
    pub truss_models: Vec<TrussModel>,
    /// Uniformity solvers.
    pub solvers: Vec<SolverKind>,
    /// Most outer iterations of every run.
    pub max_iterations: usize,
}

impl StudySettings {
    /// The default sweeps for `scene`: tolerances 1e-2 … 1e-7 m, 1, 2, 4, 8
    /// and 16 elements per rod, rings `⌈r/2⌉, r, ⌈3r/2⌉, 2r` about the
    /// scene's `r` (at least 2), every truss model, and the solvers `lp`,
    /// `bisection`, `least-squares`, `gradient`; 50 outer iterations at most.
    pub fn for_scene(scene: &Scene) -> StudySettings {
        let r = scene.front_net.rings;
        let mut rings: Vec<usize> = [r.div_ceil(2), r, (3 * r).div_ceil(2), 2 * r]
            .into_iter()
            .map(|v| v.max(2))
            .collect();
        rings.dedup();
        StudySettings {
            tolerances_m: vec![1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7],
            elements_per_rod: vec![1, 2, 4, 8, 16],
            rings,
            truss_models: vec![TrussModel::Rigid, TrussModel::Linear, TrussModel::Exact],
            solvers: vec![
                SolverKind::Lp,
                SolverKind::Bisection,
                SolverKind::LeastSquares,
                SolverKind::Gradient,
            ],
            max_iterations: LoopSettings::default().max_iterations,
        }
    }

    /// Leaves out every knob not in `knobs`.
    pub fn only(mut self, knobs: &[Knob]) -> StudySettings {
        let keep = |k: Knob| knobs.contains(&k);
        if !keep(Knob::Tolerance) {
            self.tolerances_m.clear();
        }
        if !keep(Knob::Elements) {
            self.elements_per_rod.clear();
        }
        if !keep(Knob::Rings) {
            self.rings.clear();
        }
        if !keep(Knob::Truss) {
            self.truss_models.clear();
        }
        if !keep(Knob::Solver) {
            self.solvers.clear();
        }
        self
    }

    /// Checks every value.
    ///
    /// # Errors
    /// A tolerance not finite and positive, elements per rod outside
    /// 1…[`MAX_ELEMENTS_PER_ROD`], fewer than 2 rings, or no outer iteration.
    pub fn validate(&self) -> Result<(), StudyError> {
        let bad = |key, reason: String| Err(StudyError::Setting { key, reason });
        if let Some(t) = self
            .tolerances_m
            .iter()
            .find(|t| !(t.is_finite() && **t > 0.0))
        {
            return bad("tolerances_m", format!("{t} m must be finite and positive"));
        }
        if let Some(e) = self
            .elements_per_rod
            .iter()
            .find(|e| !(1..=MAX_ELEMENTS_PER_ROD).contains(*e))
        {
            return bad(
                "elements_per_rod",
                format!("{e}: must be in 1…{MAX_ELEMENTS_PER_ROD}"),
            );
        }
        if let Some(r) = self.rings.iter().find(|r| **r < 2) {
            return bad("rings", format!("{r}: at least 2 are needed"));
        }
        if self.max_iterations == 0 {
            return bad("max_iterations", "must be at least 1".into());
        }
        Ok(())
    }
}

/// The scene's own settings, from which each knob is swept.
pub fn baseline(scene: &Scene) -> RunSettings {
    RunSettings {
        tolerance_m: LoopSettings::default().tolerance_m,
        elements_per_rod: scene.truss.elements_per_rod,
        rings: scene.front_net.rings,
        truss: scene.effects.truss,
        solver: default_solver(scene),
    }
}

/// The finest settings: the tightest tolerance and the most elements per rod
/// of the sweep and the baseline, the exact truss, the scene's default
/// solver, the scene's net.
pub fn reference(scene: &Scene, settings: &StudySettings) -> RunSettings {
    let base = baseline(scene);
    RunSettings {
        tolerance_m: settings
            .tolerances_m
            .iter()
            .copied()
            .fold(base.tolerance_m, f64::min),
        elements_per_rod: settings
            .elements_per_rod
            .iter()
            .copied()
            .fold(base.elements_per_rod, usize::max),
        rings: base.rings,
        truss: TrussModel::Exact,
        solver: default_solver(scene),
    }
}

/// One point of the study.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyPoint {
    /// What it varies.
    pub knob: Knob,
    /// The knob's value as shown (`1e-4`, `8`, `rigid`; empty for the reference).
    pub value: String,
    /// Its settings.
    pub settings: RunSettings,
}

/// The study's points in their deterministic order: the reference, then each
/// knob's values as listed, knobs in the order of [`Knob::SWEPT`].
pub fn points(scene: &Scene, settings: &StudySettings) -> Vec<StudyPoint> {
    let base = baseline(scene);
    let mut list = vec![StudyPoint {
        knob: Knob::Reference,
        value: String::new(),
        settings: reference(scene, settings),
    }];
    let mut add = |knob, value: String, settings| {
        list.push(StudyPoint {
            knob,
            value,
            settings,
        })
    };
    for &t in &settings.tolerances_m {
        let s = RunSettings {
            tolerance_m: t,
            ..base
        };
        add(Knob::Tolerance, format!("{t:e}"), s);
    }
    for &e in &settings.elements_per_rod {
        let s = RunSettings {
            elements_per_rod: e,
            ..base
        };
        add(Knob::Elements, e.to_string(), s);
    }
    for &r in &settings.rings {
        add(Knob::Rings, r.to_string(), RunSettings { rings: r, ..base });
    }
    for &truss in &settings.truss_models {
        add(
            Knob::Truss,
            value_name(&truss),
            RunSettings { truss, ..base },
        );
    }
    for &solver in &settings.solvers {
        add(
            Knob::Solver,
            value_name(&solver),
            RunSettings { solver, ..base },
        );
    }
    list
}

/// One row of `accuracy-vs-time.csv`: a point, its cost and its accuracy.
/// Missing numbers (a failed point, another net's cut lengths) are NaN.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StudyRow {
    /// What the point varies.
    pub knob: Knob,
    /// The knob's value as shown.
    pub value: String,
    /// The point's settings.
    pub settings: RunSettings,
    /// Wall time of the design: mesh, problem and outer loop, s.
    pub time_s: f64,
    /// Outer iterations.
    pub outer_iterations: Option<usize>,
    /// How the loop ended.
    pub termination: Option<Termination>,
    /// Final `‖G(C) − C‖∞`, m.
    pub boundary_residual_m: f64,
    /// The design's `Tmax/Tmin` (largest set).
    pub ratio: f64,
    /// `Tmax/Tmin` as built on the reference truss (largest set).
    pub built_ratio: f64,
    /// `|built_ratio − reference's|/reference's`.
    pub ratio_error: f64,
    /// RMS axial deviation of the front net's free nodes as built, mm.
    pub rms_mm: f64,
    /// Largest axial deviation of a front-net free node as built, mm.
    pub max_deviation_mm: f64,
    /// RMS axial distance of the built facets from the paraboloid, mm.
    pub facet_rms_mm: f64,
    /// Largest change of a built tension from the design, %.
    pub tension_change_pct: f64,
    /// Largest difference of a cut length from the reference's, mm (NaN for
    /// another net).
    pub cut_length_error_mm: f64,
    /// Why the point failed.
    pub error: Option<String>,
}

impl StudyRow {
    /// True when the point designs the reference's net (its accuracy is
    /// comparable cable by cable).
    pub fn same_net_as(&self, reference: &StudyRow) -> bool {
        self.settings.rings == reference.settings.rings
    }
}

/// What the outer loop made.
struct LoopSummary {
    iterations: usize,
    termination: Termination,
    residual_m: f64,
    ratio: f64,
}

/// A design as built on the reference truss.
struct Judged {
    built_ratio: f64,
    rms_mm: f64,
    max_deviation_mm: f64,
    facet_rms_mm: f64,
    tension_change_pct: f64,
    cut_lengths_m: Vec<f64>,
}

/// One point run and judged.
struct Measurement {
    time_s: f64,
    summary: Option<LoopSummary>,
    judged: Option<Judged>,
    error: Option<String>,
}

/// Runs the design of `run` on `scene` and judges it on a truss of
/// `judge_elements` elements per rod. Never fails: a failure is recorded.
fn measure(
    scene: &Scene,
    run: &RunSettings,
    max_iterations: usize,
    judge_elements: usize,
) -> Measurement {
    let mut scene = scene.clone();
    scene.front_net.rings = run.rings;
    scene.truss.elements_per_rod = run.elements_per_rod;
    scene.effects.truss = run.truss;
    let settings = LoopSettings {
        tolerance_m: run.tolerance_m,
        max_iterations,
        ..LoopSettings::default()
    };
    let clock = Instant::now();
    let designed = SceneNets::new(&scene).and_then(|nets| {
        let solver = run.solver.build(None);
        let outcome =
            nets.design_loop(&scene, solver.as_ref(), run.truss, &settings, &mut |_| {})?;
        Ok((nets, outcome))
    });
    let time_s = clock.elapsed().as_secs_f64();
    let (nets, outcome) = match designed {
        Ok(d) => d,
        Err(e) => {
            return Measurement {
                time_s,
                summary: None,
                judged: None,
                error: Some(e.to_string()),
            }
        }
    };
    let summary = LoopSummary {
        iterations: outcome.history.len(),
        termination: outcome.termination,
        residual_m: outcome.boundary_residual_m(),
        ratio: outcome.design.ratio,
    };
    let mut judge = scene.clone();
    judge.truss.elements_per_rod = judge_elements;
    let network = outcome.problem.network();
    let design = &outcome.design;
    let judged = verify(
        &judge,
        &nets.mesh,
        &nets.effects,
        network,
        design,
        AssemblyTruss::Flexible,
        None,
    )
    .map(|v| {
        let built_ratio = outcome
            .problem
            .sets()
            .iter()
            .map(|set| set.ratio(&v.tensions_n))
            .fold(0.0, f64::max);
        let cut_lengths_m = design
            .lengths_m
            .iter()
            .zip(&design.tensions_n)
            .map(|(&l, &t)| scene.cables.cut_length_m(l, t))
            .collect();
        Judged {
            built_ratio,
            rms_mm: v.rms_mm,
            max_deviation_mm: v.max_deviation_mm,
            facet_rms_mm: 1e3
                * nets
                    .mesh
                    .paraboloid
                    .facet_rms_m(&v.nodes_xyz_m, &nets.mesh.front_triangles),
            tension_change_pct: v.max_tension_change_pct,
            cut_lengths_m,
        }
    });
    let (judged, error) = match judged {
        Ok(j) => (Some(j), None),
        Err(e) => (
            None,
            Some(format!("verification on the reference truss: {e}")),
        ),
    };
    Measurement {
        time_s,
        summary: Some(summary),
        judged,
        error,
    }
}

/// The row of `point`, judged against the reference.
fn row(
    point: &StudyPoint,
    m: &Measurement,
    reference: &Judged,
    reference_rings: usize,
) -> StudyRow {
    let nan = f64::NAN;
    let j = m.judged.as_ref();
    let get = |f: fn(&Judged) -> f64| j.map_or(nan, f);
    let cut_length_error_mm = match j {
        Some(j)
            if point.settings.rings == reference_rings
                && j.cut_lengths_m.len() == reference.cut_lengths_m.len() =>
        {
            1e3 * j
                .cut_lengths_m
                .iter()
                .zip(&reference.cut_lengths_m)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
        }
        _ => nan,
    };
    StudyRow {
        knob: point.knob,
        value: point.value.clone(),
        settings: point.settings,
        time_s: m.time_s,
        outer_iterations: m.summary.as_ref().map(|s| s.iterations),
        termination: m.summary.as_ref().map(|s| s.termination),
        boundary_residual_m: m.summary.as_ref().map_or(nan, |s| s.residual_m),
        ratio: m.summary.as_ref().map_or(nan, |s| s.ratio),
        built_ratio: get(|j| j.built_ratio),
        ratio_error: (get(|j| j.built_ratio) - reference.built_ratio).abs() / reference.built_ratio,
        rms_mm: get(|j| j.rms_mm),
        max_deviation_mm: get(|j| j.max_deviation_mm),
        facet_rms_mm: get(|j| j.facet_rms_mm),
        tension_change_pct: get(|j| j.tension_change_pct),
        cut_length_error_mm,
        error: m.error.clone(),
    }
}

/// Runs the points of `shard` (the reference always, to judge them), `jobs`
/// at a time (1: one after the other, so each point's wall time is measured
/// alone), calling `on_point` as each finishes. Returns `(point index, row)`
/// in sweep order.
///
/// # Errors
/// Invalid settings, worker threads that cannot start, or a reference that
/// fails or does not converge.
pub fn run_study(
    scene: &Scene,
    settings: &StudySettings,
    shard: Shard,
    jobs: usize,
    on_point: &(dyn Fn(&StudyRow) + Sync),
) -> Result<Vec<(usize, StudyRow)>, StudyError> {
    settings.validate()?;
    let list = points(scene, settings);
    let reference_point = &list[0];
    let judge_elements = reference_point.settings.elements_per_rod;
    let max_iterations = settings.max_iterations;
    let measured = measure(
        scene,
        &reference_point.settings,
        max_iterations,
        judge_elements,
    );
    let failed = |message: String| StudyError::Reference {
        settings: reference_point.settings.to_string(),
        message,
    };
    if let Some(s) = measured.summary.as_ref() {
        if s.termination != Termination::Converged {
            return Err(failed(format!(
                "its outer loop stopped {:?} after {} iterations (residual {:.3e} m): a \
                 yardstick must be converged",
                s.termination, s.iterations, s.residual_m
            )));
        }
    }
    let Some(reference) = measured.judged.as_ref() else {
        return Err(failed(measured.error.clone().unwrap_or_default()));
    };
    let reference_rings = reference_point.settings.rings;
    let reference_row = row(reference_point, &measured, reference, reference_rings);
    on_point(&reference_row);
    let others: Vec<usize> = shard
        .points(list.len())
        .into_iter()
        .filter(|&k| k != 0)
        .collect();
    let work = |&k: &usize| {
        let point = &list[k];
        let m = measure(scene, &point.settings, max_iterations, judge_elements);
        let r = row(point, &m, reference, reference_rings);
        on_point(&r);
        (k, r)
    };
    let mut rows: Vec<(usize, StudyRow)> = if jobs <= 1 {
        others.iter().map(work).collect()
    } else {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(jobs)
            .build()
            .map_err(|e| StudyError::Threads {
                jobs,
                message: e.to_string(),
            })?;
        pool.install(|| others.par_iter().map(work).collect())
    };
    if shard.includes(0) {
        rows.insert(0, (0, reference_row));
    }
    Ok(rows)
}
