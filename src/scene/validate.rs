//! A scene's values against their valid ranges ([`Scene::validate`]), the
//! limits among them; an invalid value is a [`SceneError`] naming the dotted
//! key and the reason.

use super::error::SceneError;
use super::schema::{membrane_tension_n, Scene};

/// Longest scene name: it names the results folder and files made from it.
pub const MAX_NAME_LEN: usize = 128;

/// Largest elastic modulus a scene may give, Pa (diamond: 1.2e12).
pub const MAX_MODULUS_PA: f64 = 1e13;

/// Smallest elastic modulus a scene may give, Pa (soft rubber: 1e6): a
/// softer truss or cable carries nothing, and 1e-300 left the truss's
/// tangent a mechanism to roundoff.
pub const MIN_MODULUS_PA: f64 = 1e6;

/// Tallest truss, as a multiple of the aperture diameter (real rings:
/// 0.1–0.6).
pub const MAX_HEIGHT_RATIO: f64 = 10.0;

/// Largest number of beam elements per truss rod.
pub const MAX_ELEMENTS_PER_ROD: usize = 64;

/// Largest number of bays a scene may ask for.
pub const MAX_BAYS: usize = 1_000;

impl Scene {
    /// Checks every value against its valid range.
    pub fn validate(&self) -> Result<(), SceneError> {
        if self.name.is_empty()
            || !self
                .name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c))
            || self.name.starts_with('.')
        {
            return Err(SceneError::invalid(
                "name",
                format!(
                    "{:?} must be non-empty and use only letters, digits, '-', '_' and '.' \
                     (it names the results folder)",
                    self.name
                ),
            ));
        }
        if self.name.len() > MAX_NAME_LEN {
            return Err(SceneError::invalid(
                "name",
                format!(
                    "{} characters, at most {MAX_NAME_LEN}: it names the results folder and \
                     files (`<name>-sized.toml`, `<name>-at-100m.toml`) that file systems \
                     limit to 255 bytes",
                    self.name.len()
                ),
            ));
        }
        let r = &self.reflector;
        positive("reflector.aperture_diameter_m", r.aperture_diameter_m)?;
        positive("reflector.focal_length_m", r.focal_length_m)?;
        non_negative("reflector.offset_m", r.offset_m)?;

        let t = &self.truss;
        if t.bays < 3 {
            return Err(SceneError::invalid(
                "truss.bays",
                format!("{} bays: a ring truss needs at least 3", t.bays),
            ));
        }
        if t.bays > MAX_BAYS {
            return Err(SceneError::invalid(
                "truss.bays",
                format!("{} bays: more than the {MAX_BAYS} supported", t.bays),
            ));
        }
        positive("truss.height_m", t.height_m)?;
        let diameter = self.reflector.aperture_diameter_m;
        if t.height_m > MAX_HEIGHT_RATIO * diameter {
            return Err(SceneError::invalid(
                "truss.height_m",
                format!(
                    "{:e} m is more than {MAX_HEIGHT_RATIO} × the aperture ({diameter} m): the \
                     ties would span decades more than the net's cables, beyond what one \
                     force density solve balances",
                    t.height_m
                ),
            ));
        }
        if !(1..=MAX_ELEMENTS_PER_ROD).contains(&t.elements_per_rod) {
            return Err(SceneError::invalid(
                "truss.elements_per_rod",
                format!("{} must be in 1…{MAX_ELEMENTS_PER_ROD}", t.elements_per_rod),
            ));
        }
        positive("truss.tube_outer_diameter_m", t.tube_outer_diameter_m)?;
        non_negative("truss.tube_inner_diameter_m", t.tube_inner_diameter_m)?;
        if t.tube_inner_diameter_m >= t.tube_outer_diameter_m {
            return Err(SceneError::invalid(
                "truss.tube_inner_diameter_m",
                format!(
                    "{} m must be smaller than truss.tube_outer_diameter_m = {} m",
                    t.tube_inner_diameter_m, t.tube_outer_diameter_m
                ),
            ));
        }
        modulus("truss.youngs_modulus_pa", t.youngs_modulus_pa)?;
        modulus("truss.shear_modulus_pa", t.shear_modulus_pa)?;
        positive("truss.density_kg_per_m3", t.density_kg_per_m3)?;
        non_negative("truss.hinge_mass_kg", t.hinge_mass_kg)?;

        let f = &self.front_net;
        let target = self.surface.rms_mm;
        if let Some(rms) = target {
            positive("surface.rms_mm", rms)?;
        }
        if let Some(ghz) = self.surface.frequency_ghz {
            positive("surface.frequency_ghz", ghz)?;
        }
        if f.rings_to_choose() && target.is_none() {
            return Err(SceneError::invalid(
                "front_net.rings",
                "missing (or 0): give the rings (at least 2), or `[surface] rms_mm` to \
                 choose the coarsest net that holds it"
                    .to_string(),
            ));
        }
        if f.rings < 2 && !f.rings_to_choose() {
            return Err(SceneError::invalid(
                "front_net.rings",
                format!(
                    "{} ring(s): at least 2 are needed for free boundary nodes between \
                     the truss attachments",
                    f.rings
                ),
            ));
        }
        positive("front_net.boundary_sag_ratio", f.boundary_sag_ratio)?;
        if f.boundary_sag_ratio >= 0.5 {
            return Err(SceneError::invalid(
                "front_net.boundary_sag_ratio",
                format!(
                    "{} must be below 0.5 (sag as a fraction of the bay chord)",
                    f.boundary_sag_ratio
                ),
            ));
        }
        // The tension a membrane stress means depends on the net's spacing:
        // unknown while the rings are still to choose.
        let tension = (!f.rings_to_choose()).then(|| membrane_tension_n(self, 1.0));
        one_tension_of(
            "front_net",
            f.mean_tension_n,
            f.membrane_stress_n_per_m,
            tension,
        )?;
        positive("rear_net.focal_length_m", self.rear_net.focal_length_m)?;
        let r = &self.rear_net;
        one_tension_of(
            "rear_net",
            r.mean_tension_n,
            r.membrane_stress_n_per_m,
            tension,
        )?;

        let u = &self.uniformity;
        if u.groups.is_empty() {
            return Err(SceneError::invalid(
                "uniformity.groups",
                "at least one group is needed",
            ));
        }
        if let Some(g) = u
            .groups
            .iter()
            .enumerate()
            .find_map(|(i, g)| u.groups[..i].contains(g).then_some(g))
        {
            return Err(SceneError::invalid(
                "uniformity.groups",
                format!("{g:?} is listed twice"),
            ));
        }
        if !(u.min_tension_fraction > 0.0 && u.min_tension_fraction < 1.0) {
            return Err(SceneError::invalid(
                "uniformity.min_tension_fraction",
                format!("{} must lie in (0, 1)", u.min_tension_fraction),
            ));
        }

        if self
            .effects
            .rod_properties_csv
            .as_ref()
            .is_some_and(|f| f.as_os_str().is_empty())
        {
            return Err(SceneError::invalid(
                "effects.rod_properties_csv",
                "must name a CSV file (relative to the scene's folder)",
            ));
        }
        if let Some(table) = &self.effects.rod_properties {
            table.check_bays(t.bays)?;
        }

        let c = &self.cables;
        positive("cables.diameter_m", c.diameter_m)?;
        modulus("cables.youngs_modulus_pa", c.youngs_modulus_pa)?;
        positive("cables.density_kg_per_m3", c.density_kg_per_m3)?;
        positive(
            "cables.max_force_density_n_per_m",
            c.max_force_density_n_per_m,
        )?;
        if let Some(g) = &self.effects.gravity {
            non_negative(
                "effects.gravity.acceleration_m_per_s2",
                g.acceleration_m_per_s2,
            )?;
            let norm = g.direction.iter().map(|c| c * c).sum::<f64>().sqrt();
            if !(norm.is_finite() && norm > 0.0) {
                return Err(SceneError::invalid(
                    "effects.gravity.direction",
                    format!("{:?} must be a finite, non-zero vector", g.direction),
                ));
            }
        }
        if let Some(t) = &self.effects.thermal {
            thermal(t)?;
        }
        if let Some(t) = &self.tolerances {
            for (key, sigma) in t.sigmas() {
                non_negative(key, sigma)?;
            }
            if t.cable_stiffness_sigma >= MAX_RELATIVE_SIGMA {
                return Err(SceneError::invalid(
                    "tolerances.cable_stiffness_sigma",
                    format!(
                        "{} must be below {MAX_RELATIVE_SIGMA}: a normal error of that spread \
                         gives cables of no or negative stiffness",
                        t.cable_stiffness_sigma
                    ),
                ));
            }
            if t.samples == Some(0) {
                return Err(SceneError::invalid(
                    "tolerances.samples",
                    "0: a Monte Carlo needs at least one sample",
                ));
            }
        }
        Ok(())
    }
}

