//! Measured properties of individual truss rods (issue 6, DESIGN §8): an
//! optional table, `[effects] rod_properties_csv = "file.csv"`, whose rows
//! override the nominal tube section of the rods they name — the scatter of
//! composite tube properties the paper's discussion points to. Rods the table
//! does not name keep the section of `[truss]`.
//!
//! The table is read by [`crate::Scene::read`] only when the key is present,
//! validated once against the scene's bays, and applied by
//! [`crate::truss::RingTruss::builder`] (through the effect of [`crate::effects`]), so the linear and exact oracles, the limit
//! margin and the verification assembly all see the same rods.
//!
//! # Rod names
//!
//! Hinge `k` sits at the angle `2πk/N` (top hinges `0..N` are the net's first
//! attachment points, see [`crate::geometry::RingTrussLayout`]). Bay `k`
//! (`k = 0 … N−1`) spans hinges `k` and `k + 1 mod N`; its five rods, in the
//! order the builder adds them, are
//!
//! | name | from | to | index in `Model::rods()` |
//! |---|---|---|---|
//! | `batten k` | bottom hinge `k` | top hinge `k` | `5k` |
//! | `top longeron k` | top hinge `k` | top hinge `k+1` | `5k + 1` |
//! | `bottom longeron k` | bottom hinge `k` | bottom hinge `k+1` | `5k + 2` |
//! | `diagonal thick k` | bottom hinge `k` | the diagonal's middle | `5k + 3` |
//! | `diagonal thin k` | the diagonal's middle | top hinge `k+1` | `5k + 4` |
//!
//! The index is also the `rod …` a [`crate::mechanics::MechanicsError`] names.
//! In the table, names are case-insensitive and their words may be separated
//! by any spaces or `_` (`Top_Longeron 3` is `top longeron 3`).
//!
//! # Format
//!
//! ```text
//! # measured on the flight lot, 2024-03 (lines starting with # are comments)
//! rod,axial_stiffness_n,bending_stiffness_nm2
//! batten 0,1.52e8,2.41e5
//! top longeron 3,1.38e8,
//! diagonal thin 5,,1.95e5
//! ```
//!
//! * A header names the columns (case-insensitive): `rod` first, then one or more of
//!   `axial_stiffness_n` (EA, N), `bending_stiffness_nm2` (EI, N·m², both
//!   bending axes: the tubes are round), `torsion_stiffness_nm2` (GJ, N·m²)
//!   and `shear_stiffness_n` (GA with the shear area, N, both shear axes), in
//!   any order, each at most once. A column left out keeps the nominal value
//!   for every rod; an empty cell keeps it for that rod.
//! * One row per overridden rod; a rod listed twice is an error. Values must
//!   be finite numbers `> 0`. Blank lines and lines starting with `#` are
//!   skipped; fields are trimmed and may be quoted (`"batten 0"`), but carry
//!   no commas.
//!
//! Every error names the file, the line and the rod or column at fault.

use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;

use crate::mechanics::Section;

/// The five rods of a bay, in the order the builder adds them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum RodKind {
    /// Vertical batten from bottom hinge `k` to top hinge `k`.
    Batten,
    /// Upper longeron from top hinge `k` to top hinge `k + 1`.
    TopLongeron,
    /// Lower longeron from bottom hinge `k` to bottom hinge `k + 1`.
    BottomLongeron,
    /// Lower half of the diagonal, from bottom hinge `k` to its middle.
    DiagonalThick,
    /// Upper half of the diagonal, from its middle to top hinge `k + 1`.
    DiagonalThin,
}

impl RodKind {
    /// Every kind, in build order.
    pub const ALL: [RodKind; 5] = [
        RodKind::Batten,
        RodKind::TopLongeron,
        RodKind::BottomLongeron,
        RodKind::DiagonalThick,
        RodKind::DiagonalThin,
    ];

    /// The name used in the table (without the bay).
    pub fn name(self) -> &'static str {
        match self {
            RodKind::Batten => "batten",
            RodKind::TopLongeron => "top longeron",
            RodKind::BottomLongeron => "bottom longeron",
            RodKind::DiagonalThick => "diagonal thick",
            RodKind::DiagonalThin => "diagonal thin",
        }
    }
}

/// One rod of the ring truss: its kind and its bay.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct TrussRod {
    /// Which of the bay's rods.
    pub kind: RodKind,
    /// The bay, `0 … N−1`.
    pub bay: usize,
}

