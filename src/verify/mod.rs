//! Verification of a design by assembly (paper §5, DESIGN §7): every cable cut
//! to its unstressed length `L₀ = ℓ/(1 + T/EA)`, attached to the *undeformed*
//! truss, and the whole solved to static equilibrium — what will be built.
//!
//! The cables are tension-only elastic elements ([`crate::mechanics::Cable`]);
//! their prestrain is ramped as load steps from the stress-free assembly
//! (cables at the distance of their end points) to the cut lengths. The truss
//! is either rigid (the attachment points held where the layout puts them)
//! or the flexible ring truss of the scene (geometrically exact beams, hinges
//! and joints, isostatic support).
//!
//! `[effects] cable_elasticity = false` assembles inextensible cables instead
//! (design lengths, by a penalty stiffness): [`CableModel`], whose module
//! documents the model and its stiffening factor. [`Verification::cable_model`]
//! says which model an assembly used.

mod error;
mod perturbation;
mod stiffening;

pub use error::VerifyError;
pub use perturbation::Perturbation;

pub use crate::effects::{CableModel, INEXTENSIBLE_STIFFENING};

use std::borrow::Cow;
use std::time::Instant;

use nalgebra::Vector3;
use serde::Serialize;

use crate::algebra::norm3;
use crate::effects::SceneEffects;
use crate::geometry::{ReflectorMesh, RingTrussLayout};
use crate::mechanics::{
    Frame, Linearisation, Model, ModelBuilder, NodeId, StaticSettings, StaticSolver,
};
use crate::network::Network;
use crate::scene::Scene;
use crate::surface::node_rms;
use crate::truss::{ExactTruss, RingTruss, RingTrussBuilder, TrussEquilibrium, TrussOracle};
use crate::uniformity::Design;

/// What the cables are assembled on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum AssemblyTruss {
    /// Attachment points held at the layout's hinge positions.
    Rigid,
    /// The scene's ring truss, geometrically exact, undeformed before assembly.
    Flexible,
}

/// The assembled equilibrium, judged against the design.
#[derive(Debug, Clone, Serialize)]
pub struct Verification {
    /// The truss the cables were assembled on.
    pub truss: AssemblyTruss,
    /// The cables assembled: elastic or inextensible (`[effects] cable_elasticity`).
    pub cable_model: CableModel,
    /// Axial stiffness of every assembled cable, N (the penalty's for
    /// inextensible cables).
    pub cable_axial_stiffness_n: f64,
    /// RMS axial deviation of the front net's free nodes from the paraboloid, mm.
    pub rms_mm: f64,
    /// Largest axial deviation of a front-net free node from the paraboloid, mm.
    pub max_deviation_mm: f64,
    /// Largest `|T − T_design|/T_design` over all cables, %.
    pub max_tension_change_pct: f64,
    /// Largest distance of an attachment point from the boundary the design
    /// assumed, mm.
    pub boundary_deviation_mm: f64,
    /// Largest distance of a free net node from its designed position, mm.
    pub max_node_shift_mm: f64,
    /// Cables not longer than their cut length at equilibrium.
    pub slack_cables: Vec<usize>,
    /// Newton iterations of the assembly solve (every stage's, for
    /// inextensible cables).
    pub newton_iterations: usize,
    /// Load (prestrain) steps (every stage's, for inextensible cables).
    pub load_steps: usize,
    /// Wall time of building and solving the assembly, s.
    pub time_s: f64,
    /// Assembled positions of the net's nodes, m: n_nodes × 3.
    #[serde(skip)]
    pub nodes_xyz_m: Vec<[f64; 3]>,
    /// Assembled cable tensions, N: n_edges.
    #[serde(skip)]
    pub tensions_n: Vec<f64>,
    /// The deformed truss as straight segments between beam nodes, m.
    #[serde(skip)]
    pub truss_segments_m: Vec<[[f64; 3]; 2]>,
    /// The truss model's nodes at the ends of each segment (the ring
    /// truss's own numbering: [`crate::truss::RingTruss`]'s model).
    #[serde(skip)]
    pub truss_segment_nodes: Vec<[usize; 2]>,
}

