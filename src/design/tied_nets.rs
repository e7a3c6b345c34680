//! The net design for one boundary of the outer loop: a front net on the
//! paraboloid, vertical ties, and a rear net whose shape is free (DESIGN §4, §6).
//!
//! On the theoretical boundary the rear net mirrors the front net in plan and
//! the whole network has one prescribed geometry. A deformed truss moves the
//! top and bottom hinges differently; keeping the rear net's prescribed
//! geometry then forces wildly non-uniform tensions (measured on `small-hex`:
//! front ratio 1.19 → 8.1 for a 1.5 mm hinge motion), although nothing asks
//! for the rear shape. So each design is made in two stages:
//!
//! 1. **front**: the uniformity problem of the front net with vertical ties —
//!    front free nodes on the paraboloid, top hinges at the boundary `C`, each
//!    tie anchored directly below its node; any
//!    [`UniformitySolver`](crate::uniformity::UniformitySolver) solves it. A
//!    vertical tie carries no plan force, so this stage does not depend on the
//!    rear net at all;
//! 2. **rear**: the rear net keeps its plan (the front net's, so the ties stay
//!    vertical) with its bottom hinges at `C`; its force densities are the
//!    closest to the mirror `α q_front` (relative least squares) that balance
//!    the plan, `min Σ ((q − q₀)/q₀)²` s.t. `A_plan q = 0`, `q₀ = α q_front`;
//!    then the tie forces, as vertical loads, give the rear nodes' heights by
//!    one forward force density solve, and the ties' force densities follow
//!    from their new lengths. The level `α` is the one at which the rear
//!    net's interior cables carry the scene's `rear_net.mean_tension_n`
//!    (a few secant steps from the vertical balance of the nominal rear net,
//!    `α = F_rear/F` for two paraboloids): the level sets the rear net's
//!    depth, which nothing else asks for.
//!
//! Both nets therefore carry the mean tensions the scene asks for: the
//! front net's by the solver, or by scaling its design where the solver does
//! not hold the level and no load breaks the shape's invariance under
//! `q → c q` ([`Design::at_level`]).
//!
//! Before both stages the plan grid is rebuilt by the mesh's own construction
//! on the deformed top hinges, so the free nodes move with the boundary (the
//! front ones staying on the paraboloid). Holding them where they were instead
//! makes the pull on the truss so sensitive to the boundary that the outer
//! iteration diverges (measured gain ≈ 4 on `small-hex`, ≈ 8 on
//! `realistic-26m`).
//!
//! Every node then balances exactly, for any boundary: the outer loop iterates
//! on the boundary alone, as the paper's.

use std::time::Instant;

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, Side};
use serde::{Deserialize, Serialize};

use super::DesignError;

use crate::algebra::Plain;
use crate::effects::SceneEffects;
use crate::fdm::FdmStructure;
use crate::geometry::ReflectorMesh;
use crate::network::{CableGroup, Network};
use crate::uniformity::{
    most_uniform, Design, UniformityError, UniformityProblem, UniformitySet, UniformitySolver,
};

/// The two-stage design's tolerances and budgets: plain data with defaults
/// and one `validate()` ([`TiedNets::with_settings`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TiedNetSettings {
    /// For a solver whose optimum is a face (`lp`, `bisection`), the front
    /// stage takes the design closest to uniform tension with each set's
    /// ratio within this fraction of the solver's: unique, and continuous in
    /// the boundary.
    pub selection_slack: f64,
    /// Relative change of the lumped cable weights at which a design under
    /// gravity stops repeating its stages.
    pub weight_tolerance: f64,
    /// Most passes of the stages under gravity.
    pub max_weight_passes: usize,
    /// Plan offset of a tie's anchor from its node below which the tie hangs
    /// plumb, m.
    pub plumb_tolerance_m: f64,
    /// Most forward solves that plumb the ties (0: the ties stay where the
    /// front stage left their anchors).
    pub plumb_passes: usize,
    /// Relative error, in `ln`, at which the rear net holds its mean tension.
    pub rear_level_tolerance: f64,
    /// Most secant steps on the rear level (0: the vertical-balance fit,
    /// with a warning if it misses).
    pub rear_level_steps: usize,
}

