//! How the truss's give grows with the aperture (issue 16; the paper's
//! Figure 2, "the larger the reflector aperture, the greater the
//! difference", measured).
//!
//! For each aperture `D` the scene is scaled by `s = D/D₀` ([`scaled`]):
//!
//! * the dish keeps its F/D: focal lengths (front and rear), offset and
//!   truss height × `s`;
//! * the net keeps its **facet size**: rings × `s` (rounded), the bays
//!   kept. A reflector is specified by its surface error, and the error of
//!   flat facets on the paraboloid is set by the facet size (`∝ a²/F`), so
//!   a designer keeps the facets, not the rings, as the dish grows; the
//!   truss keeps its topology and every length grows × `s`;
//! * the net keeps its **membrane stress** (N/m), so its cable tensions
//!   stay those of the scene; the force density bound of eq. 5 grows × `s`
//!   with the boundary's tension (`T·rings/(8·sag)`);
//! * the tube is **sized** to the margin asked for ([`crate::sizing`],
//!   outer diameter at the scene's `d/D`): a truss that cannot carry its
//!   net is no design, and one stiffer than needed would hide the give the
//!   study measures.
//!
//! Then the three design models — the conventional one for the rigid
//! truss, the linear truss's and the exact truss's — are each cut to length
//! and assembled on the exact truss ([`crate::verify`]): the exact model's
//! and the conventional one are `design`'s own (its verification and its
//! conventional comparison), the linear one is `design --truss linear`'s.

use std::time::Instant;

use serde::Serialize;

use crate::design::{DesignRun, DesignSettings};
use crate::scene::{membrane_tension_n, Scene, TrussModel};
use crate::sizing::{size_truss, Sections, SizingError, TubeSection};
use crate::uniformity::Design;
use crate::verify::Verification;

/// Largest aperture a study may ask for, m.
pub const MAX_APERTURE_M: f64 = 1_000.0;

/// `scene` scaled to the aperture `aperture_m` (see the module's rules),
/// named `<scene>-at-<D>m`, its tube unchanged.
///
/// # Errors
/// An aperture that is not a finite number in `(0, MAX_APERTURE_M]`, a
/// scene whose rods are measured one by one, or a scaled scene that is
/// invalid (its error names the key).
pub fn scaled(scene: &Scene, aperture_m: f64) -> Result<Scene, SizingError> {
    if !(aperture_m.is_finite() && aperture_m > 0.0 && aperture_m <= MAX_APERTURE_M) {
        return Err(SizingError::Scene {
            key: "apertures",
            reason: format!(
                "{} m: an aperture is a number in (0, {MAX_APERTURE_M}] m",
                number(aperture_m)
            ),
        });
    }
    if scene.effects.rod_properties_csv.is_some() {
        return Err(SizingError::Scene {
            key: "effects.rod_properties_csv",
            reason: "measured rods belong to one truss; a scaled truss has other rods".into(),
        });
    }
    let s = aperture_m / scene.reflector.aperture_diameter_m;
    let rings = (scene.front_net.rings as f64 * s).round();
    if rings < 2.0 {
        // The net keeps its facets: too small an aperture has no net.
        return Err(SizingError::Scene {
            key: "apertures",
            reason: format!(
                "{} m: the net of {} rings at {} m keeps its facet size, {} rings at \
                 this aperture; a net has at least 2: the smallest aperture is {} m",
                number(aperture_m),
                scene.front_net.rings,
                scene.reflector.aperture_diameter_m,
                rings,
                1.5 * scene.reflector.aperture_diameter_m / scene.front_net.rings as f64
            ),
        });
    }
    let per_stress = membrane_tension_n(scene, 1.0);
    let mut out = scene.clone();
    out.name = format!("{}-at-{}m", scene.name, aperture_m);
    let r = &mut out.reflector;
    r.aperture_diameter_m = aperture_m;
    r.focal_length_m *= s;
    r.offset_m *= s;
    out.truss.height_m *= s;
    out.front_net.rings = rings as usize;
    // Scaled, not chosen for the scene's surface target.
    out.front_net.chosen = None;
    out.front_net.membrane_stress_n_per_m = Some(scene.front_net.mean_tension_n / per_stress);
    out.front_net.mean_tension_n = 0.0;
    out.rear_net.focal_length_m *= s;
    out.rear_net.membrane_stress_n_per_m = Some(scene.rear_net.mean_tension_n / per_stress);
    out.rear_net.mean_tension_n = 0.0;
    out.cables.max_force_density_n_per_m *= s;
    // Through the file format: the tensions resolved from the stresses,
    // every value validated; a scaled value out of its range is the
    // aperture's fault, said as such.
    let text = out.to_toml()?;
    Scene::from_toml(&text, &out.name).map_err(|e| SizingError::Scene {
        key: "apertures",
        reason: format!(
            "{} m: the scene scaled to this aperture is invalid: {e}",
            number(aperture_m)
        ),
    })
}

