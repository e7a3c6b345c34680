//! `ringmesh merge`: shards of `front`, `study` and `budget` joined into the
//! tables and plots of the unsharded runs.

use std::path::{Path, PathBuf};

use super::budget::{self, write_budget};
use super::front::{self, write_front};
use super::study::{self, write_study};
use super::Summary;
use crate::report::OutputSet;
use crate::report::{parse_front_row, parse_study_row, FrontRms, FrontRow, StudyRms};
use crate::shard::{self, ShardError};
use crate::study::StudyRow;
use crate::Error;

/// What `ringmesh merge` made: one table per sweep joined.
#[derive(Debug)]
pub struct MergeOutcome {
    /// The sweeps joined, in the order their shards were found.
    pub tables: Vec<MergedTable>,
}

impl MergeOutcome {
    /// What `ringmesh merge` prints: for each sweep, its command, scene,
    /// shards and rows, and the files written.
    pub fn summary(&self) -> Summary {
        let mut s = Summary::default();
        for m in &self.tables {
            say!(
                s,
                "{} of {}: {} shards, {} rows",
                m.command,
                m.scene,
                m.shards,
                m.rows
            );
            s.written(&m.written);
        }
        s
    }
}

/// One sweep joined by `ringmesh merge`.
#[derive(Debug)]
pub struct MergedTable {
    /// The command whose shards were joined (`front`, `study`).
    pub command: String,
    /// The scene's name.
    pub scene: String,
    /// Shards joined.
    pub shards: usize,
    /// Rows of the merged table.
    pub rows: usize,
    /// Files written.
    pub written: Vec<PathBuf>,
}

/// `ringmesh merge`: joins the shard CSVs among `paths` (files, or folders
/// holding `*.shard-I-of-N.csv`) into each sweep's table and plots, exactly
/// as the unsharded run writes them, in `output_dir` (default
/// `runs/<scene>/`). Shards of different scenes or settings, duplicate or
/// missing shards are refused before anything is written.
pub fn merge(paths: &[PathBuf], output_dir: Option<&Path>) -> Result<MergeOutcome, Error> {
    let files = shard::find_shards(paths)?
        .iter()
        .map(|p| shard::read_shard(p))
        .collect::<Result<Vec<_>, _>>()?;
    let merged = shard::merge(files)?;
    // Parse every table before writing any.
    enum Table {
        Front(Vec<FrontRow>),
        Study(Vec<StudyRow>),
        /// The budget's table is computed from the merged text.
        Budget,
    }
    let mut tables = Vec::new();
    for m in &merged {
        // A bad row is its own shard's fault.
        let bad = |row: usize, reason: String| ShardError::Format {
            path: m.files[m.origins.get(row).copied().unwrap_or(0)].clone(),
            reason,
        };
        let table = match m.header.command.as_str() {
            "front" => Table::Front(
                m.rows
                    .iter()
                    .enumerate()
                    .map(|(r, l)| parse_front_row(l).map_err(|e| bad(r, e.to_string())))
                    .collect::<Result<_, _>>()?,
            ),
            "study" => Table::Study(
                m.rows
                    .iter()
                    .enumerate()
                    .map(|(r, l)| parse_study_row(l).map_err(|e| bad(r, e.to_string())))
                    .collect::<Result<_, _>>()?,
            ),
            "budget" => {
                for (r, l) in m.rows.iter().enumerate() {
                    crate::budget::BudgetRow::parse(l).map_err(|e| bad(r, e.to_string()))?;
                }
                Table::Budget
            }
            other => return Err(bad(0, format!("unknown command `{other}`")).into()),
        };
        tables.push(table);
    }
    let mut outcomes = Vec::new();
    for (m, table) in merged.iter().zip(tables) {
        let dir = output_dir.map_or_else(
            || super::default_dir_named(&m.header.scene),
            Path::to_path_buf,
        );
        // The plots are drawn from the parsed rows; the table is the shards' text.
        let written = match table {
            Table::Front(rows) => {
                let set = OutputSet::begin(&dir, &front::FILES)?;
                write_front(
                    set,
                    &m.header.scene,
                    &rows,
                    None,
                    &FrontRms::Design,
                    &m.csv(),
                )?
            }
            Table::Study(rows) => {
                let set = OutputSet::begin(&dir, &study::FILES)?;
                write_study(set, &m.header.scene, &rows, &StudyRms::Design, &m.csv())?
            }
            Table::Budget => {
                let set = OutputSet::begin(&dir, &budget::FILES)?;
                let frequency_ghz = m.header.scene_file["surface"]["frequency_ghz"].as_f64();
                write_budget(
                    set,
                    &m.header.scene,
                    &m.header.settings,
                    frequency_ghz,
                    &m.csv(),
                )?
                .1
            }
        };
        outcomes.push(MergedTable {
            command: m.header.command.clone(),
            scene: m.header.scene.clone(),
            shards: m.files.len(),
            rows: m.rows.len(),
            written,
        });
    }
    Ok(MergeOutcome { tables: outcomes })
}
