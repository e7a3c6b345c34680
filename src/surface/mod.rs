//! Surface accuracy as an antenna engineer states it: how far a surface
//! (nodes, or the flat facets between them) lies from the design paraboloid
//! `z = (x² + y²)/(4F)`, raw and about the best-fit paraboloid, and what that
//! costs in gain (DESIGN §13).
//!
//! Every quantity has one name and one definition:
//!
//! * **axial deviation** `δz = z − (x² + y²)/(4F)` of a point; the **normal
//!   deviation** `δn = δz cos α` and the **half-path-length error**
//!   `ε = δz cos² α = δz · 4F²/(4F² + r²)`, with `α` the angle between the
//!   surface normal and the axis, `cos α = 2F/√(4F² + r²)` ([`PointDeviation`]);
//! * **node RMS** ([`node_rms`]): each deviation's RMS over the given nodes,
//!   every node counting once;
//! * **facet RMS** ([`facet_rms`]): each deviation's RMS over the flat
//!   triangular facets, integrated and weighted by plan (aperture) area;
//! * **best-fit node / facet RMS** ([`best_fit_nodes`], [`best_fit_facets`]):
//!   the same about the paraboloid (apex translations, two axis tilts, focal
//!   length: [`PlacedParaboloid`]) that minimises the RMS half-path-length
//!   error, the one a feed is aligned to;
//! * **Ruze gain loss** ([`ruze_gain_loss_db`]): `G/G₀ = exp(−(4π ε_rms/λ)²)`
//!   in dB, for the RMS half-path-length error `ε_rms`.
//!
//! Every RMS is about zero, not about its mean (a uniform offset counts, and
//! only the best fit removes it).
//!
//! **Why the half path length.** A ray parallel to the axis meets the
//! paraboloid at plan radius `r` and reflects to the focus, where it makes the
//! angle `ψ` with the axis: `r = 2F tan(ψ/2)`. The surface slope there is
//! `tan α = r/(2F)`, so `α = ψ/2`, and the ray meets the surface at incidence
//! `ψ/2`. Moving the surface by `δn` along its normal, towards the focus,
//! shortens the ray's path by `2 δn cos(ψ/2)`, as between two parallel mirrors
//! `δn` apart (to first order: by Fermat the path is stationary in the
//! reflected ray's direction, so its turn does not count). An axial
//! displacement `δz` is `δn = δz cos α` along the normal (its tangential part
//! slides the surface along itself), so the path changes by `2 δz cos² α`
//! and the half path length by `ε = δz · 4F²/(4F² + r²)`. A unit test checks
//! this against the exact path from a plane across the beam to the focus.
//! Ruze's `ε` is its RMS over the aperture: the plan-area-weighted facet RMS
//! of `ε`, for uniform illumination.
//!
//! **Facet RMS and DESIGN §12.** With its corners on the paraboloid, a flat
//! facet of squared plan sides `a, b, c` has the axial facet RMS
//! `√(((a + b + c)² + a² + b² + c²)/2880)/F` (exact; see [`facet_rms`]). For
//! an equilateral facet of side `L` that is §12's `L²/(4√15 F)`; the crate's
//! sector nets have thin isosceles facets (two sides `R/rings`, one
//! `chord/rings`), which give about `1/√2` of §12's figure with
//! `L = R/rings` (super-60m: 1.41 mm, 1.47 mm without the boundary sag,
//! against 2.06 mm). About the best fit a net of like facets loses their mean
//! bubble `(a + b + c)/(48F)` to the apex: equilateral facets' RMS falls 4×
//! (§12's figure), the sector nets' thin isosceles ones only ≈ 2.5×.

mod best_fit;
mod budget;
mod error;
mod gain;
mod net_choice;
mod placed;
mod quadrature;
mod rms;
mod samples;

pub use best_fit::{best_fit_facets, best_fit_nodes, BestFit};
pub use budget::{
    budget, design_surface_facet_rms_mm, design_surface_facets, FrontSurface, RawAndBestFit,
    SurfaceBudget,
};
pub use error::SurfaceError;
pub use gain::{ruze_gain_loss_db, ruze_gain_ratio, SPEED_OF_LIGHT_M_PER_S};
pub use net_choice::{
    choose_front_rings, choose_rings, max_front_rings, resolve_front_rings, FacetNet, NetChoice,
    NetFigure,
};
pub use placed::{PlacedParaboloid, PointDeviation};
pub use rms::{facet_rms, node_rms, Deviation, SurfaceRms};

#[cfg(test)]
mod tests;
