//! The sized scene as a file: the input scene's own text with only the tube
//! lines changed ([`sized_scene_text`]) — its comments, layout and choices
//! (a membrane stress rather than a tension, rings left to a surface target)
//! kept, so that it can be edited and designed again.

use toml_edit::{DocumentMut, Item, Value};

use crate::scene::Truss;

/// The `[truss]` keys a section sets ([`super::TubeSection::apply`]).
const SECTION_KEYS: [&str; 5] = [
    "tube_outer_diameter_m",
    "tube_inner_diameter_m",
    "youngs_modulus_pa",
    "shear_modulus_pa",
    "density_kg_per_m3",
];

/// `input` (the text of the scene that was sized, named `name`) with the
/// `[truss]` values of the chosen section `sized`: the diameters always, the
/// material keys where the section changed them. Every other line is kept as
/// written, each value's trailing comment too; a `name` line becomes
/// `sized_name` (a file without one takes its name from its stem), and a
/// first line says what made the file. `None` when the text has no
/// `[truss]` table holding the keys (not a scene the reader took).
pub fn sized_scene_text(
    input: &str,
    name: &str,
    sized_name: &str,
    before: &Truss,
    sized: &Truss,
    margin: f64,
) -> Option<String> {
    let mut doc: DocumentMut = input.parse().ok()?;
    let truss = doc.get_mut("truss")?.as_table_like_mut()?;
    let values = |t: &Truss| {
        [
            t.tube_outer_diameter_m,
            t.tube_inner_diameter_m,
            t.youngs_modulus_pa,
            t.shear_modulus_pa,
            t.density_kg_per_m3,
        ]
    };
    for ((key, old), new) in SECTION_KEYS.iter().zip(values(before)).zip(values(sized)) {
        let item = truss.get_mut(key)?;
        if key.starts_with("tube_") || old != new {
            set_keeping_decor(item, new)?;
        }
    }
    if let Some(item) = doc.get_mut("name") {
        let decor = item.as_value()?.decor().clone();
        *item = Item::Value(Value::from(sized_name));
        *item.as_value_mut()?.decor_mut() = decor;
    }
    let header = format!(
        "# {name} with its truss sized by `ringmesh size` for a limit margin of {margin}.\n"
    );
    Some(header + &doc.to_string())
}

/// Sets a float value, keeping the spaces and comment around it.
fn set_keeping_decor(item: &mut Item, new: f64) -> Option<()> {
    let decor = item.as_value()?.decor().clone();
    *item = Item::Value(Value::from(new));
    *item.as_value_mut()?.decor_mut() = decor;
    Some(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Scene;

    const INPUT: &str = "# my dish\nname = \"dish\"  # the name\n\n[reflector]\n\
        aperture_diameter_m = 6.0\nfocal_length_m = 4.0\n\n[truss]\nbays = 6\n\
        height_m = 1.5\n# the tube, to be sized\ntube_outer_diameter_m = 0.060   # 60 mm\n\
        tube_inner_diameter_m = 0.056\nyoungs_modulus_pa = 160e9\nshear_modulus_pa = 61.5e9\n\
        density_kg_per_m3 = 1600.0\n\n[front_net]\nrings = 3\nboundary_sag_ratio = 0.05\n\
        membrane_stress_n_per_m = 40.0  # N/m\n\n[rear_net]\nfocal_length_m = 8.0\n\
        mean_tension_n = 140.0\n\n[cables]\ndiameter_m = 0.005\nyoungs_modulus_pa = 50e9\n\
        density_kg_per_m3 = 1440.0\nmax_force_density_n_per_m = 5000.0\n";

    /// Only the tube's lines and the name change: the comments, the
    /// material written as `160e9` and the one tension key given stay.
    #[test]
    fn the_sized_text_changes_only_the_tube_lines_and_the_name() {
        let scene = Scene::from_toml(INPUT, "dish").unwrap();
        let mut sized = scene.truss.clone();
        sized.tube_outer_diameter_m = 0.08;
        sized.tube_inner_diameter_m = 0.074;
        let text =
            sized_scene_text(INPUT, "dish", "dish-sized", &scene.truss, &sized, 2.0).unwrap();
        let changed: Vec<(&str, &str)> = INPUT
            .lines()
            .zip(text.lines().skip(1))
            .filter(|(a, b)| a != b)
            .collect();
        assert_eq!(
            changed,
            [
                (
                    "name = \"dish\"  # the name",
                    "name = \"dish-sized\"  # the name"
                ),
                (
                    "tube_outer_diameter_m = 0.060   # 60 mm",
                    "tube_outer_diameter_m = 0.08   # 60 mm"
                ),
                (
                    "tube_inner_diameter_m = 0.056",
                    "tube_inner_diameter_m = 0.074"
                ),
            ],
            "{text}"
        );
        assert!(text.starts_with(
            "# dish with its truss sized by `ringmesh size` for a limit margin of 2.\n# my dish\n"
        ));
        let read = Scene::from_toml(&text, "x").unwrap();
        assert_eq!(read.truss, sized);
        assert_eq!(read.front_net.membrane_stress_n_per_m, Some(40.0));
        assert!(!text.contains("front_net.mean_tension_n") && !text.contains("mean_tension_n = 7"));
    }

    /// A catalogue section of another material changes the material lines.
    #[test]
    fn a_section_of_another_material_changes_its_lines() {
        let scene = Scene::from_toml(INPUT, "dish").unwrap();
        let section = crate::sizing::TubeSection {
            outer_diameter_m: 0.1,
            inner_diameter_m: 0.09,
            youngs_modulus_pa: 80e9,
            density_kg_per_m3: 2000.0,
        };
        let sized = section.apply(&scene.truss);
        let text =
            sized_scene_text(INPUT, "dish", "dish-sized", &scene.truss, &sized, 2.0).unwrap();
        assert_eq!(Scene::from_toml(&text, "x").unwrap().truss, sized);
        assert!(text.contains("# the tube, to be sized\n"));
    }
}
