//! The whole job of `ringmesh design`, as one library call ([`run`]): the
//! scene's nets, the outer loop with each relaxation asked for, the truss's
//! margin to its limit load under the design's pull, the design cut to length
//! and assembled on the flexible truss, and the conventional design — the
//! loop's iteration 0, made for the undeformed truss — assembled on the same
//! truss (paper §5, Figure 2).

use std::time::Instant;

use serde::Serialize;

use super::observer::{DesignObserver, DesignStage, Iterations};
use super::outer_loop::{IterationRecord, LoopOutcome, LoopSettings};
use super::relaxation::RelaxationKind;
use super::scene_nets::{default_solver, SceneNets};
use super::summary::LoopSummary;
use super::tied_nets::TiedNetSettings;
use super::DesignError;
use crate::effects::SceneEffects;
use crate::geometry::ReflectorMesh;
use crate::mechanics::LimitSearch;
use crate::network::Network;
use crate::scene::{Scene, TrussModel};
use crate::status::Termination;
use crate::surface::{budget, resolve_front_rings, FrontSurface, SurfaceBudget};
use crate::truss::{RingTruss, RingTrussBuilder, TrussError};
use crate::uniformity::{Design, SolverKind, UniformitySet};
use crate::verify::{
    assemble, Assembled, AssemblyInputs, AssemblyStart, Perturbation, Verification,
};

/// Choices of a design run: plain data with defaults.
#[derive(Debug, Clone)]
pub struct DesignSettings {
    /// The uniformity solver (default: the scene's,
    /// [`default_solver`]).
    pub solver: Option<SolverKind>,
    /// The truss model (default: the scene's `[effects] truss`).
    pub truss: Option<TrussModel>,
    /// Relaxation policies: the first makes the design; the others only add
    /// their convergence histories for comparison.
    pub relaxations: Vec<RelaxationKind>,
    /// Stopping tolerance on `‖G(C) − C‖∞`, m.
    pub tolerance_m: f64,
    /// Most outer iterations.
    pub max_iterations: usize,
    /// Tolerances and budgets of the two-stage design of each iteration.
    pub tied_nets: TiedNetSettings,
}

impl Default for DesignSettings {
    fn default() -> Self {
        let loop_settings = LoopSettings::default();
        DesignSettings {
            solver: None,
            truss: None,
            relaxations: vec![loop_settings.relaxation],
            tolerance_m: loop_settings.tolerance_m,
            max_iterations: loop_settings.max_iterations,
            tied_nets: TiedNetSettings::default(),
        }
    }
}

/// One relaxation policy's run of the outer loop.
#[derive(Debug, Clone, Serialize)]
pub struct LoopRun {
    /// The policy.
    pub relaxation: RelaxationKind,
    /// How it ended, its iterations, final residual and wall time (a
    /// comparison run that failed: [`LoopSummary::failed`]).
    #[serde(flatten)]
    pub summary: LoopSummary,
    /// Per iteration.
    pub history: Vec<IterationRecord>,
    /// Why a comparison run stopped without a result (the truss found no
    /// equilibrium once the iteration ran away, say).
    pub error: Option<String>,
}

/// Where a design run's wall time goes, s: every stage once, so that the
/// stages, less the time two of them ran side by side (`beside_s`), add up
/// to `total_s` (up to the writing of `design.json` itself).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Timings {
    /// Reading the scene (and the tables it names).
    pub read_s: f64,
    /// The effects, the mesh, the uniformity problem and the two-stage
    /// design problem.
    pub mesh_s: f64,
    /// Building the design loop's truss oracle (frame, symbolic analysis).
    pub truss_setup_s: f64,
    /// The design loop's uniformity designs, one per outer iteration.
    pub uniformity_s: Vec<f64>,
    /// The design loop's truss responses, one per outer iteration.
    pub truss_s: Vec<f64>,
    /// The rest of the design loop (relaxation, bookkeeping).
    pub loop_other_s: f64,
    /// The other relaxations' loops, run for comparison.
    pub comparison_loops_s: f64,
    /// The truss's limit margin under the design's pull (on a second core,
    /// beside the stages after it).
    pub margin_s: f64,
    /// The design cut to length and assembled.
    pub verification_s: f64,
    /// The surface error budget (facet RMS and best fits).
    pub surface_s: f64,
    /// The conventional design (the loop's iteration 0) assembled.
    pub conventional_s: f64,
    /// Writing every file but `design.json`.
    pub writing_s: f64,
    /// The wall time the margin ran beside the verification, the surface
    /// budget and the conventional design: counted in two stages above, and
    /// once in [`Timings::stages_s`].
    pub beside_s: f64,
    /// Wall time from reading the scene to writing `design.json`.
    pub total_s: f64,
}

