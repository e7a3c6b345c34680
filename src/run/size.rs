//! `ringmesh size`: the lightest tube section that carries a scene's net
//! with a margin ([`crate::sizing::size_truss`]), and its files.

use std::path::{Path, PathBuf};

use super::{default_output_dir, read_scene, Summary};
use crate::design::DesignSettings;
use crate::mechanics::LimitBound;
use crate::report::{readable, sizing_csv, sizing_plot, write_atomic, OutputSet};
use crate::resources::{check_scene, SceneCommand};
use crate::sizing::{
    catalogue, size_truss_observed, sized_scene_text, SectionTrial, Sections, Sizing,
    SizingObserver,
};
use crate::Error;

/// What `ringmesh size` made.
#[derive(Debug)]
pub struct SizeOutcome {
    /// The sizing.
    pub sizing: Sizing,
    /// Files written.
    pub written: Vec<PathBuf>,
}

impl SizeOutcome {
    /// What `ringmesh size` prints: the section chosen and how many were
    /// tried, the files written.
    pub fn summary(&self) -> Summary {
        let s = &self.sizing;
        let chosen = &s.trials[s.chosen];
        let mut summary = Summary::default();
        say!(
            summary,
            "lightest section with a margin ≥ {} of {} tried: {}",
            s.margin,
            s.trials.len(),
            section_line(chosen)
        );
        summary.written(&self.written);
        summary
    }
}

/// One section a sizing tried, on one line: the tube, its mass and margin,
/// whether it carries the net, its design's iterations and RMS as built
/// (or why it has no design), the time.
pub fn section_line(t: &SectionTrial) -> String {
    let c = &t.section;
    let outcome = match (&t.failure, t.summary, t.rms_mm) {
        (Some(f), _, _) => format!("no design: {f}"),
        (None, Some(s), Some(rms)) => format!(
            "{} outer iterations, RMS as built {} mm",
            s.outer_iterations,
            readable(rms, 3)
        ),
        (None, _, _) => String::new(),
    };
    format!(
        "{:.1}/{:.1} mm tube: {:.0} kg, margin {:.3}{}, {}; {outcome} ({:.1} s)",
        1e3 * c.outer_diameter_m,
        1e3 * c.inner_diameter_m,
        t.mass_kg,
        t.margin,
        if t.bound == Some(LimitBound::SearchEnd) {
            " (searched to its end)"
        } else {
            ""
        },
        if t.carries {
            "carries"
        } else {
            "does not carry"
        },
        t.time_s
    )
}

/// `ringmesh size`: reads the scene (and the catalogue `sections`, if
/// given; else the outer diameter is searched at the scene's `d/D`), sizes
/// its truss for `margin` and writes `sizing.csv` (every section tried),
/// `sizing.png/.svg` (their margin against their mass, the chosen one
/// marked) and
/// `<scene>-sized.toml` (the input file with the chosen section's tube
/// lines, named `<scene>-sized`: its comments and layout kept) into `output_dir` (default `runs/<scene>/`).
/// `observer` sees each section tried, and each outer iteration and stage
/// of its design.
///
/// # Errors
/// The scene's, the catalogue's and the sizing's errors, and the writers';
/// nothing is written unless a section was found.
pub fn size(
    scene_path: &Path,
    margin: f64,
    sections: Option<&Path>,
    settings: &DesignSettings,
    output_dir: Option<&Path>,
    observer: &mut dyn SizingObserver,
) -> Result<SizeOutcome, Error> {
    let scene = read_scene(scene_path)?;
    let sections = match sections {
        Some(path) => Sections::Catalogue(catalogue::read(path, &scene.truss)?),
        None => Sections::Continuous {
            start_m: scene.truss.tube_outer_diameter_m,
        },
    };
    let dir = output_dir.map_or_else(|| default_output_dir(&scene), Path::to_path_buf);
    let sized_name = format!("{}-sized", scene.name);
    let toml_name = format!("{sized_name}.toml");
    check_scene(&scene, SceneCommand::Design, 1)?;
    let set = OutputSet::begin(
        &dir,
        &["sizing.csv", "sizing.png", "sizing.svg", &toml_name],
    )?;
    let mut sizing = size_truss_observed(&scene, &sections, margin, settings, observer)?;
    sizing.scene.name = sized_name;
    // The input's own text with the tube lines changed (comments and choices
    // kept); the scene as serialised only if that text cannot be edited.
    let edited = std::fs::read_to_string(scene_path).ok().and_then(|input| {
        sized_scene_text(
            &input,
            &scene.name,
            &sizing.scene.name,
            &scene.truss,
            &sizing.scene.truss,
            margin,
        )
    });
    let text = match edited {
        Some(text) => text,
        None => format!(
            "# {} with its truss sized by `ringmesh size` for a limit margin of {}.\n{}",
            scene.name,
            margin,
            sizing.scene.to_toml()?
        ),
    };
    write_atomic(
        &set.path("sizing.csv"),
        sizing_csv(&sizing.trials).as_bytes(),
    )?;
    write_atomic(&set.path(&toml_name), text.as_bytes())?;
    let title = format!(
        "{}: tube sections tried for a limit margin of {margin}",
        scene.name
    );
    sizing_plot(
        &sizing.trials,
        sizing.chosen,
        margin,
        &title,
        &set.path("sizing.png"),
        &set.path("sizing.svg"),
    )?;
    Ok(SizeOutcome {
        sizing,
        written: set.commit()?,
    })
}
