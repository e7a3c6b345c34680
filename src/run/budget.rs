//! `ringmesh budget`: the error budget of a scene as built on the flexible
//! truss — facets, design, thermal cases, manufacturing tolerances (Monte
//! Carlo and linearised), their root-sum-square and the gain loss — as
//! `budget.csv`, `budget.json`, `budget-samples.csv` (every point) and a
//! plot; or one shard's points, for `ringmesh merge`.

use std::path::{Path, PathBuf};

use super::{default_output_dir, read_scene, write_shard, Progress, Summary};
use crate::budget::{
    self, BudgetDesign, BudgetRow, BudgetSettings, BudgetTable, BudgetTimings, PointKind,
    POINT_COLUMNS,
};
use crate::design::DesignSettings;
use crate::report::{budget_plot, readable, write_atomic, write_json, OutputSet};
use crate::shard::Shard;
use crate::Error;

/// The files of a whole budget.
pub(crate) const FILES: [&str; 5] = [
    "budget.csv",
    "budget.json",
    "budget-samples.csv",
    "budget.png",
    "budget.svg",
];

/// Slack cables a printout names per thermal case (the files name all).
const PRINTED_SLACK: usize = 20;

/// The stem of the points' table and its shards.
pub(crate) const STEM: &str = "budget-samples";

/// What `ringmesh budget` made.
#[derive(Debug)]
pub struct BudgetOutcome {
    /// Samples and seed.
    pub settings: BudgetSettings,
    /// The rows measured (a shard's only, when sharded), in sweep order.
    pub rows: Vec<BudgetRow>,
    /// The table (none for a shard).
    pub table: Option<BudgetTable>,
    /// Where the time went.
    pub timings: BudgetTimings,
    /// Files written.
    pub written: Vec<PathBuf>,
}

impl BudgetOutcome {
    /// What `ringmesh budget` prints: the table's terms (or the shard's
    /// rows), slack cables by case, failed samples, timings, files.
    pub fn summary(&self) -> Summary {
        let mut s = Summary::default();
        match &self.table {
            Some(table) => table_lines(&mut s, table),
            None => say!(s, "{} points measured", self.rows.len()),
        }
        let t = &self.timings;
        let mut times = format!(
            "design {} s, assembly {} s, tangent {} s",
            readable(t.design_s, 3),
            readable(t.assembly_s, 3),
            readable(t.linearise_s, 3)
        );
        if let Some(c) = t.thermal_case_s {
            times += &format!(", per thermal case {} s", readable(c, 3));
        }
        if let Some(c) = t.sample_s {
            times += &format!(", per sample {} s (parallel)", readable(c, 3));
        }
        if let Some(c) = t.linear_point_s {
            times += &format!(", per linearised point {} s", readable(c, 3));
        }
        say!(s, "time: {times}");
        s.written(&self.written);
        s
    }
}

fn table_lines(s: &mut Summary, table: &BudgetTable) {
    for t in &table.terms {
        let linear = match (t.linear_raw_mm, t.linear_best_fit_mm) {
            (Some(r), Some(b)) => {
                format!("; linearised {} / {} mm", readable(r, 4), readable(b, 4))
            }
            _ => String::new(),
        };
        let gain = t.gain_loss_db.map_or(String::new(), |g| {
            format!(", gain loss {} dB", readable(g, 3))
        });
        say!(
            s,
            "{}: RMS raw {} mm, best fit {} mm{gain}{linear}",
            t.term,
            readable(t.raw_mm, 4),
            readable(t.best_fit_mm, 4)
        );
    }
    for (case, slack) in &table.thermal_slack_cables {
        if !slack.is_empty() {
            let list: Vec<String> = slack
                .iter()
                .take(PRINTED_SLACK)
                .map(|k| k.to_string())
                .collect();
            let more = match slack.len() > PRINTED_SLACK {
                true => " … (all in budget.json and budget-samples.csv)",
                false => "",
            };
            say!(
                s,
                "thermal case {case}: {} cables slack: {}{more}",
                slack.len(),
                list.join(" ")
            );
        }
    }
    if let Some(w) = &table.worst_thermal_case {
        say!(s, "the total counts the worst thermal case, {w}");
    }
    if table.samples > 0 {
        say!(
            s,
            "tolerances: {} Monte Carlo samples (sampling error of the mean square ≈ √(2/n) = \
             {} of it); linearised: the same draws through the design's tangent",
            table.samples,
            readable((2.0 / table.samples as f64).sqrt(), 2)
        );
    }
    for f in &table.failed_cases {
        say!(s, "thermal case failed (left out of the total): {f}");
    }
    for f in &table.failed_samples {
        say!(s, "failed: {f}");
    }
}