/// Newton iterations allowed from the truss guess before the ramp takes
/// over. The designed assemblies of every shipped scene converge from it in
/// one, the 26 m scenes' conventional ones in 2–4; super-60m's conventional
/// one (72 cables going slack) did not converge in the 20 it used to be
/// given, and its ramp then took 8 — the 20 were 60 % of that comparison's
/// time (super-60m 11.0 s → 4.9 s with this budget, same equilibrium).
const GUESS_ITERATIONS: usize = 4;

fn vector(p: &[f64; 3]) -> Vector3<f64> {
    Vector3::new(p[0], p[1], p[2])
}

fn array(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

/// Assemble `design` (made on `network`, whose fixed nodes are the attachment
/// points in the truss's order and sit on the boundary the design assumed) on
/// `truss`, and solve.
///
/// `equilibrium` is the flexible truss's equilibrium under the design's pull
/// when the caller has it (the design loop's last, of the same scene's exact
/// truss); without it, it is solved here. The loop's own is the better start:
/// on a truss with a soft mode, two solves to the same force tolerance can
/// differ by more than the net tolerates (a 120-bay ring with a 56 mm net
/// cable: 3.1e-6 m at the hinges, against the loop's 6.8e-19 m fixed-point
/// residual — and Newton diverged from the 79 N that put on the net).
///
/// # Errors
/// A design of another network, an invalid assembly (named), or no
/// equilibrium.
pub fn verify(
    scene: &Scene,
    mesh: &ReflectorMesh,
    effects: &SceneEffects,
    network: &Network,
    design: &Design,
    truss: AssemblyTruss,
    equilibrium: Option<&TrussEquilibrium>,
) -> Result<Verification, VerifyError> {
    let frame = match truss {
        AssemblyTruss::Rigid => None,
        AssemblyTruss::Flexible => Some(RingTruss::builder(scene, &mesh.truss, effects)),
    };
    verify_on_frame(
        scene,
        mesh,
        effects,
        network,
        design,
        frame.as_ref(),
        equilibrium,
    )
}

/// [`verify`] on the flexible truss's frame `frame` (constructed once by the
/// caller, [`RingTruss::builder`], and copied here), or on the rigid
/// attachment points when `frame` is `None`.
///
/// # Errors
/// As [`verify`].
pub fn verify_on_frame(
    scene: &Scene,
    mesh: &ReflectorMesh,
    effects: &SceneEffects,
    network: &Network,
    design: &Design,
    frame: Option<&RingTrussBuilder>,
    equilibrium: Option<&TrussEquilibrium>,
) -> Result<Verification, VerifyError> {
    let inputs = AssemblyInputs {
        scene,
        mesh,
        effects,
        network,
        design,
        frame,
    };
    let start = equilibrium.map_or(AssemblyStart::Unknown, AssemblyStart::Truss);
    Ok(assemble(&inputs, start, &Perturbation::none())?.verification)
}

/// What an assembly is made of: the scene, its mesh and effects, the design
/// (made on `network`, whose fixed nodes are the attachment points in the
/// truss's order) and the flexible truss's frame (`None`: the rigid
/// attachment points).
#[derive(Debug, Clone, Copy)]
pub struct AssemblyInputs<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Its nets and truss layout.
    pub mesh: &'a ReflectorMesh,
    /// Its effects.
    pub effects: &'a SceneEffects,
    /// The network the design is made on.
    pub network: &'a Network,
    /// The design.
    pub design: &'a Design,
    /// The flexible truss's frame, or `None` for the rigid truss.
    pub frame: Option<&'a RingTrussBuilder>,
}

/// An assembled equilibrium: its verification, and what a perturbed
/// assembly starts from ([`assemble`] with `start`) or is linearised about
/// ([`Assembled::linearise`]).
#[derive(Clone)]
pub struct Assembled {
    /// The assembly judged against the design.
    pub verification: Verification,
    /// The whole assembly's state (truss, net points, multipliers) and
    /// constraint scale: a start for the same assembly perturbed.
    pub state: TrussEquilibrium,
    solver: StaticSolver,
}

/// The models of one assembly: the truss (perturbed) and the net's points,
/// and the cables to put on them — built into a model only when a path
/// asks for it ([`AssemblyModels::cut`] and the ramps), since a budget's
/// samples mostly need the first alone.
struct AssemblyModels {
    /// Truss and points only.
    bare: ModelBuilder,
    /// Every cable: its model nodes, EA, the distance of its ends in
    /// `bare` and its (perturbed) cut length.
    cables: Vec<CableItem>,
    /// Model node of each net node.
    node_of: Vec<NodeId>,
}

