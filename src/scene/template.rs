//! The commented starting scene `ringmesh init` writes ([`template`]): every
//! key of the format, the optional ones commented out, each with its unit and
//! meaning (the reference is `docs/scene.md`). It designs as it is, in about
//! a second.

/// A starting scene named `name`: a 6 m centre-fed dish on a 6-bay ring, its
/// optional keys shown commented out with their defaults.
pub fn template(name: &str) -> String {
    TEMPLATE.replace("{name}", name)
}

const TEMPLATE: &str = r#"# A starting scene written by `ringmesh init`: a 6 m centre-fed dish on a
# 6-bay ring truss, designed in about a second by
#     ringmesh design THIS-FILE
# Every key is described in docs/scene.md (unit, default, range). Keys shown
# commented out are optional, with their default value.

name = "{name}"                 # names the output folder runs/<name>/.

[reflector]
aperture_diameter_m = 6.0       # m, the aperture circle's diameter in plan.
focal_length_m = 4.0            # m, F of z = (x² + y²)/(4F): dish depth 0.5625 m.
# offset_m = 0.0                # m, axis to aperture centre (0: centre-fed).

[truss]
bays = 6                        # battens = top hinges; bay chord 3 m here.
height_m = 1.5                  # m, batten length; must leave every tie > 0.
tube_outer_diameter_m = 0.060   # m (`ringmesh size` chooses it for a margin).
tube_inner_diameter_m = 0.056   # m
youngs_modulus_pa = 160e9       # Pa (carbon fibre composite).
shear_modulus_pa = 61.5e9       # Pa
density_kg_per_m3 = 1600.0      # kg/m³
# supports = "isostatic"        # a 3-2-1 support: the net's pull deforms the truss freely.
# elements_per_rod = 4          # beam elements per rod (1…64).
# element = "se3"               # or "crisfield-jelenic" (the paper's element).
# hinge_mass_kg = 0.0           # kg per hinge (weighs only under [effects.gravity]).

[front_net]
rings = 3                       # subdivisions of a sector's edge; leave out to
                                # have [surface] rms_mm choose them.
boundary_sag_ratio = 0.05       # boundary cable's sag at mid-bay / bay chord (< 0.5).
mean_tension_n = 70.0           # N, mean tension of the interior cables; or
# membrane_stress_n_per_m = 40.0  # N/m instead (better for dense nets): give one.

[rear_net]
focal_length_m = 8.0            # m, the rear paraboloid's F (rear level ≈ 2× front).
mean_tension_n = 140.0          # N; or membrane_stress_n_per_m (one of the two).

[cables]
diameter_m = 0.005              # m
youngs_modulus_pa = 50e9        # Pa (sets the cut lengths L₀ = ℓ/(1 + T/EA)).
density_kg_per_m3 = 1440.0      # kg/m³
max_force_density_n_per_m = 5000.0  # N/m, the bound [q] on every force density.

# [uniformity]
# groups = ["front"]            # nets made uniform: "front", "rear" (first holds its tension).
# min_tension_fraction = 0.001  # other cables keep this fraction of the smallest tension.

# [effects]
# truss = "exact"               # the design loop's truss: "rigid", "linear" or "exact".
# cable_elasticity = true       # verification with elastic (true) or inextensible cables.
# rod_properties_csv = "rods.csv"  # measured EA/EI per rod (src/scene/rod_properties.rs).

# [effects.gravity]             # a ground test; absent: orbit.
# acceleration_m_per_s2 = 9.81  # m/s²
# direction = [0.0, 0.0, -1.0]  # z from the vertex to the focus: aperture up.

# [surface]
# rms_mm = 1.5                  # mm, target facet RMS of the design surface.
# frequency_ghz = 2.2           # GHz, the gain loss is reported at it.
"#;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Scene;

    #[test]
    fn the_template_reads_as_a_valid_scene_named_as_asked() {
        let scene = Scene::from_toml(&template("my-dish"), "unused").unwrap();
        assert_eq!(scene.name, "my-dish");
        assert_eq!(scene.front_net.rings, 3);
    }

    /// Every commented-out key, uncommented, still reads: the template shows
    /// keys the format has, with values it takes.
    #[test]
    fn the_templates_commented_keys_are_keys_of_the_format() {
        let text: String = template("my-dish")
            .lines()
            .map(|l| match l.strip_prefix("# ") {
                Some(rest) if rest.starts_with('[') || rest.contains(" = ") => rest,
                _ => l,
            })
            .map(|l| {
                // The alternatives to the given tensions and the rings stay out.
                if l.starts_with("membrane_stress") || l.starts_with("rod_properties_csv") {
                    ""
                } else {
                    l
                }
            })
            .collect::<Vec<_>>()
            .join("\n");
        assert!(text.contains("\n[effects.gravity]"), "{text}");
        let scene = Scene::from_toml(&text, "unused").unwrap();
        assert!(scene.effects.gravity.is_some());
        assert_eq!(scene.surface.rms_mm, Some(1.5));
    }
}
