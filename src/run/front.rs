//! `ringmesh front`: the design front of a scene, each solver's accuracy knob
//! swept, as a table and plots (or one shard's points).

use std::path::{Path, PathBuf};

use super::{default_output_dir, read_scene, write_shard, Progress, Summary};
use crate::design::scene_problem;
use crate::report::{
    front_csv, front_plot, front_row, json_name, readable, write_atomic, FrontRms, FrontRow,
    FrontY, OutputSet, RmsAxis, FRONT_COLUMNS,
};
use crate::resources::{check_memory, check_scene, SceneCommand};
use crate::scene::Scene;
use crate::shard::Shard;
use crate::study;
use crate::surface::design_surface_facet_rms_mm;
use crate::uniformity::{
    design_front, design_front_chains, front_chains, front_jobs, FrontPoint, SolverKind,
    UniformityProblem,
};
use crate::Error;

/// What `ringmesh front` made.
#[derive(Debug)]
pub struct FrontOutcome {
    /// The points run, in sweep order.
    pub points: Vec<FrontPoint>,
    /// The surface RMS the points are drawn at.
    pub rms: FrontRms,
    /// Files written.
    pub written: Vec<PathBuf>,
}

impl FrontOutcome {
    /// What `ringmesh front` prints: one line per point (its ratio, RMS and
    /// time, or why it failed), the facet RMS a total RMS is drawn with, the
    /// files written.
    pub fn summary(&self) -> Summary {
        let mut s = Summary::default();
        for p in &self.points {
            match &p.outcome {
                Ok(t) => say!(
                    s,
                    "{} {}: Tmax/Tmin {}, RMS {} mm, {} s ({})",
                    study::value_name(&p.solver),
                    p.solver.knob_text(&readable(p.knob, 3)),
                    readable(p.ratio, 7),
                    readable(p.rms_mm, 4),
                    readable(p.time_s, 3),
                    json_name(t)
                ),
                Err(e) => say!(
                    s,
                    "{} {}: failed: {e}",
                    study::value_name(&p.solver),
                    p.solver.knob_text(&readable(p.knob, 3))
                ),
            }
        }
        if let FrontRms::Total { facets_mm } = self.rms {
            say!(
                s,
                "drawn against total RMS √(facets² + RMS²), facets: facet RMS of the net's \
                 design surface {} mm",
                readable(facets_mm, 4)
            );
        }
        s.written(&self.written);
        s
    }
}

/// `ringmesh front`: the design front of a scene (each solver's knob swept in
/// parallel), written as `front.csv`, `front.png` and `front.svg`, the plot
/// drawn against the surface RMS `rms` chooses; with a `shard`, only that
/// shard's points, written as `front.shard-I-of-N.csv` (see
/// [`crate::shard`]; `ringmesh merge` makes the table and the plot).
pub fn front(
    scene_path: &Path,
    solvers: &[SolverKind],
    points: usize,
    rms: RmsAxis,
    output_dir: Option<&Path>,
    shard: Option<Shard>,
    progress: &dyn Progress,
) -> Result<FrontOutcome, Error> {
    let scene = read_scene(scene_path)?;
    let dir = output_dir.map_or_else(|| default_output_dir(&scene), Path::to_path_buf);
    // A shard writes one file under the folder's lock once computed; the
    // whole front takes the folder before computing.
    check_scene(
        &scene,
        SceneCommand::Optimize,
        rayon::current_num_threads() as u64,
    )?;
    // Each point's job, result and row: a few hundred bytes.
    let rows = (points as u64).saturating_mul(solvers.len().max(1) as u64);
    check_memory(
        &format!("--points {points}"),
        &format!("{rows} points' jobs, results and rows"),
        rows.saturating_mul(BYTES_PER_POINT),
    )?;
    let set = match shard {
        Some(_) => None,
        None => Some(OutputSet::begin(&dir, &FILES)?),
    };
    let (problem, rms) = front_problem(&scene, rms)?;
    let jobs = front_jobs(&problem, solvers, points);
    // A shard takes whole warm-start chains (the chains c with c mod N = I),
    // so each of its points starts from the neighbour it has unsharded.
    let chains = front_chains(&jobs);
    let units: Vec<usize> = chains.iter().map(ExactSizeIterator::len).collect();
    let indices = shard
        .unwrap_or(Shard::WHOLE)
        .points_in_units(jobs.len(), &units);
    let mine: Vec<&[(SolverKind, f64)]> = shard
        .unwrap_or(Shard::WHOLE)
        .points(chains.len())
        .into_iter()
        .map(|c| &jobs[chains[c].clone()])
        .collect();
    progress.start(indices.len());
    let front = design_front_chains(&problem, &mine, &|p: &FrontPoint| {
        let outcome = match &p.outcome {
            Ok(_) => format!(
                "Tmax/Tmin {}, RMS {} mm",
                readable(p.ratio, 7),
                readable(p.rms_mm, 4)
            ),
            Err(e) => format!("failed: {e}"),
        };
        progress.step(&format!(
            "{} {}: {outcome}",
            study::value_name(&p.solver),
            p.solver.knob_text(&readable(p.knob, 3))
        ));
    });
    let Some(set) = set else {
        let shard = shard.unwrap_or(Shard::WHOLE);
        let settings = serde_json::json!({
            "solvers": solvers.iter().map(study::value_name).collect::<Vec<_>>(),
            "points": points,
        });
        let rows: Vec<(usize, String)> = indices
            .iter()
            .zip(&front)
            .filter_map(|(&k, p)| FrontRow::of(p).map(|r| (k, front_row(&r))))
            .collect();
        let path = write_shard(
            &dir,
            "front",
            "front",
            &scene,
            shard,
            (jobs.len(), units),
            settings,
            FRONT_COLUMNS,
            &rows,
        )?;
        return Ok(FrontOutcome {
            points: front,
            rms,
            written: vec![path],
        });
    };
    let rows: Vec<FrontRow> = front.iter().filter_map(FrontRow::of).collect();
    let failed: Vec<(String, f64)> = front
        .iter()
        .filter(|p| p.outcome.is_err())
        .map(|p| (study::value_name(&p.solver), p.knob))
        .collect();
    let paths = write_front(
        set,
        &scene.name,
        &rows,
        Some(&failed),
        &rms,
        &front_csv(&rows),
    )?;
    Ok(FrontOutcome {
        points: front,
        rms,
        written: paths,
    })
}

