//! Sweeps split across machines: `--shard I/N` runs every N-th unit of a
//! sweep starting at I, and `ringmesh merge` joins the shards' CSVs into the
//! table the unsharded run writes.
//!
//! Shards are numbered from 0, as a Slurm job array's `$SLURM_ARRAY_TASK_ID`
//! with `--array=0-(N-1)`: shard `I/N` runs the units `u` with `u mod N = I`,
//! in the sweep's deterministic order. A unit is one point, or a run of
//! consecutive points that must be computed together to come out as they do
//! unsharded — a warm-start chain, each point starting from its neighbour.
//!
//! A shard's CSV (`<table>.shard-I-of-N.csv`) is the sweep's CSV with two
//! additions: a first line `# ringmesh shard {…}` whose JSON names the
//! command, the scene (its whole resolved file), the sweep's settings, the
//! shard and the number of points; and a leading `point` column, the row's
//! index in the whole sweep. [`merge`] refuses shards whose command, scene,
//! settings, shard count or point count differ, duplicate or missing shards,
//! and rows outside their shard; it returns the rows in sweep order without
//! the `point` column — byte for byte the unsharded table's rows.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use serde::{Deserialize, Serialize};
use serde_json::Value;

/// The first characters of a shard CSV.
pub const SHARD_MARK: &str = "# ringmesh shard ";

/// One shard of a sweep: index `I` (from 0) of `N`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// This shard, `0 ≤ index < count`.
    pub index: usize,
    /// Shards in all, at least 1.
    pub count: usize,
}

impl Shard {
    /// The whole sweep as one shard.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// A shard, checked.
    ///
    /// # Errors
    /// `count = 0` or `index ≥ count`.
    pub fn new(index: usize, count: usize) -> Result<Shard, ShardError> {
        if count == 0 {
            return Err(ShardError::Spec {
                given: format!("{index}/{count}"),
                reason: "the shard count must be at least 1".into(),
            });
        }
        if index >= count {
            return Err(ShardError::Spec {
                given: format!("{index}/{count}"),
                reason: format!(
                    "shards are numbered from 0 to {} (as $SLURM_ARRAY_TASK_ID with \
                     --array=0-{})",
                    count - 1,
                    count - 1
                ),
            });
        }
        Ok(Shard { index, count })
    }

    /// True when point `k` of the sweep belongs to this shard.
    pub fn includes(&self, k: usize) -> bool {
        k % self.count == self.index
    }

    /// The points of a sweep of `total` points that this shard runs, in order.
    pub fn points(&self, total: usize) -> Vec<usize> {
        (self.index..total).step_by(self.count).collect()
    }

    /// The points this shard runs, in order, when the sweep's points are
    /// dealt in `units`: the lengths of consecutive runs of points kept
    /// together (empty: every point is a unit of its own, as in
    /// [`Shard::points`]).
    pub fn points_in_units(&self, total: usize, units: &[usize]) -> Vec<usize> {
        if units.is_empty() {
            return self.points(total);
        }
        let mut start = 0;
        let mut points = Vec::new();
        for (u, &len) in units.iter().enumerate() {
            if self.includes(u) {
                points.extend(start..start + len);
            }
            start += len;
        }
        points
    }

    /// The shard's file name for a table `stem` (`front`, `accuracy-vs-time`):
    /// `<stem>.shard-I-of-N.csv`.
    pub fn file_name(&self, stem: &str) -> String {
        format!("{stem}.shard-{}-of-{}.csv", self.index, self.count)
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = ShardError;

    /// Parses `I/N`.
    fn from_str(s: &str) -> Result<Shard, ShardError> {
        let (i, n) = s.split_once('/').ok_or_else(|| ShardError::Spec {
            given: s.to_string(),
            reason: "expected I/N, e.g. 0/4".into(),
        })?;
        let number = |v: &str| {
            v.trim().parse::<usize>().map_err(|_| ShardError::Spec {
                given: s.to_string(),
                reason: "expected I/N with whole numbers".into(),
            })
        };
        Shard::new(number(i)?, number(n)?)
    }
}

/// What a shard says about itself (the JSON of its first line).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShardHeader {
    /// The command that made it (`front`, `study`).
    pub command: String,
    /// The scene's name.
    pub scene: String,
    /// This shard.
    pub shard: Shard,
    /// Points of the whole sweep.
    pub points: usize,
    /// The sweep's settings, resolved.
    pub settings: Value,
    /// The whole resolved scene.
    pub scene_file: Value,
    /// How the points are dealt to shards (see [`Shard::points_in_units`]):
    /// lengths of consecutive runs of points; empty, one unit a point.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub units: Vec<usize>,
}

