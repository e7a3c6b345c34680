//! The plan reduction of a tied net's uniformity problem (DESIGN §4),
//! recognised from the physics of the network, not from its group names or
//! the order of its nodes and cables.
//!
//! * The **net** is the uniformity set's cables and every other cable joining
//!   two of their nodes (a boundary outside the set, say).
//! * Every free node of the net must have, as its only cable leaving the net,
//!   one **vertical tie** (plan component at most [`TIE_PLAN_TOLERANCE`] of its
//!   length) to a node outside the net: a fixed anchor, or a free node of a
//!   **rear net**.
//! * A rear net (the remaining cables) must mirror the net cable by cable
//!   through the ties: rear cable `[a, b]` ↔ net cable `[f(a), f(b)]`, `f` the
//!   tie of a free rear node, a fixed rear node matched by its plan vector.
//!
//! Ties carry no plan force, so the plan equilibrium of the net involves net
//! cables only: the uniformity LP is a *plan* problem, two rows per free net
//! node instead of three per free node of the whole network, and no tie or
//! rear unknowns. Its solution is completed exactly:
//!
//! * each tie balances the vertical pull of the net at its node,
//!   `q_t (z_i − z_r) = Σ_j q_ij (z_j − z_i)` (on the paraboloid
//!   `z = ρ²/(4F)` with plan equilibrium this is `Σ_j q_ij |p_j − p_i|²/(4F) > 0`);
//! * a rear net takes `q_rear = α q_net` cable by cable: plan equilibrium
//!   holds on the same plan grid, and vertical equilibrium with the ties holds
//!   for one `α` (`F_rear/F` for two paraboloids), fitted by least squares.
//!
//! The plan LP relaxes the full LP (it keeps a subset of its constraints), so a
//! completion that balances every free node and respects every bound proves its
//! optimum is the full optimum. [`PlanReduction::complete`] checks exactly that
//! and says why not otherwise (nodes off the paraboloid, a rear net that does
//! not mirror in geometry): the caller then solves the full problem. Why a
//! network is not a tied net names the node or cable ([`LayoutError`]).

use super::ipm::RatioLp;
use super::UniformityProblem;
use crate::algebra::norm3;
use crate::fdm::NONE;

/// A cable whose plan component is at most this fraction of its length counts
/// as vertical: a tie, whose plan force the plan problem drops. A tie of
/// tension `T` and relative plan component `δ` pulls its node sideways by `δT`;
/// at `δ ≤ 1e-9` that is within [`COMPLETION_TOLERANCE`] of the largest
/// tension, the imbalance the completion accepts (and verifies on the full
/// geometry). It is far above the rounding of coordinates computed separately
/// for a node and its anchor by another program (`|x| ε ≈ 50 m · 1.1e-16`,
/// 6e-15 of a 1 m tie, 6e-12 of a 1 mm one), which a tolerance near 1e-12
/// would not be.
pub(crate) const TIE_PLAN_TOLERANCE: f64 = 1e-9;
/// Largest out-of-balance force of a completed design, relative to its largest
/// tension, for the completion to count as exact.
const COMPLETION_TOLERANCE: f64 = 1e-9;
/// Largest mismatch of plan vectors, relative to the cable length, for a rear
/// cable at a fixed node to mirror a net cable (the completion then verifies
/// the balance exactly).
const MIRROR_TOLERANCE: f64 = 1e-6;