impl Default for TiedNetSettings {
    fn default() -> Self {
        TiedNetSettings {
            selection_slack: 1e-3,
            weight_tolerance: 1e-13,
            max_weight_passes: 8,
            plumb_tolerance_m: 1e-13,
            plumb_passes: 6,
            rear_level_tolerance: 1e-13,
            rear_level_steps: 20,
        }
    }
}

impl TiedNetSettings {
    /// Check the settings.
    ///
    /// # Errors
    /// [`DesignError::Setting`] naming the first field (`tied_nets.…`) out of
    /// its range: a slack or tolerance that is negative or not finite, or no
    /// pass of the stages.
    pub fn validate(&self) -> Result<(), DesignError> {
        for (key, value) in [
            ("tied_nets.selection_slack", self.selection_slack),
            ("tied_nets.weight_tolerance", self.weight_tolerance),
            ("tied_nets.plumb_tolerance_m", self.plumb_tolerance_m),
            ("tied_nets.rear_level_tolerance", self.rear_level_tolerance),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(DesignError::Setting {
                    key,
                    reason: format!("{value} must be finite and ≥ 0"),
                });
            }
        }
        if self.max_weight_passes == 0 {
            return Err(DesignError::Setting {
                key: "tied_nets.max_weight_passes",
                reason: "must be at least 1".into(),
            });
        }
        Ok(())
    }
}

/// What stage 2 finds: the rear force densities and node positions (the rear
/// net's numbering), the level `α`, and a warning if the level missed.
struct RearStage {
    q: Vec<f64>,
    nodes_xyz_m: Vec<[f64; 3]>,
    alpha: f64,
    warning: Option<String>,
}

/// Largest component difference of two load lists (`b` may be empty: zero).
fn max_difference(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .enumerate()
        .map(|(i, p)| {
            let q = b.get(i).copied().unwrap_or([0.0; 3]);
            (0..3).map(|c| (p[c] - q[c]).abs()).fold(0.0, f64::max)
        })
        .fold(0.0, f64::max)
}

/// A reflector's front net, rear net and ties, split for the two-stage design.
#[derive(Debug, Clone)]
pub struct TiedNets {
    /// The whole network's problem (the scene's sets, surface and bounds).
    full: UniformityProblem,
    /// Front net + vertical ties to anchors below their nodes.
    front: UniformityProblem,
    /// Rear net alone (rear node `i` of the whole network is `i − n_front`).
    rear: FdmStructure,
    /// Nodes of the front net.
    n_front: usize,
    /// Number of front-net cables (the rear mirror of cable `k` is `k + n`).
    n_front_cables: usize,
    /// Each tie: (cable, front node, rear node) in the whole network.
    ties: Vec<(usize, usize, usize)>,
    /// The mesh: its plan grid is rebuilt on the deformed top hinges.
    mesh: ReflectorMesh,
    /// The effects that load the nets (the cables' self weight).
    effects: SceneEffects,
    /// Tolerances and budgets of the stages.
    settings: TiedNetSettings,
}

/// A two-stage design on one boundary.
#[derive(Debug, Clone)]
pub struct TiedDesign {
    /// The whole network's design (forward solve of every node with all `q`).
    pub design: Design,
    /// The whole network's problem at the geometry designed for.
    pub problem: UniformityProblem,
    /// The rear level `α = q_rear/q_front` of the mirror.
    pub alpha: f64,
    /// The first stage's design (front net and ties): the start of the next
    /// boundary's ([`TiedNets::design_from`]).
    pub front: Design,
}

