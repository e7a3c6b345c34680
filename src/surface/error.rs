//! What can go wrong measuring a surface: invalid input, a best fit that does
//! not converge, a net-density target that no net meets.

use crate::scene::SceneError;

/// An invalid surface measurement, or one that cannot be completed.
#[derive(Debug, thiserror::Error)]
pub enum SurfaceError {
    /// A scene whose net cannot be built at some ring count.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The design paraboloid's focal length is not a positive number.
    #[error("focal length {focal_length_m} m: a paraboloid needs a finite, positive focal length")]
    FocalLength {
        /// The focal length given, m.
        focal_length_m: f64,
    },
    /// No nodes to measure.
    #[error("no nodes to measure the surface at")]
    NoNodes,
    /// No facets to measure.
    #[error("no facets to measure the surface over")]
    NoFacets,
    /// A node with a NaN or infinite coordinate.
    #[error("node {node} has a non-finite coordinate {xyz_m:?}")]
    NonFiniteNode {
        /// Index of the node.
        node: usize,
        /// Its coordinates, m.
        xyz_m: [f64; 3],
    },
    /// A facet naming a node that does not exist.
    #[error("facet {facet} names node {node}, but there are {n_nodes} nodes")]
    FacetNode {
        /// Index of the facet.
        facet: usize,
        /// The node it names.
        node: usize,
        /// Number of nodes given.
        n_nodes: usize,
    },
    /// Every facet is flat in plan: there is no aperture to weight by.
    #[error("the {n_facets} facets cover no plan area")]
    NoPlanArea {
        /// Number of facets given.
        n_facets: usize,
    },
    /// The points do not determine the six parameters of a paraboloid (too few,
    /// or all on one circle about the axis, ...).
    #[error(
        "the {n_samples} points do not determine a best-fit paraboloid: its six parameters \
         (apex, axis tilts, focal length) are not independent on them"
    )]
    FitDegenerate {
        /// Number of points (nodes, or quadrature points of the facets).
        n_samples: usize,
    },
    /// A target RMS that is not a positive number.
    #[error("target RMS {rms_m} m: must be finite and positive")]
    Target {
        /// The target given, m.
        rms_m: f64,
    },
    /// A frequency that is not a positive number.
    #[error("frequency {frequency_hz} Hz: must be finite and positive")]
    Frequency {
        /// The frequency given, Hz.
        frequency_hz: f64,
    },
    /// An RMS half-path-length error that is negative or not finite.
    #[error("RMS half-path-length error {rms_m} m: must be finite and non-negative")]
    HalfPathRms {
        /// The RMS given, m.
        rms_m: f64,
    },
    /// An empty range of ring counts, or one starting at zero.
    #[error("rings {first}..={last}: the range must be non-empty and start at 1 or more")]
    RingsRange {
        /// First ring count of the range.
        first: usize,
        /// Last ring count of the range.
        last: usize,
    },
    /// Even the finest net allowed misses the target.
    #[error(
        "`surface.rms_mm` = {} mm: no net up to {rings} rings (the finest this scene's \
         generator makes and the memory limit allows) meets it: {rings} rings give a facet RMS of {} mm",
        nanometres(*target_rms_m), nanometres(*facet_rms_m)
    )]
    TargetNotMet {
        /// The target, m.
        target_rms_m: f64,
        /// The finest ring count allowed.
        rings: usize,
        /// Its facet RMS, m.
        facet_rms_m: f64,
    },
    /// The facet RMS rose as the net was refined, near the chosen net: the
    /// search's premise (finer is better) does not hold there.
    #[error(
        "the facet RMS does not fall as the net is refined: {coarser_rings} rings give \
         {coarser_rms_m:e} m, {finer_rings} rings {finer_rms_m:e} m"
    )]
    NotMonotone {
        /// The coarser ring count.
        coarser_rings: usize,
        /// Its facet RMS, m.
        coarser_rms_m: f64,
        /// The finer ring count.
        finer_rings: usize,
        /// Its facet RMS, m.
        finer_rms_m: f64,
    },
}

/// A length in m as mm, to the nanometre (a message's precision).
fn nanometres(m: f64) -> f64 {
    (m * 1e9).round() / 1e6
}

impl SurfaceError {
    /// True when the error is the caller's input: the input checks of the
    /// public entry points (a target, a band, a range of rings, a scene); the
    /// rest arise on computed geometry (a built surface, a fit) or a search
    /// whose premise fails, and are not the user's.
    pub fn is_bad_input(&self) -> bool {
        matches!(
            self,
            SurfaceError::Target { .. }
                | SurfaceError::Frequency { .. }
                | SurfaceError::RingsRange { .. }
                | SurfaceError::TargetNotMet { .. }
                | SurfaceError::Scene(_)
        )
    }
}
