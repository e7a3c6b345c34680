//! Tube sections and the catalogue CSV they come from
//! (`outer_diameter_m,inner_diameter_m[,youngs_modulus_pa,density_kg_per_m3]`).

use std::io::Read;
use std::path::Path;

use serde::Serialize;

use super::error::SizingError;
use crate::scene::Truss;

/// One round tube: the section every rod of the ring truss is made of.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TubeSection {
    /// Outer diameter, m.
    pub outer_diameter_m: f64,
    /// Inner diameter, m.
    pub inner_diameter_m: f64,
    /// Young's modulus, Pa.
    pub youngs_modulus_pa: f64,
    /// Density, kg/m³.
    pub density_kg_per_m3: f64,
}

impl TubeSection {
    /// The section of `truss`.
    pub fn of(truss: &Truss) -> Self {
        TubeSection {
            outer_diameter_m: truss.tube_outer_diameter_m,
            inner_diameter_m: truss.tube_inner_diameter_m,
            youngs_modulus_pa: truss.youngs_modulus_pa,
            density_kg_per_m3: truss.density_kg_per_m3,
        }
    }

    /// `truss` made of this section; its shear modulus keeps the truss's
    /// ratio `G/E`.
    pub fn apply(&self, truss: &Truss) -> Truss {
        Truss {
            tube_outer_diameter_m: self.outer_diameter_m,
            tube_inner_diameter_m: self.inner_diameter_m,
            youngs_modulus_pa: self.youngs_modulus_pa,
            shear_modulus_pa: truss.shear_modulus_pa * self.youngs_modulus_pa
                / truss.youngs_modulus_pa,
            density_kg_per_m3: self.density_kg_per_m3,
            ..truss.clone()
        }
    }

    /// Area, m².
    pub fn area_m2(&self) -> f64 {
        std::f64::consts::FRAC_PI_4
            * (self.outer_diameter_m.powi(2) - self.inner_diameter_m.powi(2))
    }

    /// Mass per length, kg/m.
    pub fn mass_per_length_kg_per_m(&self) -> f64 {
        self.density_kg_per_m3 * self.area_m2()
    }

    /// Bending stiffness `E·π(D⁴ − d⁴)/64`, N·m².
    pub fn bending_stiffness_nm2(&self) -> f64 {
        self.youngs_modulus_pa
            * std::f64::consts::PI
            * (self.outer_diameter_m.powi(4) - self.inner_diameter_m.powi(4))
            / 64.0
    }
}

/// Largest catalogue file read, bytes.
const MAX_BYTES: u64 = 1 << 20;

/// The columns of a catalogue, in order; the last two may be left out.
const COLUMNS: [&str; 4] = [
    "outer_diameter_m",
    "inner_diameter_m",
    "youngs_modulus_pa",
    "density_kg_per_m3",
];

/// Reads a catalogue file; sections without `youngs_modulus_pa` and
/// `density_kg_per_m3` take `truss`'s.
///
/// # Errors
/// The file cannot be read, or its content is invalid (see [`parse`]).
pub fn read(path: &Path, truss: &Truss) -> Result<Vec<TubeSection>, SizingError> {
    let shown = path.display().to_string();
    let io = |e: std::io::Error| SizingError::Catalogue {
        path: shown.clone(),
        line: None,
        reason: e.to_string(),
    };
    let mut text = String::new();
    std::fs::File::open(path)
        .map_err(io)?
        .take(MAX_BYTES + 1)
        .read_to_string(&mut text)
        .map_err(io)?;
    if text.len() as u64 > MAX_BYTES {
        return Err(SizingError::Catalogue {
            path: shown,
            line: None,
            reason: format!("larger than {MAX_BYTES} bytes: not a catalogue"),
        });
    }
    parse(&text, &shown, truss)
}

