//! `ringmesh study`: what accuracy costs in time ([`crate::study`]), as a
//! table and plots (or one shard's points).

use std::path::{Path, PathBuf};

use super::{default_output_dir, read_scene, write_shard, Progress, Summary};
use crate::geometry::build_mesh;
use crate::report::{
    decimal, readable, strategies_plot, study_csv, study_plot, study_row, write_atomic, OutputSet,
    RmsAxis, StudyRms, STUDY_COLUMNS,
};
use crate::resources::{check_scene_jobs, SceneCommand};
use crate::scene::{Scene, TrussModel};
use crate::shard::Shard;
use crate::study::{self, Knob, StudyRow, StudySettings};
use crate::surface::design_surface_facet_rms_mm;
use crate::uniformity::SolverKind;
use crate::Error;

/// Choices of `ringmesh study`, resolved by the CLI; `None` keeps the
/// default sweep of [`StudySettings::for_scene`].
#[derive(Debug, Clone)]
pub struct StudyOptions {
    /// The knobs swept (the others are left out).
    pub knobs: Vec<Knob>,
    /// Outer-loop tolerances, m.
    pub tolerances_m: Option<Vec<f64>>,
    /// Elements per truss rod.
    pub elements_per_rod: Option<Vec<usize>>,
    /// Front-net rings.
    pub rings: Option<Vec<usize>>,
    /// Truss models.
    pub truss_models: Option<Vec<TrussModel>>,
    /// Uniformity solvers.
    pub solvers: Option<Vec<SolverKind>>,
    /// Most outer iterations of a run.
    pub max_iterations: Option<usize>,
    /// Points run at once (1: one after the other, each timed alone).
    pub jobs: usize,
    /// The surface RMS the plot is drawn against.
    pub rms: RmsAxis,
}

impl Default for StudyOptions {
    fn default() -> Self {
        StudyOptions {
            knobs: Knob::SWEPT.to_vec(),
            tolerances_m: None,
            elements_per_rod: None,
            rings: None,
            truss_models: None,
            solvers: None,
            max_iterations: None,
            jobs: 1,
            rms: RmsAxis::Design,
        }
    }
}

impl StudyOptions {
    /// The study's settings for `scene`.
    pub fn settings(&self, scene: &Scene) -> StudySettings {
        let mut s = StudySettings::for_scene(scene);
        if let Some(v) = &self.tolerances_m {
            s.tolerances_m.clone_from(v);
        }
        if let Some(v) = &self.elements_per_rod {
            s.elements_per_rod.clone_from(v);
        }
        if let Some(v) = &self.rings {
            s.rings.clone_from(v);
        }
        if let Some(v) = &self.truss_models {
            s.truss_models.clone_from(v);
        }
        if let Some(v) = &self.solvers {
            s.solvers.clone_from(v);
        }
        if let Some(n) = self.max_iterations {
            s.max_iterations = n;
        }
        s.only(&self.knobs)
    }
}

/// What `ringmesh study` made.
#[derive(Debug)]
pub struct StudyOutcome {
    /// The scene's name.
    pub scene: String,
    /// `(point index, row)` of the points run, in sweep order.
    pub rows: Vec<(usize, StudyRow)>,
    /// Points of the whole sweep.
    pub points: usize,
    /// The surface RMS the rows are drawn at.
    pub rms: StudyRms,
    /// Files written.
    pub written: Vec<PathBuf>,
}

