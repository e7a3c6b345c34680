//! The budget's points and its table. A run measures points in a fixed
//! order — the facets, the design as built, each thermal case, then the
//! Monte Carlo samples — each one row of `budget-samples.csv` (the sweep a
//! shard splits: [`crate::shard`]); the table (`budget.csv`, `budget.json`)
//! is computed from the rows alone, so a merged run's equals the
//! unsharded one's bit for bit (every number is written in Rust's shortest
//! round-trip form).

use serde::Serialize;

use super::core::Measured;
use super::BudgetError;
use crate::surface::ruze_gain_loss_db;

/// What a point of the budget measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PointKind {
    /// The design surface's flat facets (the mesh's geometry).
    Facets,
    /// The design as built.
    Design,
    /// A thermal load case.
    Thermal,
    /// A manufacturing-tolerance sample.
    Sample,
}

impl PointKind {
    fn name(self) -> &'static str {
        match self {
            PointKind::Facets => "facets",
            PointKind::Design => "design",
            PointKind::Thermal => "thermal",
            PointKind::Sample => "sample",
        }
    }

    fn parse(s: &str) -> Option<Self> {
        [
            PointKind::Facets,
            PointKind::Design,
            PointKind::Thermal,
            PointKind::Sample,
        ]
        .into_iter()
        .find(|k| k.name() == s)
    }
}

/// One point of the budget: its measurement by the nonlinear assembly and
/// (thermal cases and samples) by the linearised one, or why it failed.
#[derive(Debug, Clone, PartialEq)]
pub struct BudgetRow {
    /// What it measures.
    pub kind: PointKind,
    /// Its name (a case's, `sample k`, `facets`, `design`).
    pub name: String,
    /// The nonlinear measurement, or the reason it failed.
    pub nonlinear: Result<Measured, String>,
    /// The linearised measurement (none for facets and design), or the
    /// reason it failed.
    pub linear: Option<Result<Measured, String>>,
}

/// The columns of `budget-samples.csv`.
pub const POINT_COLUMNS: &str = "kind,name,raw_mm,best_fit_mm,half_path_mm,focal_length_m,\
max_tension_change_pct,slack_count,slack_cables,linear_raw_mm,linear_best_fit_mm,\
linear_half_path_mm,linear_focal_length_m,linear_slack_count,error";

fn clean(s: &str) -> String {
    s.replace([',', '\n', '\r'], ";")
}

fn measured_cells(m: &Result<Measured, String>, slack_list: bool) -> (Vec<String>, Option<String>) {
    match m {
        Ok(m) => {
            let mut cells = vec![
                m.raw_mm.to_string(),
                m.best_fit_mm.to_string(),
                m.half_path_mm.to_string(),
                m.focal_length_m.to_string(),
            ];
            if slack_list {
                cells.push(m.max_tension_change_pct.to_string());
            }
            cells.push(m.slack_cables.len().to_string());
            if slack_list {
                let list: Vec<String> = m.slack_cables.iter().map(|k| k.to_string()).collect();
                cells.push(list.join(" "));
            }
            (cells, None)
        }
        Err(e) => (
            vec![String::new(); if slack_list { 7 } else { 5 }],
            Some(clean(e)),
        ),
    }
}

impl BudgetRow {
    /// The row of `budget-samples.csv` ([`POINT_COLUMNS`]).
    pub fn csv(&self) -> String {
        let (mut cells, mut error) = measured_cells(&self.nonlinear, true);
        let (linear, linear_error) = match &self.linear {
            Some(l) => measured_cells(l, false),
            None => (vec![String::new(); 5], None),
        };
        cells.extend(linear);
        if let Some(e) = linear_error {
            error = Some(match error {
                Some(n) => format!("{n}; linearised: {e}"),
                None => format!("linearised: {e}"),
            });
        }
        format!(
            "{},{},{},{}",
            self.kind.name(),
            clean(&self.name),
            cells.join(","),
            error.unwrap_or_default()
        )
    }

