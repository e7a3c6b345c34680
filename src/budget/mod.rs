//! The error budget of a dish as built (issue 35, DESIGN §13): what each
//! error source does to the surface on the flexible truss — the facets,
//! the design, each thermal load case in orbit, and the manufacturing
//! tolerances — raw and about the best-fit paraboloid, their
//! root-sum-square and the gain lost at the scene's frequency.
//!
//! One core serves every source ([`PerturbedAssembly`], `core.rs`): the
//! design's cut cables assembled on the exact truss once, then each
//! perturbation ([`crate::verify::Perturbation`]: cable cut lengths and EA,
//! rod stretches, hinge offsets) assembled from that equilibrium —
//! nonlinear: chord iterations with the design's factored tangent, the
//! tangent refactored numerically where they slow down (slack cables), and
//! Newton with load steps where that fails; linearised: one solve with the
//! same factored tangent. A thermal case (`thermal.rs`, from
//! [`crate::effects::ThermalExpansion`]) and a tolerance sample
//! (`tolerances.rs`, seeded per sample) are each one perturbation. Each
//! source's term is the change it makes to the design's surface as built
//! ([`PerturbedAssembly::change`]): the design's own error is its own term.
//!
//! **Linearised against Monte Carlo.** Each sample is assembled twice, by
//! Newton and through the design's tangent (one back-substitution per
//! sample on one factorisation), so the two are compared on the same draws:
//! their difference is the nonlinearity alone, free of sampling error;
//! the sampling error of either mean square over `n` samples is about
//! `√(2/n)` of it (a sum of many independent squared terms).
//!
//! The points of a budget — facets, design, cases, samples — are one
//! sweep: `--shard I/N` measures every N-th ([`crate::shard`]), and the
//! table is computed from the rows alone (`table.rs`), merged or not.

mod core;
mod table;
mod thermal;
mod tolerances;

pub use self::core::{Measured, PerturbedAssembly};
pub use table::{BudgetRow, BudgetTable, BudgetTerm, PointKind, POINT_COLUMNS};
pub use thermal::thermal_perturbation;
pub use tolerances::ToleranceModel;

use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use crate::design::{self, DesignError, DesignSettings};
use crate::effects::ThermalExpansion;
use crate::scene::Scene;
use crate::shard::Shard;
use crate::surface::{best_fit_facets, facet_rms, SurfaceError};
use crate::verify::VerifyError;

/// Monte Carlo samples of a scene with `[tolerances]` that names none.
pub const DEFAULT_SAMPLES: usize = 100;

/// Seed of a scene that names none.
pub const DEFAULT_SEED: u64 = 1;

/// Why a budget cannot be made.
#[derive(Debug, thiserror::Error)]
pub enum BudgetError {
    /// The design failed.
    #[error(transparent)]
    Design(#[from] DesignError),
    /// The design's assembly failed (a failed case or sample is a row).
    #[error(transparent)]
    Verify(#[from] VerifyError),
    /// A surface that cannot be measured.
    #[error(transparent)]
    Surface(#[from] SurfaceError),
    /// A scene the budget cannot take, naming the key.
    #[error("{key}: {reason}")]
    Scene {
        /// The key.
        key: &'static str,
        /// Why.
        reason: String,
    },
    /// A row of `budget-samples.csv` that cannot be read.
    #[error("budget row {row:?}: {reason}")]
    Row {
        /// The row's beginning.
        row: String,
        /// What is wrong.
        reason: String,
    },
}

impl BudgetError {
    /// True when the input is at fault.
    pub fn is_bad_input(&self) -> bool {
        match self {
            BudgetError::Design(e) => e.is_bad_input(),
            BudgetError::Verify(e) => e.is_bad_input(),
            BudgetError::Surface(e) => e.is_bad_input(),
            BudgetError::Scene { .. } | BudgetError::Row { .. } => true,
        }
    }
}

/// Which design a budget builds and perturbs.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BudgetDesign {
    /// The design for the flexible truss (the outer loop's converged one).
    #[default]
    Flexible,
    /// The conventional design — the loop's iteration 0, made for the
    /// undeformed truss (DESIGN §7) — built on the same flexible truss: its
    /// budget against the flexible design's shows which error the
    /// flexible-truss design removes and what is left.
    Conventional,
}

impl BudgetDesign {
    /// Its name in files and printouts.
    pub fn name(self) -> &'static str {
        match self {
            BudgetDesign::Flexible => "flexible",
            BudgetDesign::Conventional => "conventional",
        }
    }
}

/// What a budget draws: samples and seed (the scene's `[tolerances]` or the
/// command line's), and the design it builds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct BudgetSettings {
    /// Monte Carlo samples (0 without tolerances).
    pub samples: usize,
    /// Their seed.
    pub seed: u64,
    /// The design built.
    pub design: BudgetDesign,
}

