//! The surface error budget of a design as built (issue 34): what the mesh's
//! flat facets cost, what the design method and the flexible truss leave at
//! the nodes, their root-sum-square, each raw and about the best-fit
//! paraboloid, the surface the built facets really make, and the gain lost
//! at the scene's frequency.
//!
//! The terms, each one quantity of [`crate::surface`] on named points:
//!
//! * **facets** — facet RMS of the *design surface*: the front net's facets
//!   with their corners where the design puts them (on the paraboloid): the
//!   geometry of the mesh, set by its density alone;
//! * **design as built** — node RMS of the front net's *free nodes as
//!   built* (cut cables assembled on the flexible truss): what the design
//!   method and the truss model leave (the paper's "RMS surface");
//! * **total** — `√(facets² + design²)`, the two independent terms combined
//!   as an engineer's budget does;
//! * **facets as built** — facet RMS of the facets through the built nodes:
//!   the surface the mesh really makes, both errors at once (it equals the
//!   total when the node errors are small and uncorrelated with the facets'
//!   bulge);
//! * **gain loss** — Ruze's loss at `[surface] frequency_ghz` from the RMS
//!   half-path-length error of the facets as built about their best-fit
//!   paraboloid (the feed is aligned to it).
//!
//! Every RMS is axial unless its name says otherwise; "best fit" is about
//! the paraboloid fitted to the same points ([`super::best_fit_facets`],
//! [`super::best_fit_nodes`]).

use serde::Serialize;

use super::{
    best_fit_facets, best_fit_nodes, facet_rms, node_rms, ruze_gain_loss_db, BestFit,
    PlacedParaboloid, SurfaceError,
};
use crate::geometry::{Paraboloid, ReflectorMesh};
use crate::scene::{ChosenRings, SurfaceSpec};
use crate::status::Termination;

/// An axial RMS raw and about its best-fit paraboloid, mm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RawAndBestFit {
    /// About the design paraboloid, mm.
    pub raw_mm: f64,
    /// About the paraboloid fitted to the same points, mm.
    pub best_fit_mm: f64,
}

impl RawAndBestFit {
    /// The root-sum-square of two independent terms, raw and best fit alike.
    pub fn rss(self, other: RawAndBestFit) -> RawAndBestFit {
        RawAndBestFit {
            raw_mm: self.raw_mm.hypot(other.raw_mm),
            best_fit_mm: self.best_fit_mm.hypot(other.best_fit_mm),
        }
    }
}

/// The front net's points a budget is measured on.
#[derive(Debug, Clone, Copy)]
pub struct FrontSurface<'a> {
    /// The front net's nodes as designed, m (first `n` nodes of the network).
    pub designed_m: &'a [[f64; 3]],
    /// The same nodes as built, m.
    pub built_m: &'a [[f64; 3]],
    /// Which of them are free (the attachments sit on the truss).
    pub free: &'a [bool],
    /// The facets, node indices.
    pub triangles: &'a [[usize; 3]],
}

/// The surface error budget of a design as built (see the module).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SurfaceBudget {
    /// The scene's target facet RMS (design surface), mm.
    pub target_rms_mm: Option<f64>,
    /// Whether the design surface's facet RMS meets the target.
    pub target_met: Option<bool>,
    /// Rings of the front net.
    pub rings: usize,
    /// How they were chosen for the target, when the scene left them to it.
    pub rings_chosen: Option<ChosenRings>,
    /// Facet RMS of the design surface.
    pub facets: RawAndBestFit,
    /// Node RMS of the free front nodes as built.
    pub design_as_built: RawAndBestFit,
    /// `√(facets² + design as built²)`.
    pub total: RawAndBestFit,
    /// Facet RMS of the facets through the built nodes.
    pub facets_as_built: RawAndBestFit,
    /// RMS half-path-length error of the facets as built about their best
    /// fit, mm: Ruze's ε.
    pub half_path_best_fit_mm: f64,
    /// The paraboloid that fits the facets as built.
    pub best_fit: PlacedParaboloid,
    /// The scene's frequency, GHz.
    pub frequency_ghz: Option<f64>,
    /// Ruze's gain loss at it, dB (positive).
    pub gain_loss_db: Option<f64>,
    /// Best fits that stopped before converging (their RMS is then an upper
    /// bound of the best fit's: [`BestFit::termination`]).
    pub warnings: Vec<String>,
}

