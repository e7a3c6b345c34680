//! The net for a surface target: the coarsest ring count whose design-surface
//! facets meet a facet RMS, found by a few net generations (a model-guided
//! bracket, then bisection), never by a design.

use super::rms::{check_paraboloid, facet_rms, Deviation};
use super::SurfaceError;
use crate::geometry::{build_mesh, Paraboloid, ReflectorMesh, MAX_NODES, MIN_CABLE_LENGTH_RATIO};
use crate::resources::{check_scene, SceneCommand};
use crate::scene::{ChosenRings, Scene};
use serde::Serialize;
use std::collections::BTreeMap;
use std::ops::RangeInclusive;

/// Ring counts below the chosen one checked to fail, with falling RMS, after
/// the search (the one just below is the search's own).
const CHECKED_BELOW: usize = 3;

/// A faceted surface: nodes and the flat triangles between them.
#[derive(Debug, Clone, PartialEq)]
pub struct FacetNet {
    /// Node positions, m: n_nodes.
    pub nodes_m: Vec<[f64; 3]>,
    /// Facets, node indices: n_facets.
    pub triangles: Vec<[usize; 3]>,
}

impl FacetNet {
    /// The front net of a mesh and its facets (at the mesh's node positions:
    /// on the design paraboloid for a mesh fresh from [`build_mesh`]).
    pub fn front_of(mesh: &ReflectorMesh) -> FacetNet {
        FacetNet {
            nodes_m: mesh.network.nodes[..mesh.n_front_nodes].to_vec(),
            triangles: mesh.front_triangles.clone(),
        }
    }
}

/// One net of the search and its figure.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct NetFigure {
    /// Rings of the net.
    pub rings: usize,
    /// Its facet RMS (the deviation the target is of), m.
    pub facet_rms_m: f64,
}

/// The coarsest net meeting a facet RMS target.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NetChoice {
    /// The chosen net: its facet RMS is at most the target.
    pub chosen: NetFigure,
    /// The net one ring coarser, which misses the target; `None` when the
    /// chosen one is the coarsest allowed.
    pub next_coarser: Option<NetFigure>,
    /// Nets generated and measured in all.
    pub nets_built: usize,
}

/// The nets generated so far and their figures.
struct Search<'a, F> {
    paraboloid: &'a Paraboloid,
    deviation: Deviation,
    facets: F,
    figures: BTreeMap<usize, f64>,
}

impl<F, E> Search<'_, F>
where
    F: FnMut(usize) -> Result<FacetNet, E>,
    E: From<SurfaceError>,
{
    fn figure(&mut self, rings: usize) -> Result<f64, E> {
        if let Some(&v) = self.figures.get(&rings) {
            return Ok(v);
        }
        let net = (self.facets)(rings)?;
        let v = facet_rms(self.paraboloid, &net.nodes_m, &net.triangles)?.get(self.deviation);
        self.figures.insert(rings, v);
        Ok(v)
    }
}

/// The coarsest ring count in `rings` whose facets, built by `facets(rings)`
/// on the design surface, have a facet RMS ([`facet_rms`] of `deviation`, about
/// the design paraboloid, not best-fit) at most `target_rms_m`.
///
/// Facet RMS falls about as `1/rings²` (facets of side ∝ 1/rings, deviation
/// ∝ side²/F), so from the coarsest net the search guesses the count that
/// meets the target, steps on from guesses until one does, then bisects
/// between the last that misses and the first that meets: a handful of nets,
/// whatever the count. It then checks that the facet RMS falls through
/// the answer (the counts up to 3 below and 1 above): a rise there is
/// [`SurfaceError::NotMonotone`], not a silent wrong answer.
///
/// # Errors
/// A focal length that is not positive, a target that is not, an empty range
/// or one starting at 0, no net in range meeting the target
/// ([`SurfaceError::TargetNotMet`]), a rise of the RMS near the answer; the
/// errors of `facets` and of [`facet_rms`] on its nets.
pub fn choose_rings<F, E>(
    paraboloid: &Paraboloid,
    target_rms_m: f64,
    deviation: Deviation,
    rings: RangeInclusive<usize>,
    facets: F,
) -> Result<NetChoice, E>
where
    F: FnMut(usize) -> Result<FacetNet, E>,
    E: From<SurfaceError>,
{
    check_paraboloid(paraboloid)?;
    if !(target_rms_m.is_finite() && target_rms_m > 0.0) {
        return Err(SurfaceError::Target {
            rms_m: target_rms_m,
        }
        .into());
    }
    let (first, last) = (*rings.start(), *rings.end());
    if first == 0 || first > last {
        return Err(SurfaceError::RingsRange { first, last }.into());
    }
    let mut search = Search {
        paraboloid,
        deviation,
        facets,
        figures: BTreeMap::new(),
    };
    let meets = |v: f64| v <= target_rms_m;
    let (mut lo, mut f_lo) = (first, search.figure(first)?);
    let chosen = if meets(f_lo) {
        first
    } else {
        // lo misses; find hi that meets, guessing from RMS ∝ 1/rings².
        let mut hi = loop {
            if lo == last {
                return Err(SurfaceError::TargetNotMet {
                    target_rms_m,
                    rings: last,
                    facet_rms_m: f_lo,
                }
                .into());
            }
            // A float-to-integer cast saturates: a huge guess is clamped.
            let guess = (lo as f64 * (f_lo / target_rms_m).sqrt()).ceil() as usize;
            let next = guess.clamp(lo + 1, last);
            let f_next = search.figure(next)?;
            if meets(f_next) {
                break next;
            }
            (lo, f_lo) = (next, f_next);
        };
        // The guess is usually right or one too many: try one below first.
        if hi - lo > 1 && meets(search.figure(hi - 1)?) {
            hi -= 1;
        } else {
            lo = lo.max(hi - 1);
        }
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if meets(search.figure(mid)?) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        hi
    };
    // The RMS must fall through the answer.
    let window = chosen.saturating_sub(CHECKED_BELOW).max(first)..=(chosen + 1).min(last);
    let mut previous: Option<(usize, f64)> = None;
    for r in window {
        let v = search.figure(r)?;
        if let Some((coarser_rings, coarser_rms_m)) = previous {
            if v > coarser_rms_m {
                return Err(SurfaceError::NotMonotone {
                    coarser_rings,
                    coarser_rms_m,
                    finer_rings: r,
                    finer_rms_m: v,
                }
                .into());
            }
        }
        previous = Some((r, v));
    }
    let at = |r: usize| NetFigure {
        rings: r,
        facet_rms_m: search.figures[&r],
    };
    Ok(NetChoice {
        chosen: at(chosen),
        next_coarser: (chosen > first).then(|| at(chosen - 1)),
        nets_built: search.figures.len(),
    })
}

