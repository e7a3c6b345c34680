//! The plan reduction of a reflector's front-net problem (DESIGN §4).
//!
//! A reflector mesh (see `geometry::net`) lays out its cables as: the front net
//! `0..n`, the rear net `n..2n` on the same plan grid in the same order (rear
//! node `i + o` below front node `i`), then one vertical tie `[i, i + o]` per free
//! front node. Ties carry no plan force, so the plan equilibrium of the front
//! net involves front-net cables only: the uniformity LP of a set inside the
//! front net is a *plan* problem, two rows per front free node instead of three
//! per free node of both nets and no tie or rear unknowns. Its solution is
//! completed exactly:
//!
//! * each tie balances the vertical pull of the front net at its node,
//!   `q_t (z_i − z_r) = Σ_j q_ij (z_j − z_i)` (on the paraboloid
//!   `z = ρ²/(4F)` with plan equilibrium this is `Σ_j q_ij |p_j − p_i|²/(4F) > 0`);
//! * the rear net takes `q_rear = α q_front` cable by cable: plan equilibrium
//!   holds on the same plan grid, and vertical equilibrium with the ties holds
//!   for one `α` (`F_rear/F` for two paraboloids), fitted by least squares.
//!
//! The rear net may also be absent, every tie anchored at a fixed node below
//! its front node (the front stage of the outer design loop, see
//! `design::TiedNets`): then the completion is the ties alone.
//!
//! The plan LP relaxes the full LP (it keeps a subset of its constraints), so a
//! completion that balances every free node and respects every bound proves its
//! optimum is the full optimum. [`PlanReduction::complete`] checks exactly that
//! and reports why not otherwise (a deformed boundary that breaks the mirror,
//! a tie that would push): the caller then solves the full problem.

use super::ipm::RatioLp;
use super::UniformityProblem;

/// Relative size of a plan component below which a cable counts as vertical.
const VERTICAL: f64 = 1e-12;
/// Largest out-of-balance force of a completed design, relative to its largest
/// tension, for the completion to count as exact.
const COMPLETION_TOLERANCE: f64 = 1e-9;

/// Why a problem is not the single-set front-net problem of a reflector mesh.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(crate) enum LayoutError {
    /// No vertical ties at the end of the cable list (or an odd count before
    /// them when there is a rear net).
    #[error("the network does not end with the vertical ties of a reflector mesh")]
    NoTies,
    /// A rear cable does not mirror its front cable.
    #[error("cable {rear} is not the rear-net mirror of front-net cable {front}")]
    NotMirrored {
        /// The rear-net cable.
        rear: usize,
        /// The front-net cable it should mirror.
        front: usize,
    },
    /// Several sets, or a set with cables outside the front net.
    #[error("the uniformity set is not inside the front net")]
    SetOutsideFrontNet,
    /// A tie that does not hang below its front node.
    #[error("tie {tie} does not join a front node to the node below it")]
    TieMisplaced {
        /// The tie.
        tie: usize,
    },
    /// A front node with two ties.
    #[error("front node {node} has two ties")]
    TwoTies {
        /// The front node.
        node: usize,
    },
    /// A free front node without a tie.
    #[error("front node {node} has no tie")]
    NoTie {
        /// The front node.
        node: usize,
    },
}

/// Why a completed plan solution is not the optimum of the full problem.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(crate) enum CompletionError {
    /// No positive rear level balances the ties.
    #[error(
        "the rear net cannot balance the ties with a positive multiple of the front force \
         densities (α = {alpha:.3e})"
    )]
    RearLevel {
        /// The least-squares level found.
        alpha: f64,
    },
    /// The completion does not balance the prescribed geometry.
    #[error(
        "the completed design leaves {residual_n:.3e} N out of balance (largest tension \
         {max_tension_n:.3e} N): the rear net does not mirror the front net"
    )]
    OutOfBalance {
        /// Largest out-of-balance force, N.
        residual_n: f64,
        /// Largest tension, N.
        max_tension_n: f64,
    },
    /// A tie or rear cable below the tension floor.
    #[error(
        "cable {cable} of the completion carries {tension:.3e} of the smallest set tension, \
         below the floor {floor}"
    )]
    BelowFloor {
        /// The cable.
        cable: usize,
        /// Its tension per unit smallest set tension.
        tension: f64,
        /// The floor, `min_tension_fraction`.
        floor: f64,
    },
}