impl ShardHeader {
    /// The unit of point `k` (`None` past the sweep's end).
    fn unit_of(&self, k: usize) -> Option<usize> {
        if self.units.is_empty() {
            return (k < self.points).then_some(k);
        }
        let mut end = 0;
        self.units.iter().position(|&len| {
            end += len;
            k < end
        })
    }
}

/// A shard CSV read back.
#[derive(Debug, Clone)]
pub struct ShardFile {
    /// Where it was read.
    pub path: PathBuf,
    /// Its header.
    pub header: ShardHeader,
    /// The table's column line (without `point`).
    pub columns: String,
    /// `(point, row)`, the row without `point` and without its newline.
    pub rows: Vec<(usize, String)>,
}

/// Shards joined.
#[derive(Debug, Clone)]
pub struct Merged {
    /// The common header (its `shard` is the first shard's).
    pub header: ShardHeader,
    /// The table's column line.
    pub columns: String,
    /// The rows in sweep order.
    pub rows: Vec<String>,
    /// The files merged, by shard index.
    pub files: Vec<PathBuf>,
    /// Which of `files` each row came from.
    pub origins: Vec<usize>,
}

impl Merged {
    /// The merged table: the column line and the rows, as the unsharded run
    /// writes it.
    pub fn csv(&self) -> String {
        let mut s = String::with_capacity(
            self.columns.len() + 1 + self.rows.iter().map(|r| r.len() + 1).sum::<usize>(),
        );
        s.push_str(&self.columns);
        s.push('\n');
        for row in &self.rows {
            s.push_str(row);
            s.push('\n');
        }
        s
    }
}

/// A bad shard specification, or shards that cannot be merged.
#[derive(Debug, thiserror::Error)]
pub enum ShardError {
    /// A bad `--shard I/N`.
    #[error("--shard {given:?}: {reason}")]
    Spec {
        /// The specification as given.
        given: String,
        /// What is wrong with it.
        reason: String,
    },
    /// Reading a file or folder failed.
    #[error("reading {path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A file that is not a shard CSV.
    #[error("{path}: not a ringmesh shard: {reason}")]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// No shard CSV among the paths given.
    #[error("no shard files (*.shard-I-of-N.csv) in {}", list(.searched))]
    NoShards {
        /// The files and folders searched.
        searched: Vec<PathBuf>,
    },
    /// Two shards of different sweeps.
    #[error("{first} and {other} are shards of different sweeps: their {what} differ{detail}")]
    Mismatch {
        /// A shard of the sweep.
        first: PathBuf,
        /// A shard that does not belong to it.
        other: PathBuf,
        /// What differs (`scene`, `settings`, …).
        what: String,
        /// The differing values, when short.
        detail: String,
    },
    /// The same shard twice.
    #[error("shard {shard} of `{command}` given twice: {first} and {other}")]
    Duplicate {
        /// The command.
        command: String,
        /// The shard.
        shard: Shard,
        /// One file.
        first: PathBuf,
        /// The other.
        other: PathBuf,
    },
    /// Shards missing from the sweep.
    #[error("`{command}` sweep incomplete: shards {missing:?} of {count} are missing")]
    Missing {
        /// The command.
        command: String,
        /// The missing shard indices.
        missing: Vec<usize>,
        /// Shards in all.
        count: usize,
    },
}

impl ShardError {
    /// True when the user's input is at fault (every case but I/O).
    pub fn is_bad_input(&self) -> bool {
        !matches!(self, ShardError::Io { .. })
    }
}

/// A shard's CSV: the header line, then `point,` + each row under `columns`.
/// Rows must not contain newlines.
pub fn shard_csv(header: &ShardHeader, columns: &str, rows: &[(usize, String)]) -> String {
    let json = serde_json::to_string(header).expect("a shard header serialises");
    let mut s = format!("{SHARD_MARK}{json}\npoint,{columns}\n");
    for (k, row) in rows {
        debug_assert!(!row.contains('\n'), "a CSV row spans lines");
        s.push_str(&format!("{k},{row}\n"));
    }
    s
}