/// One cable of an assembly ([`AssemblyModels`]).
struct CableItem {
    nodes: [NodeId; 2],
    ea_n: f64,
    start_m: f64,
    cut_m: f64,
}

impl AssemblyModels {
    fn new(inputs: &AssemblyInputs<'_>, perturbation: &Perturbation) -> Result<Self, VerifyError> {
        let AssemblyInputs {
            scene,
            mesh,
            network,
            design,
            frame,
            ..
        } = *inputs;
        let layout = &mesh.truss;
        let hinges: Vec<[f64; 3]> = layout
            .top_m
            .iter()
            .chain(&layout.bottom_m)
            .copied()
            .collect();
        if network.fixed.len() != hinges.len() {
            return Err(VerifyError::NetworkOfAnotherTruss {
                fixed_nodes: network.fixed.len(),
                attachments: hinges.len(),
            });
        }
        let n_rods = frame.map_or(0, |f| f.builder.rod_count());
        perturbation.check(network.n_edges(), n_rods, hinges.len())?;
        let offset = |k: usize| {
            perturbation
                .hinge_offsets_m
                .as_ref()
                .map_or(Vector3::zeros(), |o| vector(&o[k]))
        };
        let (mut b, attachments, dead_loads) = match frame {
            None => {
                if perturbation.rod_stretch.is_some() {
                    return Err(VerifyError::Unsupported(
                        "a rigid truss has no rods to stretch".into(),
                    ));
                }
                let mut b = ModelBuilder::new();
                let points = hinges
                    .iter()
                    .enumerate()
                    .map(|(k, p)| {
                        let n = b.add_point(vector(p) + offset(k));
                        b.fix(n, [true; 6]);
                        n
                    })
                    .collect::<Vec<_>>();
                (b, points, Vec::new())
            }
            Some(frame) => {
                let RingTrussBuilder {
                    mut builder,
                    attachments,
                    dead_loads,
                    ..
                } = frame.clone();
                if let Some(stretch) = &perturbation.rod_stretch {
                    builder.stretch_rods(stretch);
                }
                if perturbation.hinge_offsets_m.is_some() {
                    for (k, &n) in attachments.iter().enumerate() {
                        builder.displace_node(n, offset(k));
                    }
                }
                (builder, attachments, dead_loads)
            }
        };
        // Net node → model node: attachments for the fixed ones, new points for the
        // free ones at their designed positions.
        let mut node_of: Vec<Option<NodeId>> = vec![None; network.n_nodes()];
        for (k, &i) in network.fixed.iter().enumerate() {
            node_of[i] = Some(attachments[k]);
        }
        for (i, slot) in node_of.iter_mut().enumerate() {
            if slot.is_none() {
                *slot = Some(b.add_point(vector(&design.nodes_xyz_m[i])));
            }
        }
        let node_of: Vec<NodeId> = node_of
            .into_iter()
            .map(|n| n.expect("every node mapped"))
            .collect();
        // The effects' dead loads: the truss's self weight, and the net's nodal
        // loads of the design (the cables' self weight, lumped as designed).
        for l in dead_loads {
            b.add_load(l.node, l.force_n, l.moment_nm);
        }
        for (i, p) in network.loads.iter().flatten().enumerate() {
            if p.iter().any(|&v| v != 0.0) {
                b.add_load(node_of[i], vector(p), nalgebra::Vector3::zeros());
            }
        }
        let ea = scene.cables.axial_stiffness_n();
        let cables = network
            .edges
            .iter()
            .enumerate()
            .map(|(k, &[i, j])| {
                let nodes = [node_of[i], node_of[j]];
                let start_m = match (b.frame(nodes[0]), b.frame(nodes[1])) {
                    (Some(fa), Some(fc)) => (fc.position_m - fa.position_m).norm(),
                    _ => 0.0,
                };
                let designed_m = scene
                    .cables
                    .cut_length_m(design.lengths_m[k], design.tensions_n[k]);
                let factor = |f: &Option<Vec<f64>>| f.as_ref().map_or(1.0, |f| f[k]);
                CableItem {
                    nodes,
                    ea_n: ea * factor(&perturbation.cable_stiffness_factors),
                    start_m,
                    cut_m: designed_m * factor(&perturbation.cable_length_factors),
                }
            })
            .collect();
        Ok(AssemblyModels {
            bare: b,
            cables,
            node_of,
        })
    }