/// Facet RMS of a mesh's front net as generated (its design surface: nodes
/// on the paraboloid), raw and about the best-fit paraboloid.
///
/// # Errors
/// A net whose facets cannot be measured or fitted.
pub fn design_surface_facets(mesh: &ReflectorMesh) -> Result<RawAndBestFit, SurfaceError> {
    let nodes = &mesh.network.nodes[..mesh.n_front_nodes];
    facets_about(&mesh.paraboloid, nodes, &mesh.front_triangles).map(|(rms, _)| rms)
}

/// Facet RMS of a mesh's front net as generated (its design surface), axial
/// and raw, mm: [`design_surface_facets`] without the fit.
///
/// # Errors
/// A net whose facets cannot be measured.
pub fn design_surface_facet_rms_mm(mesh: &ReflectorMesh) -> Result<f64, SurfaceError> {
    let nodes = &mesh.network.nodes[..mesh.n_front_nodes];
    Ok(1e3 * facet_rms(&mesh.paraboloid, nodes, &mesh.front_triangles)?.axial_m)
}

/// Facet RMS of `nodes`' facets raw and best fit, and the fit.
fn facets_about(
    paraboloid: &Paraboloid,
    nodes: &[[f64; 3]],
    triangles: &[[usize; 3]],
) -> Result<(RawAndBestFit, BestFit), SurfaceError> {
    let raw = facet_rms(paraboloid, nodes, triangles)?;
    let fit = best_fit_facets(paraboloid, nodes, triangles)?;
    Ok((
        RawAndBestFit {
            raw_mm: 1e3 * raw.axial_m,
            best_fit_mm: 1e3 * fit.rms.axial_m,
        },
        fit,
    ))
}

/// The budget of `surface` on `paraboloid` for the scene's `spec`, its net
/// of `rings` rings (`chosen` when the target chose them).
///
/// # Errors
/// A surface that cannot be measured or fitted ([`SurfaceError`]).
pub fn budget(
    paraboloid: &Paraboloid,
    surface: FrontSurface<'_>,
    spec: &SurfaceSpec,
    rings: usize,
    chosen: Option<&ChosenRings>,
) -> Result<SurfaceBudget, SurfaceError> {
    let mm = |m: f64| 1e3 * m;
    let (facets, design_fit) = facets_about(paraboloid, surface.designed_m, surface.triangles)?;
    let (facets_as_built, fit) = facets_about(paraboloid, surface.built_m, surface.triangles)?;
    let free: Vec<[f64; 3]> = surface
        .built_m
        .iter()
        .zip(surface.free)
        .filter(|(_, &f)| f)
        .map(|(p, _)| *p)
        .collect();
    let node_fit = best_fit_nodes(paraboloid, &free)?;
    let design_as_built = RawAndBestFit {
        raw_mm: mm(node_rms(paraboloid, &free)?.axial_m),
        best_fit_mm: mm(node_fit.rms.axial_m),
    };
    let warnings = [
        ("facets (design surface)", &design_fit),
        ("design as built", &node_fit),
        ("facets as built", &fit),
    ]
    .iter()
    .filter(|(_, f)| f.termination != Termination::Converged)
    .map(|(term, f)| {
        format!(
            "the best fit of the {term} stopped ({:?} after {} iterations): its RMS is an \
             upper bound",
            f.termination, f.iterations
        )
    })
    .collect();
    let half_path_best_fit_mm = mm(fit.rms.half_path_m);
    let gain_loss_db = spec
        .frequency_ghz
        .map(|ghz| ruze_gain_loss_db(fit.rms.half_path_m, 1e9 * ghz))
        .transpose()?;
    Ok(SurfaceBudget {
        target_rms_mm: spec.rms_mm,
        target_met: spec.rms_mm.map(|t| facets.raw_mm <= t),
        rings,
        rings_chosen: chosen.cloned(),
        facets,
        design_as_built,
        total: facets.rss(design_as_built),
        facets_as_built,
        half_path_best_fit_mm,
        best_fit: fit.paraboloid,
        frequency_ghz: spec.frequency_ghz,
        gain_loss_db,
        warnings,
    })
}