/// The recognised layout of a reflector mesh and its plan problem.
#[derive(Debug, Clone)]
pub(crate) struct PlanReduction {
    /// Front-net cables `0..n_front_cables`; rear cable `k + n_front_cables`.
    n_front_cables: usize,
    /// False when every tie ends at a fixed anchor (no rear net).
    rear: bool,
    /// Each tie: (cable, front node, rear node).
    ties: Vec<(usize, usize, usize)>,
    /// The plan LP over the front-net cables.
    lp: RatioLp<2>,
}

impl PlanReduction {
    /// Recognises the reflector layout in a single-set problem without loads,
    /// or says why the problem is not of that form.
    pub(crate) fn new(problem: &UniformityProblem) -> Result<Self, LayoutError> {
        let network = problem.network();
        let m = network.n_edges();
        let u = network.edges_vectors();
        let is_vertical = |k: usize| {
            let [x, y, z] = u[k];
            x.hypot(y) <= VERTICAL * z.abs()
        };
        let n_ties = (0..m).rev().take_while(|&k| is_vertical(k)).count();
        let structure = problem.structure();
        let edges = &network.edges;
        let rear = !edges[m - n_ties..]
            .iter()
            .all(|&[_, r]| structure.free_index(r).is_none());
        if n_ties == 0 || (rear && (m - n_ties) % 2 != 0) {
            return Err(LayoutError::NoTies);
        }
        let n = if rear { (m - n_ties) / 2 } else { m - n_ties };
        let first_tie = m - n_ties;
        let offset = edges[first_tie][1].wrapping_sub(edges[first_tie][0]);
        if let Some(k) = (0..n).find(|&k| {
            is_vertical(k) || (rear && edges[k + n] != [edges[k][0] + offset, edges[k][1] + offset])
        }) {
            return Err(LayoutError::NotMirrored {
                rear: k + n,
                front: k,
            });
        }
        if problem.sets().len() != 1 || problem.sets()[0].edges.iter().any(|&k| k >= n) {
            return Err(LayoutError::SetOutsideFrontNet);
        }

        // Plan rows: the free nodes of the front net, each with exactly one tie.
        let mut local = vec![None; network.n_nodes()];
        let mut n_free = 0;
        for &i in edges[..n].iter().flatten() {
            if local[i].is_none() && structure.free_index(i).is_some() {
                local[i] = Some(n_free);
                n_free += 1;
            }
        }
        let mut tied = vec![false; n_free];
        let mut ties = Vec::with_capacity(n_ties);
        for (k, &[i, r]) in edges.iter().enumerate().skip(first_tie) {
            let Some(f) = local[i].filter(|_| !rear || r == i + offset) else {
                return Err(LayoutError::TieMisplaced { tie: k });
            };
            if std::mem::replace(&mut tied[f], true) {
                return Err(LayoutError::TwoTies { node: i });
            }
            ties.push((k, i, r));
        }
        if let Some(f) = tied.iter().position(|&t| !t) {
            let i = local.iter().position(|&l| l == Some(f)).unwrap_or(f);
            return Err(LayoutError::NoTie { node: i });
        }

        let mut in_set = vec![false; n];
        for &k in &problem.sets()[0].edges {
            in_set[k] = true;
        }
        let lp = RatioLp {
            n_free,
            ends: edges[..n].iter().map(|e| e.map(|i| local[i])).collect(),
            vectors: u[..n].iter().map(|&[x, y, _]| [x, y]).collect(),
            lengths: problem.lengths_m()[..n].to_vec(),
            in_set,
            min_other_tension: problem.min_tension_fraction,
        };
        Ok(PlanReduction {
            n_front_cables: n,
            rear,
            ties,
            lp,
        })
    }