impl BudgetSettings {
    /// The scene's, overridden by `samples` and `seed` when given.
    pub fn of(scene: &Scene, samples: Option<usize>, seed: Option<u64>) -> Self {
        let t = scene.tolerances.as_ref();
        BudgetSettings {
            samples: match t {
                None => 0,
                Some(t) => samples.or(t.samples).unwrap_or(DEFAULT_SAMPLES),
            },
            seed: seed.or(t.and_then(|t| t.seed)).unwrap_or(DEFAULT_SEED),
            design: BudgetDesign::Flexible,
        }
    }
}

/// Where a budget's time went, s.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct BudgetTimings {
    /// The design (`design::run`).
    pub design_s: f64,
    /// The design's assembly on the exact truss.
    pub assembly_s: f64,
    /// Factoring its tangent.
    pub linearise_s: f64,
    /// Each thermal case's nonlinear assembly, mean.
    pub thermal_case_s: Option<f64>,
    /// Each sample's nonlinear assembly, mean (wall time of all over their
    /// number: the samples run in parallel).
    pub sample_s: Option<f64>,
    /// Each linearised point (case or sample: one residual, one solve, the
    /// surface measured), mean.
    pub linear_point_s: Option<f64>,
}

/// A budget run: the rows of its points (all, or a shard's).
#[derive(Debug, Clone)]
pub struct BudgetRun {
    /// `(point, row)` in sweep order.
    pub rows: Vec<(usize, BudgetRow)>,
    /// Points of the whole sweep.
    pub points: usize,
    /// Where the time went.
    pub timings: BudgetTimings,
}

/// Points of the budget of `scene` with `settings`: facets, design, each
/// thermal case, each sample.
pub fn point_count(scene: &Scene, settings: &BudgetSettings) -> usize {
    2 + scene.effects.thermal.as_ref().map_or(0, |t| t.cases.len()) + settings.samples
}