impl TiedNets {
    /// The split of `mesh`'s network; `full` is the scene's uniformity problem
    /// on that network (its sets must lie in the front net).
    ///
    /// # Errors
    /// A network that is not a reflector mesh (front, mirrored rear, vertical
    /// ties), or a uniformity set with rear-net cables.
    pub fn new(mesh: &ReflectorMesh, full: UniformityProblem) -> Result<Self, UniformityError> {
        let network = full.network();
        let groups = &mesh.groups;
        let is_front = |g: CableGroup| matches!(g, CableGroup::Front | CableGroup::Boundary);
        let n_front_cables = groups.iter().take_while(|&&g| is_front(g)).count();
        let n_front = mesh.n_front_nodes;
        let ties: Vec<(usize, usize, usize)> = (0..network.n_edges())
            .filter(|&k| groups[k] == CableGroup::Tie)
            .map(|k| {
                let [a, b] = network.edges[k];
                (k, a.min(b), a.max(b))
            })
            .collect();
        let mirrored = (0..n_front_cables).all(|k| {
            let [i, j] = network.edges[k];
            network.edges.get(k + n_front_cables) == Some(&[i + n_front, j + n_front])
        });
        let vertical = ties.iter().all(|&(_, i, r)| {
            r == i + n_front && {
                let (a, b) = (network.nodes[i], network.nodes[r]);
                a[0] == b[0] && a[1] == b[1]
            }
        });
        if !mirrored || !vertical || 2 * n_front_cables + ties.len() != network.n_edges() {
            return Err(UniformityError::invalid(
                "network",
                "not a reflector mesh (front net, mirrored rear net, vertical ties)",
            ));
        }
        if let Some(set) = full
            .sets()
            .iter()
            .find(|s| s.edges.iter().any(|&k| k >= n_front_cables))
        {
            return Err(UniformityError::invalid(
                format!("uniformity set `{}`", set.name),
                "cables outside the front net: the outer loop designs the front net and lets \
                 the rear net follow (q_rear ≈ α q_front)",
            ));
        }

        // Stage 1: front nodes 0..n_front, then one anchor per tie.
        let label = |k: usize| network.group_of(k).to_string();
        let mut nodes = network.nodes[..n_front].to_vec();
        let mut edges = network.edges[..n_front_cables].to_vec();
        let mut q = network.q[..n_front_cables].to_vec();
        let mut labels: Vec<String> = (0..n_front_cables).map(label).collect();
        let mut fixed = mesh.front_attachments.clone();
        for (t, &(k, i, r)) in ties.iter().enumerate() {
            nodes.push(network.nodes[r]);
            edges.push([i, n_front + t]);
            q.push(network.q[k]);
            labels.push(label(k));
            fixed.push(n_front + t);
        }
        let front_network = Network {
            nodes,
            edges,
            fixed,
            q,
            loads: None,
            groups: Some(labels),
        };
        let sets: Vec<UniformitySet> = full.sets().to_vec();
        let mut front = UniformityProblem::new(
            front_network,
            sets,
            full.surface_nodes().to_vec(),
            full.surface(),
            full.max_force_density_n_per_m,
        )?;
        front.min_tension_fraction = full.min_tension_fraction;

        // Stage 2: the rear net alone.
        let rear_network = Network {
            nodes: network.nodes[n_front..].to_vec(),
            edges: network.edges[n_front_cables..2 * n_front_cables]
                .iter()
                .map(|&[i, j]| [i - n_front, j - n_front])
                .collect(),
            fixed: mesh.rear_attachments.iter().map(|&i| i - n_front).collect(),
            q: network.q[n_front_cables..2 * n_front_cables].to_vec(),
            loads: None,
            groups: None,
        };
        let rear = FdmStructure::new(&rear_network)?;
        Ok(TiedNets {
            full,
            front,
            rear,
            n_front,
            n_front_cables,
            ties,
            mesh: mesh.clone(),
            effects: SceneEffects::none(),
            settings: TiedNetSettings::default(),
        })
    }

