//! The static solver's core, shared by every algorithm that follows the
//! equilibrium path (load control, arc length, the stability test): the
//! solver (the model, its assembled system, its length and coordinate
//! scales), the convergence test, and the weighted norm of increments in
//! which steps are measured — rotations weighted by the mean element length
//! so that both are lengths, multipliers not counted.

use std::sync::Arc;

use super::assembly::{Forces, State, System};
use super::model::{MechanicsError, Model};
use super::settings::StaticSettings;
use crate::algebra::norm_inf;

/// Largest ratio of the force floor of [`StaticSolver::converged`] to the
/// loads that a solve accepts. At a floor as large as the loads, every step
/// 'converges' where it starts. The floor is pessimistic — paper-26m's ring
/// under 1e-6 of its pull (floor/loads = 0.083) agrees with the linear
/// model to 9e-6 — so only floors near the loads are refused.
const RESOLUTION: f64 = 0.5;

/// A static solver for one model: the structure is analysed once, then any
/// number of solves (new loads through [`StaticSolver::model_mut`]), and
/// any number of models of the same structure
/// ([`StaticSolver::with_model`]).
#[derive(Clone)]
pub struct StaticSolver {
    model: Model,
    system: Arc<System>,
    /// Size of the frame, m.
    length_scale: f64,
    /// Largest coordinate magnitude, m (sets the roundoff of positions).
    coordinate_scale: f64,
}

impl StaticSolver {
    /// Analyse the structure of `model`.
    ///
    /// # Errors
    /// A pattern faer cannot analyse.
    pub fn new(model: Model) -> Result<Self, MechanicsError> {
        let system = Arc::new(System::new(&model)?);
        Ok(Self::of(model, system))
    }

    /// A solver of `model`, a model of this one's structure — the same
    /// nodes, supports, elements, cables and joints in the same order, only
    /// their parameters differ (a cable's cut length, a rod's stretch) —
    /// that shares this one's analysis: the dof numbering, the pattern and
    /// the symbolic factorisation (on super-100m's assembly, 1.1 s a
    /// model). Its constraint scale is this model's.
    ///
    /// # Errors
    /// A model of another structure.
    pub fn with_model(&self, model: Model) -> Result<Self, MechanicsError> {
        self.check_structure(&model)?;
        Ok(Self::of(model, Arc::clone(&self.system)))
    }

    fn of(model: Model, system: Arc<System>) -> Self {
        let (mut lo, mut hi) = (
            nalgebra::Vector3::repeat(f64::MAX),
            nalgebra::Vector3::repeat(f64::MIN),
        );
        for f in &model.reference {
            lo = lo.inf(&f.position_m);
            hi = hi.sup(&f.position_m);
        }
        let length_scale = (hi - lo).norm().max(1e-9);
        let coordinate_scale = lo.amax().max(hi.amax());
        StaticSolver {
            model,
            system,
            length_scale,
            coordinate_scale,
        }
    }

    /// Refuses a model of another structure than this solver's.
    ///
    /// # Errors
    /// [`MechanicsError::Invalid`] when the node, element, cable or joint
    /// counts, the supports or the nodes' dofs differ.
    pub(crate) fn check_structure(&self, changed: &Model) -> Result<(), MechanicsError> {
        let model = &self.model;
        let same = changed.node_count() == model.node_count()
            && changed.node_dofs == model.node_dofs
            && changed.fixed == model.fixed
            && changed.elements.len() == model.elements.len()
            && changed.cables.len() == model.cables.len()
            && changed.joints.len() == model.joints.len()
            && changed
                .elements
                .iter()
                .zip(&model.elements)
                .all(|(a, b)| a.nodes == b.nodes)
            && changed
                .cables
                .iter()
                .zip(&model.cables)
                .all(|(a, b)| a.nodes == b.nodes)
            && changed
                .joints
                .iter()
                .zip(&model.joints)
                .all(|(a, b)| a.nodes == b.nodes && a.rows() == b.rows());
        if !same {
            return Err(MechanicsError::invalid(
                "model",
                "another structure than the analysed one (nodes, supports, elements, \
                 cables or joints differ)",
            ));
        }
        Ok(())
    }

    /// The model.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The constraint scale `s` of the analysed structure, N/m: the joint
    /// multipliers of its states are scaled by it (a state carried to a
    /// solver of another scale has them rescaled by the ratio).
    pub fn constraint_scale(&self) -> f64 {
        self.system.scale
    }

    /// The model, to change its loads.
    pub fn model_mut(&mut self) -> &mut Model {
        &mut self.model
    }

    /// Largest component of the reference loads.
    pub(super) fn load_scale(&self) -> f64 {
        self.model
            .loads
            .iter()
            .map(|l| l.force_n.amax().max(l.moment_nm.amax()))
            .fold(0.0, f64::max)
    }

