//! The study's plan: the knobs and their values (plain data, validated),
//! the baseline each knob is swept from, the reference, and the points in
//! their deterministic order.

use serde::{Deserialize, Serialize};

use super::StudyError;
use crate::design::{default_solver, LoopSettings};
use crate::scene::{Scene, TrussModel, MAX_ELEMENTS_PER_ROD};
use crate::uniformity::SolverKind;

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
    /// scene's `r` (at least 2), every truss model of the registry
    /// ([`crate::truss::MODELS`]), and the solvers `lp`,
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
            truss_models: crate::truss::MODELS.to_vec(),
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