    /// The same nets under the nodal loads of `effects` (none: weightless,
    /// as in orbit). Each design evaluates the loads at the geometry it
    /// designs for — for the cables' self weight: the front net's, the ties
    /// to the rear heights it starts from, half to each end node — in both
    /// stages and in the whole network's forward solve. Along the axis the
    /// ties absorb vertical loads and the front net's plan problem is
    /// unchanged; across it the loads enter plan equilibrium (front and rear).
    pub fn with_effects(mut self, effects: &SceneEffects) -> Self {
        self.effects = effects.clone();
        self
    }

    /// The same nets designed with `settings` (the defaults otherwise).
    ///
    /// # Errors
    /// Settings out of range ([`TiedNetSettings::validate`]).
    pub fn with_settings(mut self, settings: TiedNetSettings) -> Result<Self, DesignError> {
        settings.validate()?;
        self.settings = settings;
        Ok(self)
    }

    /// The tolerances and budgets the stages run with.
    pub fn settings(&self) -> &TiedNetSettings {
        &self.settings
    }

    /// The two-stage design for attachment points `boundary_m` (top hinges,
    /// then bottom hinges: the order of the network's fixed nodes).
    ///
    /// # Errors
    /// A boundary of the wrong size, a stage that fails, rear force densities
    /// that cannot stay positive, or a tie that would have to push (named).
    pub fn design(
        &self,
        solver: &dyn UniformitySolver,
        boundary_m: &[[f64; 3]],
    ) -> Result<TiedDesign, UniformityError> {
        self.design_from(solver, boundary_m, None)
    }

    /// [`TiedNets::design`] with the first stage started from `start`'s
    /// (a neighbouring boundary's design: [`UniformitySolver::solve_from`]).
    ///
    /// # Errors
    /// As [`TiedNets::design`].
    pub fn design_from(
        &self,
        solver: &dyn UniformitySolver,
        boundary_m: &[[f64; 3]],
        start: Option<&TiedDesign>,
    ) -> Result<TiedDesign, UniformityError> {
        let clock = Instant::now();
        let network = self.full.network();
        if boundary_m.len() != network.fixed.len() {
            return Err(UniformityError::invalid(
                "boundary",
                format!(
                    "{} points given, {} attachment points expected",
                    boundary_m.len(),
                    network.fixed.len()
                ),
            ));
        }
        let n_front = self.n_front;
        // The plan grid rebuilt on the top hinges' plan positions: the free
        // nodes move with the boundary (front on the paraboloid, rear below).
        let plan = self
            .mesh
            .front_plan(&boundary_m[..self.mesh.front_attachments.len()]);
        let mut whole = network.nodes.clone();
        for (i, &[x, y]) in plan.iter().enumerate() {
            whole[i] = [x, y, self.mesh.paraboloid.z(x, y)];
            whole[i + n_front] = [x, y, whole[i + n_front][2]];
        }
        for (&i, p) in network.fixed.iter().zip(boundary_m) {
            whole[i] = *p;
        }
        // Without weight one pass; with it, the weight of the ties depends on
        // the rear heights stage 2 finds: repeat until the lumped weights are
        // those of the geometry designed (a few passes: they change little).
        let mut weights = self.effects.net_loads_n(&whole, &network.edges);
        let mut passes = 0;
        let (front_design, q, alpha) = loop {
            passes += 1;
            let (front_design, q, alpha) = self.stages(
                solver,
                &mut whole,
                weights.as_deref(),
                start.map(|s| &s.front),
            )?;
            let Some(new) = self.effects.net_loads_n(&whole, &network.edges) else {
                break (front_design, q, alpha);
            };
            let change = max_difference(&new, weights.as_deref().unwrap_or(&[]));
            let scale = max_difference(&new, &[]);
            let settings = &self.settings;
            if change <= settings.weight_tolerance * scale || passes >= settings.max_weight_passes {
                // The weights of this pass: the design balances them exactly.
                break (front_design, q, alpha);
            }
            weights = Some(new);
        };

        // The whole network at its new geometry, judged by one forward solve.
        let problem = self.full.with_positions(whole)?.with_loads(weights)?;
        let design = Design::evaluate(
            &problem,
            &front_design.solver,
            q,
            front_design.termination,
            front_design.iterations,
            clock.elapsed(),
            front_design.warnings.clone(),
        )?;
        Ok(TiedDesign {
            design,
            problem,
            alpha,
            front: front_design,
        })
    }

