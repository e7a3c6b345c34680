//! `ringmesh front`: the design front of a scene, each solver's accuracy knob
//! swept, as a table and plots (or one shard's points).

use std::path::{Path, PathBuf};

use super::{default_output_dir, write_shard, Progress};
use crate::design::scene_problem;
use crate::report::{front_csv, front_plot, front_row, write_atomic, FrontRow, FRONT_COLUMNS};
use crate::scene::Scene;
use crate::shard::Shard;
use crate::study;
use crate::uniformity::{design_front_points, front_jobs, FrontPoint, SolverKind};
use crate::Error;

/// `ringmesh front`: the design front of a scene (each solver's knob swept in
/// parallel), written as `front.csv`, `front.png` and `front.svg`; with a
/// `shard`, only that shard's points, written as `front.shard-I-of-N.csv`
/// (see [`crate::shard`]; `ringmesh merge` makes the table and the plot).
pub fn front(
    scene_path: &Path,
    solvers: &[SolverKind],
    points: usize,
    output_dir: Option<&Path>,
    shard: Option<Shard>,
    progress: &dyn Progress,
) -> Result<(Vec<FrontPoint>, Vec<PathBuf>), Error> {
    let scene = Scene::read(scene_path)?;
    let (_, problem) = scene_problem(&scene)?;
    let jobs = front_jobs(&problem, solvers, points);
    let indices = shard.unwrap_or(Shard::WHOLE).points(jobs.len());
    let mine: Vec<(SolverKind, f64)> = indices.iter().map(|&k| jobs[k]).collect();
    progress.start(mine.len());
    let front = design_front_points(&problem, &mine, &|p: &FrontPoint| {
        let outcome = match &p.outcome {
            Ok(_) => format!("ratio {:.6}, RMS {:.3e} mm", p.ratio, p.rms_mm),
            Err(e) => format!("failed: {e}"),
        };
        progress.step(&format!(
            "{} knob {:.3e}: {outcome}",
            study::value_name(&p.solver),
            p.knob
        ));
    });
    let dir = output_dir.map_or_else(|| default_output_dir(&scene), Path::to_path_buf);
    if let Some(shard) = shard {
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
            jobs.len(),
            settings,
            FRONT_COLUMNS,
            &rows,
        )?;
        return Ok((front, vec![path]));
    }
    let rows: Vec<FrontRow> = front.iter().filter_map(FrontRow::of).collect();
    let failed: Vec<(String, f64)> = front
        .iter()
        .filter(|p| p.outcome.is_err())
        .map(|p| (study::value_name(&p.solver), p.knob))
        .collect();
    let paths = write_front(&dir, &scene.name, &rows, Some(&failed), &front_csv(&rows))?;
    Ok((front, paths))
}

/// `front.csv` (the table `csv`), `front.png`, `front.svg` (drawn from `rows`,
/// the `failed` points — solver, knob — listed when known).
pub(crate) fn write_front(
    dir: &Path,
    scene: &str,
    rows: &[FrontRow],
    failed: Option<&[(String, f64)]>,
    csv: &str,
) -> Result<Vec<PathBuf>, Error> {
    let paths = [
        dir.join("front.csv"),
        dir.join("front.png"),
        dir.join("front.svg"),
    ];
    let title = format!("{scene}: tension uniformity against surface accuracy");
    front_plot(rows, failed, &title, &paths[1], &paths[2])?;
    write_atomic(&paths[0], csv.as_bytes())?;
    Ok(paths.to_vec())
}