/// Why a problem is not the plan problem of a tied net (each names the cable
/// or node at fault).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(crate) enum LayoutError {
    /// Several uniformity sets.
    #[error("{0} uniformity sets; the plan reduction takes one")]
    Sets(usize),
    /// A net cable without a plan component.
    #[error("net cable {cable} (nodes {nodes:?}) is vertical: its vertical force has no plan counterpart")]
    VerticalNetCable {
        /// The cable.
        cable: usize,
        /// Its nodes.
        nodes: [usize; 2],
    },
    /// A cable leaving the net that is not vertical.
    #[error(
        "tie {cable} at node {node} is {angle_deg:.3}° off vertical (plan component \
         {relative:.1e} of its length, tolerance {TIE_PLAN_TOLERANCE:.0e})"
    )]
    TiltedTie {
        /// The cable leaving the net.
        cable: usize,
        /// Its net node.
        node: usize,
        /// Its angle to the vertical, degrees.
        angle_deg: f64,
        /// Its plan component per unit length.
        relative: f64,
    },
    /// A free net node without a tie.
    #[error("free node {node} of the net has no tie: its vertical balance does not follow from the plan")]
    NoTie {
        /// The node.
        node: usize,
    },
    /// A free net node with two ties.
    #[error("free node {node} of the net has two ties, {first} and {second}")]
    TwoTies {
        /// The node.
        node: usize,
        /// One tie.
        first: usize,
        /// The other.
        second: usize,
    },
    /// A free node outside the net that holds two ties.
    #[error("free node {node} outside the net holds two ties, {first} and {second}")]
    SharedAnchor {
        /// The node.
        node: usize,
        /// One tie.
        first: usize,
        /// The other.
        second: usize,
    },
    /// A tie to a free node that no rear net holds.
    #[error("tie {tie} ends at free node {node}, which no other cable holds")]
    LooseAnchor {
        /// The tie.
        tie: usize,
        /// Its free end outside the net.
        node: usize,
    },
    /// A cable outside the net and the ties, with no rear net to belong to.
    #[error("cable {cable} (nodes {nodes:?}) is neither in the net nor a tie, and no tie holds a rear net")]
    Stray {
        /// The cable.
        cable: usize,
        /// Its nodes.
        nodes: [usize; 2],
    },
    /// A free rear node without a tie.
    #[error("free node {node} of the rear net has no tie")]
    UntiedRearNode {
        /// The node.
        node: usize,
    },
    /// A rear cable that mirrors no net cable (or one mirrored already).
    #[error("rear cable {cable} (nodes {nodes:?}) mirrors no net cable")]
    NotMirrored {
        /// The rear cable.
        cable: usize,
        /// Its nodes.
        nodes: [usize; 2],
    },
    /// A net cable without a rear mirror.
    #[error("net cable {cable} has no rear mirror")]
    Unmirrored {
        /// The net cable.
        cable: usize,
    },
}

/// Why a completed plan solution is not the optimum of the full problem.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(crate) enum CompletionError {
    /// No positive rear level balances the ties.
    #[error(
        "the rear net cannot balance the ties with a positive multiple of the net's force \
         densities (α = {alpha:.3e})"
    )]
    RearLevel {
        /// The least-squares level found.
        alpha: f64,
    },
    /// The completion does not balance the prescribed geometry.
    #[error(
        "the completed design leaves {residual_n:.3e} N out of balance (largest tension \
         {max_tension_n:.3e} N): the rear net does not mirror the net"
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
         below the floor {floor} (net nodes off a paraboloid?)"
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

/// A tie: the cable, its net node, its other end.
#[derive(Debug, Clone, Copy)]
struct Tie {
    cable: usize,
    node: usize,
    anchor: usize,
}

/// The recognised tied net and its plan problem.
#[derive(Debug, Clone)]
pub(crate) struct PlanReduction {
    /// The net's cables (problem indices), in the plan LP's order.
    net: Vec<usize>,
    /// One tie per free net node.
    ties: Vec<Tie>,
    /// Each rear cable with the net cable it mirrors (problem indices).
    rear: Vec<(usize, usize)>,
    /// The plan LP over the net's cables.
    lp: RatioLp<2>,
}

impl PlanReduction {
    /// Recognises a tied net in a single-set problem without loads, or says
    /// why the problem is not of that form.
    pub(crate) fn new(problem: &UniformityProblem) -> Result<Self, LayoutError> {
        if problem.sets().len() != 1 {
            return Err(LayoutError::Sets(problem.sets().len()));
        }
        let network = problem.network();
        let edges = &network.edges;
        let x = &network.nodes;
        let (n_nodes, m) = (network.n_nodes(), network.n_edges());
        let structure = problem.structure();
        let free = |i: usize| structure.free_index(i).is_some();
        let lengths = problem.lengths_m();
        let plan_length = |k: usize| {
            let [i, j] = edges[k];
            (x[i][0] - x[j][0]).hypot(x[i][1] - x[j][1])
        };

        // The net: the set's nodes and every cable joining two of them.
        let mut in_set = vec![false; m];
        let mut net_node = vec![false; n_nodes];
        for &k in &problem.sets()[0].edges {
            in_set[k] = true;
            for i in edges[k] {
                net_node[i] = true;
            }
        }
        let in_net: Vec<bool> = edges
            .iter()
            .map(|&[i, j]| net_node[i] && net_node[j])
            .collect();
        let net: Vec<usize> = (0..m).filter(|&k| in_net[k]).collect();
        if let Some(&k) = net
            .iter()
            .find(|&&k| plan_length(k) <= TIE_PLAN_TOLERANCE * lengths[k])
        {
            return Err(LayoutError::VerticalNetCable {
                cable: k,
                nodes: edges[k],
            });
        }

        // Ties: every cable leaving the net at a free node, vertical, one per node.
        let mut tie_of = vec![NONE; n_nodes];
        let mut ties = Vec::new();
        for k in (0..m).filter(|&k| !in_net[k]) {
            let [a, b] = edges[k];
            let (node, anchor) = match (net_node[a] && free(a), net_node[b] && free(b)) {
                (true, _) => (a, b),
                (_, true) => (b, a),
                _ => continue,
            };
            let relative = plan_length(k) / lengths[k];
            if relative > TIE_PLAN_TOLERANCE {
                return Err(LayoutError::TiltedTie {
                    cable: k,
                    node,
                    angle_deg: relative.asin().to_degrees(),
                    relative,
                });
            }
            if tie_of[node] != NONE {
                return Err(LayoutError::TwoTies {
                    node,
                    first: tie_of[node],
                    second: k,
                });
            }
            tie_of[node] = k;
            ties.push(Tie {
                cable: k,
                node,
                anchor,
            });
        }
        // Plan rows: the free net nodes, in order of first appearance.
        let mut local = vec![None; n_nodes];
        let mut n_free = 0;
        for &k in &net {
            for i in edges[k] {
                if local[i].is_none() && free(i) {
                    if tie_of[i] == NONE {
                        return Err(LayoutError::NoTie { node: i });
                    }
                    local[i] = Some(n_free);
                    n_free += 1;
                }
            }
        }

        let rear = rear_mirror(problem, &in_net, &net_node, &tie_of, &ties)?;
        let lp = RatioLp {
            n_free,
            ends: net.iter().map(|&k| edges[k].map(|i| local[i])).collect(),
            vectors: net
                .iter()
                .map(|&k| {
                    let [i, j] = edges[k];
                    [x[i][0] - x[j][0], x[i][1] - x[j][1]]
                })
                .collect(),
            lengths: net.iter().map(|&k| lengths[k]).collect(),
            in_set: net.iter().map(|&k| in_set[k]).collect(),
            min_other_tension: problem.min_tension_fraction,
        };
        Ok(PlanReduction {
            net,
            ties,
            rear,
            lp,
        })
    }