/// `x` for a message: as written when it is of a reader's size, with an
/// exponent otherwise (`1e-300`, not three hundred zeros).
fn number(x: f64) -> String {
    if x == 0.0 || (1e-3..1e7).contains(&x.abs()) || !x.is_finite() {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// `scene` scaled to each of `apertures_m` ([`scaled`]), in order.
///
/// # Errors
/// No aperture, an aperture given twice, and [`scaled`]'s.
pub fn scaled_scenes(scene: &Scene, apertures_m: &[f64]) -> Result<Vec<Scene>, SizingError> {
    if apertures_m.is_empty() {
        return Err(SizingError::Scene {
            key: "apertures",
            reason: "no aperture given".into(),
        });
    }
    // Each aperture once: a repeated one would size and design the same
    // reflector twice (and write its scene twice).
    for (k, d) in apertures_m.iter().enumerate() {
        if apertures_m[..k].contains(d) {
            return Err(SizingError::Scene {
                key: "apertures",
                reason: format!("{} m is given twice", number(*d)),
            });
        }
    }
    apertures_m.iter().map(|&d| scaled(scene, d)).collect()
}

/// What the study runs.
#[derive(Debug, Clone)]
pub struct ApertureSettings {
    /// The apertures, m, in the order run.
    pub apertures_m: Vec<f64>,
    /// The limit margin each truss is sized to.
    pub margin: f64,
    /// The design runs' settings (their truss model is the study's).
    pub design: DesignSettings,
}

/// One design model's design of one aperture, as built on the exact truss.
#[derive(Debug, Clone, Serialize)]
pub struct ModelResult {
    /// The truss model the design was made for.
    pub model: TrussModel,
    /// Outer iterations (1 for the rigid truss: one design).
    pub outer_iterations: usize,
    /// The design's `Tmax/Tmin` (the largest over the uniformity sets).
    pub ratio: f64,
    /// The same of the assembled tensions (infinite, empty in the CSV and
    /// null in the JSON, when a cable of a set is slack).
    pub built_ratio: f64,
    /// Surface RMS as built, mm.
    pub rms_mm: f64,
    /// Largest surface deviation as built, mm.
    pub max_deviation_mm: f64,
    /// Largest tension change from the design, as built, %.
    pub tension_change_pct: f64,
    /// Largest difference of a cable's cut length from the exact model's, mm.
    pub cut_length_error_mm: f64,
    /// Largest distance of a hinge from where the design assumed it, mm.
    pub boundary_deviation_mm: f64,
    /// Cables slack as built.
    pub slack_cables: usize,
    /// Wall time of the design (the loop, or the one rigid-truss design), s.
    pub design_time_s: f64,
    /// Wall time of the assembly, s.
    pub assembly_time_s: f64,
}

/// One aperture of the study.
#[derive(Debug, Clone, Serialize)]
pub struct ApertureResult {
    /// The aperture, m.
    pub aperture_m: f64,
    /// The scaled scene, its truss sized.
    #[serde(skip)]
    pub scene: Scene,
    /// Rings of the net.
    pub rings: usize,
    /// Net nodes (front, rear).
    pub nodes: usize,
    /// The sized tube.
    pub section: TubeSection,
    /// Mass of the truss's tubes, kg.
    pub truss_mass_kg: f64,
    /// The certified limit margin of the exact design.
    pub margin: f64,
    /// Designs the sizing made.
    pub sizing_designs: usize,
    /// Wall time of the sizing, s.
    pub sizing_time_s: f64,
    /// Largest hinge displacement of the exact truss under the exact
    /// design's pull, mm: the truss's give.
    pub hinge_motion_mm: f64,
    /// The rigid (conventional), linear and exact designs.
    pub models: Vec<ModelResult>,
}

/// Runs the study on `scene`; `observe` sees each aperture as it finishes.
///
/// # Errors
/// A bad aperture, margin or scene, no section that carries an aperture's
/// net, or a design that fails (each names its aperture).
pub fn run_aperture_study(
    scene: &Scene,
    settings: &ApertureSettings,
    observe: &mut dyn FnMut(&ApertureResult),
) -> Result<Vec<ApertureResult>, SizingError> {
    let scenes = scaled_scenes(scene, &settings.apertures_m)?;
    // The first guess of a tube: the scene's, grown as `s^¾` — a strut's
    // buckling load `∝ EI/L² ∝ D⁴/s²` against a pull `∝ s`.
    let mut guess = (
        scene.reflector.aperture_diameter_m,
        scene.truss.tube_outer_diameter_m,
    );
    let exact = DesignSettings {
        truss: Some(TrussModel::Exact),
        ..settings.design.clone()
    };
    let mut results = Vec::new();
    for scaled in scenes {
        let aperture_m = scaled.reflector.aperture_diameter_m;
        let start_m = guess.1 * (aperture_m / guess.0).powf(0.75);
        let clock = Instant::now();
        let sizing = size_truss(
            &scaled,
            &Sections::Continuous { start_m },
            settings.margin,
            &exact,
            &mut |_| {},
        )?;
        let sizing_time_s = clock.elapsed().as_secs_f64();
        let sized = sizing.scene;
        let chosen = &sizing.trials[sizing.chosen];
        guess = (aperture_m, chosen.section.outer_diameter_m);
        let linear = crate::design::run(
            &sized,
            &DesignSettings {
                truss: Some(TrussModel::Linear),
                ..settings.design.clone()
            },
            &mut |_, _| {},
        )?;
        let result = aperture_result(
            sized,
            &sizing.run,
            &linear,
            chosen.section,
            chosen.mass_kg,
            sizing.trials.len(),
            sizing_time_s,
        );
        observe(&result);
        results.push(result);
    }
    Ok(results)
}

/// The figures of one aperture from its exact and linear design runs.
fn aperture_result(
    scene: Scene,
    exact: &DesignRun,
    linear: &DesignRun,
    section: TubeSection,
    truss_mass_kg: f64,
    sizing_designs: usize,
    sizing_time_s: f64,
) -> ApertureResult {
    let sets = &exact.sets;
    let cut_lengths = |design: &Design| -> Vec<f64> {
        design
            .lengths_m
            .iter()
            .zip(&design.tensions_n)
            .map(|(&l, &t)| scene.cables.cut_length_m(l, t))
            .collect()
    };
    let reference = cut_lengths(&exact.report.net);
    let model = |model: TrussModel,
                 design: &Design,
                 built: &Verification,
                 outer_iterations: usize,
                 design_time_s: f64| ModelResult {
        model,
        outer_iterations,
        ratio: design.ratio,
        built_ratio: sets
            .iter()
            .map(|set| set.ratio(&built.tensions_n))
            .fold(0.0, f64::max),
        rms_mm: built.rms_mm,
        max_deviation_mm: built.max_deviation_mm,
        tension_change_pct: built.max_tension_change_pct,
        cut_length_error_mm: 1e3
            * cut_lengths(design)
                .iter()
                .zip(&reference)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max),
        boundary_deviation_mm: built.boundary_deviation_mm,
        slack_cables: built.slack_cables.len(),
        design_time_s,
        assembly_time_s: built.time_s,
    };
    let report = &exact.report;
    let (Some(conventional), Some(conventional_net)) =
        (&report.conventional, &exact.conventional_net)
    else {
        unreachable!("the exact truss deforms: design compares the conventional design");
    };
    let models = vec![
        model(
            TrussModel::Rigid,
            conventional_net,
            conventional,
            1,
            report.history[0].design_time_s,
        ),
        model(
            TrussModel::Linear,
            &linear.report.net,
            &linear.report.verification,
            linear.report.outer_iterations,
            linear.report.timings.design_loop_s(),
        ),
        model(
            TrussModel::Exact,
            &report.net,
            &report.verification,
            report.outer_iterations,
            report.timings.design_loop_s(),
        ),
    ];
    let layout = &exact.mesh.truss;
    let hinges = layout.top_m.iter().chain(&layout.bottom_m);
    let hinge_motion_mm = 1e3
        * hinges
            .zip(&report.boundary_m)
            .map(|(a, b)| crate::algebra::norm3(std::array::from_fn(|i| a[i] - b[i])))
            .fold(0.0, f64::max);
    ApertureResult {
        aperture_m: scene.reflector.aperture_diameter_m,
        rings: scene.front_net.rings,
        nodes: exact.network.n_nodes(),
        section,
        truss_mass_kg,
        margin: report.limit_margin.as_ref().map_or(0.0, |m| m.stable_to),
        sizing_designs,
        sizing_time_s,
        hinge_motion_mm,
        models,
        scene,
    }
}