impl Timings {
    /// The design loop's stages from its outcome and `loop_s`, its wall time
    /// with the oracle's construction.
    fn design_loop(&mut self, loop_s: f64, outcome: &LoopOutcome) {
        self.uniformity_s = outcome.history.iter().map(|r| r.design_time_s).collect();
        self.truss_s = outcome.history.iter().map(|r| r.truss_time_s).collect();
        self.truss_setup_s = loop_s - outcome.time_s;
        self.loop_other_s = outcome.time_s
            - self.uniformity_s.iter().sum::<f64>()
            - self.truss_s.iter().sum::<f64>();
    }

    /// The design loop's wall time with its truss's set-up, s.
    pub fn design_loop_s(&self) -> f64 {
        self.truss_setup_s
            + self.uniformity_s.iter().sum::<f64>()
            + self.truss_s.iter().sum::<f64>()
            + self.loop_other_s
    }

    /// The sum of the stages, s (`total_s` less what no stage measured).
    pub fn stages_s(&self) -> f64 {
        self.read_s
            + self.mesh_s
            + self.truss_setup_s
            + self.uniformity_s.iter().sum::<f64>()
            + self.truss_s.iter().sum::<f64>()
            + self.loop_other_s
            + self.comparison_loops_s
            + self.margin_s
            + self.verification_s
            + self.surface_s
            + self.conventional_s
            + self.writing_s
            - self.beside_s
    }
}

/// `design.json`: the outer loop's design, its verification by assembly, and
/// the conventional (rigid-truss) design verified on the same truss.
#[derive(Debug, Clone, Serialize)]
pub struct DesignReport {
    /// The scene's name.
    pub scene: String,
    /// The uniformity solver.
    pub solver: String,
    /// The truss model of the loop.
    pub truss: TrussModel,
    /// The relaxation policy that made the design.
    pub relaxation: RelaxationKind,
    /// How the loop ended.
    pub termination: Termination,
    /// Outer iterations.
    pub outer_iterations: usize,
    /// Final fixed-point residual `‖G(C) − C‖∞`, m.
    pub boundary_residual_m: f64,
    /// The loop's stopping tolerance on it, m.
    pub tolerance_m: f64,
    /// The design's largest set ratio `Tmax/Tmin`.
    pub ratio: f64,
    /// Wall time of the whole run (every loop, verifications), s.
    pub time_s: f64,
    /// The design loop's iterations.
    pub history: Vec<IterationRecord>,
    /// Every policy run, the design's first.
    pub runs: Vec<LoopRun>,
    /// The design cut to length and assembled.
    pub verification: Verification,
    /// The surface error budget of the design as built: facets, design,
    /// total, raw and best fit, the gain loss at the scene's frequency.
    pub surface: SurfaceBudget,
    /// The rigid-truss design assembled on the same truss (absent when the
    /// loop's truss is rigid: then it is the design itself).
    pub conventional: Option<Verification>,
    /// The flexible truss's limit load under the design's pull (DESIGN §9):
    /// stable up to `stable_to` × the pull (absent for a rigid truss).
    pub limit_margin: Option<LimitSearch>,
    /// The boundary the design is made for, `C` (top hinges, then bottom), m.
    pub boundary_m: Vec<[f64; 3]>,
    /// The design: q, tensions, lengths, nodes, reactions, spreads.
    pub net: Design,
    /// Where the wall time went (reading and writing are the command's:
    /// zero when the library is called directly).
    pub timings: Timings,
}