impl TrussRod {
    /// Rod `kind` of bay `bay`.
    pub fn new(kind: RodKind, bay: usize) -> Self {
        TrussRod { kind, bay }
    }

    /// The rod's index in the built frame's `Model::rods()`: `5·bay + j`,
    /// `j` the kind's place in [`RodKind::ALL`].
    pub fn index(&self) -> usize {
        5 * self.bay + self.kind as usize
    }

    /// Every rod of a truss of `bays` bays, in build order (by [`Self::index`]).
    pub fn all(bays: usize) -> impl Iterator<Item = TrussRod> {
        (0..bays).flat_map(|bay| RodKind::ALL.map(|kind| TrussRod { kind, bay }))
    }

    /// Parses a name such as `top longeron 3` (case-insensitive; words
    /// separated by spaces or `_`); `None` when it names no kind of rod or
    /// its bay is not a number.
    pub fn parse(name: &str) -> Option<TrussRod> {
        let lower = name.to_ascii_lowercase();
        let words: Vec<&str> = lower
            .split(|c: char| c.is_whitespace() || c == '_')
            .filter(|w| !w.is_empty())
            .collect();
        let (bay, kind_words) = words.split_last()?;
        let kind_name = kind_words.join(" ");
        let kind = RodKind::ALL.into_iter().find(|k| k.name() == kind_name)?;
        let bay = bay.parse().ok()?;
        Some(TrussRod { kind, bay })
    }
}

impl fmt::Display for TrussRod {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} {}", self.kind.name(), self.bay)
    }
}

/// The stiffnesses one row overrides; `None` keeps the nominal value.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RodStiffness {
    /// Axial stiffness EA, N.
    pub axial_stiffness_n: Option<f64>,
    /// Bending stiffness EI about both section axes, N·m².
    pub bending_stiffness_nm2: Option<f64>,
    /// Torsional stiffness GJ, N·m².
    pub torsion_stiffness_nm2: Option<f64>,
    /// Shear stiffness GA (shear area included) along both section axes, N.
    pub shear_stiffness_n: Option<f64>,
}

impl RodStiffness {
    /// `nominal` with the values this row gives.
    pub fn apply(&self, nominal: &Section) -> Section {
        Section {
            axial_n: self.axial_stiffness_n.unwrap_or(nominal.axial_n),
            shear_n: self.shear_stiffness_n.map_or(nominal.shear_n, |v| [v; 2]),
            torsion_nm2: self.torsion_stiffness_nm2.unwrap_or(nominal.torsion_nm2),
            bending_nm2: self
                .bending_stiffness_nm2
                .map_or(nominal.bending_nm2, |v| [v; 2]),
        }
    }

    fn slot(&mut self, column: Column) -> &mut Option<f64> {
        match column {
            Column::Axial => &mut self.axial_stiffness_n,
            Column::Bending => &mut self.bending_stiffness_nm2,
            Column::Torsion => &mut self.torsion_stiffness_nm2,
            Column::Shear => &mut self.shear_stiffness_n,
        }
    }
}

/// A value column of the table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Column {
    Axial,
    Bending,
    Torsion,
    Shear,
}

impl Column {
    const ALL: [Column; 4] = [
        Column::Axial,
        Column::Bending,
        Column::Torsion,
        Column::Shear,
    ];

    fn name(self) -> &'static str {
        match self {
            Column::Axial => "axial_stiffness_n",
            Column::Bending => "bending_stiffness_nm2",
            Column::Torsion => "torsion_stiffness_nm2",
            Column::Shear => "shear_stiffness_n",
        }
    }
}