/// Reads a shard CSV.
///
/// # Errors
/// I/O, or a file without the shard header, the `point` column or valid
/// point indices.
pub fn read_shard(path: &Path) -> Result<ShardFile, ShardError> {
    let text = crate::input::read_input(path).map_err(|source| {
        if source.kind() == std::io::ErrorKind::InvalidData {
            // Read, but not text (or too large): the file's fault, not the
            // machine's.
            ShardError::Format {
                path: path.to_path_buf(),
                reason: source.to_string(),
            }
        } else {
            ShardError::Io {
                path: path.to_path_buf(),
                source,
            }
        }
    })?;
    let format = |reason: String| ShardError::Format {
        path: path.to_path_buf(),
        reason,
    };
    let mut lines = text.lines();
    let first = lines.next().unwrap_or_default();
    let json = first
        .strip_prefix(SHARD_MARK)
        .ok_or_else(|| format(format!("its first line does not start with {SHARD_MARK:?}")))?;
    let header: ShardHeader =
        serde_json::from_str(json).map_err(|e| format(format!("its header: {e}")))?;
    let dealt: usize = header.units.iter().sum();
    if !header.units.is_empty() && (dealt != header.points || header.units.contains(&0)) {
        return Err(format(format!(
            "its units {:?} do not deal out its {} points",
            header.units, header.points
        )));
    }
    let columns = lines
        .next()
        .and_then(|l| l.strip_prefix("point,"))
        .ok_or_else(|| format("its second line is not a `point,…` column line".into()))?
        .to_string();
    let mut rows = Vec::new();
    for (n, line) in lines.enumerate() {
        let (k, row) = line
            .split_once(',')
            .and_then(|(k, row)| Some((k.parse::<usize>().ok()?, row)))
            .ok_or_else(|| format(format!("row {} has no point index", n + 1)))?;
        if !header.unit_of(k).is_some_and(|u| header.shard.includes(u)) {
            return Err(format(format!(
                "row {} is point {k}, which is not in shard {} of a {}-point sweep",
                n + 1,
                header.shard,
                header.points
            )));
        }
        rows.push((k, row.to_string()));
    }
    Ok(ShardFile {
        path: path.to_path_buf(),
        header,
        columns,
        rows,
    })
}

/// The shard CSVs among `paths`: files as given, folders searched (not
/// recursively) for `*.shard-I-of-N.csv`, sorted by name.
///
/// # Errors
/// An unreadable folder, or no shard file at all.
pub fn find_shards(paths: &[PathBuf]) -> Result<Vec<PathBuf>, ShardError> {
    let mut found = Vec::new();
    for path in paths {
        if path.is_dir() {
            let io = |source| ShardError::Io {
                path: path.clone(),
                source,
            };
            let mut in_dir: Vec<PathBuf> = std::fs::read_dir(path)
                .map_err(io)?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.is_file() && is_shard_name(p))
                .collect();
            in_dir.sort();
            found.extend(in_dir);
        } else if path.exists() {
            found.push(path.clone());
        } else {
            return Err(ShardError::Format {
                path: path.clone(),
                reason: "no such file or folder".to_string(),
            });
        }
    }
    if found.is_empty() {
        return Err(ShardError::NoShards {
            searched: paths.to_vec(),
        });
    }
    Ok(found)
}

/// Paths joined by ", ", for messages.
fn list(paths: &[PathBuf]) -> String {
    let shown: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    shown.join(", ")
}

/// `<stem>.shard-I-of-N.csv`.
fn is_shard_name(path: &Path) -> bool {
    let Some(name) = path.file_name().and_then(|n| n.to_str()) else {
        return false;
    };
    let Some(rest) = name.strip_suffix(".csv") else {
        return false;
    };
    let Some((_, spec)) = rest.rsplit_once(".shard-") else {
        return false;
    };
    spec.split_once("-of-")
        .is_some_and(|(i, n)| i.parse::<usize>().is_ok() && n.parse::<usize>().is_ok())
}