impl DesignReport {
    /// The design loop's summary: its run, the first of `runs`.
    ///
    /// # Panics
    /// If `runs` is empty ([`run`] always records the design's).
    #[track_caller]
    pub fn design_summary(&self) -> LoopSummary {
        self.runs
            .first()
            .expect("the design's run is recorded")
            .summary
    }
}

/// A design run: the report and what its files are drawn from.
#[derive(Debug)]
pub struct DesignRun {
    /// The report (`design.json`).
    pub report: DesignReport,
    /// The scene's nets and truss layout.
    pub mesh: ReflectorMesh,
    /// The network at the design's geometry (the final boundary `C`).
    pub network: Network,
    /// The conventional design (the loop's iteration 0), when the truss
    /// deforms: the one `report.conventional` assembles.
    pub conventional_net: Option<Design>,
    /// The uniformity sets the design makes uniform (cables of `network`).
    pub sets: Vec<UniformitySet>,
    /// The design assembled on the flexible truss (`report.verification`'s
    /// equilibrium), when the truss deforms: what a perturbed assembly of
    /// it starts from ([`crate::budget`]).
    pub assembled: Option<Assembled>,
    /// The conventional design's network and its assembly on the same truss
    /// (`report.conventional`'s), when the truss deforms.
    pub conventional_assembly: Option<(Network, Assembled)>,
}

/// The outer design loop (net design ⇄ truss response) of `scene` with each
/// relaxation `settings` asks for, the design verified by assembly, its
/// margin to the truss's limit load, and the conventional design (the loop's
/// iteration 0) verified on the same truss. `observe` sees each outer
/// iteration of each policy.
///
/// # Errors
/// Invalid settings or scene values, a design or truss that fails, or a pull
/// past the truss's limit load ([`TrussError::PastLimitLoad`]); a comparison
/// policy that fails is recorded in its [`LoopRun`], not an error.
pub fn run(
    scene: &Scene,
    settings: &DesignSettings,
    observe: &mut dyn FnMut(RelaxationKind, &IterationRecord),
) -> Result<DesignRun, DesignError> {
    run_observed(scene, settings, &mut Iterations(observe))
}