impl StudyOutcome {
    /// What `ringmesh study` prints: a table of the points run (knob,
    /// value, design time, accuracy as built, or why a point failed), the
    /// facet RMS a total RMS is drawn with, the files written.
    pub fn summary(&self) -> Summary {
        let mut s = Summary::default();
        say!(
            s,
            "{}: {} of {} points (time: design wall time; accuracy: as built on the reference truss)",
            self.scene,
            self.rows.len(),
            self.points
        );
        say!(
            s,
            "{:>5} {:>10} {:>13} {:>9} {:>10} {:>13} {:>11} {:>13} {:>13}",
            "point",
            "knob",
            "value",
            "time s",
            "RMS mm",
            "Tmax/Tmin err",
            "tension %",
            "cut len mm",
            "facet RMS mm"
        );
        for (k, r) in &self.rows {
            let value = if r.value.is_empty() { "-" } else { &r.value };
            let g = |v: f64| {
                if v.is_finite() {
                    readable(v, 4)
                } else {
                    "-".into()
                }
            };
            match &r.error {
                Some(e) => say!(
                    s,
                    "{k:>5} {:>10} {value:>13} {:>9.3}  failed: {e}",
                    r.knob.name(),
                    r.time_s
                ),
                None => say!(
                    s,
                    "{k:>5} {:>10} {value:>13} {:>9.3} {:>10} {:>13} {:>11} {:>13} {:>13}",
                    r.knob.name(),
                    r.time_s,
                    g(r.rms_mm),
                    g(r.ratio_error),
                    g(r.tension_change_pct),
                    g(r.cut_length_error_mm),
                    g(r.facet_rms_mm)
                ),
            }
        }
        if let StudyRms::Total { facets_mm } = &self.rms {
            let nets: Vec<String> = facets_mm
                .iter()
                .map(|(rings, f)| format!("{rings} rings {} mm", readable(*f, 4)))
                .collect();
            say!(
                s,
                "drawn against total RMS √(facets² + RMS²), facets: facet RMS of each net's \
                 design surface: {}",
                nets.join(", ")
            );
        }
        s.written(&self.written);
        s
    }
}

/// The study's file stem, as a literal (`concat!` builds [`FILES`] from it).
macro_rules! stem {
    () => {
        "accuracy-vs-time"
    };
}

/// The settings of a study of `scene` with `options`, validated, and its
/// workload checked against the memory limit: the scene's net and each net
/// the rings knob asks for, refused up front (not a failed row once the
/// study has run).
fn study_settings(scene: &Scene, options: &StudyOptions) -> Result<StudySettings, Error> {
    let settings = options.settings(scene);
    settings.validate()?;
    check_scene_jobs(scene, SceneCommand::Design, options.jobs.max(1) as u64)?;
    for &rings in &settings.rings {
        let mut net = scene.clone();
        net.front_net.rings = rings;
        check_scene_jobs(&net, SceneCommand::Design, options.jobs.max(1) as u64)?;
    }
    Ok(settings)
}

/// The whole study of `scene` in memory, without files: `(point index,
/// row)` in sweep order; `on_point` sees each row as it finishes. What a
/// library user (the Python bindings) calls.
///
/// # Errors
/// Invalid options, a workload beyond the memory limit, a reference point
/// that fails; a point that fails is a row with its error.
pub fn study_rows(
    scene: &Scene,
    options: &StudyOptions,
    on_point: &(dyn Fn(&StudyRow) + Sync),
) -> Result<Vec<(usize, StudyRow)>, Error> {
    let settings = study_settings(scene, options)?;
    Ok(study::run_study(
        scene,
        &settings,
        Shard::WHOLE,
        options.jobs,
        on_point,
    )?)
}

/// The name of the study's table and plots.
pub const STUDY_STEM: &str = stem!();