/// Joins the shards of one or more sweeps: files are grouped by command, and
/// each group must be exactly the shards `0..N` of one sweep.
///
/// # Errors
/// Shards of different scenes, settings, shard or point counts, or column
/// lines; a shard given twice; a shard missing.
pub fn merge(files: Vec<ShardFile>) -> Result<Vec<Merged>, ShardError> {
    let mut by_command: BTreeMap<String, Vec<ShardFile>> = BTreeMap::new();
    for file in files {
        by_command
            .entry(file.header.command.clone())
            .or_default()
            .push(file);
    }
    by_command.into_values().map(merge_one).collect()
}

/// Joins the shards of one command.
fn merge_one(mut files: Vec<ShardFile>) -> Result<Merged, ShardError> {
    files.sort_by_key(|f| f.header.shard.index);
    let first = &files[0];
    for other in &files[1..] {
        let (a, b) = (&first.header, &other.header);
        let mismatch = |what: &str, detail: String| ShardError::Mismatch {
            first: first.path.clone(),
            other: other.path.clone(),
            what: what.to_string(),
            detail,
        };
        if a.scene_file != b.scene_file {
            let detail = if a.scene != b.scene {
                format!(" (`{}` and `{}`)", a.scene, b.scene)
            } else {
                format!(" (both named `{}`, with different values)", a.scene)
            };
            return Err(mismatch("scenes", detail));
        }
        if a.settings != b.settings {
            return Err(mismatch(
                "settings",
                format!(" ({} and {})", a.settings, b.settings),
            ));
        }
        if a.shard.count != b.shard.count {
            return Err(mismatch(
                "shard counts",
                format!(" ({} and {})", a.shard.count, b.shard.count),
            ));
        }
        if a.points != b.points {
            return Err(mismatch(
                "point counts",
                format!(" ({} and {})", a.points, b.points),
            ));
        }
        if a.units != b.units {
            return Err(mismatch(
                "units",
                format!(" ({:?} and {:?})", a.units, b.units),
            ));
        }
        if first.columns != other.columns {
            return Err(mismatch("columns", String::new()));
        }
    }
    for pair in files.windows(2) {
        if pair[0].header.shard == pair[1].header.shard {
            return Err(ShardError::Duplicate {
                command: pair[0].header.command.clone(),
                shard: pair[0].header.shard,
                first: pair[0].path.clone(),
                other: pair[1].path.clone(),
            });
        }
    }
    let count = first.header.shard.count;
    let present: Vec<usize> = files.iter().map(|f| f.header.shard.index).collect();
    let missing: Vec<usize> = (0..count).filter(|i| !present.contains(i)).collect();
    if !missing.is_empty() {
        return Err(ShardError::Missing {
            command: first.header.command.clone(),
            missing,
            count,
        });
    }
    let header = first.header.clone();
    let columns = first.columns.clone();
    let paths = files.iter().map(|f| f.path.clone()).collect();
    let mut rows: Vec<(usize, usize, String)> = files
        .into_iter()
        .enumerate()
        .flat_map(|(f, file)| file.rows.into_iter().map(move |(k, row)| (k, f, row)))
        .collect();
    rows.sort_by_key(|r| r.0);
    if let Some(pair) = rows.windows(2).find(|p| p[0].0 == p[1].0) {
        let paths: &Vec<PathBuf> = &paths;
        return Err(ShardError::Format {
            path: paths[pair[1].1].clone(),
            reason: format!(
                "point {} appears twice (also in {})",
                pair[0].0,
                paths[pair[0].1].display()
            ),
        });
    }
    Ok(Merged {
        header,
        columns,
        origins: rows.iter().map(|r| r.1).collect(),
        rows: rows.into_iter().map(|r| r.2).collect(),
        files: paths,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shard_spec_is_zero_based_and_checked() {
        assert_eq!(
            "2/3".parse::<Shard>().unwrap(),
            Shard { index: 2, count: 3 }
        );
        assert_eq!(" 0 / 1".parse::<Shard>().unwrap(), Shard::WHOLE);
        for bad in ["3/3", "0/0", "1", "a/2", "-1/2", "1/2/3"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad} accepted");
        }
    }

    #[test]
    fn shards_partition_the_sweep_in_order() {
        let total = 11;
        let mut all: Vec<usize> = (0..4)
            .flat_map(|i| Shard::new(i, 4).unwrap().points(total))
            .collect();
        assert_eq!(Shard::new(1, 4).unwrap().points(total), vec![1, 5, 9]);
        all.sort();
        assert_eq!(all, (0..total).collect::<Vec<_>>());
    }

    #[test]
    fn units_go_whole_to_one_shard_and_partition_the_sweep() {
        // A chain of four, three single points, a chain of two.
        let units = [4, 1, 1, 1, 2];
        let shards: Vec<Vec<usize>> = (0..2)
            .map(|i| Shard::new(i, 2).unwrap().points_in_units(9, &units))
            .collect();
        assert_eq!(shards[0], vec![0, 1, 2, 3, 5, 7, 8]);
        assert_eq!(shards[1], vec![4, 6]);
        let mut header = header(1, 2, Value::Null);
        (header.points, header.units) = (9, units.to_vec());
        let owned: Vec<usize> = (0..10)
            .filter(|&k| header.unit_of(k).is_some_and(|u| header.shard.includes(u)))
            .collect();
        assert_eq!(owned, shards[1]);
        assert_eq!(Shard::WHOLE.points_in_units(3, &[]), vec![0, 1, 2]);
    }

    #[test]
    fn shard_names_are_recognised() {
        assert!(is_shard_name(Path::new("a/front.shard-0-of-3.csv")));
        assert!(is_shard_name(Path::new(
            "accuracy-vs-time.shard-12-of-40.csv"
        )));
        assert!(!is_shard_name(Path::new("front.csv")));
        assert!(!is_shard_name(Path::new("front.shard-x-of-3.csv")));
    }

    fn header(index: usize, count: usize, settings: Value) -> ShardHeader {
        ShardHeader {
            command: "front".into(),
            scene: "s".into(),
            shard: Shard::new(index, count).unwrap(),
            points: 5,
            units: Vec::new(),
            settings,
            scene_file: serde_json::json!({"name": "s"}),
        }
    }

    fn write(dir: &Path, h: &ShardHeader, rows: &[(usize, String)]) -> PathBuf {
        let path = dir.join(h.shard.file_name("front"));
        crate::report::write_atomic(&path, shard_csv(h, "a,b", rows).as_bytes()).unwrap();
        path
    }

    #[test]
    fn merge_restores_sweep_order_and_refuses_mismatches() {
        let dir = tempfile::tempdir().unwrap();
        let settings = serde_json::json!({"points": 5});
        let rows = |i: usize| -> Vec<(usize, String)> {
            Shard::new(i, 2)
                .unwrap()
                .points(5)
                .into_iter()
                .map(|k| (k, format!("{k},x")))
                .collect()
        };
        let a = write(dir.path(), &header(0, 2, settings.clone()), &rows(0));
        let b = write(dir.path(), &header(1, 2, settings.clone()), &rows(1));
        let files = find_shards(&[dir.path().to_path_buf()]).unwrap();
        assert_eq!(files, vec![a.clone(), b.clone()]);
        let read = |p: &Path| read_shard(p).unwrap();
        let merged = merge(vec![read(&b), read(&a)]).unwrap();
        assert_eq!(merged.len(), 1);
        assert_eq!(merged[0].csv(), "a,b\n0,x\n1,x\n2,x\n3,x\n4,x\n");

        assert!(matches!(
            merge(vec![read(&a)]),
            Err(ShardError::Missing { ref missing, .. }) if missing == &[1]
        ));
        assert!(matches!(
            merge(vec![read(&a), read(&a)]),
            Err(ShardError::Duplicate { .. })
        ));
        let other = tempfile::tempdir().unwrap();
        let c = write(
            other.path(),
            &header(1, 2, serde_json::json!({"points": 6})),
            &rows(1),
        );
        let e = merge(vec![read(&a), read(&c)]).unwrap_err();
        assert!(e.to_string().contains("settings differ"), "{e}");
    }

    #[test]
    fn a_row_outside_its_shard_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = write(
            dir.path(),
            &header(0, 2, Value::Null),
            &[(1, "1,x".to_string())],
        );
        assert!(matches!(read_shard(&path), Err(ShardError::Format { .. })));
    }
}