    /// The plan LP over the net's cables.
    pub(crate) fn lp(&self) -> &RatioLp<2> {
        &self.lp
    }

    /// Number of ties.
    #[cfg(test)]
    pub(crate) fn n_ties(&self) -> usize {
        self.ties.len()
    }

    /// True when the ties hold a rear net (else they end at fixed anchors).
    pub(crate) fn has_rear(&self) -> bool {
        !self.rear.is_empty()
    }

    /// Completes the net's force densities (the plan LP's order, unscaled:
    /// smallest set tension 1) with the ties and the rear net, and checks that
    /// the result balances the prescribed geometry and keeps every bound of the
    /// full LP.
    pub(crate) fn complete(
        &self,
        problem: &UniformityProblem,
        q_net: &[f64],
    ) -> Result<Vec<f64>, CompletionError> {
        let network = problem.network();
        let x = &network.nodes;
        let mut q = vec![0.0; network.n_edges()];
        for (&k, &v) in self.net.iter().zip(q_net) {
            q[k] = v;
        }
        let pull = vertical_pull(network, self.net.iter().copied(), &q);
        for t in &self.ties {
            q[t.cable] = pull[t.node] / (x[t.node][2] - x[t.anchor][2]);
        }
        if self.has_rear() {
            self.complete_rear(network, &mut q)?;
        }
        self.check(problem, q)
    }

    /// The rear net `q_rear = α q_net`, α from the rear nodes' vertical
    /// balance against the ties (least squares).
    fn complete_rear(
        &self,
        network: &crate::Network,
        q: &mut [f64],
    ) -> Result<(), CompletionError> {
        let x = &network.nodes;
        for &(k, mirror) in &self.rear {
            q[k] = q[mirror];
        }
        let rear_pull = vertical_pull(network, self.rear.iter().map(|&(k, _)| k), q);
        // α V_r + q_t (z_i − z_r) = 0 at every rear node held by a tie.
        let (mut num, mut den) = (0.0, 0.0);
        for t in &self.ties {
            let tie = q[t.cable] * (x[t.node][2] - x[t.anchor][2]);
            num -= tie * rear_pull[t.anchor];
            den += rear_pull[t.anchor] * rear_pull[t.anchor];
        }
        let alpha = num / den;
        if !(alpha.is_finite() && alpha > 0.0) {
            return Err(CompletionError::RearLevel { alpha });
        }
        for &(k, _) in &self.rear {
            q[k] *= alpha;
        }
        Ok(())
    }

    /// `q` if it balances the prescribed geometry and keeps the full LP's
    /// bounds, else why not.
    fn check(&self, problem: &UniformityProblem, q: Vec<f64>) -> Result<Vec<f64>, CompletionError> {
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
        let completed = self
            .ties
            .iter()
            .map(|t| t.cable)
            .chain(self.rear.iter().map(|&(k, _)| k));
        for k in completed {
            if tensions[k].is_nan() || tensions[k] < floor {
                return Err(CompletionError::BelowFloor {
                    cable: k,
                    tension: tensions[k],
                    floor: problem.min_tension_fraction,
                });
            }
        }
        Ok(q)
    }
}

