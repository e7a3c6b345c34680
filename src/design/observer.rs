//! What a design run reports as it goes ([`DesignObserver`], argmin's
//! observers): each outer iteration, and each stage after the loop as it
//! begins ([`DesignStage`]). The library never prints; the command line
//! attaches a progress bar or a log line.

use super::outer_loop::IterationRecord;
use super::relaxation::RelaxationKind;

/// A stage of a design after its outer loop, in the order they run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DesignStage {
    /// The truss's limit load under the converged design's pull.
    Margin,
    /// The cut cables assembled on the flexible truss.
    Verification,
    /// The surface error budget of the design as built.
    Surface,
    /// The conventional (rigid-truss) design assembled on the same truss.
    Conventional,
}

impl DesignStage {
    /// Every stage, in order.
    pub const ALL: [DesignStage; 4] = [
        DesignStage::Margin,
        DesignStage::Verification,
        DesignStage::Surface,
        DesignStage::Conventional,
    ];

    /// What the stage does, in a few words (a progress line).
    pub fn description(self) -> &'static str {
        match self {
            DesignStage::Margin => "limit margin: the truss's limit load under the design's pull",
            DesignStage::Verification => "verification: the cut cables assembled on the truss",
            DesignStage::Surface => "surface error budget of the design as built",
            DesignStage::Conventional => "the conventional design assembled on the same truss",
        }
    }
}

/// Sees a design run as it goes; every method does nothing by default.
pub trait DesignObserver {
    /// An outer iteration of the loop of `relaxation` finished.
    fn iteration(&mut self, _relaxation: RelaxationKind, _record: &IterationRecord) {}
    /// A stage after the loop begins.
    fn stage(&mut self, _stage: DesignStage) {}
}

/// An observer of the outer iterations alone.
pub(crate) struct Iterations<'a>(pub &'a mut dyn FnMut(RelaxationKind, &IterationRecord));

impl DesignObserver for Iterations<'_> {
    fn iteration(&mut self, relaxation: RelaxationKind, record: &IterationRecord) {
        (self.0)(relaxation, record)
    }
}