    /// A row of `budget-samples.csv` read back.
    ///
    /// # Errors
    /// A row that is not one [`BudgetRow::csv`] writes.
    pub fn parse(line: &str) -> Result<BudgetRow, BudgetError> {
        let bad = |reason: &str| BudgetError::Row {
            row: line.chars().take(80).collect(),
            reason: reason.to_string(),
        };
        let cells: Vec<&str> = line.split(',').collect();
        if cells.len() != POINT_COLUMNS.split(',').count() {
            return Err(bad("wrong number of columns"));
        }
        let kind = PointKind::parse(cells[0]).ok_or_else(|| bad("unknown kind"))?;
        let number = |s: &str| s.parse::<f64>().map_err(|_| bad("not a number"));
        let count = |s: &str| s.parse::<usize>().map_err(|_| bad("not a count"));
        let error = cells[14];
        let (nonlinear_error, linear_error) = match error.split_once("linearised: ") {
            Some((n, l)) => (n.trim_end_matches("; ").to_string(), Some(l.to_string())),
            None => (error.to_string(), None),
        };
        let nonlinear = if cells[2].is_empty() {
            Err(nonlinear_error)
        } else {
            let slack_cables = if cells[8].is_empty() {
                Vec::new()
            } else {
                cells[8]
                    .split(' ')
                    .map(count)
                    .collect::<Result<Vec<_>, _>>()?
            };
            if slack_cables.len() != count(cells[7])? {
                return Err(bad("slack count and list differ"));
            }
            Ok(Measured {
                raw_mm: number(cells[2])?,
                best_fit_mm: number(cells[3])?,
                half_path_mm: number(cells[4])?,
                focal_length_m: number(cells[5])?,
                max_tension_change_pct: number(cells[6])?,
                slack_cables,
            })
        };
        let linear = match kind {
            PointKind::Facets | PointKind::Design => None,
            _ if cells[9].is_empty() => Some(Err(linear_error.unwrap_or_default())),
            _ => Some(Ok(Measured {
                raw_mm: number(cells[9])?,
                best_fit_mm: number(cells[10])?,
                half_path_mm: number(cells[11])?,
                focal_length_m: number(cells[12])?,
                max_tension_change_pct: f64::NAN,
                slack_cables: vec![usize::MAX; count(cells[13])?],
            })),
        };
        Ok(BudgetRow {
            kind,
            name: cells[1].to_string(),
            nonlinear,
            linear,
        })
    }
}

/// One line of the budget table: RMS raw and about the best fit, mm, by
/// the nonlinear assembly and (where there is one) the linearised one.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BudgetTerm {
    /// The term (`facets`, `design as built`, `thermal: <case>`,
    /// `tolerances (rms)`, `tolerances (p95)`, `total (rss)`).
    pub term: String,
    /// Axial RMS about the design paraboloid, mm.
    pub raw_mm: f64,
    /// Axial RMS about the best-fit paraboloid, mm.
    pub best_fit_mm: f64,
    /// RMS half-path-length error about the best fit, mm (Ruze's ε).
    pub half_path_mm: f64,
    /// Ruze's gain loss at the scene's frequency, dB.
    pub gain_loss_db: Option<f64>,
    /// The linearised estimate's raw RMS, mm.
    pub linear_raw_mm: Option<f64>,
    /// The linearised estimate's best-fit RMS, mm.
    pub linear_best_fit_mm: Option<f64>,
    /// Slack cables (a thermal case's), or samples with slack cables.
    pub slack: Option<usize>,
}