/// A table that cannot be used; every variant names the file and the line.
#[derive(Debug, thiserror::Error)]
pub enum RodPropertiesError {
    /// Reading the file failed.
    #[error("reading {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// The header is missing or names an unknown or repeated column.
    #[error("{path}, line {line}: {reason}")]
    Header {
        /// The file.
        path: String,
        /// The line, from 1.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A row that cannot be read as one rod's values (wrong field count, no value).
    #[error("{path}, line {line}: {reason}")]
    Row {
        /// The file.
        path: String,
        /// The line, from 1.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A rod that is not in the truss, or listed twice.
    #[error("{path}, line {line}: rod `{rod}`: {reason}")]
    Rod {
        /// The file.
        path: String,
        /// The line, from 1.
        line: usize,
        /// The rod as written.
        rod: String,
        /// What is wrong.
        reason: String,
    },
    /// A value that is not a finite positive number.
    #[error("{path}, line {line}: rod `{rod}`, column `{column}`: {reason}")]
    Value {
        /// The file.
        path: String,
        /// The line, from 1.
        line: usize,
        /// The rod.
        rod: String,
        /// The column.
        column: &'static str,
        /// What is wrong.
        reason: String,
    },
}

impl RodPropertiesError {
    /// The line at fault (from 1), when the error is about one.
    pub fn line(&self) -> Option<usize> {
        match self {
            RodPropertiesError::Io { .. } => None,
            RodPropertiesError::Header { line, .. }
            | RodPropertiesError::Row { line, .. }
            | RodPropertiesError::Rod { line, .. }
            | RodPropertiesError::Value { line, .. } => Some(*line),
        }
    }
}

/// The overrides of one table, validated against a truss of known bays.
#[derive(Debug, Clone, PartialEq)]
pub struct RodProperties {
    /// Where the table came from (for messages).
    source: String,
    /// Overridden rods with the line that gave them.
    rows: BTreeMap<TrussRod, (usize, RodStiffness)>,
}

impl RodProperties {
    /// Reads and validates the table at `path` for a truss of `bays` bays.
    ///
    /// # Errors
    /// The file cannot be read, or its content is invalid (see [`Self::parse`]).
    pub fn read(path: &Path, bays: usize) -> Result<Self, RodPropertiesError> {
        let shown = path.display().to_string();
        let text = crate::input::read_input(path).map_err(|source| RodPropertiesError::Io {
            path: shown.clone(),
            source,
        })?;
        Self::parse(&text, &shown, bays)
    }

    /// Parses and validates table text (`source` names it in errors) for a
    /// truss of `bays` bays.
    ///
    /// # Errors
    /// A missing or bad header, a row with the wrong number of fields or no
    /// value, an unknown or repeated rod, a value that is not a finite
    /// number `> 0`, or a table with no row; each names the line.
    pub fn parse(text: &str, source: &str, bays: usize) -> Result<Self, RodPropertiesError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l.trim()))
            .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
        let header_error = |line: usize, reason: String| RodPropertiesError::Header {
            path: source.to_string(),
            line,
            reason,
        };
        let expected = "expected a header such as `rod,axial_stiffness_n,bending_stiffness_nm2`";
        let Some((header_line, header)) = lines.next() else {
            return Err(header_error(1, format!("the table is empty: {expected}")));
        };
        let names: Vec<String> = header
            .split(',')
            .map(|f| field(f).to_ascii_lowercase())
            .collect();
        if names[0] != "rod" {
            return Err(header_error(
                header_line,
                format!("the first column is `{}`: {expected}", names[0]),
            ));
        }
        let mut columns: Vec<Column> = Vec::with_capacity(names.len() - 1);
        for name in &names[1..] {
            let Some(column) = Column::ALL.into_iter().find(|c| c.name() == name) else {
                let known: Vec<&str> = Column::ALL.iter().map(|c| c.name()).collect();
                return Err(header_error(
                    header_line,
                    format!("unknown column `{name}`: known are {}", known.join(", ")),
                ));
            };
            if columns.contains(&column) {
                return Err(header_error(
                    header_line,
                    format!("column `{name}` appears twice"),
                ));
            }
            columns.push(column);
        }
        if columns.is_empty() {
            return Err(header_error(
                header_line,
                format!("no value column: {expected}"),
            ));
        }

