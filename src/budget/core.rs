//! The perturbed assembly: a design's cut cables assembled on the exact
//! truss once, then again for each perturbation — a thermal case, a
//! tolerance sample — warm-started from that equilibrium (nonlinear), or
//! by one solve with its tangent factored once (linearised). Both paths
//! end in the same measurement of the surface ([`Measured`]), so a case and
//! a sample are one thing to the rest of the budget.

use super::BudgetError;
use crate::effects::SceneEffects;
use crate::geometry::ReflectorMesh;
use crate::network::Network;
use crate::scene::Scene;
use crate::surface::{best_fit_nodes, node_rms};
use crate::truss::{RingTruss, RingTrussBuilder};
use crate::uniformity::Design;
use crate::verify::{
    assemble, Assembled, AssemblyInputs, AssemblyStart, Linearised, Perturbation, Verification,
};

/// A design assembled on the scene's exact truss, ready to be perturbed.
pub struct PerturbedAssembly<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Its nets and layout.
    pub mesh: &'a ReflectorMesh,
    /// The network the design is made on.
    pub network: &'a Network,
    /// The design.
    pub design: &'a Design,
    effects: SceneEffects,
    frame: RingTrussBuilder,
    /// The design as built (no perturbation).
    pub nominal: Assembled,
    /// Its free front nodes' positions as built, m.
    nominal_front_m: Vec<[f64; 3]>,
    /// The free front nodes (net indices).
    free_front: Vec<usize>,
}

/// The surface of one assembly against the design's as built: the budget
/// term of whatever perturbed it.
#[derive(Debug, Clone, PartialEq)]
pub struct Measured {
    /// RMS axial deviation of the free front nodes, raw, mm: the design's
    /// own for the design, the change the perturbation makes otherwise.
    pub raw_mm: f64,
    /// The same about its best-fit paraboloid, mm.
    pub best_fit_mm: f64,
    /// RMS half-path-length error about the best fit, mm (Ruze's ε).
    pub half_path_mm: f64,
    /// Focal length of the best-fit paraboloid, m.
    pub focal_length_m: f64,
    /// Largest `|T − T_design|/T_design`, %.
    pub max_tension_change_pct: f64,
    /// Cables slack at equilibrium (network order).
    pub slack_cables: Vec<usize>,
}

impl<'a> PerturbedAssembly<'a> {
    /// `design` (made on `network` of `mesh`) assembled on the exact truss
    /// of `scene`: `nominal` where the caller has it (the design run's,
    /// [`crate::design::DesignRun::assembled`]), otherwise assembled here.
    ///
    /// # Errors
    /// A truss or assembly that fails.
    pub fn new(
        scene: &'a Scene,
        mesh: &'a ReflectorMesh,
        network: &'a Network,
        design: &'a Design,
        nominal: Option<Assembled>,
    ) -> Result<Self, BudgetError> {
        let effects = SceneEffects::of(scene);
        let frame = RingTruss::builder(scene, &mesh.truss, &effects);
        let inputs = AssemblyInputs {
            scene,
            mesh,
            effects: &effects,
            network,
            design,
            frame: Some(&frame),
        };
        let nominal = match nominal {
            Some(nominal) => nominal,
            None => assemble(&inputs, AssemblyStart::Unknown, &Perturbation::none())?,
        };
        let fixed = network.fixed_mask();
        let free_front: Vec<usize> = (0..mesh.n_front_nodes).filter(|&i| !fixed[i]).collect();
        let nominal_front_m = free_front
            .iter()
            .map(|&i| nominal.verification.nodes_xyz_m[i])
            .collect();
        Ok(PerturbedAssembly {
            scene,
            mesh,
            network,
            design,
            effects,
            frame,
            nominal,
            nominal_front_m,
            free_front,
        })
    }