/// The error budget (`budget.csv`, `budget.json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BudgetTable {
    /// The terms, in order: facets, design, each thermal case, the
    /// tolerances' RMS (root mean square over the samples) and 95th
    /// percentile, the total.
    pub terms: Vec<BudgetTerm>,
    /// Monte Carlo samples measured (failed ones excluded).
    pub samples: usize,
    /// Samples whose nonlinear assembly failed, with why.
    pub failed_samples: Vec<String>,
    /// Thermal cases whose nonlinear assembly failed, with why (their
    /// linearised estimate is in `budget-samples.csv`; the total leaves
    /// them out, and says so here).
    pub failed_cases: Vec<String>,
    /// The thermal case with the largest best-fit RMS, the one the total
    /// counts (cases are alternatives: the orbit is in one at a time).
    pub worst_thermal_case: Option<String>,
    /// Thermal cases and their slack cables (network order).
    pub thermal_slack_cables: Vec<(String, Vec<usize>)>,
    /// The scene's frequency, GHz.
    pub frequency_ghz: Option<f64>,
}

/// The linearised measurement of a row, when it has one that succeeded.
fn linear_of(r: &BudgetRow) -> Option<&Measured> {
    r.linear.as_ref().and_then(|l| l.as_ref().ok())
}

/// The 95th percentile of `values` (nearest rank), NaN when empty.
fn p95(values: &[f64]) -> f64 {
    let mut v: Vec<f64> = values.to_vec();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let rank = ((0.95 * v.len() as f64).ceil() as usize).clamp(1, v.len());
    v[rank - 1]
}

/// The root mean square of `values`, NaN when empty.
fn rms(values: &[f64]) -> f64 {
    (values.iter().map(|v| v * v).sum::<f64>() / values.len() as f64).sqrt()
}