    /// The truss and points with every cable's unstressed length ramped
    /// between `ends(cable)` ([`crate::mechanics::Cable`]'s load factors 0
    /// and 1).
    fn with_cables(&self, ends: impl Fn(usize, &CableItem) -> [f64; 2]) -> ModelBuilder {
        let mut b = self.bare.clone();
        for (k, c) in self.cables.iter().enumerate() {
            b.add_cable(c.nodes[0], c.nodes[1], c.ea_n, ends(k, c));
        }
        b
    }

    /// Truss, points and cables at their cut lengths.
    fn cut(&self) -> ModelBuilder {
        self.with_cables(|_, c| [c.cut_m, c.cut_m])
    }

    /// The same with the cables' unstressed lengths ramped from the
    /// stress-free distance of their ends.
    fn ramped(&self) -> ModelBuilder {
        self.with_cables(|_, c| [c.start_m, c.cut_m])
    }

    /// The same with the cables ramped from `from_m` (network order), the
    /// cut lengths at which a warm start is an equilibrium, to their own.
    fn ramped_from(&self, from_m: &[f64]) -> ModelBuilder {
        self.with_cables(|k, c| [from_m[k], c.cut_m])
    }
}

/// The static solver's settings of every assembly: forces balanced to 1e-12
/// of the cables' (the net's tolerance is far below the truss's).
fn assembly_settings() -> StaticSettings {
    StaticSettings {
        tolerance: 1e-12,
        ..StaticSettings::default()
    }
}

/// Load steps a perturbed assembly's ramp from the design's cut lengths is
/// given: one whose net goes slack piece by piece can otherwise take
/// hundreds of cut steps, each a factorisation (a super-60m thermal case
/// ran for more than 5 minutes); past them the point fails, saying so,
/// and a budget reports it.
const PERTURBED_MAX_STEPS: usize = 40;

/// Chord (and Newton) iterations a perturbed assembly is given from its
/// design's tangent ([`Linearised::solve`]) before load steps take over:
/// super-60m's tolerance samples take 12–14.
const CHORD_ITERATIONS: usize = 40;