/// Parses catalogue text (`source` names it in errors): a header of the
/// first two, three or four of `outer_diameter_m,inner_diameter_m,
/// youngs_modulus_pa,density_kg_per_m3`, then one section per line;
/// blank lines and lines starting with `#` are skipped.
///
/// # Errors
/// A bad header, a row with the wrong number of fields, a value that is not
/// a finite number `> 0` (the inner diameter `>= 0`: a solid rod is a
/// section, as in a scene), a modulus outside the scene's range
/// ([`crate::scene::modulus_range`]), an inner diameter not below the
/// outer one, or no row; each names the line.
pub fn parse(text: &str, source: &str, truss: &Truss) -> Result<Vec<TubeSection>, SizingError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let error = |line: usize, reason: String| SizingError::Catalogue {
        path: source.to_string(),
        line: Some(line),
        reason,
    };
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let expected = format!("expected the header `{}`", COLUMNS.join(","));
    let Some((header_line, header)) = lines.next() else {
        return Err(error(1, format!("the catalogue is empty: {expected}")));
    };
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    if names.len() < 2 || names.len() > COLUMNS.len() || names != COLUMNS[..names.len()] {
        return Err(error(
            header_line,
            format!("header `{header}`: {expected} (the last two optional)"),
        ));
    }
    let mut sections = Vec::new();
    for (line, row) in lines {
        let fields: Vec<&str> = row.split(',').map(str::trim).collect();
        if fields.len() != names.len() {
            return Err(error(
                line,
                format!("{} fields, the header has {}", fields.len(), names.len()),
            ));
        }
        let mut values = [0.0, 0.0, truss.youngs_modulus_pa, truss.density_kg_per_m3];
        for (k, field) in fields.iter().enumerate() {
            // A solid rod (inner diameter 0) is a section, as in a scene.
            let least = if k == 1 { 0.0 } else { f64::MIN_POSITIVE };
            values[k] = match field.parse::<f64>() {
                Ok(v) if v.is_finite() && v >= least => v,
                _ => {
                    let bound = if k == 1 { ">= 0" } else { "> 0" };
                    return Err(error(
                        line,
                        format!("`{}` = `{field}`: not a finite number {bound}", COLUMNS[k]),
                    ));
                }
            };
        }
        if let Err(reason) = crate::scene::modulus_range(values[2]) {
            return Err(error(line, format!("`youngs_modulus_pa`: {reason}")));
        }
        let [outer_diameter_m, inner_diameter_m, youngs_modulus_pa, density_kg_per_m3] = values;
        if inner_diameter_m >= outer_diameter_m {
            return Err(error(
                line,
                format!(
                    "`inner_diameter_m` = {inner_diameter_m} is not below `outer_diameter_m` = \
                     {outer_diameter_m}"
                ),
            ));
        }
        sections.push(TubeSection {
            outer_diameter_m,
            inner_diameter_m,
            youngs_modulus_pa,
            density_kg_per_m3,
        });
    }
    if sections.is_empty() {
        return Err(error(header_line, "no section below the header".into()));
    }
    Ok(sections)
}

/// The sections worth trying, lightest first: a section at least as heavy
/// as a lighter one and no stiffer in bending (`EI`) cannot be the lightest
/// that carries the net, its margin growing with its bending stiffness, and
/// is left out.
pub fn undominated(sections: &[TubeSection]) -> Vec<TubeSection> {
    let mut sorted = sections.to_vec();
    sorted.sort_by(|a, b| {
        a.mass_per_length_kg_per_m()
            .total_cmp(&b.mass_per_length_kg_per_m())
            .then(
                b.bending_stiffness_nm2()
                    .total_cmp(&a.bending_stiffness_nm2()),
            )
    });
    let mut stiffest = 0.0;
    sorted.retain(|s| {
        let keep = s.bending_stiffness_nm2() > stiffest;
        stiffest = f64::max(stiffest, s.bending_stiffness_nm2());
        keep
    });
    sorted
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Scene;

    fn truss() -> Truss {
        let text = std::fs::read_to_string("problems/small-hex.toml").unwrap();
        Scene::from_toml(&text, "small-hex").unwrap().truss
    }

    #[test]
    fn a_catalogue_takes_the_trusss_material_where_it_gives_none() {
        let t = truss();
        let text = "# carbon tubes\nouter_diameter_m,inner_diameter_m\n0.05,0.046\n\n0.06,0.056\n";
        let sections = parse(text, "c.csv", &t).unwrap();
        assert_eq!(sections.len(), 2);
        assert_eq!(sections[1].youngs_modulus_pa, t.youngs_modulus_pa);
        let full = "outer_diameter_m,inner_diameter_m,youngs_modulus_pa,density_kg_per_m3\n\
                    0.05,0.046,2e11,7800\n";
        assert_eq!(
            parse(full, "c.csv", &t).unwrap()[0].density_kg_per_m3,
            7800.0
        );
    }

    #[test]
    fn bad_catalogues_name_the_line() {
        let t = truss();
        for (text, line, needle) in [
            ("", 1, "empty"),
            ("diameter\n0.05\n", 1, "header"),
            ("outer_diameter_m,inner_diameter_m\n", 1, "no section"),
            (
                "outer_diameter_m,inner_diameter_m\n0.05,0.046\n0.05\n",
                3,
                "1 fields",
            ),
            (
                "outer_diameter_m,inner_diameter_m\n0.05,nan\n",
                2,
                "inner_diameter_m",
            ),
            (
                "outer_diameter_m,inner_diameter_m\n0.05,0.06\n",
                2,
                "not below",
            ),
            (
                "outer_diameter_m,inner_diameter_m\n-0.05,0.01\n",
                2,
                "outer_diameter_m",
            ),
        ] {
            let e = parse(text, "c.csv", &t).unwrap_err();
            let SizingError::Catalogue { line: Some(l), .. } = &e else {
                panic!("{e:?}");
            };
            assert_eq!(*l, line, "{text:?}: {e}");
            assert!(e.to_string().contains(needle), "{text:?}: {e}");
        }
    }

    #[test]
    fn dominated_sections_are_left_out_lightest_first() {
        let tube = |outer: f64, inner: f64| TubeSection {
            outer_diameter_m: outer,
            inner_diameter_m: inner,
            youngs_modulus_pa: 1e11,
            density_kg_per_m3: 1600.0,
        };
        // The thick 40 mm tube is heavier than the thin 60 mm one and less
        // stiff: never the lightest that carries.
        let sections = [tube(0.08, 0.076), tube(0.04, 0.02), tube(0.06, 0.056)];
        let kept = undominated(&sections);
        assert_eq!(kept, vec![tube(0.06, 0.056), tube(0.08, 0.076)]);
    }
}
