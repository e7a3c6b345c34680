//! Node RMS and facet RMS of a surface about the design paraboloid, each
//! axial, normal and in half path length (definitions in [`crate::surface`]).

use super::placed::PlacedParaboloid;
use super::samples::Samples;
use super::SurfaceError;
use crate::geometry::Paraboloid;
use serde::Serialize;

/// Which deviation an RMS is of (see [`super::PointDeviation`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Deviation {
    /// Along the axis, δz.
    Axial,
    /// Along the surface normal, δn = δz cos α.
    Normal,
    /// Half the reflected ray's path change, ε = δz cos² α: what sets the gain.
    HalfPathLength,
}

/// Root mean squares of the three deviations of one set of points (nodes, or
/// the facets' surface) about one paraboloid, each about zero (not about its
/// mean: a uniform offset counts; the best fit is what removes it).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SurfaceRms {
    /// RMS axial deviation, m.
    pub axial_m: f64,
    /// RMS normal deviation, m.
    pub normal_m: f64,
    /// RMS half-path-length error, m: Ruze's ε.
    pub half_path_m: f64,
}

impl SurfaceRms {
    /// The RMS of deviation `which`, m.
    pub fn get(&self, which: Deviation) -> f64 {
        match which {
            Deviation::Axial => self.axial_m,
            Deviation::Normal => self.normal_m,
            Deviation::HalfPathLength => self.half_path_m,
        }
    }
}

/// Rejects a focal length that is not a finite positive number.
pub(crate) fn check_paraboloid(paraboloid: &Paraboloid) -> Result<(), SurfaceError> {
    let f = paraboloid.focal_length_m;
    if f.is_finite() && f > 0.0 {
        Ok(())
    } else {
        Err(SurfaceError::FocalLength { focal_length_m: f })
    }
}

/// The weighted RMS of the deviations of `samples` from `placed`.
pub(crate) fn rms_about(placed: &PlacedParaboloid, samples: &Samples) -> SurfaceRms {
    let (mut weight, mut axial, mut normal, mut half_path) = (0.0, 0.0, 0.0, 0.0);
    let deviation = placed.deviations();
    samples.for_each(|p, w| {
        let d = deviation(p);
        weight += w;
        axial += w * d.axial_m * d.axial_m;
        normal += w * d.normal_m * d.normal_m;
        half_path += w * d.half_path_m * d.half_path_m;
    });
    SurfaceRms {
        axial_m: (axial / weight).sqrt(),
        normal_m: (normal / weight).sqrt(),
        half_path_m: (half_path / weight).sqrt(),
    }
}

/// **Node RMS**: the deviations of the nodes `nodes_m` from the design
/// paraboloid, every node counting once, `√(Σᵢ dᵢ²/n)` for each of the three
/// deviations. Pass the nodes the RMS is about (for a net, its free nodes: the
/// attachments sit on the surface by construction).
///
/// # Errors
/// No nodes, a non-finite coordinate, a focal length that is not positive.
pub fn node_rms(paraboloid: &Paraboloid, nodes_m: &[[f64; 3]]) -> Result<SurfaceRms, SurfaceError> {
    check_paraboloid(paraboloid)?;
    let samples = Samples::nodes(nodes_m)?;
    Ok(rms_about(&PlacedParaboloid::design(paraboloid), &samples))
}

/// **Facet RMS**: the deviation of the flat triangular facets `triangles`
/// (node indices into `nodes_m`) from the design paraboloid, integrated over
/// the facets and weighted by **plan area** (the projection on the aperture
/// plane, normal to the axis): `√(∫ d² dA_plan / ∫ dA_plan)` — the surface a
/// faceted net really makes, between its nodes as well as at them, each piece
/// of aperture counting alike as it does in Ruze's aperture integral.
///
/// On a facet, with barycentric coordinates `λ`, the axial deviation
/// `Σ λᵢ zᵢ − (|Σ λᵢ pᵢ|²)/(4F)` (`pᵢ` the plan corners) is quadratic in plan,
/// so its square is integrated exactly by the facet rule (a collapsed
/// Gauss product of 36 points, exact to degree 10). The normal and
/// half-path deviations multiply it by `cos α` and `cos² α`, smooth functions
/// of `r²/(4F²)`; the same rule integrates their squares to 1e-9 relative on
/// facets of 0.8 F (checked against 4·10⁴ samples a facet) and to about 6e-8
/// on facets of 1.6 F (paper-26m at 2 rings, the coarsest net a study makes).
///
/// With its corners on the paraboloid a facet of squared plan sides `a, b, c`
/// deviates axially by `Σᵢ<ⱼ λᵢλⱼ ℓᵢⱼ²/(4F)`, whence exactly
/// `mean² = ((a + b + c)² + a² + b² + c²)/(2880 F²)` and
/// `mean = (a + b + c)/(48 F)`; an equilateral facet of side L gives
/// `L²/(4√15 F)` (DESIGN §12). The crate's sector nets (see
/// [`crate::geometry`]) have thin isosceles facets, two sides `ℓ = R/rings`
/// and one `chord/rings`: their facet RMS is `≈ ℓ²/(4√30 F)`, about
/// `1/√2` of §12's figure with `L = ℓ`.
///
/// # Errors
/// No facets, a corner that is not a node or not finite, facets without plan
/// area, a focal length that is not positive.
pub fn facet_rms(
    paraboloid: &Paraboloid,
    nodes_m: &[[f64; 3]],
    triangles: &[[usize; 3]],
) -> Result<SurfaceRms, SurfaceError> {
    check_paraboloid(paraboloid)?;
    let samples = Samples::facets(nodes_m, triangles)?;
    Ok(rms_about(&PlacedParaboloid::design(paraboloid), &samples))
}