    /// Refuses loads below the force resolution of the model's own
    /// stiffness: positions carry a roundoff of `ε × coordinates`, which the
    /// stiffest member turns into forces of about `64 ε s × coordinates`
    /// (the convergence test's floor, `s` the stiffness scale). Loads below
    /// `floor / RESOLUTION` cannot be balanced in double precision: measured
    /// on the cantilever with EI = 100 N·m² under 62.8 N·m, EA = 1e16 N
    /// (floor 1.4e3 N) 'converged' undeformed in 0 iterations.
    ///
    /// # Errors
    /// [`MechanicsError::Unresolvable`] naming the floor and the loads.
    pub(super) fn check_resolvable(&self) -> Result<(), MechanicsError> {
        let loads = self.load_scale();
        let floor = 64.0 * f64::EPSILON * self.system.scale * self.coordinate_scale;
        if loads > 0.0 && floor > RESOLUTION * loads {
            return Err(MechanicsError::Unresolvable { floor, loads });
        }
        Ok(())
    }

    /// The unstressed reference state.
    pub fn reference_state(&self) -> State {
        self.system.reference_state(&self.model)
    }

    /// The assembled system: dof numbering, pattern, symbolic LU.
    pub(super) fn system(&self) -> &System {
        &self.system
    }

    /// The force residual `‖F‖∞` at an evaluation and whether it is converged:
    /// `‖F‖∞ ≤ tol · max(λ‖f_ext‖∞, ‖reactions‖∞, cable forces)` and joint gaps `≤ tol · L`,
    /// where the force test never asks for less than the roundoff of the
    /// assembled forces, `ε · (EA/L)_max · |x|_max` (coordinates of tens of
    /// metres and stiff tubes put it near 1e-7 N).
    pub(super) fn converged(
        &self,
        ev: &Forces,
        lambda: f64,
        settings: &StaticSettings,
    ) -> (f64, bool) {
        self.converged_within(ev, lambda, settings, 1.0)
    }

    /// [`StaticSolver::converged`] with the tolerances × `factor`.
    pub(super) fn converged_within(
        &self,
        ev: &Forces,
        lambda: f64,
        settings: &StaticSettings,
        factor: f64,
    ) -> (f64, bool) {
        let n = self.system.n_free;
        let force = norm_inf(&ev.residual[..n]);
        let gap = norm_inf(&ev.residual[n..]) / self.system.scale;
        if !(force.is_finite() && gap.is_finite()) {
            return (f64::NAN, false);
        }
        let reaction_scale = norm_inf(ev.reactions.as_flattened());
        let roundoff =
            64.0 * f64::EPSILON * (ev.internal_scale + self.system.scale * self.coordinate_scale);
        let force_scale = (self.load_scale() * lambda.abs())
            .max(reaction_scale)
            .max(ev.prestress_scale);
        let tol = factor * (settings.tolerance * force_scale).max(roundoff);
        (
            force,
            force <= tol && gap <= factor * settings.tolerance * self.length_scale,
        )
    }

    /// The Newton increment test, the residual scaled by the stiffness:
    /// converged when the increment `δ = −J⁻¹R` (weighted norm) is at most
    /// `tol · L`, `L` the frame's size. The force test of
    /// [`StaticSolver::converged`] compares forces with the loads; a very
    /// stiff member (GA = 1e4·EA, EA = 1e8·EI/L²) leaves a roundoff in its
    /// forces far above that test — 2.5e-9 N against 1e-10 N on a shear-rigid
    /// cantilever, which then stalled at load factor 0 — while the same
    /// roundoff moves the nodes only by `roundoff / stiffness`. Newton
    /// converging quadratically, the state after such an increment is an
    /// equilibrium to `(tol·L)²/L`.
    pub(super) fn increment_converged(
        &self,
        delta: &[f64],
        w: &[f64],
        settings: &StaticSettings,
    ) -> bool {
        wdot(w, delta, delta).sqrt() <= settings.tolerance * self.length_scale
    }

    /// Weights of the weighted norm: 1 on translations, `ℓ` (the mean
    /// element length) on rotations, 0 on multipliers.
    pub(super) fn weights(&self) -> Vec<f64> {
        let model = &self.model;
        let system = &self.system;
        let mean_length = if model.elements.is_empty() {
            self.length_scale
        } else {
            model.elements.iter().map(|e| e.length_m).sum::<f64>() / model.elements.len() as f64
        };
        let mut w = vec![0.0; system.n_rows];
        for n in 0..model.node_count() {
            for c in 0..6 {
                if let Some(i) = system.unknown(n, c) {
                    w[i] = if c < 3 { 1.0 } else { mean_length };
                }
            }
        }
        w
    }
}

/// The weighted dot product `Σ wᵢ² aᵢ bᵢ` (weights of [`StaticSolver::weights`]).
pub(super) fn wdot(w: &[f64], a: &[f64], b: &[f64]) -> f64 {
    w.iter()
        .zip(a)
        .zip(b)
        .map(|((w, a), b)| w * w * a * b)
        .sum()
}