    /// The two stages on the geometry `whole` (front nodes and boundary
    /// final, rear heights a start) under the nodal `weights`: the front
    /// design, every `q`, and `α`; `whole` gets the rear heights found.
    fn stages(
        &self,
        solver: &dyn UniformitySolver,
        whole: &mut [[f64; 3]],
        weights: Option<&[[f64; 3]]>,
        start: Option<&Design>,
    ) -> Result<(Design, Vec<f64>, f64), UniformityError> {
        let network = self.full.network();
        let (n_front, n) = (self.n_front, self.n_front_cables);
        // Stage 1: the front net with vertical ties.
        let mut front_nodes = whole[..n_front].to_vec();
        front_nodes.extend(self.ties.iter().map(|&(_, _, r)| whole[r]));
        let front_loads = weights.map(|w| {
            let mut loads = w[..n_front].to_vec();
            loads.resize(front_nodes.len(), [0.0; 3]);
            loads
        });
        let front = self
            .front
            .with_positions(front_nodes)?
            .with_loads(front_loads)?;
        let mut front_design = match start {
            Some(start) => solver.solve_from(&front, start),
            None => solver.solve(&front),
        }?
        .feasible()?;
        if !solver.unique_design() {
            // A point of the optimal face that moves continuously with C.
            let bounds: Vec<f64> = front_design
                .sets
                .iter()
                .map(|s| s.ratio * (1.0 + self.settings.selection_slack))
                .collect();
            let mut selected = most_uniform(&front, &front_design.solver, &bounds)?.feasible()?;
            selected.iterations += front_design.iterations;
            selected.warnings.splice(0..0, front_design.warnings);
            front_design = selected;
        }
        let (front, front_design) = self.plumb_ties(front, front_design)?;
        let mut front_design = front_design.at_level(&front)?;
        let q_front = &front_design.q;
        let balanced = &front_design.nodes_xyz_m;
        for &(_, i, r) in &self.ties {
            whole[r][..2].copy_from_slice(&balanced[i][..2]);
        }

        // Stage 2: rear force densities balancing the plan, then heights.
        let rear = self.rear_stage(q_front, &front_design.tensions_n[n..], whole, weights)?;
        if let Some(warning) = rear.warning {
            front_design.warnings.push(warning);
        }
        for &i in self.rear.free_nodes() {
            whole[n_front + i] = rear.nodes_xyz_m[i];
        }
        let (q_rear, alpha) = (rear.q, rear.alpha);
        let q_front = &front_design.q;
        let mut q = vec![0.0; network.n_edges()];
        q[..n].copy_from_slice(&q_front[..n]);
        q[n..2 * n].copy_from_slice(&q_rear);
        for (t, &(k, i, r)) in self.ties.iter().enumerate() {
            let top = front_design.nodes_xyz_m[i][2];
            let length = top - whole[r][2];
            if length.is_nan() || length <= 0.0 {
                return Err(UniformityError::invalid(
                    format!("tie {k}"),
                    format!(
                        "the rear node {r} rises to {:.4} m, above front node {i} at {top:.4} m — \
                         the rear net is too slack for this boundary",
                        whole[r][2]
                    ),
                ));
            }
            q[k] = front_design.tensions_n[n + t] / length;
        }

        Ok((front_design, q, alpha))
    }