/// [`run`], with `observer` told of each outer iteration and of each stage
/// after the loop as it begins.
///
/// # Errors
/// As [`run`].
pub fn run_observed(
    scene: &Scene,
    settings: &DesignSettings,
    observer: &mut dyn DesignObserver,
) -> Result<DesignRun, DesignError> {
    let clock = Instant::now();
    let mut timings = Timings::default();
    // A scene that leaves its net to a surface target gets the coarsest net
    // that meets it (the command layer has usually chosen it already).
    let resolved = resolve_front_rings(scene)?;
    let scene = &resolved;
    let model = settings.truss.unwrap_or(scene.effects.truss);
    let mut scene_nets = SceneNets::new(scene)?;
    scene_nets.nets = scene_nets.nets.with_settings(settings.tied_nets.clone())?;
    timings.mesh_s = clock.elapsed().as_secs_f64();
    let (mesh, nets) = (&scene_nets.mesh, &scene_nets.nets);
    let solver = settings
        .solver
        .unwrap_or_else(|| default_solver(scene))
        .build(None);
    let relaxations = if settings.relaxations.is_empty() {
        vec![RelaxationKind::default()]
    } else {
        settings.relaxations.clone()
    };
    let mut runs = Vec::new();
    let mut outcome = None;
    for &relaxation in &relaxations {
        let loop_settings = LoopSettings {
            relaxation,
            tolerance_m: settings.tolerance_m,
            max_iterations: settings.max_iterations,
            ..LoopSettings::default()
        };
        let mut history = Vec::new();
        let loop_clock = Instant::now();
        let result = scene_nets.design_loop(solver.as_ref(), model, &loop_settings, &mut |r| {
            history.push(r.clone());
            observer.iteration(relaxation, r)
        });
        let loop_s = loop_clock.elapsed().as_secs_f64();
        if outcome.is_some() {
            timings.comparison_loops_s += loop_s;
        }
        match result {
            Ok(result) => {
                if outcome.is_none() {
                    timings.design_loop(loop_s, &result);
                }
                runs.push(LoopRun {
                    relaxation,
                    summary: LoopSummary::of(&result),
                    history: result.history.clone(),
                    error: None,
                });
                outcome.get_or_insert(result);
            }
            // A comparison run may fail without losing the design.
            Err(e) if outcome.is_some() => runs.push(LoopRun {
                relaxation,
                summary: LoopSummary::failed(&history),
                history,
                error: Some(e.to_string()),
            }),
            // No truss equilibrium: say how far below the pull the truss's
            // stability ends (the rigid-truss design's pull, the loop's first).
            Err(
                e @ DesignError::Truss {
                    source: TrussError::NoEquilibrium { .. },
                    ..
                },
            ) => {
                let first =
                    nets.design(solver.as_ref(), &crate::truss::layout_points(&mesh.truss))?;
                return Err(
                    match design_margin(scene_nets.truss_frame(), &first.design) {
                        Err(past) => past,
                        Ok(_) => e,
                    },
                );
            }
            Err(e) => return Err(e),
        }
    }
    let outcome = outcome.expect("at least one relaxation");
    let effects = &scene_nets.effects;
    // The flexible truss's frame, constructed once for the loop's oracle,
    // the margin and both assemblies.
    let frame = outcome.truss_deforms.then(|| scene_nets.truss_frame());
    // The margin needs only the truss and the design: it runs on a second
    // core beside the verification, the surface budget and the conventional
    // design (which follow one another), and its error, the first stage's,
    // is the one returned.
    let after_loop = Instant::now();
    observer.stage(DesignStage::Margin);
    let (margin, later) = std::thread::scope(|scope| {
        let margin = scope.spawn(|| {
            let stage = Instant::now();
            let margin = frame
                .map(|frame| design_margin(frame, &outcome.design))
                .transpose();
            (margin, stage.elapsed().as_secs_f64())
        });
        let later = later_stages(
            scene,
            mesh,
            effects,
            &outcome,
            frame,
            observer,
            &mut timings,
        );
        let margin = margin
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        (margin, later)
    });
    let (limit_margin, margin_s) = margin;
    let limit_margin = limit_margin?;
    let Later {
        network,
        sets,
        verification,
        surface,
        conventional_assembly,
        assembled,
    } = later?;
    timings.margin_s = margin_s;
    timings.beside_s =
        (margin_s + timings.verification_s + timings.surface_s + timings.conventional_s
            - after_loop.elapsed().as_secs_f64())
        .max(0.0);
    let conventional = conventional_assembly
        .as_ref()
        .map(|(_, a)| a.verification.clone());
    let conventional_net = conventional_assembly
        .as_ref()
        .map(|_| outcome.initial.design.clone());
    let report = DesignReport {
        scene: scene.name.clone(),
        solver: solver.name().to_string(),
        truss: model,
        relaxation: relaxations[0],
        termination: outcome.termination,
        outer_iterations: outcome.history.len(),
        boundary_residual_m: outcome.boundary_residual_m(),
        tolerance_m: settings.tolerance_m,
        ratio: outcome.design.ratio,
        time_s: clock.elapsed().as_secs_f64(),
        history: outcome.history.clone(),
        runs,
        verification,
        surface,
        conventional,
        limit_margin,
        boundary_m: outcome.boundary_m.clone(),
        net: outcome.design,
        timings,
    };
    Ok(DesignRun {
        report,
        mesh: scene_nets.mesh,
        network,
        conventional_net,
        sets,
        assembled,
        conventional_assembly,
    })
}