/// The budget of `scene`: its design (`design::run` with `design`), then
/// the points of `shard` (see the module), calling `observe` after each.
///
/// # Errors
/// A scene the budget cannot take (inextensible cables, neither thermal
/// cases nor tolerances), a design or its assembly that fails. A case or
/// sample that fails is a row that says why.
pub fn run(
    scene: &Scene,
    design: &DesignSettings,
    settings: &BudgetSettings,
    shard: Shard,
    observe: &(dyn Fn(&BudgetRow) + Sync),
) -> Result<BudgetRun, BudgetError> {
    if !scene.effects.cable_elasticity {
        return Err(BudgetError::Scene {
            key: "effects.cable_elasticity",
            reason: "false: a budget perturbs the cables' cut lengths and EA, which \
                     inextensible cables do not have"
                .into(),
        });
    }
    let mut timings = BudgetTimings::default();
    let conventional_network;
    let clock = Instant::now();
    let mut run = design::run(scene, design, &mut |_, _| {})?;
    timings.design_s = clock.elapsed().as_secs_f64();
    let scene = &resolve(scene)?;
    // The design run's own assembly is the nominal one (on a rigid-truss
    // scene it has none on the exact truss, and the core assembles it).
    let (network, net, nominal) = match settings.design {
        BudgetDesign::Flexible => (&run.network, &run.report.net, run.assembled.take()),
        BudgetDesign::Conventional => {
            match (run.conventional_assembly.take(), &run.conventional_net) {
                (Some((network, assembled)), Some(net)) => {
                    conventional_network = network;
                    (&conventional_network, net, Some(assembled))
                }
                _ => {
                    return Err(BudgetError::Scene {
                        key: "effects.truss",
                        reason: "rigid: the design is made for the undeformed truss already, \
                             there is no conventional design to compare"
                            .into(),
                    })
                }
            }
        }
    };
    let clock = Instant::now();
    let core = PerturbedAssembly::new(scene, &run.mesh, network, net, nominal)?;
    timings.assembly_s = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    let tangent = core.linearise()?;
    timings.linearise_s = clock.elapsed().as_secs_f64();

    let thermal = ThermalExpansion::of(scene);
    let cases = thermal.as_ref().map_or(&[][..], |t| t.cases());
    let tolerances = scene
        .tolerances
        .as_ref()
        .map(|t| ToleranceModel::new(t, &run.mesh, network, net, &scene.cables));
    let points = point_count(scene, settings);
    let mine = shard.points(points);
    let first_sample = 2 + cases.len();
    let mesh = &run.mesh;
    // Time of the linearised points (solve and measurement), and their count.
    let linear_time = std::sync::Mutex::new((0.0f64, 0usize));
    let row_of = |k: usize| -> Result<BudgetRow, BudgetError> {
        let measured =
            |r: Result<_, BudgetError>| r.and_then(|v| core.change(&v)).map_err(|e| e.to_string());
        let row = if k == 0 {
            let nodes = &mesh.network.nodes[..mesh.n_front_nodes];
            let raw = facet_rms(&mesh.paraboloid, nodes, &mesh.front_triangles)?;
            let fit = best_fit_facets(&mesh.paraboloid, nodes, &mesh.front_triangles)?;
            BudgetRow {
                kind: PointKind::Facets,
                name: "facets".into(),
                nonlinear: Ok(Measured {
                    raw_mm: 1e3 * raw.axial_m,
                    best_fit_mm: 1e3 * fit.rms.axial_m,
                    half_path_mm: 1e3 * fit.rms.half_path_m,
                    focal_length_m: fit.paraboloid.focal_length_m,
                    max_tension_change_pct: 0.0,
                    slack_cables: Vec::new(),
                }),
                linear: None,
            }
        } else if k == 1 {
            BudgetRow {
                kind: PointKind::Design,
                name: "design".into(),
                nonlinear: Ok(core.design_surface()?),
                linear: None,
            }
        } else {
            let (kind, name, p) = if k < first_sample {
                let case = &cases[k - 2];
                let effect = thermal.as_ref().expect("cases come from the effect");
                let p = thermal_perturbation(effect, case, mesh, network, &net.nodes_xyz_m);
                (PointKind::Thermal, case.name.clone(), p)
            } else {
                let s = k - first_sample;
                let model = tolerances.as_ref().expect("samples come from tolerances");
                (
                    PointKind::Sample,
                    format!("sample {s}"),
                    model.sample(settings.seed, s),
                )
            };
            let nonlinear = measured(core.nonlinear(&tangent, &p));
            let clock = Instant::now();
            let linear = Some(measured(core.linear(&tangent, &p)));
            let mut spent = linear_time.lock().unwrap_or_else(|e| e.into_inner());
            spent.0 += clock.elapsed().as_secs_f64();
            spent.1 += 1;
            BudgetRow {
                kind,
                name,
                nonlinear,
                linear,
            }
        };
        observe(&row);
        Ok(row)
    };
    let (fixed, sampled): (Vec<usize>, Vec<usize>) = mine.iter().partition(|&&k| k < first_sample);
    let mut rows = Vec::with_capacity(mine.len());
    let clock = Instant::now();
    for &k in &fixed {
        rows.push((k, row_of(k)?));
    }
    let n_cases = fixed.iter().filter(|&&k| k >= 2).count();
    if n_cases > 0 {
        timings.thermal_case_s = Some(clock.elapsed().as_secs_f64() / n_cases as f64);
    }
    let clock = Instant::now();
    let sampled_rows = sampled
        .par_iter()
        .map(|&k| row_of(k).map(|r| (k, r)))
        .collect::<Result<Vec<_>, _>>()?;
    if !sampled.is_empty() {
        timings.sample_s = Some(clock.elapsed().as_secs_f64() / sampled.len() as f64);
    }
    rows.extend(sampled_rows);
    let (spent, count) = *linear_time.lock().unwrap_or_else(|e| e.into_inner());
    if count > 0 {
        timings.linear_point_s = Some(spent / count as f64);
    }
    Ok(BudgetRun {
        rows,
        points,
        timings,
    })
}

/// The scene with its rings chosen (as the design chose them).
fn resolve(scene: &Scene) -> Result<Scene, BudgetError> {
    Ok(crate::surface::resolve_front_rings(scene)?)
}