    /// The front stage's `design` judged again with every tie anchored
    /// straight below the node it holds, where the design balances that node:
    /// the design geometry for the exact solvers (no change), the free
    /// geometry for `gradient`, whose slanted ties would otherwise lose their
    /// plan pull in the whole network (measured on `small-hex`: the front
    /// net's mean tension 1.8e-8 off its target). The rear nodes go below
    /// the same points, so the whole network's forward solve finds both
    /// stages' tensions again. A few forward solves at most: each moves the
    /// nodes by the plan pull of the last offset.
    fn plumb_ties(
        &self,
        mut front: UniformityProblem,
        mut design: Design,
    ) -> Result<(UniformityProblem, Design), UniformityError> {
        let n_front = self.n_front;
        let mut last = f64::INFINITY;
        for _ in 0..self.settings.plumb_passes {
            let mut nodes = front.network().nodes.clone();
            let mut offset: f64 = 0.0;
            for (t, &(_, i, _)) in self.ties.iter().enumerate() {
                let (top, anchor) = (design.nodes_xyz_m[i], &mut nodes[n_front + t]);
                offset = offset.max((top[0] - anchor[0]).hypot(top[1] - anchor[1]));
                anchor[..2].copy_from_slice(&top[..2]);
            }
            if offset <= self.settings.plumb_tolerance_m || offset >= last {
                break;
            }
            last = offset;
            front = front.with_positions(nodes)?;
            let q = design.q.clone();
            design = design.judged_again(&front, q)?;
        }
        Ok((front, design))
    }

    /// Stage 2 for the front design `q_front` whose ties pull with
    /// `tie_tensions`: the rear force densities closest to the mirror
    /// `α q_front` that balance the plan ([`TiedNets::balance_plan`], affine
    /// in `α`), then
    /// the rear heights under the ties' pull, at the level `α` at which the
    /// rear net's interior cables carry the scene's mean tension
    /// ([`ReflectorMesh::rear_mean_tension_n`]). The level sets the rear
    /// net's depth (its shape is free): secant steps on `ln α` from the
    /// vertical-balance fit [`TiedNets::alpha`], which the mean tension
    /// follows nearly in proportion (measured: 3 secant steps to 1e-13 on
    /// small-hex and realistic-26m, 5 on paper-26m). A level that cannot be
    /// reached keeps the best one and says so.
    fn rear_stage(
        &self,
        q_front: &[f64],
        tie_tensions: &[f64],
        whole: &[[f64; 3]],
        weights: Option<&[[f64; 3]]>,
    ) -> Result<RearStage, UniformityError> {
        let (n_front, n) = (self.n_front, self.n_front_cables);
        let rear_plan: Vec<[f64; 3]> = whole[n_front..].iter().map(|p| [p[0], p[1], 0.0]).collect();
        let plan_loads = weights.map_or_else(
            || vec![[0.0; 3]; rear_plan.len()],
            |w| w[n_front..].to_vec(),
        );
        let mut loads = plan_loads.clone();
        for (&(_, _, r), t) in self.ties.iter().zip(tie_tensions) {
            loads[r - n_front][2] += t;
        }
        let rear_nodes = whole[n_front..].to_vec();
        let interior: Vec<usize> = (0..n)
            .filter(|&k| self.mesh.groups[k + n] == CableGroup::Rear)
            .collect();
        let target = self.mesh.rear_mean_tension_n;
        // The balance is affine in the level: its weights scale with α², its
        // start with α, so `q(α) = α q₁ + d` with `q₁` the unloaded balance of
        // the mirror at α = 1 and `d` what the plan loads add — one or two
        // factorisations for every secant step, not one per step.
        let unloaded = self.balance_plan(&rear_plan, &q_front[..n], None)?;
        let added: Option<Vec<f64>> = if plan_loads.iter().any(|p| p[0] != 0.0 || p[1] != 0.0) {
            let loaded = self.balance_plan(&rear_plan, &q_front[..n], Some(&plan_loads))?;
            Some(loaded.iter().zip(&unloaded).map(|(l, u)| l - u).collect())
        } else {
            None
        };
        let at = |alpha: f64| -> Result<(RearStage, f64), UniformityError> {
            let q: Vec<f64> = match &added {
                Some(added) => unloaded
                    .iter()
                    .zip(added)
                    .map(|(u, d)| alpha * u + d)
                    .collect(),
                None => unloaded.iter().map(|u| alpha * u).collect(),
            };
            self.check_rear_tension(&q)?;
            let rear = self.rear.solve(&q, &rear_nodes, Some(&loads))?;
            let mean = interior
                .iter()
                .map(|&k| rear.edges_forces_n[k])
                .sum::<f64>()
                / interior.len() as f64;
            let stage = RearStage {
                q,
                nodes_xyz_m: rear.nodes_xyz_m,
                alpha,
                warning: None,
            };
            Ok((stage, (mean / target).ln()))
        };
        let mut a = self.alpha(q_front).ln();
        let (mut best, mut f) = at(a.exp())?;
        if interior.is_empty() {
            return Ok(best);
        }
        let (tolerance, steps) = (
            self.settings.rear_level_tolerance,
            self.settings.rear_level_steps,
        );
        let mut previous: Option<(f64, f64)> = None;
        for _ in 0..steps {
            if f.abs() <= tolerance {
                return Ok(best);
            }
            // The mean tension is nearly proportional to α: slope 1 first.
            let slope = match previous {
                Some((a0, f0)) if f != f0 => (f - f0) / (a - a0),
                _ => 1.0,
            };
            previous = Some((a, f));
            a -= f / slope;
            let (stage, next) = at(a.exp())?;
            if !next.is_finite() {
                break;
            }
            (best, f) = (stage, next);
        }
        if f.abs() > tolerance {
            best.warning = Some(format!(
                "the rear net's mean tension is {} N, not the scene's {} N \
                 (rear_net.mean_tension_n): its level did not converge in {steps} steps",
                target * f.exp(),
                target,
            ));
        }
        Ok(best)
    }