/// Where an assembly's Newton starts ([`assemble`]).
#[derive(Clone, Copy)]
pub enum AssemblyStart<'a> {
    /// Nothing known: the flexible truss's equilibrium under the design's
    /// pull is solved here (a rigid truss has none to solve).
    Unknown,
    /// The flexible truss's equilibrium under the design's pull (the design
    /// loop's last, see [`verify`]).
    Truss(&'a TrussEquilibrium),
    /// The same design's assembled equilibrium, for the design perturbed:
    /// its state starts Newton, its structure's analysis is shared
    /// ([`StaticSolver::with_model`]), and where Newton does not converge
    /// at once the cut lengths are ramped from its own.
    Assembly(&'a Assembled),
    /// The assembly of another design on the same network and truss, for a
    /// design whose net balances the *undeformed* truss (the conventional
    /// one beside the flexible): its analysis is shared, and Newton starts
    /// from the undeformed truss, where this net is in balance with its cut
    /// lengths, the prestrain ramped as from [`AssemblyStart::Unknown`].
    /// Measured against the two other starts: this design's own truss
    /// equilibrium under its pull (the deformed truss with the net where it
    /// was designed, out of balance by the boundary's motion) took 4 Newton
    /// iterations that did not converge on super-60m and super-100m before
    /// this path's 7 and 4, and converged in 4 where this path takes 2 on
    /// paper-26m and target-40m (super-100m's conventional stage 10.5 →
    /// 5.1–6.3 s); the other design's assembled state took 4 + 19 on
    /// super-60m.
    Beside(&'a Assembled),
}

/// Assemble `inputs`' design, as built with `perturbation`, and solve from
/// `start`.
///
/// From a truss equilibrium, Newton takes [`GUESS_ITERATIONS`]; if that
/// fails, the prestrain is ramped from the undeformed truss in load steps
/// (beside another design's assembly, at once). From the same design's
/// assembly, Newton takes as many; then the cut lengths are ramped from the
/// assembly's, in at most
/// [`PERTURBED_MAX_STEPS`] load steps, and the assembly fails if that
/// fails (the ramp from the undeformed truss would repeat the design's
/// whole assembly to find what this path could not, and took minutes for
/// nothing on small-hex's samples of 2 mm cut-length errors).
///
/// # Errors
/// As [`verify`]; a perturbation of the wrong size or one the assembly
/// cannot take (named); inextensible cables with a perturbation; a start
/// assembly of another structure.
pub fn assemble(
    inputs: &AssemblyInputs<'_>,
    start: AssemblyStart<'_>,
    perturbation: &Perturbation,
) -> Result<Assembled, VerifyError> {
    let AssemblyInputs {
        scene,
        mesh,
        effects,
        network,
        design,
        frame,
    } = *inputs;
    let clock = Instant::now();
    let n_edges = network.n_edges();
    if design.q.len() != n_edges || design.nodes_xyz_m.len() != network.n_nodes() {
        return Err(VerifyError::DesignOfAnotherNetwork {
            design_cables: design.q.len(),
            design_nodes: design.nodes_xyz_m.len(),
            network_cables: n_edges,
            network_nodes: network.n_nodes(),
        });
    }
    let cable_model = effects.cable_model();
    if cable_model == CableModel::Inextensible && !perturbation.is_none() {
        return Err(VerifyError::Unsupported(
            "inextensible cables (`[effects] cable_elasticity = false`) are assembled at \
             their design lengths only"
                .into(),
        ));
    }
    let models = AssemblyModels::new(inputs, perturbation)?;
    let ea = scene.cables.axial_stiffness_n();
    let settings = assembly_settings();
    // One Newton solve, no step cuts, a few iterations: from a good guess
    // it converges at once; otherwise a ramp is the better path.
    let once = StaticSettings {
        min_step: settings.initial_step,
        max_iterations: GUESS_ITERATIONS,
        ..settings.clone()
    };
    // The analysis of the structure: shared with another assembly's where
    // the start comes with one.
    let shared = match start {
        AssemblyStart::Assembly(a) | AssemblyStart::Beside(a) => Some(&a.solver),
        AssemblyStart::Unknown | AssemblyStart::Truss(_) => None,
    };
    let solver_of = |b: ModelBuilder| -> Result<StaticSolver, VerifyError> {
        let model = b.build()?;
        Ok(match shared {
            Some(s) => s.with_model(model)?,
            None => StaticSolver::new(model)?,
        })
    };
    let mut found = None;
    if let AssemblyStart::Assembly(from) = start {
        let start = &from.state.state;
        let solver = solver_of(models.cut())?;
        let s = solver.solve_from(start.clone(), 0.0, &once)?;
        if s.converged() {
            found = Some((solver, s));
        } else {
            let from_m: Vec<f64> = from
                .solver
                .model()
                .cables()
                .iter()
                .map(|c| c.rest_length_m(1.0))
                .collect();
            let solver = solver_of(models.ramped_from(&from_m))?;
            let ramp = StaticSettings {
                max_steps: PERTURBED_MAX_STEPS,
                ..settings.clone()
            };
            let s = solver.solve_from(start.clone(), 0.0, &ramp)?;
            // At load factor 1 its model is the perturbed assembly's.
            found = Some((solver, s));
        }
    } else {
        // For a net designed on the deformed truss, first from the truss as
        // the design's pull deforms it (the equilibrium sought is near:
        // Newton from the undeformed truss can diverge, the hinge motion
        // being many times the cables' elastic stretch); then, if that
        // fails, from the undeformed truss with the prestrain ramped in load
        // steps — at once for a net designed on the undeformed truss.
        let guess = match (frame, start) {
            (None, _) | (_, AssemblyStart::Beside(_)) => None,
            (Some(_), AssemblyStart::Truss(e)) => Some(Cow::Borrowed(e)),
            (Some(frame), _) => truss_guess(frame, &mesh.truss, design)?.map(Cow::Owned),
        };
        if let Some(guess) = &guess {
            let solver = solver_of(models.cut())?;
            let mut start = solver.reference_state();
            let frames = &guess.state.frames;
            start.frames[..frames.len()].copy_from_slice(frames);
            start.set_multipliers(&guess.state);
            start.rescale_multipliers(guess.constraint_scale / solver.constraint_scale());
            let s = solver.solve_from(start, 0.0, &once)?;
            if s.converged() {
                found = Some((solver, s));
            }
        }
    }
    let (solver, solution) = match found {
        Some(found) => found,
        None => {
            let solver = solver_of(models.ramped())?;
            let s = solver.solve(&settings)?;
            (solver, s)
        }
    };
    if !solution.converged() {
        return Err(VerifyError::NoEquilibrium {
            termination: solution.termination,
            load_factor: solution.load_factor,
        });
    }
    // Inextensible cables: the elastic equilibrium stiffened in stages.
    let (solver, solution, newton_iterations, load_steps) = match cable_model {
        CableModel::Elastic => {
            let (n, s) = (solution.newton_iterations, solution.steps.len());
            (solver, solution, n, s)
        }
        CableModel::Inextensible => {
            let targets: Vec<[f64; 2]> = network
                .edges
                .iter()
                .enumerate()
                .map(|(k, _)| [design.lengths_m[k], design.tensions_n[k]])
                .collect();
            stiffening::stiffen(&models.bare, &targets, ea, solver, solution, &settings)?
        }
    };
    let mut verification = measure(
        inputs,
        &models.node_of,
        solver.model(),
        &solution.state.frames,
        cable_model,
    )?;
    verification.newton_iterations = newton_iterations;
    verification.load_steps = load_steps;
    verification.time_s = clock.elapsed().as_secs_f64();
    let state = TrussEquilibrium {
        constraint_scale: solver.constraint_scale(),
        state: solution.state,
    };
    Ok(Assembled {
        verification,
        state,
        solver,
    })
}

impl std::fmt::Debug for Assembled {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Assembled")
            .field("verification", &self.verification)
            .finish_non_exhaustive()
    }
}

impl Assembled {
    /// The assembly's tangent at its equilibrium, factored once: the
    /// first-order response of the same assembly perturbed
    /// ([`Linearised::respond`]).
    ///
    /// # Errors
    /// A tangent that cannot be factored.
    pub fn linearise(&self) -> Result<Linearised<'_>, VerifyError> {
        Ok(Linearised {
            tangent: self.solver.linearise(&self.state.state, 1.0)?,
        })
    }
}