/// What the stages after the margin make: the design's network and sets, its
/// verification by assembly, the surface budget, the conventional design's
/// assembly, and the design's own assembly when the truss deforms.
struct Later {
    network: Network,
    sets: Vec<UniformitySet>,
    verification: Verification,
    surface: SurfaceBudget,
    conventional_assembly: Option<(Network, Assembled)>,
    assembled: Option<Assembled>,
}

/// The stages after the loop that follow one another — the verification,
/// the surface budget and the conventional design — each timed in
/// `timings` and announced to `observer` as it begins.
fn later_stages(
    scene: &Scene,
    mesh: &ReflectorMesh,
    effects: &SceneEffects,
    outcome: &LoopOutcome,
    frame: Option<&RingTrussBuilder>,
    observer: &mut dyn DesignObserver,
    timings: &mut Timings,
) -> Result<Later, DesignError> {
    observer.stage(DesignStage::Verification);
    let stage = Instant::now();
    let network = outcome.problem.network().clone();
    let sets = outcome.problem.sets().to_vec();
    let inputs = AssemblyInputs {
        scene,
        mesh,
        effects,
        network: &network,
        design: &outcome.design,
        frame,
    };
    let start = outcome
        .truss_equilibrium
        .as_ref()
        .map_or(AssemblyStart::Unknown, AssemblyStart::Truss);
    let assembled = assemble(&inputs, start, &Perturbation::none())?;
    let verification = assembled.verification.clone();
    timings.verification_s = stage.elapsed().as_secs_f64();
    observer.stage(DesignStage::Surface);
    let stage = Instant::now();
    let n_front = mesh.n_front_nodes;
    let surface = budget(
        &mesh.paraboloid,
        FrontSurface {
            // The design surface: the net as generated, on the paraboloid
            // (the same net `mesh` and the choice of rings measure).
            designed_m: &mesh.network.nodes[..n_front],
            built_m: &verification.nodes_xyz_m[..n_front],
            free: &network.fixed_mask()[..n_front]
                .iter()
                .map(|fixed| !fixed)
                .collect::<Vec<_>>(),
            triangles: &mesh.front_triangles,
        },
        &scene.surface,
        scene.front_net.rings,
        scene.front_net.chosen.as_ref(),
    )?;
    timings.surface_s = stage.elapsed().as_secs_f64();
    observer.stage(DesignStage::Conventional);
    let stage = Instant::now();
    // The conventional design is the loop's iteration 0: the design for the
    // undeformed attachment points, assembled from the undeformed truss on
    // the design's analysis of the assembly (the same network and truss,
    // other cut lengths).
    let conventional_assembly = match frame {
        None => None,
        Some(frame) => {
            let network = outcome.initial.problem.network();
            let inputs = AssemblyInputs {
                scene,
                mesh,
                effects,
                network,
                design: &outcome.initial.design,
                frame: Some(frame),
            };
            let conventional = assemble(
                &inputs,
                AssemblyStart::Beside(&assembled),
                &Perturbation::none(),
            )?;
            Some((network.clone(), conventional))
        }
    };
    let assembled = frame.map(|_| assembled);
    timings.conventional_s = stage.elapsed().as_secs_f64();
    Ok(Later {
        network,
        sets,
        verification,
        surface,
        conventional_assembly,
        assembled,
    })
}

/// The margin of the ring truss of `frame` ([`SceneNets::truss_frame`]) to
/// its limit load under `design`'s pull.
///
/// # Errors
/// A truss that cannot be built, or a pull it cannot carry stably
/// ([`TrussError::PastLimitLoad`]).
pub fn design_margin(
    frame: &RingTrussBuilder,
    design: &Design,
) -> Result<LimitSearch, DesignError> {
    // The net pulls on its supports with −F_g.
    let pull = design.pull_n();
    let truss = RingTruss::from_frame(frame.clone()).map_err(TrussError::from)?;
    let margin = crate::truss::limit_margin(truss, &pull)?;
    if margin.stable_to < 1.0 {
        return Err(TrussError::PastLimitLoad {
            stable_to: margin.stable_to,
            bound: margin.bound,
        }
        .into());
    }
    Ok(margin)
}