    /// The rear level `α` that best balances the nominal rear net vertically
    /// against the ties of `q_front` (least squares over rear free nodes):
    /// `α Σ_j q_f (z_j − z_i) + t_i = 0` at rear node `i`.
    fn alpha(&self, q_front: &[f64]) -> f64 {
        let x = &self.full.network().nodes;
        let n = self.n_front_cables;
        let edges = &self.full.network().edges;
        let (mut a, mut b) = (vec![0.0; x.len()], vec![0.0; x.len()]);
        for k in 0..n {
            let [i, j] = edges[k + n];
            let pull = q_front[k] * (x[j][2] - x[i][2]);
            a[i] += pull;
            a[j] -= pull;
        }
        for (t, &(_, i, r)) in self.ties.iter().enumerate() {
            b[r] += q_front[n + t] * (x[i][2] - x[r][2]);
        }
        let (mut ab, mut aa) = (0.0, 0.0);
        for &i in self.rear.free_nodes() {
            let i = i + self.n_front;
            ab += a[i] * b[i];
            aa += a[i] * a[i];
        }
        -ab / aa
    }

    /// The force densities closest to `q0` (relative least squares) in plan
    /// equilibrium with the loads' plan components `p` at the rear free
    /// nodes (`None`: no loads): `q = q₀ − Q₀² Aᵀ μ`, `(A Q₀² Aᵀ) μ = A q₀ − p`, `A` the plan
    /// equilibrium matrix (2 rows per free node; sparse Cholesky, one
    /// refinement step).
    fn balance_plan(
        &self,
        plan: &[[f64; 3]],
        q0: &[f64],
        loads_n: Option<&[[f64; 3]]>,
    ) -> Result<Vec<f64>, UniformityError> {
        let structure = &self.rear;
        let rows = 2 * structure.free_nodes().len();
        let column = |k: usize| {
            let [i, j] = structure.edges()[k];
            let u = [plan[i][0] - plan[j][0], plan[i][1] - plan[j][1]];
            let mut entries = Vec::with_capacity(4);
            for (node, sign) in [(i, 1.0), (j, -1.0)] {
                if let Some(f) = structure.free_index(node) {
                    entries.push((2 * f, sign * u[0]));
                    entries.push((2 * f + 1, sign * u[1]));
                }
            }
            entries
        };
        // The residual `A q − p`.
        let a_times = |q: &[f64]| {
            let mut r = vec![0.0; rows];
            if let Some(loads_n) = loads_n {
                for (f, &i) in structure.free_nodes().iter().enumerate() {
                    r[2 * f] -= loads_n[i][0];
                    r[2 * f + 1] -= loads_n[i][1];
                }
            }
            for (k, &qk) in q.iter().enumerate() {
                for (row, v) in column(k) {
                    r[row] += v * qk;
                }
            }
            r
        };
        let mut triplets = Vec::new();
        for (k, &w) in q0.iter().enumerate() {
            let entries = column(k);
            for &(ra, va) in &entries {
                for &(rb, vb) in &entries {
                    if rb <= ra {
                        triplets.push(Triplet::new(ra, rb, w * w * va * vb));
                    }
                }
            }
        }
        let failed = |e: String| UniformityError::SolverFailed {
            solver: "rear plan balance",
            status: e,
        };
        let s = SparseColMat::try_new_from_triplets(rows, rows, &triplets)
            .map_err(|e| failed(e.plain()))?;
        let symbolic =
            SymbolicLlt::try_new(s.symbolic(), Side::Lower).map_err(|e| failed(e.plain()))?;
        let llt = Llt::try_new_with_symbolic(symbolic, s.as_ref(), Side::Lower).map_err(|e| {
            failed(format!(
                "the rear net's plan is not stiff with its hinges: {}",
                e.plain()
            ))
        })?;
        let mut q = q0.to_vec();
        for _ in 0..2 {
            let r = a_times(&q);
            let mut mu = Mat::from_fn(rows, 1, |i, _| r[i]);
            llt.solve_in_place(mu.as_mut());
            for (k, qk) in q.iter_mut().enumerate() {
                let at_mu: f64 = column(k).iter().map(|&(row, v)| v * mu[(row, 0)]).sum();
                *qk -= q0[k] * q0[k] * at_mu;
            }
        }
        Ok(q)
    }