    /// The plan LP over the front-net cables.
    pub(crate) fn lp(&self) -> &RatioLp<2> {
        &self.lp
    }

    /// Completes front-net force densities (unscaled: smallest set tension 1)
    /// with the ties and the rear net, and checks that the result balances the
    /// prescribed geometry and keeps every bound of the full LP.
    pub(crate) fn complete(
        &self,
        problem: &UniformityProblem,
        q_front: &[f64],
    ) -> Result<Vec<f64>, CompletionError> {
        let n = self.n_front_cables;
        let network = problem.network();
        let x = &network.nodes;
        let m = network.n_edges();
        let mut q = vec![0.0; m];
        q[..n].copy_from_slice(q_front);

        let front_pull = vertical_pull(network, 0..n, &q);
        for &(k, i, r) in &self.ties {
            q[k] = front_pull[i] / (x[i][2] - x[r][2]);
        }
        if self.rear {
            self.complete_rear(network, &mut q)?;
        }
        self.check(problem, q)
    }

    /// The rear net `q_rear = α q_front`, α from the rear nodes' vertical
    /// balance against the ties (least squares).
    fn complete_rear(
        &self,
        network: &crate::Network,
        q: &mut [f64],
    ) -> Result<(), CompletionError> {
        let n = self.n_front_cables;
        let x = &network.nodes;
        // α from the rear nodes' vertical balance: α V_r + q_t (z_i − z_r) = 0.
        for k in 0..n {
            q[k + n] = q[k];
        }
        let rear_pull = vertical_pull(network, n..2 * n, q);
        let (mut num, mut den) = (0.0, 0.0);
        for &(k, i, r) in &self.ties {
            let tie = q[k] * (x[i][2] - x[r][2]);
            num -= tie * rear_pull[r];
            den += rear_pull[r] * rear_pull[r];
        }
        let alpha = num / den;
        if !(alpha.is_finite() && alpha > 0.0) {
            return Err(CompletionError::RearLevel { alpha });
        }
        q[n..2 * n].iter_mut().for_each(|v| *v *= alpha);
        Ok(())
    }

    /// `q` if it balances the prescribed geometry and keeps the full LP's
    /// bounds, else why not.
    fn check(&self, problem: &UniformityProblem, q: Vec<f64>) -> Result<Vec<f64>, CompletionError> {
        let n = self.n_front_cables;
        let m = q.len();
        let lengths = problem.lengths_m();
        let tensions: Vec<f64> = q.iter().zip(lengths).map(|(q, l)| q * l).collect();
        let max_tension = tensions.iter().copied().fold(0.0, f64::max);
        let residual = problem.prescribed_residual_n(&q);
        if residual.is_nan() || residual > COMPLETION_TOLERANCE * max_tension {
            return Err(CompletionError::OutOfBalance {
                residual_n: residual,
                max_tension_n: max_tension,
            });
        }
        let floor = problem.min_tension_fraction * (1.0 - 1e-9);
        if let Some(k) = (n..m).find(|&k| tensions[k].is_nan() || tensions[k] < floor) {
            return Err(CompletionError::BelowFloor {
                cable: k,
                tension: tensions[k],
                floor: problem.min_tension_fraction,
            });
        }
        Ok(q)
    }
}

/// Vertical pull of the cables `range` at every node: `Σ_j q_ij (z_j − z_i)`.
fn vertical_pull(network: &crate::Network, range: std::ops::Range<usize>, q: &[f64]) -> Vec<f64> {
    let x = &network.nodes;
    let mut v = vec![0.0; network.n_nodes()];
    for k in range {
        let [i, j] = network.edges[k];
        let f = q[k] * (x[j][2] - x[i][2]);
        v[i] += f;
        v[j] -= f;
    }
    v
}