/// The design front of `scene` in memory, without files: each of `solvers`'
/// knob swept over `points` values (as [`front`] sweeps them), and the
/// surface RMS `rms` chooses to draw them at; `on_point` sees each point as
/// it finishes (from the solving threads). What a library user (the Python
/// bindings) calls.
///
/// # Errors
/// A scene whose problem cannot be stated, a workload beyond the memory
/// limit; a point that fails is a point with its error.
pub fn front_points(
    scene: &Scene,
    solvers: &[SolverKind],
    points: usize,
    rms: RmsAxis,
    on_point: &(dyn Fn(&FrontPoint) + Sync),
) -> Result<(Vec<FrontPoint>, FrontRms), Error> {
    let scene = crate::surface::resolve_front_rings(scene)?;
    check_scene(
        &scene,
        SceneCommand::Optimize,
        rayon::current_num_threads() as u64,
    )?;
    let (problem, rms) = front_problem(&scene, rms)?;
    Ok((design_front(&problem, solvers, points, on_point), rms))
}

/// The problem a front of `scene` solves, and the RMS `rms` chooses to draw
/// its points at.
fn front_problem(scene: &Scene, rms: RmsAxis) -> Result<(UniformityProblem, FrontRms), Error> {
    let (mesh, problem) = scene_problem(scene)?;
    let rms = match rms {
        RmsAxis::Design => FrontRms::Design,
        RmsAxis::Total => FrontRms::Total {
            facets_mm: design_surface_facet_rms_mm(&mesh)?,
        },
    };
    // The front's solves need the problem alone.
    drop(mesh);
    Ok((problem, rms))
}

/// Memory of one point of a front beside the solves: its job, its result,
/// its row of text.
const BYTES_PER_POINT: u64 = 512;

/// The files of a whole front.
pub(crate) const FILES: [&str; 5] = [
    "front.csv",
    "front.png",
    "front.svg",
    "front-time.png",
    "front-time.svg",
];

/// `front.csv` (the table `csv`), `front.png`, `front.svg`, `front-time.png`, `front-time.svg` (drawn from `rows`
/// against `rms`, the `failed` points — solver, knob — listed when known),
/// written into `set` (begun with [`FILES`]) and swapped in.
pub(crate) fn write_front(
    set: OutputSet,
    scene: &str,
    rows: &[FrontRow],
    failed: Option<&[(String, f64)]>,
    rms: &FrontRms,
    csv: &str,
) -> Result<Vec<PathBuf>, Error> {
    let title = format!("{scene}: tension uniformity against surface accuracy");
    front_plot(
        rows,
        failed,
        (rms, FrontY::Ratio),
        &title,
        &set.path("front.png"),
        &set.path("front.svg"),
    )?;
    // The strategies' cost: every solver's accuracy against its time.
    let title = format!("{scene}: what each solver's surface accuracy costs in time");
    front_plot(
        rows,
        failed,
        (rms, FrontY::Time),
        &title,
        &set.path("front-time.png"),
        &set.path("front-time.svg"),
    )?;
    write_atomic(&set.path("front.csv"), csv.as_bytes())?;
    set.seal()?;
    Ok(set.commit()?)
}