/// Largest relative standard deviation of a stiffness.
pub const MAX_RELATIVE_SIGMA: f64 = 0.2;

/// Largest free thermal strain `|α ΔT|` a case may ask for: far beyond any
/// material in orbit (carbon tubes 1e-6/K, aramid cords −4e-6/K, steel
/// 1.2e-5/K over ±150 K: 2e-3).
pub const MAX_THERMAL_STRAIN: f64 = 0.01;

/// `[effects.thermal]`: finite coefficients, named cases, fields whose
/// strain stays small.
fn thermal(t: &super::schema::Thermal) -> Result<(), SceneError> {
    let finite = |key: &'static str, v: f64| {
        if v.is_finite() {
            Ok(())
        } else {
            Err(SceneError::invalid(
                key,
                format!("{v} must be a finite number"),
            ))
        }
    };
    finite(
        "effects.thermal.cable_expansion_per_k",
        t.cable_expansion_per_k,
    )?;
    finite(
        "effects.thermal.tube_expansion_per_k",
        t.tube_expansion_per_k,
    )?;
    if let Some(a) = t.tie_expansion_per_k {
        finite("effects.thermal.tie_expansion_per_k", a)?;
    }
    if t.cases.is_empty() {
        return Err(SceneError::invalid(
            "effects.thermal.cases",
            "no case: give at least one `[[effects.thermal.cases]]`",
        ));
    }
    let alpha = t
        .cable_expansion_per_k
        .abs()
        .max(t.tube_expansion_per_k.abs())
        .max(t.tie_expansion_per_k.unwrap_or(0.0).abs());
    for (i, c) in t.cases.iter().enumerate() {
        let named = |reason: String| {
            SceneError::invalid(
                "effects.thermal.cases",
                format!("case {} ({:?}): {reason}", i + 1, c.name),
            )
        };
        if c.name.trim().is_empty() || c.name.contains(['\n', ',', '"']) {
            return Err(named(
                "a case needs a name without commas, quotes or line breaks".into(),
            ));
        }
        if t.cases[..i].iter().any(|o| o.name == c.name) {
            return Err(named("the name is given twice".into()));
        }
        let values = [c.uniform_k, c.gradient_k_per_m, c.front_k, c.rear_k];
        if values
            .iter()
            .chain(&c.gradient_direction)
            .any(|v| !v.is_finite())
        {
            return Err(named("every value must be a finite number".into()));
        }
        if c.gradient_k_per_m != 0.0 && c.gradient_direction.iter().all(|&v| v == 0.0) {
            return Err(named("gradient_direction must not be zero".into()));
        }
        // The largest change anywhere: bounded by the terms' sum over a
        // dish of at most the aperture… the gradient is checked per metre.
        let most = c.uniform_k.abs() + c.front_k.abs().max(c.rear_k.abs());
        if alpha * most > MAX_THERMAL_STRAIN
            || alpha * c.gradient_k_per_m.abs() > MAX_THERMAL_STRAIN
        {
            return Err(named(format!(
                "a free strain |α ΔT| above {MAX_THERMAL_STRAIN} (K or K/m too large for the \
                 coefficients)"
            )));
        }
    }
    Ok(())
}

