//! A scene's nets ready for the outer loop: the mesh, the front net's
//! uniformity problem for the theoretical boundary, and the two-stage design
//! problem built on it, with the loads of the effects the scene asks for.

use std::sync::OnceLock;

use super::outer_loop::{design_loop, IterationRecord, LoopOutcome, LoopSettings};
use super::tied_nets::TiedNets;
use super::DesignError;
use crate::effects::SceneEffects;
use crate::geometry::{build_mesh, ReflectorMesh};
use crate::scene::{Scene, TrussModel};
use crate::truss::{oracle_on_frame, RingTruss, RingTrussBuilder};
use crate::uniformity::{SolverKind, UniformityProblem, UniformitySolver};

/// The uniformity problem of a scene's front net for its theoretical boundary,
/// under the nodal loads of the effects the scene asks for (the cables' self
/// weight under gravity).
///
/// # Errors
/// A mesh or uniformity problem that cannot be built.
pub fn scene_problem(scene: &Scene) -> Result<(ReflectorMesh, UniformityProblem), DesignError> {
    problem_with(scene, &SceneEffects::of(scene))
}

/// The uniformity solver a scene is designed with when none is named
/// ([`SolverKind::default_for`]: gravity loads the nets).
pub fn default_solver(scene: &Scene) -> SolverKind {
    SolverKind::default_for(
        scene.uniformity.groups.len(),
        scene.effects.gravity.is_some(),
    )
}

/// [`scene_problem`] with the effects already built.
fn problem_with(
    scene: &Scene,
    effects: &SceneEffects,
) -> Result<(ReflectorMesh, UniformityProblem), DesignError> {
    let mesh = build_mesh(scene)?;
    let mut problem = UniformityProblem::from_mesh(
        &mesh,
        &scene.uniformity_targets(),
        scene.cables.max_force_density_n_per_m,
    )?;
    problem.min_tension_fraction = scene.uniformity.min_tension_fraction;
    let loads = effects.net_loads_n(&mesh.network.nodes, &mesh.network.edges);
    Ok((mesh, problem.with_loads(loads)?))
}

/// A scene's nets ready for the outer loop: the mesh and its two-stage
/// design problem ([`TiedNets`]).
pub struct SceneNets {
    /// The scene's nets and truss layout.
    pub mesh: ReflectorMesh,
    /// The two-stage design problem on them.
    pub nets: TiedNets,
    /// The effects the scene asks for, built once for every stage.
    pub effects: SceneEffects,
    /// The ring truss's frame, constructed the first time a stage needs it
    /// ([`SceneNets::truss_frame`]) and copied to each stage after.
    frame: OnceLock<RingTrussBuilder>,
    /// The scene the nets and the frame are made of.
    scene: Scene,
}

impl SceneNets {
    /// Builds the effects, the mesh and the design problem of `scene`.
    ///
    /// # Errors
    /// An invalid mesh or uniformity problem.
    pub fn new(scene: &Scene) -> Result<SceneNets, DesignError> {
        SceneNets::with_effects(scene, SceneEffects::of(scene))
    }

    /// Builds the mesh and the design problem of `scene` under `effects`
    /// (the scene's own, or more: see [`SceneEffects::with`]).
    ///
    /// # Errors
    /// An invalid mesh or uniformity problem.
    pub fn with_effects(scene: &Scene, effects: SceneEffects) -> Result<SceneNets, DesignError> {
        let (mesh, problem) = problem_with(scene, &effects)?;
        let nets = TiedNets::new(&mesh, problem)?.with_effects(&effects);
        Ok(SceneNets {
            mesh,
            nets,
            effects,
            frame: OnceLock::new(),
            scene: scene.clone(),
        })
    }

    /// One run of the outer loop (net design ⇄ truss response) with a fresh
    /// truss oracle of `model` (the scene's truss values), calling `observe`
    /// after every iteration.
    ///
    /// # Errors
    /// A truss that cannot be built, or the loop's errors.
    pub fn design_loop(
        &self,
        solver: &dyn UniformitySolver,
        model: TrussModel,
        settings: &LoopSettings,
        observe: &mut dyn FnMut(&IterationRecord),
    ) -> Result<LoopOutcome, DesignError> {
        let mut oracle = oracle_on_frame(model, &self.mesh.truss, || self.truss_frame().clone())?;
        design_loop(&self.nets, solver, oracle.as_mut(), settings, observe)
    }

    /// The frame of the scene's ring truss on this mesh's layout, with the
    /// effects: constructed once (the first call), for the loop's oracle, the
    /// limit margin and every assembly.
    pub fn truss_frame(&self) -> &RingTrussBuilder {
        self.frame
            .get_or_init(|| RingTruss::builder(&self.scene, &self.mesh.truss, &self.effects))
    }
}