/// The most rings [`build_mesh`] accepts for `scene`'s bays and aperture: the
/// node cap [`MAX_NODES`] (front and rear nets) and the first ring's cable of
/// at least [`MIN_CABLE_LENGTH_RATIO`] × aperture.
pub fn max_front_rings(scene: &Scene) -> usize {
    let bays = scene.truss.bays.max(1);
    // 1 + bays·r(r + 1)/2 front nodes, at most MAX_NODES/2.
    let by_nodes = {
        let mut r = ((MAX_NODES as f64) / bays as f64).sqrt() as usize + 1;
        while r > 1 && 1 + bays * r * (r + 1) / 2 > MAX_NODES / 2 {
            r -= 1;
        }
        r
    };
    let by_cables = ((std::f64::consts::PI / bays as f64).sin() / MIN_CABLE_LENGTH_RATIO) as usize;
    by_nodes.min(by_cables).max(1)
}

/// The most rings, up to `most`, whose net `mesh` may build within the
/// memory limit ([`check_scene`]): a search for a target never builds a net
/// the run could not hold (at least 2, which the run's own check then refuses
/// if even they do not fit).
fn rings_within_memory(scene: &Scene, most: usize) -> usize {
    let fits = |rings: usize| {
        let mut trial = scene.clone();
        trial.front_net.rings = rings;
        check_scene(&trial, SceneCommand::Mesh, 1).is_ok()
    };
    if fits(most) {
        return most;
    }
    let (mut lo, mut hi) = (2, most);
    if !fits(lo) {
        return lo;
    }
    // fits(lo), !fits(hi).
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if fits(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// [`choose_rings`] for `scene`'s front net: the scene's own net generator
/// ([`build_mesh`], nodes on the design paraboloid) at each ring count
/// from 2 (the fewest with free boundary nodes) to [`max_front_rings`], the
/// scene's `front_net.rings` ignored.
///
/// # Errors
/// As [`choose_rings`]; a scene [`build_mesh`] refuses at some ring count.
pub fn choose_front_rings(
    scene: &Scene,
    target_rms_m: f64,
    deviation: Deviation,
) -> Result<NetChoice, SurfaceError> {
    let paraboloid = Paraboloid {
        focal_length_m: scene.reflector.focal_length_m,
    };
    choose_rings(
        &paraboloid,
        target_rms_m,
        deviation,
        2..=rings_within_memory(scene, max_front_rings(scene)),
        |rings| {
            // The scene with these rings, its tensions resolved for them.
            let trial = scene.clone().with_rings(rings)?;
            Ok(FacetNet::front_of(&build_mesh(&trial)?))
        },
    )
}

/// `scene` complete: when its file left `front_net.rings` to `[surface]
/// rms_mm`, with the coarsest net whose design surface meets that target
/// (axial facet RMS, [`choose_front_rings`]) and how it was chosen
/// ([`ChosenRings`]); otherwise `scene` as it is.
///
/// # Errors
/// A target no net meets, or a scene invalid with the chosen rings.
pub fn resolve_front_rings(scene: &Scene) -> Result<Scene, SurfaceError> {
    let (true, Some(target_rms_mm)) = (scene.front_net.rings_to_choose(), scene.surface.rms_mm)
    else {
        return Ok(scene.clone());
    };
    let choice = choose_front_rings(scene, 1e-3 * target_rms_mm, Deviation::Axial)?;
    let mut resolved = scene.clone().with_rings(choice.chosen.rings)?;
    resolved.front_net.chosen = Some(ChosenRings {
        target_rms_mm,
        facet_rms_mm: 1e3 * choice.chosen.facet_rms_m,
        next_coarser: choice.next_coarser.map(|n| (n.rings, 1e3 * n.facet_rms_m)),
        nets_built: choice.nets_built,
    });
    Ok(resolved)
}