/// An assembly's tangent at its equilibrium, factored ([`Assembled::linearise`]).
pub struct Linearised<'a> {
    tangent: Linearisation<'a>,
}

impl Linearised<'_> {
    /// The assembly of `inputs` (those the linearised one was made of) as
    /// built with `perturbation`, to first order in it: one solve with the
    /// factored tangent. Its `newton_iterations` and `load_steps` are 0.
    ///
    /// # Errors
    /// A perturbation of the wrong size or one the assembly cannot take.
    pub fn respond(
        &self,
        inputs: &AssemblyInputs<'_>,
        perturbation: &Perturbation,
    ) -> Result<Verification, VerifyError> {
        let clock = Instant::now();
        let models = AssemblyModels::new(inputs, perturbation)?;
        let model = models.cut().build()?;
        let state = self.tangent.respond(&model)?;
        let cable_model = inputs.effects.cable_model();
        let mut v = measure(inputs, &models.node_of, &model, &state.frames, cable_model)?;
        v.time_s = clock.elapsed().as_secs_f64();
        Ok(v)
    }

    /// The assembly of `inputs` as built with `perturbation`, solved
    /// (nonlinear, to [`assemble`]'s tolerance) by chord iterations with the
    /// factored tangent ([`Linearisation::solve`]): no factorisation, so a
    /// small perturbation costs a few residuals and solves. `None` where
    /// they do not converge fast — [`assemble`] from the design's state is
    /// then the path. Its `newton_iterations` are the chord iterations,
    /// `load_steps` 1.
    ///
    /// # Errors
    /// A perturbation of the wrong size or one the assembly cannot take.
    pub fn solve(
        &self,
        inputs: &AssemblyInputs<'_>,
        perturbation: &Perturbation,
    ) -> Result<Option<Verification>, VerifyError> {
        let clock = Instant::now();
        let models = AssemblyModels::new(inputs, perturbation)?;
        let model = models.cut().build()?;
        let settings = StaticSettings {
            max_iterations: CHORD_ITERATIONS,
            ..assembly_settings()
        };
        let Some((state, iterations)) = self.tangent.solve(&model, &settings)? else {
            return Ok(None);
        };
        let cable_model = inputs.effects.cable_model();
        let mut v = measure(inputs, &models.node_of, &model, &state.frames, cable_model)?;
        v.newton_iterations = iterations;
        v.load_steps = 1;
        v.time_s = clock.elapsed().as_secs_f64();
        Ok(Some(v))
    }
}