        let mut rows = BTreeMap::new();
        for (line, row) in lines {
            let fields: Vec<String> = row.split(',').map(field).collect();
            if fields.len() != names.len() {
                return Err(RodPropertiesError::Row {
                    path: source.to_string(),
                    line,
                    reason: format!(
                        "{} fields, the header has {} ({})",
                        fields.len(),
                        names.len(),
                        names.join(",")
                    ),
                });
            }
            let written = &fields[0];
            let rod_error = |reason: String| RodPropertiesError::Rod {
                path: source.to_string(),
                line,
                rod: written.clone(),
                reason,
            };
            let Some(rod) = TrussRod::parse(written) else {
                return Err(rod_error(format!(
                    "unknown rod: expected `batten K`, `top longeron K`, `bottom longeron K`, \
                     `diagonal thick K` or `diagonal thin K`, K a bay 0 … {}",
                    bays.saturating_sub(1)
                )));
            };
            if rod.bay >= bays {
                return Err(rod_error(no_such_bay(bays)));
            }
            if let Some((first, _)) = rows.get(&rod) {
                return Err(rod_error(format!("listed twice (first on line {first})")));
            }
            let mut stiffness = RodStiffness::default();
            for (&column, cell) in columns.iter().zip(&fields[1..]) {
                if cell.is_empty() {
                    continue;
                }
                let value_error = |reason: String| RodPropertiesError::Value {
                    path: source.to_string(),
                    line,
                    rod: rod.to_string(),
                    column: column.name(),
                    reason,
                };
                let value: f64 = cell
                    .parse()
                    .map_err(|_| value_error(format!("`{cell}` is not a number")))?;
                if !(value.is_finite() && value > 0.0) {
                    return Err(value_error(format!("`{cell}` must be a finite number > 0")));
                }
                *stiffness.slot(column) = Some(value);
            }
            if stiffness == RodStiffness::default() {
                return Err(rod_error(
                    "every value cell is empty: the row overrides nothing".into(),
                ));
            }
            rows.insert(rod, (line, stiffness));
        }
        if rows.is_empty() {
            return Err(RodPropertiesError::Row {
                path: source.to_string(),
                line: header_line,
                reason: "the header is followed by no row: the table overrides no rod".into(),
            });
        }
        Ok(RodProperties {
            source: source.to_string(),
            rows,
        })
    }

    /// Checks that every rod of the table is in a truss of `bays` bays (the
    /// table was read for the scene's bays; a scene changed since is checked
    /// again by [`crate::Scene::validate`]).
    ///
    /// # Errors
    /// The first rod beyond the bays, named with its line.
    pub fn check_bays(&self, bays: usize) -> Result<(), RodPropertiesError> {
        match self.rows.iter().find(|(rod, _)| rod.bay >= bays) {
            Some((rod, (line, _))) => Err(RodPropertiesError::Rod {
                path: self.source.clone(),
                line: *line,
                rod: rod.to_string(),
                reason: no_such_bay(bays),
            }),
            None => Ok(()),
        }
    }

    /// Where the table came from.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// Number of overridden rods.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// True when no rod is overridden (never for a parsed table).
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// The values given for `rod`, if it is overridden.
    pub fn get(&self, rod: TrussRod) -> Option<&RodStiffness> {
        self.rows.get(&rod).map(|(_, s)| s)
    }

    /// The overridden rods and their values, in build order.
    pub fn iter(&self) -> impl Iterator<Item = (TrussRod, &RodStiffness)> {
        self.rows.iter().map(|(rod, (_, s))| (*rod, s))
    }

    /// The section of `rod`: `nominal` with the values the table gives for it.
    pub fn section(&self, rod: TrussRod, nominal: &Section) -> Section {
        self.get(rod).map_or(*nominal, |s| s.apply(nominal))
    }
}

/// A trimmed field without its surrounding double quotes.
fn field(raw: &str) -> String {
    let t = raw.trim();
    t.strip_prefix('"')
        .and_then(|s| s.strip_suffix('"'))
        .unwrap_or(t)
        .trim()
        .to_string()
}