    /// Refuses rear force densities that are not positive, naming the
    /// cables.
    fn check_rear_tension(&self, q: &[f64]) -> Result<(), UniformityError> {
        let negative: Vec<usize> = (0..q.len())
            .filter(|&k| q[k].is_nan() || q[k] <= 0.0)
            .collect();
        if !negative.is_empty() {
            return Err(UniformityError::invalid(
                format!(
                    "rear-net cables {:?}",
                    negative
                        .iter()
                        .take(8)
                        .map(|k| k + self.n_front_cables)
                        .collect::<Vec<_>>()
                ),
                "cannot stay in tension with the deformed bottom hinges",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The defaults pass; a tolerance out of range or no pass of the stages
    /// is refused by its dotted name.
    #[test]
    fn tied_net_settings_out_of_range_are_named() {
        assert!(TiedNetSettings::default().validate().is_ok());
        let cases = [
            (
                TiedNetSettings {
                    selection_slack: -1e-3,
                    ..TiedNetSettings::default()
                },
                "tied_nets.selection_slack",
            ),
            (
                TiedNetSettings {
                    weight_tolerance: f64::INFINITY,
                    ..TiedNetSettings::default()
                },
                "tied_nets.weight_tolerance",
            ),
            (
                TiedNetSettings {
                    plumb_tolerance_m: f64::NAN,
                    ..TiedNetSettings::default()
                },
                "tied_nets.plumb_tolerance_m",
            ),
            (
                TiedNetSettings {
                    rear_level_tolerance: -1.0,
                    ..TiedNetSettings::default()
                },
                "tied_nets.rear_level_tolerance",
            ),
            (
                TiedNetSettings {
                    max_weight_passes: 0,
                    ..TiedNetSettings::default()
                },
                "tied_nets.max_weight_passes",
            ),
        ];
        for (settings, field) in cases {
            match settings.validate() {
                Err(DesignError::Setting { key, .. }) => assert_eq!(key, field),
                other => panic!("{field}: {other:?}"),
            }
        }
    }
}