    fn inputs(&self) -> AssemblyInputs<'_> {
        AssemblyInputs {
            scene: self.scene,
            mesh: self.mesh,
            effects: &self.effects,
            network: self.network,
            design: self.design,
            frame: Some(&self.frame),
        }
    }

    /// Rods of the truss's frame.
    pub fn rods(&self) -> usize {
        self.frame.builder.rod_count()
    }

    /// The assembly with `perturbation`, solved from the design's
    /// equilibrium: by chord iterations with `tangent`
    /// ([`PerturbedAssembly::linearise`]) where they converge fast, by
    /// Newton otherwise — the same equilibrium to the solver's tolerance.
    ///
    /// # Errors
    /// No equilibrium, or a perturbation the assembly cannot take.
    pub fn nonlinear(
        &self,
        tangent: &Linearised<'_>,
        perturbation: &Perturbation,
    ) -> Result<Verification, BudgetError> {
        match self.chord(tangent, perturbation)? {
            Some(v) => Ok(v),
            None => self.newton(perturbation),
        }
    }

    /// The assembly with `perturbation` solved by chord iterations with
    /// `tangent` ([`Linearised::solve`]), `None` where they are slow: the
    /// first path of [`PerturbedAssembly::nonlinear`].
    ///
    /// # Errors
    /// A perturbation the assembly cannot take.
    pub fn chord(
        &self,
        tangent: &Linearised<'_>,
        perturbation: &Perturbation,
    ) -> Result<Option<Verification>, BudgetError> {
        Ok(tangent.solve(&self.inputs(), perturbation)?)
    }

    /// The assembly with `perturbation` solved by Newton from the design's
    /// equilibrium ([`assemble`]), the cut lengths ramped from the design's
    /// if it does not converge at once: the path of
    /// [`PerturbedAssembly::nonlinear`] where the chord iterations are slow.
    ///
    /// # Errors
    /// No equilibrium, or a perturbation the assembly cannot take.
    pub fn newton(&self, perturbation: &Perturbation) -> Result<Verification, BudgetError> {
        let a = assemble(
            &self.inputs(),
            AssemblyStart::Assembly(&self.nominal),
            perturbation,
        )?;
        Ok(a.verification)
    }

    /// The assembly's tangent factored once, for [`PerturbedAssembly::linear`].
    ///
    /// # Errors
    /// A tangent that cannot be factored.
    pub fn linearise(&self) -> Result<Linearised<'_>, BudgetError> {
        Ok(self.nominal.linearise()?)
    }

    /// The assembly with `perturbation` to first order: one solve with
    /// `tangent` ([`PerturbedAssembly::linearise`]).
    ///
    /// # Errors
    /// A perturbation the assembly cannot take.
    pub fn linear(
        &self,
        tangent: &Linearised<'_>,
        perturbation: &Perturbation,
    ) -> Result<Verification, BudgetError> {
        Ok(tangent.respond(&self.inputs(), perturbation)?)
    }

    /// The design's own surface as built: its free front nodes against the
    /// paraboloid.
    ///
    /// # Errors
    /// A surface that cannot be fitted.
    pub fn design_surface(&self) -> Result<Measured, BudgetError> {
        self.measure_points(&self.nominal_front_m, &self.nominal.verification)
    }

    /// The change `built` makes to the design's surface as built: each free
    /// front node of the design (on the paraboloid) moved by the difference
    /// between `built` and the design as built, measured raw and about its
    /// best fit — the term of the budget that the perturbation alone
    /// contributes (the design's own error is its own term).
    ///
    /// # Errors
    /// A surface that cannot be fitted.
    pub fn change(&self, built: &Verification) -> Result<Measured, BudgetError> {
        let points: Vec<[f64; 3]> = self
            .free_front
            .iter()
            .zip(&self.nominal_front_m)
            .map(|(&i, n)| {
                let (d, b) = (self.design.nodes_xyz_m[i], built.nodes_xyz_m[i]);
                std::array::from_fn(|c| d[c] + (b[c] - n[c]))
            })
            .collect();
        self.measure_points(&points, built)
    }

    fn measure_points(
        &self,
        points: &[[f64; 3]],
        built: &Verification,
    ) -> Result<Measured, BudgetError> {
        let paraboloid = &self.mesh.paraboloid;
        let raw = node_rms(paraboloid, points)?;
        let fit = best_fit_nodes(paraboloid, points)?;
        Ok(Measured {
            raw_mm: 1e3 * raw.axial_m,
            best_fit_mm: 1e3 * fit.rms.axial_m,
            half_path_mm: 1e3 * fit.rms.half_path_m,
            focal_length_m: fit.paraboloid.focal_length_m,
            max_tension_change_pct: built.max_tension_change_pct,
            slack_cables: built.slack_cables.clone(),
        })
    }

    /// The built positions of the free front nodes (for tests: the design
    /// as built is [`PerturbedAssembly::nominal`]'s).
    pub fn free_front(&self) -> &[usize] {
        &self.free_front
    }
}