impl BudgetTable {
    /// The table of `rows` (every point of the budget, in order) at the
    /// scene's `frequency_ghz`.
    pub fn of(rows: &[BudgetRow], frequency_ghz: Option<f64>) -> BudgetTable {
        let gain = |half_path_mm: f64| {
            frequency_ghz.and_then(|ghz| ruze_gain_loss_db(1e-3 * half_path_mm, 1e9 * ghz).ok())
        };
        let term = |name: String, m: &Measured, linear: Option<&Measured>, slack: Option<usize>| {
            BudgetTerm {
                term: name,
                raw_mm: m.raw_mm,
                best_fit_mm: m.best_fit_mm,
                half_path_mm: m.half_path_mm,
                gain_loss_db: gain(m.half_path_mm),
                linear_raw_mm: linear.map(|l| l.raw_mm),
                linear_best_fit_mm: linear.map(|l| l.best_fit_mm),
                slack,
            }
        };
        let mut terms = Vec::new();
        let mut total = [0.0f64; 3];
        let mut linear_total = [0.0f64; 2];
        let mut add = |m: &Measured, l: Option<&Measured>| {
            total[0] += m.raw_mm.powi(2);
            total[1] += m.best_fit_mm.powi(2);
            total[2] += m.half_path_mm.powi(2);
            let l = l.unwrap_or(m);
            linear_total[0] += l.raw_mm.powi(2);
            linear_total[1] += l.best_fit_mm.powi(2);
        };
        for r in rows
            .iter()
            .filter(|r| matches!(r.kind, PointKind::Facets | PointKind::Design))
        {
            if let Ok(m) = &r.nonlinear {
                let name = match r.kind {
                    PointKind::Facets => "facets".to_string(),
                    _ => "design as built".to_string(),
                };
                terms.push(term(name, m, None, None));
                add(m, None);
            }
        }
        let mut worst: Option<(&BudgetRow, &Measured)> = None;
        let mut thermal_slack_cables = Vec::new();
        for r in rows.iter().filter(|r| r.kind == PointKind::Thermal) {
            if let Ok(m) = &r.nonlinear {
                terms.push(term(
                    format!("thermal: {}", r.name),
                    m,
                    linear_of(r),
                    Some(m.slack_cables.len()),
                ));
                thermal_slack_cables.push((r.name.clone(), m.slack_cables.clone()));
                if worst.is_none_or(|(_, w)| m.best_fit_mm > w.best_fit_mm) {
                    worst = Some((r, m));
                }
            }
        }
        if let Some((r, m)) = worst {
            add(m, linear_of(r));
        }
        let samples: Vec<(&Measured, Option<&Measured>)> = rows
            .iter()
            .filter(|r| r.kind == PointKind::Sample)
            .filter_map(|r| r.nonlinear.as_ref().ok().map(|m| (m, linear_of(r))))
            .collect();
        // "name: why" of each point of `kind` that failed.
        let failed = |kind: PointKind| -> Vec<String> {
            rows.iter()
                .filter(|r| r.kind == kind)
                .filter_map(|r| {
                    r.nonlinear
                        .as_ref()
                        .err()
                        .map(|e| format!("{}: {e}", r.name))
                })
                .collect()
        };
        let failed_cases = failed(PointKind::Thermal);
        let failed_samples = failed(PointKind::Sample);
        if !samples.is_empty() {
            let column = |f: &dyn Fn(&Measured) -> f64| {
                samples.iter().map(|(m, _)| f(m)).collect::<Vec<_>>()
            };
            let linear_column = |f: &dyn Fn(&Measured) -> f64| {
                samples
                    .iter()
                    .filter_map(|(_, l)| l.map(f))
                    .collect::<Vec<_>>()
            };
            let slack = samples
                .iter()
                .filter(|(m, _)| !m.slack_cables.is_empty())
                .count();
            for (name, stat) in [
                ("tolerances (rms)", rms as fn(&[f64]) -> f64),
                ("tolerances (p95)", p95 as fn(&[f64]) -> f64),
            ] {
                let m = Measured {
                    raw_mm: stat(&column(&|m| m.raw_mm)),
                    best_fit_mm: stat(&column(&|m| m.best_fit_mm)),
                    half_path_mm: stat(&column(&|m| m.half_path_mm)),
                    focal_length_m: f64::NAN,
                    max_tension_change_pct: f64::NAN,
                    slack_cables: Vec::new(),
                };
                let l = Measured {
                    raw_mm: stat(&linear_column(&|m| m.raw_mm)),
                    best_fit_mm: stat(&linear_column(&|m| m.best_fit_mm)),
                    ..m.clone()
                };
                terms.push(term(name.to_string(), &m, Some(&l), Some(slack)));
                if name == "tolerances (rms)" {
                    add(&m, Some(&l));
                }
            }
        }
        let half_path_mm = total[2].sqrt();
        terms.push(BudgetTerm {
            term: "total (rss)".to_string(),
            raw_mm: total[0].sqrt(),
            best_fit_mm: total[1].sqrt(),
            half_path_mm,
            gain_loss_db: gain(half_path_mm),
            linear_raw_mm: Some(linear_total[0].sqrt()),
            linear_best_fit_mm: Some(linear_total[1].sqrt()),
            slack: None,
        });
        BudgetTable {
            terms,
            samples: samples.len(),
            failed_samples,
            failed_cases,
            worst_thermal_case: worst.map(|(r, _)| r.name.clone()),
            thermal_slack_cables,
            frequency_ghz,
        }
    }

    /// `budget.csv`.
    pub fn csv(&self) -> String {
        let opt = |v: Option<f64>| v.map_or(String::new(), |v| v.to_string());
        let mut s = String::from(
            "term,raw_mm,best_fit_mm,half_path_mm,gain_loss_db,linear_raw_mm,\
             linear_best_fit_mm,slack\n",
        );
        for t in &self.terms {
            s.push_str(&format!(
                "{},{},{},{},{},{},{},{}\n",
                clean(&t.term),
                t.raw_mm,
                t.best_fit_mm,
                t.half_path_mm,
                opt(t.gain_loss_db),
                opt(t.linear_raw_mm),
                opt(t.linear_best_fit_mm),
                t.slack.map_or(String::new(), |s| s.to_string())
            ));
        }
        s
    }
}