/// The rear net: every cable neither in the net nor a tie, each with the net
/// cable it mirrors; empty when every tie ends at a fixed anchor.
fn rear_mirror(
    problem: &UniformityProblem,
    in_net: &[bool],
    net_node: &[bool],
    tie_of: &[usize],
    ties: &[Tie],
) -> Result<Vec<(usize, usize)>, LayoutError> {
    let network = problem.network();
    let (edges, x) = (&network.edges, &network.nodes);
    let (n_nodes, m) = (network.n_nodes(), network.n_edges());
    let structure = problem.structure();
    let free = |i: usize| structure.free_index(i).is_some();
    let mut is_tie = vec![false; m];
    // The net node hung on each free anchor (the mirror map of rear nodes).
    let mut held = vec![NONE; n_nodes];
    for t in ties {
        is_tie[t.cable] = true;
        if free(t.anchor) {
            if held[t.anchor] != NONE {
                return Err(LayoutError::SharedAnchor {
                    node: t.anchor,
                    first: tie_of[held[t.anchor]],
                    second: t.cable,
                });
            }
            held[t.anchor] = t.node;
        }
    }
    let others: Vec<usize> = (0..m).filter(|&k| !in_net[k] && !is_tie[k]).collect();
    let Some(free_anchor) = ties.iter().find(|t| free(t.anchor)) else {
        return match others.first() {
            Some(&k) => Err(LayoutError::Stray {
                cable: k,
                nodes: edges[k],
            }),
            None => Ok(Vec::new()),
        };
    };
    if others.is_empty() {
        return Err(LayoutError::LooseAnchor {
            tie: free_anchor.cable,
            node: free_anchor.anchor,
        });
    }
    // Net cables by node (compressed rows).
    let mut start = vec![0usize; n_nodes + 1];
    for k in (0..m).filter(|&k| in_net[k]) {
        for i in edges[k] {
            start[i + 1] += 1;
        }
    }
    for i in 0..n_nodes {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut at = vec![0usize; start[n_nodes]];
    for k in (0..m).filter(|&k| in_net[k]) {
        for i in edges[k] {
            at[fill[i]] = k;
            fill[i] += 1;
        }
    }
    let other_end = |k: usize, i: usize| {
        let [a, b] = edges[k];
        if a == i {
            b
        } else {
            a
        }
    };
    let mut mirrored = vec![false; m];
    let mut rear = Vec::with_capacity(others.len());
    for &k in &others {
        let [a, b] = edges[k];
        for i in [a, b] {
            if free(i) && held[i] == NONE {
                return Err(LayoutError::UntiedRearNode { node: i });
            }
        }
        let not_mirrored = LayoutError::NotMirrored {
            cable: k,
            nodes: edges[k],
        };
        let mirror = match (free(a), free(b)) {
            (true, true) => {
                let (fa, fb) = (held[a], held[b]);
                at[start[fa]..start[fa + 1]]
                    .iter()
                    .copied()
                    .find(|&c| other_end(c, fa) == fb)
            }
            (true, false) | (false, true) => {
                let (r_free, r_fixed) = if free(a) { (a, b) } else { (b, a) };
                let f = held[r_free];
                let want = [x[r_fixed][0] - x[r_free][0], x[r_fixed][1] - x[r_free][1]];
                let tolerance = MIRROR_TOLERANCE * problem.lengths_m()[k];
                at[start[f]..start[f + 1]].iter().copied().find(|&c| {
                    let o = other_end(c, f);
                    !free(o)
                        && !net_node[r_fixed]
                        && norm3([
                            x[o][0] - x[f][0] - want[0],
                            x[o][1] - x[f][1] - want[1],
                            0.0,
                        ]) <= tolerance
                })
            }
            (false, false) => None,
        };
        match mirror {
            Some(c) if !std::mem::replace(&mut mirrored[c], true) => rear.push((k, c)),
            _ => return Err(not_mirrored),
        }
    }
    if let Some(k) = (0..m).find(|&k| in_net[k] && !mirrored[k]) {
        return Err(LayoutError::Unmirrored { cable: k });
    }
    Ok(rear)
}

/// Vertical pull of the cables `cables` at every node: `Σ_j q_ij (z_j − z_i)`.
fn vertical_pull(
    network: &crate::Network,
    cables: impl Iterator<Item = usize>,
    q: &[f64],
) -> Vec<f64> {
    let x = &network.nodes;
    let mut v = vec![0.0; network.n_nodes()];
    for k in cables {
        let [i, j] = network.edges[k];
        let f = q[k] * (x[j][2] - x[i][2]);
        v[i] += f;
        v[j] -= f;
    }
    v
}