fn no_such_bay(bays: usize) -> String {
    format!(
        "no such rod: the truss has {bays} bays, numbered 0 … {}",
        bays.saturating_sub(1)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn nominal() -> Section {
        Section::tube(0.06, 0.056, 160e9, 61.5e9)
    }

    #[test]
    fn names_round_trip_and_index_in_build_order() {
        for (i, rod) in TrussRod::all(7).enumerate() {
            assert_eq!(rod.index(), i);
            assert_eq!(TrussRod::parse(&rod.to_string()), Some(rod));
        }
        assert_eq!(
            TrussRod::parse("  Top_Longeron   3 "),
            Some(TrussRod::new(RodKind::TopLongeron, 3))
        );
        assert_eq!(
            TrussRod::parse("diagonal_thin\t12"),
            Some(TrussRod::new(RodKind::DiagonalThin, 12))
        );
        for bad in [
            "",
            "batten",
            "longeron 2",
            "batten x",
            "batten -1",
            "batten 1.5",
            "3",
            "diagonal-thin 2",
        ] {
            assert_eq!(TrussRod::parse(bad), None, "{bad:?}");
        }
    }

    #[test]
    fn rows_override_only_their_columns_and_rods() {
        let text = "\u{feff}# measured\n\nrod, bending_stiffness_nm2 ,axial_stiffness_n\r\n\
                    \"batten 0\",2e5,1.5e8\n\
                    top longeron 5,,1e8\n\
                    # skipped\n\
                    DIAGONAL THIN 2,3e5,\n";
        let table = RodProperties::parse(text, "t.csv", 6).unwrap();
        assert_eq!(table.len(), 3);
        let n = nominal();
        let batten = table.section(TrussRod::new(RodKind::Batten, 0), &n);
        assert_eq!(batten.axial_n, 1.5e8);
        assert_eq!(batten.bending_nm2, [2e5, 2e5]);
        assert_eq!(
            (batten.shear_n, batten.torsion_nm2),
            (n.shear_n, n.torsion_nm2)
        );
        let longeron = table.section(TrussRod::new(RodKind::TopLongeron, 5), &n);
        assert_eq!(longeron.axial_n, 1e8);
        assert_eq!(longeron.bending_nm2, n.bending_nm2);
        let thin = table.section(TrussRod::new(RodKind::DiagonalThin, 2), &n);
        assert_eq!((thin.axial_n, thin.bending_nm2), (n.axial_n, [3e5; 2]));
        assert_eq!(table.section(TrussRod::new(RodKind::Batten, 1), &n), n);

        let all = "rod,axial_stiffness_n,bending_stiffness_nm2,torsion_stiffness_nm2,\
                   shear_stiffness_n\nbottom longeron 1,1,2,3,4\n";
        let s = RodProperties::parse(all, "t.csv", 3)
            .unwrap()
            .section(TrussRod::new(RodKind::BottomLongeron, 1), &n);
        assert_eq!(s.diagonal(), [1.0, 4.0, 4.0, 3.0, 2.0, 2.0]);
    }

    /// Each kind of bad table is refused with its line and the rod or
    /// column at fault in the message.
    #[test]
    fn bad_tables_name_the_line_and_the_rod() {
        let header = "rod,axial_stiffness_n,bending_stiffness_nm2\n";
        let cases: &[(&str, usize, &[&str])] = &[
            ("", 1, &["empty"]),
            ("# only a comment\n", 1, &["empty"]),
            (
                "name,axial_stiffness_n\nbatten 0,1\n",
                1,
                &["first column", "name"],
            ),
            ("rod,axial_stiffness\nbatten 0,1\n", 1, &["axial_stiffness"]),
            (
                "rod,axial_stiffness_n,axial_stiffness_n\nbatten 0,1,2\n",
                1,
                &["twice"],
            ),
            ("rod\nbatten 0\n", 1, &["no value column"]),
            ("\n#c\nrod,axial_stiffness_n\n", 3, &["no row"]),
            ("batten 0,1,2,3\n", 2, &["4 fields", "3"]),
            ("batten 0,1\n", 2, &["2 fields"]),
            ("longeron 0,1,2\n", 2, &["`longeron 0`", "unknown rod"]),
            ("batten 6,1,2\n", 2, &["`batten 6`", "6 bays"]),
            (
                "batten 1,1,2\ntop longeron 0,1,2\nBatten 1,3,4\n",
                4,
                &["`Batten 1`", "line 2"],
            ),
            (
                "batten 1,1,x\n",
                2,
                &["`batten 1`", "bending_stiffness_nm2", "`x`"],
            ),
            ("batten 1,0,1\n", 2, &["axial_stiffness_n", "> 0"]),
            ("batten 1,-3,1\n", 2, &["axial_stiffness_n", "> 0"]),
            ("batten 1,1,inf\n", 2, &["bending_stiffness_nm2", "finite"]),
            ("batten 1,NaN,1\n", 2, &["axial_stiffness_n", "finite"]),
            ("batten 1,,\n", 2, &["`batten 1`", "overrides nothing"]),
        ];
        for (body, line, words) in cases {
            let text = if body.starts_with("batten") || body.starts_with("longeron") {
                format!("{header}{body}")
            } else {
                body.to_string()
            };
            let e = RodProperties::parse(&text, "rods.csv", 6)
                .expect_err(&format!("accepted {text:?}"));
            let message = e.to_string();
            assert_eq!(e.line(), Some(*line), "{text:?}: {message}");
            assert!(message.starts_with("rods.csv, line "), "{message}");
            for w in *words {
                assert!(message.contains(w), "{text:?}: {message} lacks {w:?}");
            }
        }
    }

    #[test]
    fn a_table_checked_against_fewer_bays_names_the_rod() {
        let table = RodProperties::parse(
            "rod,axial_stiffness_n\nbatten 1,1\nbatten 4,1\n",
            "r.csv",
            6,
        )
        .unwrap();
        assert!(table.check_bays(6).is_ok());
        let e = table.check_bays(4).unwrap_err();
        assert_eq!(e.line(), Some(3));
        assert!(e.to_string().contains("`batten 4`"), "{e}");
    }
}
