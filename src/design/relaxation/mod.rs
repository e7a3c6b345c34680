//! Relaxation policies of the outer loop (DESIGN §6): how the next boundary
//! is chosen from the last ones.
//!
//! A policy is a [`Relaxation`]: it owns its state (the previous `ξ`, the
//! Aitken factor, Anderson's history) and answers one question per outer
//! iteration, the next iterate. The shipped policies, one file each:
//!
//! * [`Paper`] — the paper's rule as written: the full step
//!   `x_{k+1} = G(x_k)` while `ξ` decreases, else the half step
//!   `x_k + (G(x_k) − x_k)/2`;
//! * [`Aitken`] — Aitken's dynamic relaxation `x_{k+1} = x_k + ω_k r_k`;
//! * [`Anderson`] — Anderson mixing of depth m (type II, Walker–Ni 2011).
//!
//! [`RelaxationKind`] is the registry the command line and the reports name
//! them by: a new policy is one file here and one arm in
//! [`RelaxationKind::build`] (a policy used only from code — a test's, say —
//! needs neither: pass it to [`super::design_loop_with`]).

mod aitken;
mod anderson;
mod paper;

use serde::{Deserialize, Serialize};

pub use aitken::{aitken_factor, Aitken};
pub use anderson::Anderson;
pub use paper::{paper_step, Paper};

/// The next iterate a policy chose, and the factor it reports.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// `x_{k+1}`, flattened attachment points, m.
    pub x: Vec<f64>,
    /// The relaxation factor `ω` of `x_{k+1} = x_k + ω r_k` (1: the full
    /// step; Anderson, which mixes several, reports 1).
    pub factor: f64,
}

/// A relaxation policy of the outer loop: owns its state, chooses the next
/// boundary from the current one and its image.
pub trait Relaxation {
    /// The policy's name in reports.
    fn name(&self) -> &str;

    /// The next iterate from `x = x_k`, its image `image = G(x_k)`, the
    /// residual `residual = G(x_k) − x_k` (all flattened attachment points,
    /// m) and `xi = ξ_k`, the largest attachment point's distance in the
    /// residual, m. Called once per outer iteration, the last included.
    fn next(&mut self, x: &[f64], image: &[f64], residual: &[f64], xi: f64) -> Step;
}

/// The policies the command line and the reports name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum RelaxationKind {
    /// The paper's rule: full step while ξ decreases, else the half step.
    Paper,
    /// Aitken's dynamic scalar relaxation.
    Aitken,
    /// Anderson mixing of the last 10 iterates (`LoopSettings::anderson_depth`).
    #[default]
    Anderson,
}

impl RelaxationKind {
    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            RelaxationKind::Paper => "paper",
            RelaxationKind::Aitken => "aitken",
            RelaxationKind::Anderson => "anderson",
        }
    }

    /// A fresh policy of this kind; `anderson_depth`: the differences
    /// Anderson mixing keeps.
    pub fn build(self, anderson_depth: usize) -> Box<dyn Relaxation> {
        match self {
            RelaxationKind::Paper => Box::new(Paper::default()),
            RelaxationKind::Aitken => Box::new(Aitken::default()),
            RelaxationKind::Anderson => Box::new(Anderson::new(anderson_depth)),
        }
    }
}

/// `x + ω r`, elementwise.
pub(crate) fn relaxed_step(x: &[f64], residual: &[f64], omega: f64) -> Vec<f64> {
    x.iter().zip(residual).map(|(c, r)| c + omega * r).collect()
}