/// The assembled equilibrium `frames` of `model` judged against the design
/// (iterations, steps and time left 0 for the caller).
fn measure(
    inputs: &AssemblyInputs<'_>,
    node_of: &[NodeId],
    model: &Model,
    frames: &[Frame],
    cable_model: CableModel,
) -> Result<Verification, VerifyError> {
    let AssemblyInputs {
        scene,
        mesh,
        network,
        design,
        frame,
        ..
    } = *inputs;
    let truss = match frame {
        Some(_) => AssemblyTruss::Flexible,
        None => AssemblyTruss::Rigid,
    };
    let ea = cable_model.axial_stiffness_n(&scene.cables);
    let nodes_xyz_m: Vec<[f64; 3]> = node_of
        .iter()
        .map(|&n| array(&frames[n].position_m))
        .collect();
    let (tensions_n, slack_cables) = cable_tensions(model, frames);

    let fixed = network.fixed_mask();
    let surface: Vec<usize> = (0..mesh.n_front_nodes).filter(|&i| !fixed[i]).collect();
    // The node RMS of the free front nodes, as every report names it.
    let free_front: Vec<[f64; 3]> = surface.iter().map(|&i| nodes_xyz_m[i]).collect();
    let rms = node_rms(&mesh.paraboloid, &free_front)?.axial_m;
    let max_deviation = free_front
        .iter()
        .map(|&p| mesh.paraboloid.axial_deviation(p).abs())
        .fold(0.0, f64::max);
    let distance = |p: &[f64; 3], q: &[f64; 3]| norm3(std::array::from_fn(|c| p[c] - q[c]));
    let boundary = network
        .fixed
        .iter()
        .map(|&i| distance(&nodes_xyz_m[i], &network.nodes[i]))
        .fold(0.0, f64::max);
    let shift = (0..network.n_nodes())
        .filter(|&i| !fixed[i])
        .map(|i| distance(&nodes_xyz_m[i], &design.nodes_xyz_m[i]))
        .fold(0.0, f64::max);
    let change = tensions_n
        .iter()
        .zip(&design.tensions_n)
        .map(|(t, d)| ((t - d) / d).abs())
        .fold(0.0, f64::max);
    let truss_segment_nodes: Vec<[usize; 2]> = model
        .rods()
        .iter()
        .flat_map(|rod| rod.nodes.windows(2).map(|w| [w[0], w[1]]))
        .collect();
    let truss_segments_m = truss_segment_nodes
        .iter()
        .map(|&[a, b]| [array(&frames[a].position_m), array(&frames[b].position_m)])
        .collect();
    Ok(Verification {
        truss,
        cable_model,
        cable_axial_stiffness_n: ea,
        rms_mm: 1e3 * rms,
        max_deviation_mm: 1e3 * max_deviation,
        max_tension_change_pct: 100.0 * change,
        boundary_deviation_mm: 1e3 * boundary,
        max_node_shift_mm: 1e3 * shift,
        slack_cables,
        newton_iterations: 0,
        load_steps: 0,
        time_s: 0.0,
        nodes_xyz_m,
        tensions_n,
        truss_segments_m,
        truss_segment_nodes,
    })
}

/// The flexible truss's equilibrium under the design's pull (`None` when
/// the truss finds none): the start of the assembled solve.
fn truss_guess(
    frame: &RingTrussBuilder,
    layout: &RingTrussLayout,
    design: &Design,
) -> Result<Option<TrussEquilibrium>, VerifyError> {
    let mut exact = ExactTruss::new(RingTruss::from_frame(frame.clone())?, layout)?;
    Ok(match exact.respond(&design.pull_n()) {
        Ok(_) => exact.equilibrium(),
        Err(_) => None,
    })
}

/// Tension of every cable of `model` at `frames` (full prestrain), and the
/// slack ones.
fn cable_tensions(model: &Model, frames: &[Frame]) -> (Vec<f64>, Vec<usize>) {
    let mut slack = Vec::new();
    let tensions = model
        .cables()
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let [a, b] = c.nodes();
            let s = c.state(&frames[a].position_m, &frames[b].position_m, 1.0);
            if s.slack {
                slack.push(k);
            }
            s.tension_n
        })
        .collect();
    (tensions, slack)
}