/// Exactly one of `<net>.mean_tension_n` and `<net>.membrane_stress_n_per_m`
/// (a resolved scene has both, consistent: `tension_per_stress` N per N/m;
/// `None` while the net's rings, which set it, are still to choose).
fn one_tension_of(
    net: &'static str,
    mean_tension_n: f64,
    stress: Option<f64>,
    tension_per_stress: Option<f64>,
) -> Result<(), SceneError> {
    let (mean_key, stress_key) = match net {
        "front_net" => (
            "front_net.mean_tension_n",
            "front_net.membrane_stress_n_per_m",
        ),
        _ => (
            "rear_net.mean_tension_n",
            "rear_net.membrane_stress_n_per_m",
        ),
    };
    match stress {
        None if mean_tension_n == 0.0 => Err(SceneError::invalid(
            mean_key,
            format!("missing: give `{mean_key}` (N) or `{stress_key}` (N/m)"),
        )),
        None => positive(mean_key, mean_tension_n),
        Some(n) => {
            positive(stress_key, n)?;
            let Some(tension_per_stress) = tension_per_stress else {
                // The rings are still to choose: the stress alone, as given.
                if mean_tension_n != 0.0 {
                    return Err(SceneError::invalid(
                        stress_key,
                        format!("give either `{mean_key}` or `{stress_key}`, not both"),
                    ));
                }
                return Ok(());
            };
            let resolved = n * tension_per_stress;
            if (mean_tension_n - resolved).abs() > 1e-12 * resolved {
                return Err(SceneError::invalid(
                    stress_key,
                    format!(
                        "give either `{mean_key}` or `{stress_key}`, not both (the stress \
                         means {resolved:.6} N)"
                    ),
                ));
            }
            Ok(())
        }
    }
}

/// An elastic modulus: positive, and at most [`MAX_MODULUS_PA`] (stiffer than
/// any material; 1e300 made the truss's Newton 'converge' in 0 iterations).
fn modulus(key: &'static str, value: f64) -> Result<(), SceneError> {
    positive(key, value)?;
    modulus_range(value).map_err(|reason| SceneError::invalid(key, reason))
}

/// Why a finite positive modulus, Pa, is outside
/// [[`MIN_MODULUS_PA`], [`MAX_MODULUS_PA`]]: the scene's rule, which a
/// tube catalogue's line follows too.
///
/// # Errors
/// The reason, in words.
pub fn modulus_range(value: f64) -> Result<(), String> {
    if value > MAX_MODULUS_PA {
        return Err(format!(
            "{value:e} Pa is stiffer than any material (at most {MAX_MODULUS_PA:e} Pa)"
        ));
    }
    if value < MIN_MODULUS_PA {
        return Err(format!(
            "{value:e} Pa is softer than any structural material (at least {MIN_MODULUS_PA:e} Pa)"
        ));
    }
    Ok(())
}

fn positive(key: &'static str, value: f64) -> Result<(), SceneError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(SceneError::invalid(
            key,
            format!("{value} must be a finite number > 0"),
        ))
    }
}

fn non_negative(key: &'static str, value: f64) -> Result<(), SceneError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(SceneError::invalid(
            key,
            format!("{value} must be a finite number ≥ 0"),
        ))
    }
}