/// `ringmesh study`: what accuracy costs in time ([`crate::study`]). Writes
/// `accuracy-vs-time.csv`, `.png` and `.svg` (drawn against the surface RMS
/// `options.rms` chooses) and `strategies.png`, `.svg` (every solver's time
/// against its accuracy); with a `shard`, only that
/// shard's points (and the reference, run to judge them), written as
/// `accuracy-vs-time.shard-I-of-N.csv`.
pub fn study(
    scene_path: &Path,
    options: &StudyOptions,
    output_dir: Option<&Path>,
    shard: Option<Shard>,
    progress: &dyn Progress,
) -> Result<StudyOutcome, Error> {
    let scene = read_scene(scene_path)?;
    let dir = output_dir.map_or_else(|| default_output_dir(&scene), Path::to_path_buf);
    // A shard writes one file under the folder's lock once computed; the
    // whole study takes the folder before computing.
    let settings = study_settings(&scene, options)?;
    let set = match shard {
        Some(_) => None,
        None => Some(OutputSet::begin(&dir, &FILES)?),
    };
    let total = study::points(&scene, &settings).len();
    let part = shard.unwrap_or(Shard::WHOLE);
    let runs = part.points(total).len() + usize::from(!part.includes(0));
    progress.start(runs);
    let rows = study::run_study(&scene, &settings, part, options.jobs, &|r: &StudyRow| {
        let outcome = match &r.error {
            Some(e) => format!("failed: {e}"),
            None => format!(
                "RMS as built {} mm, design {} s",
                readable(r.rms_mm, 4),
                decimal(r.time_s, 3)
            ),
        };
        let point = format!("{} {}", r.knob.name(), r.value);
        progress.step(&format!("{}: {outcome}", point.trim_end()));
    })?;
    let rms = match options.rms {
        RmsAxis::Design => StudyRms::Design,
        RmsAxis::Total => StudyRms::Total {
            facets_mm: design_surface_facets_by_rings(&scene, &rows)?,
        },
    };
    let written = match set {
        None => {
            let shard = shard.unwrap_or(Shard::WHOLE);
            let lines: Vec<(usize, String)> =
                rows.iter().map(|(k, r)| (*k, study_row(r))).collect();
            let settings = serde_json::to_value(&settings).expect("settings serialise");
            vec![write_shard(
                &dir,
                STUDY_STEM,
                "study",
                &scene,
                shard,
                (total, Vec::new()),
                settings,
                STUDY_COLUMNS,
                &lines,
            )?]
        }
        Some(set) => {
            let table: Vec<StudyRow> = rows.iter().map(|(_, r)| r.clone()).collect();
            write_study(set, &scene.name, &table, &rms, &study_csv(&table))?
        }
    };
    Ok(StudyOutcome {
        scene: scene.name,
        rows,
        points: total,
        rms,
        written,
    })
}

/// The facet RMS of the design surface of each net the successful `rows`
/// designed, `(rings, mm)` in ascending rings: the scene's front net with
/// their rings, as the study builds it.
///
/// # Errors
/// A net that cannot be built or measured.
fn design_surface_facets_by_rings(
    scene: &Scene,
    rows: &[(usize, StudyRow)],
) -> Result<Vec<(usize, f64)>, Error> {
    let mut rings: Vec<usize> = rows
        .iter()
        .filter(|(_, r)| r.error.is_none())
        .map(|(_, r)| r.settings.rings)
        .collect();
    rings.sort_unstable();
    rings.dedup();
    rings
        .into_iter()
        .map(|r| {
            let mut net = scene.clone();
            net.front_net.rings = r;
            Ok((r, design_surface_facet_rms_mm(&build_mesh(&net)?)?))
        })
        .collect()
}

/// The strategies figure's file stem, as a literal (for [`FILES`]).
macro_rules! strategies_stem {
    () => {
        "strategies"
    };
}

/// The name of the strategies figure (every solver's time against its
/// accuracy), written beside the study's table.
pub const STRATEGIES_STEM: &str = strategies_stem!();

/// The files of a whole study (stem [`STUDY_STEM`], and the strategies
/// figure [`STRATEGIES_STEM`]).
pub(crate) const FILES: [&str; 5] = [
    concat!(stem!(), ".csv"),
    concat!(stem!(), ".png"),
    concat!(stem!(), ".svg"),
    concat!(strategies_stem!(), ".png"),
    concat!(strategies_stem!(), ".svg"),
];

/// `accuracy-vs-time.csv` (the table `csv`), `.png`, `.svg` (drawn from
/// `rows` against `rms`) and `strategies.png`, `.svg` (the solver knob's
/// rows: every solver's time against its accuracy), written into `set`
/// (begun with [`FILES`]) and swapped in.
pub(crate) fn write_study(
    set: OutputSet,
    scene: &str,
    rows: &[StudyRow],
    rms: &StudyRms,
    csv: &str,
) -> Result<Vec<PathBuf>, Error> {
    let [csv_path, png, svg, strategies_png, strategies_svg] = FILES.map(|name| set.path(name));
    let title =
        format!("{scene}: what accuracy costs in time (designs as built on the reference truss)");
    study_plot(rows, rms, &title, &png, &svg)?;
    let title = format!(
        "{scene}: each solver's time against its accuracy (designs as built on the reference truss)"
    );
    strategies_plot(rows, rms, &title, &strategies_png, &strategies_svg)?;
    write_atomic(&csv_path, csv.as_bytes())?;
    set.seal()?;
    Ok(set.commit()?)
}