/// `ringmesh budget`: the budget of `design` of the scene at `scene_path`
/// with `samples` and `seed` (the scene's `[tolerances]` when not given),
/// written into `output_dir` (default `runs/<scene>/`, the conventional
/// design's `runs/<scene>/conventional/`); with `shard`, only that shard's
/// points as `budget-samples.shard-I-of-N.csv`.
pub fn budget(
    scene_path: &Path,
    (samples, seed): (Option<usize>, Option<u64>),
    design: BudgetDesign,
    output_dir: Option<&Path>,
    shard: Option<Shard>,
    progress: &dyn Progress,
) -> Result<BudgetOutcome, Error> {
    let scene = read_scene(scene_path)?;
    let dir = output_dir.map_or_else(
        || match design {
            BudgetDesign::Flexible => default_output_dir(&scene),
            BudgetDesign::Conventional => default_output_dir(&scene).join("conventional"),
        },
        Path::to_path_buf,
    );
    let settings = BudgetSettings {
        design,
        ..BudgetSettings::of(&scene, samples, seed)
    };
    let set = match shard {
        Some(_) => None,
        None => Some(OutputSet::begin(&dir, &FILES)?),
    };
    let whole = shard.unwrap_or(Shard::WHOLE);
    progress.start(whole.points(budget::point_count(&scene, &settings)).len());
    let run = budget::run(
        &scene,
        &DesignSettings::default(),
        &settings,
        whole,
        &|row: &BudgetRow| {
            let what = match &row.nonlinear {
                Ok(m) => format!("best fit {} mm", readable(m.best_fit_mm, 3)),
                Err(e) => format!("failed: {e}"),
            };
            progress.step(&format!("{}: {what}", row.name));
        },
    )?;
    let settings_json = serde_json::json!({
        "samples": settings.samples,
        "seed": settings.seed,
        "design": settings.design.name(),
    });
    let lines: Vec<(usize, String)> = run.rows.iter().map(|(k, r)| (*k, r.csv())).collect();
    let rows: Vec<BudgetRow> = run.rows.into_iter().map(|(_, r)| r).collect();
    let Some(set) = set else {
        let path = write_shard(
            &dir,
            STEM,
            "budget",
            &scene,
            whole,
            (run.points, Vec::new()),
            settings_json,
            POINT_COLUMNS,
            &lines,
        )?;
        return Ok(BudgetOutcome {
            settings,
            rows,
            table: None,
            timings: run.timings,
            written: vec![path],
        });
    };
    let mut csv = format!("{POINT_COLUMNS}\n");
    for (_, line) in &lines {
        csv.push_str(line);
        csv.push('\n');
    }
    let (table, written) = write_budget(
        set,
        &scene.name,
        &settings_json,
        scene.surface.frequency_ghz,
        &csv,
    )?;
    Ok(BudgetOutcome {
        settings,
        rows,
        table: Some(table),
        timings: run.timings,
        written,
    })
}

/// The budget's files from `csv`, the points' table (what the unsharded
/// run and `merge` both have): the rows read back, the table computed
/// from them, everything written into `set` (begun with [`FILES`]) and
/// swapped in.
pub(crate) fn write_budget(
    set: OutputSet,
    scene: &str,
    settings: &serde_json::Value,
    frequency_ghz: Option<f64>,
    csv: &str,
) -> Result<(BudgetTable, Vec<PathBuf>), Error> {
    let rows = csv
        .lines()
        .skip(1)
        .map(BudgetRow::parse)
        .collect::<Result<Vec<_>, _>>()?;
    let table = BudgetTable::of(&rows, frequency_ghz);
    let samples: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.kind == PointKind::Sample)
        .filter_map(|r| {
            let n = r.nonlinear.as_ref().ok()?.best_fit_mm;
            let l = r
                .linear
                .as_ref()
                .and_then(|l| l.as_ref().ok())
                .map_or(f64::NAN, |l| l.best_fit_mm);
            Some((n, l))
        })
        .collect();
    let design = settings["design"].as_str().unwrap_or("flexible");
    budget_plot(
        &table,
        &samples,
        &format!("{scene}: error budget of the {design} design as built on the flexible truss"),
        &set.path("budget.png"),
        &set.path("budget.svg"),
    )?;
    write_atomic(&set.path("budget.csv"), table.csv().as_bytes())?;
    write_atomic(&set.path("budget-samples.csv"), csv.as_bytes())?;
    write_json(
        &set.path("budget.json"),
        &serde_json::json!({
            "scene": scene,
            "settings": settings,
            "table": table,
        }),
    )?;
    set.seal()?;
    Ok((table, set.commit()?))
}
