//! CSV tables: the cable table a manufacturer needs, the design front and the
//! accuracy study — and the rows of the last two read back, for `merge`.

use std::fmt::Write;

use crate::design::{LoopRun, LoopSummary};
use crate::network::Network;
use crate::scene::{Cables, TrussModel};
use crate::sizing::SectionTrial;
use crate::study::{value_name, ApertureResult, Knob, RunSettings, StudyRow};
use crate::uniformity::{Design, FrontPoint, SolverKind};

use super::number::{decimal, readable};

/// `id,group,i,j,q,tension_n,length_m,cut_length_m`: one row per cable, with the
/// unstressed cut length `L0 = ℓ/(1 + T/EA)` (DESIGN §7).
///
/// # Panics
/// If `design` does not belong to `network`.
#[track_caller]
pub fn cables_csv(network: &Network, design: &Design, cables: &Cables) -> String {
    assert_eq!(
        design.q.len(),
        network.n_edges(),
        "design of another network"
    );
    let mut s = String::from("id,group,i,j,q,tension_n,length_m,cut_length_m\n");
    for (k, &[i, j]) in network.edges.iter().enumerate() {
        let (t, l) = (design.tensions_n[k], design.lengths_m[k]);
        let _ = writeln!(
            s,
            "{k},{},{i},{j},{},{},{},{}",
            network.group_of(k),
            decimal(design.q[k], 13),
            decimal(t, 13),
            decimal(l, 13),
            decimal(cables.cut_length_m(l, t), 13)
        );
    }
    s
}

/// One row of `front.csv`: a successful design of the front.
#[derive(Debug, Clone, PartialEq)]
pub struct FrontRow {
    /// The solver's command-line name.
    pub solver: String,
    /// Its accuracy knob.
    pub knob: f64,
    /// `Tmax/Tmin` over the uniformity sets (the largest).
    pub ratio: f64,
    /// RMS surface error of the forward solve, mm.
    pub rms_mm: f64,
    /// Wall time of the solve, s.
    pub time_s: f64,
}

impl FrontRow {
    /// The row of a point of the front; `None` for a failed point.
    pub fn of(point: &FrontPoint) -> Option<FrontRow> {
        point.outcome.is_ok().then(|| FrontRow {
            solver: value_name(&point.solver),
            knob: point.knob,
            ratio: point.ratio,
            rms_mm: point.rms_mm,
            time_s: point.time_s,
        })
    }
}

/// The columns of `front.csv`.
pub const FRONT_COLUMNS: &str = "solver,knob,ratio,rms_mm,time_s";

/// One line of `front.csv` (without its newline).
pub fn front_row(row: &FrontRow) -> String {
    format!(
        "{},{},{},{},{}",
        row.solver,
        readable(row.knob, 7),
        readable(row.ratio, 11),
        readable(row.rms_mm, 7),
        readable(row.time_s, 7)
    )
}

/// `solver,knob,ratio,rms_mm,time_s`: the design front, one row per
/// successful point.
pub fn front_csv(rows: &[FrontRow]) -> String {
    table(FRONT_COLUMNS, rows.iter().map(front_row))
}

/// Reads a line of `front.csv` back.
///
/// # Errors
/// A line that is not one, with the reason.
pub fn parse_front_row(line: &str) -> Result<FrontRow, RowError> {
    let f = split_row(line, 5)?;
    Ok(FrontRow {
        solver: f[0].clone(),
        knob: number(&f[1], "knob")?,
        ratio: number(&f[2], "ratio")?,
        rms_mm: number(&f[3], "rms_mm")?,
        time_s: number(&f[4], "time_s")?,
    })
}

/// The columns of `accuracy-vs-time.csv`.
pub const STUDY_COLUMNS: &str = "knob,value,tolerance_m,elements_per_rod,rings,truss,solver,\
    time_s,outer_iterations,termination,boundary_residual_m,ratio,built_ratio,ratio_error,\
    rms_mm,max_deviation_mm,facet_rms_mm,tension_change_pct,cut_length_error_mm,error";

/// One line of `accuracy-vs-time.csv` (without its newline); missing numbers
/// are empty.
pub fn study_row(r: &StudyRow) -> String {
    let g = |v: f64| finite(v, 7);
    let s = &r.settings;
    format!(
        "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
        r.knob.name(),
        r.value,
        readable(s.tolerance_m, 7),
        s.elements_per_rod,
        s.rings,
        value_name(&s.truss),
        value_name(&s.solver),
        readable(r.time_s, 5),
        r.summary
            .map_or(String::new(), |s| s.outer_iterations.to_string()),
        r.summary
            .map_or(String::new(), |s| json_name(&s.termination)),
        g(r.summary.map_or(f64::NAN, |s| s.boundary_residual_m)),
        finite(r.ratio, 11),
        finite(r.built_ratio, 11),
        g(r.ratio_error),
        g(r.rms_mm),
        g(r.max_deviation_mm),
        g(r.facet_rms_mm),
        g(r.tension_change_pct),
        g(r.cut_length_error_mm),
        r.error.as_deref().map_or(String::new(), quote),
    )
}

/// A unit variant's name as the JSON files spell it (`converged`,
/// `max_iterations`), not Rust's `Debug` (which it falls back to for a
/// value that is not a plain name).
pub fn json_name<T: serde::Serialize + std::fmt::Debug>(value: &T) -> String {
    match serde_json::to_value(value) {
        Ok(serde_json::Value::String(name)) => name,
        _ => format!("{value:?}"),
    }
}

/// The accuracy study, one row per point, in sweep order.
pub fn study_csv(rows: &[StudyRow]) -> String {
    table(STUDY_COLUMNS, rows.iter().map(study_row))
}

/// Reads a line of `accuracy-vs-time.csv` back.
///
/// # Errors
/// A line that is not one, with the reason.
pub fn parse_study_row(line: &str) -> Result<StudyRow, RowError> {
    let f = split_row(line, 20)?;
    let optional = |text: &str, name: &'static str| -> Result<f64, RowError> {
        if text.is_empty() {
            Ok(f64::NAN)
        } else {
            number(text, name)
        }
    };
    let truss = <TrussModel as clap::ValueEnum>::from_str(&f[5], false)
        .map_err(|_| RowError::value("truss", &f[5], "truss model"))?;
    let solver = <SolverKind as clap::ValueEnum>::from_str(&f[6], false)
        .map_err(|_| RowError::value("solver", &f[6], "solver"))?;
    // The loop's summary: its iterations and termination both, or neither
    // (a point that failed before its loop ended). The file holds the
    // design's time, not the loop's own.
    let summary = match (f[8].is_empty(), f[9].is_empty()) {
        (true, true) => None,
        (false, false) => Some(LoopSummary {
            termination: serde_json::from_value(serde_json::Value::String(f[9].clone()))
                .map_err(|_| RowError::value("termination", &f[9], "termination"))?,
            outer_iterations: whole(&f[8], "outer_iterations")?,
            boundary_residual_m: optional(&f[10], "boundary_residual_m")?,
            time_s: f64::NAN,
        }),
        (true, false) => return Err(RowError::value("outer_iterations", "", "whole number")),
        (false, true) => return Err(RowError::value("termination", "", "termination")),
    };
    Ok(StudyRow {
        knob: Knob::from_name(&f[0]).ok_or_else(|| RowError::value("knob", &f[0], "knob"))?,
        value: f[1].clone(),
        settings: RunSettings {
            tolerance_m: number(&f[2], "tolerance_m")?,
            elements_per_rod: whole(&f[3], "elements_per_rod")?,
            rings: whole(&f[4], "rings")?,
            truss,
            solver,
        },
        time_s: number(&f[7], "time_s")?,
        summary,
        ratio: optional(&f[11], "ratio")?,
        built_ratio: optional(&f[12], "built_ratio")?,
        ratio_error: optional(&f[13], "ratio_error")?,
        rms_mm: optional(&f[14], "rms_mm")?,
        max_deviation_mm: optional(&f[15], "max_deviation_mm")?,
        facet_rms_mm: optional(&f[16], "facet_rms_mm")?,
        tension_change_pct: optional(&f[17], "tension_change_pct")?,
        cut_length_error_mm: optional(&f[18], "cut_length_error_mm")?,
        error: (!f[19].is_empty()).then(|| f[19].clone()),
    })
}

/// A column line and rows, each ended by a newline.
fn table(columns: &str, rows: impl Iterator<Item = String>) -> String {
    let mut s = format!("{columns}\n");
    for row in rows {
        s.push_str(&row);
        s.push('\n');
    }
    s
}

/// A text field: quoted when it holds a comma or a quote (quotes doubled);
/// line breaks become spaces, so a row stays on one line.
fn quote(text: &str) -> String {
    let text = text.replace(['\n', '\r'], " ");
    if text.contains([',', '"']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text
    }
}

/// The fields of a CSV line (quoted fields unquoted), exactly `n` of them.
fn split_row(line: &str, n: usize) -> Result<Vec<String>, RowError> {
    let mut fields = Vec::with_capacity(n);
    let mut field = String::new();
    let mut chars = line.chars().peekable();
    let mut quoted = false;
    while let Some(c) = chars.next() {
        match (quoted, c) {
            (true, '"') if chars.peek() == Some(&'"') => {
                field.push('"');
                chars.next();
            }
            (true, '"') => quoted = false,
            (false, '"') if field.is_empty() => quoted = true,
            (false, ',') => fields.push(std::mem::take(&mut field)),
            (_, c) => field.push(c),
        }
    }
    fields.push(field);
    if fields.len() == n {
        Ok(fields)
    } else {
        Err(RowError::FieldCount {
            found: fields.len(),
            expected: n,
        })
    }
}

fn number(text: &str, name: &'static str) -> Result<f64, RowError> {
    text.parse()
        .map_err(|_| RowError::value(name, text, "number"))
}

fn whole(text: &str, name: &'static str) -> Result<usize, RowError> {
    text.parse()
        .map_err(|_| RowError::value(name, text, "whole number"))
}

/// A CSV row of ours that cannot be read back.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RowError {
    /// Too many or too few fields.
    #[error("{found} fields, {expected} expected")]
    FieldCount {
        /// Fields found.
        found: usize,
        /// Fields of the table.
        expected: usize,
    },
    /// A field that is not what its column holds.
    #[error("{column}: {text:?} is not a {expected}")]
    Value {
        /// The column.
        column: &'static str,
        /// The field as written.
        text: String,
        /// What the column holds (`number`, `solver`, …).
        expected: &'static str,
    },
}

impl RowError {
    fn value(column: &'static str, text: &str, expected: &'static str) -> Self {
        RowError::Value {
            column,
            text: text.to_string(),
            expected,
        }
    }
}

/// `outer_diameter_m,…`: one row per section a sizing tried, in the order
/// tried; missing numbers are empty.
pub fn sizing_csv(trials: &[SectionTrial]) -> String {
    let mut s = String::from(
        "outer_diameter_m,inner_diameter_m,youngs_modulus_pa,density_kg_per_m3,mass_kg,margin,\
         bound,outer_iterations,termination,rms_mm,carries,time_s,failure\n",
    );
    for t in trials {
        let c = &t.section;
        let _ = writeln!(
            s,
            "{:.7},{:.7},{},{},{},{:.6},{},{},{},{},{},{:.3},{}",
            c.outer_diameter_m,
            c.inner_diameter_m,
            readable(c.youngs_modulus_pa, 7),
            readable(c.density_kg_per_m3, 7),
            readable(t.mass_kg, 7),
            t.margin,
            t.bound.map_or("", |b| b.kind()),
            t.summary.map_or(0, |s| s.outer_iterations),
            t.summary
                .map_or(String::new(), |s| json_name(&s.termination)),
            t.rms_mm.map_or(String::new(), |v| readable(v, 7)),
            t.carries,
            t.time_s,
            t.failure.as_deref().map_or(String::new(), quote),
        );
    }
    s
}

/// `aperture_m,…`: one row per aperture and design model (rigid, linear,
/// exact), the aperture's figures repeated on each.
pub fn aperture_csv(results: &[ApertureResult]) -> String {
    let mut s = String::from(
        "aperture_m,rings,nodes,outer_diameter_m,inner_diameter_m,truss_mass_kg,margin,\
         sizing_designs,sizing_time_s,hinge_motion_mm,model,outer_iterations,ratio,built_ratio,\
         rms_mm,max_deviation_mm,tension_change_pct,cut_length_error_mm,boundary_deviation_mm,\
         slack_cables,design_time_s,assembly_time_s\n",
    );
    for r in results {
        for m in &r.models {
            let _ = writeln!(
                s,
                "{},{},{},{:.7},{:.7},{},{:.6},{},{:.3},{},{},{},{},{},{},{},{},{},{},{},{:.3},{:.3}",
                r.aperture_m,
                r.rings,
                r.nodes,
                r.section.outer_diameter_m,
                r.section.inner_diameter_m,
                readable(r.truss_mass_kg, 7),
                r.margin,
                r.sizing_designs,
                r.sizing_time_s,
                readable(r.hinge_motion_mm, 7),
                value_name(&m.model),
                m.outer_iterations,
                finite(m.ratio, 11),
                finite(m.built_ratio, 11),
                readable(m.rms_mm, 7),
                readable(m.max_deviation_mm, 7),
                readable(m.tension_change_pct, 7),
                readable(m.cut_length_error_mm, 7),
                readable(m.boundary_deviation_mm, 7),
                m.slack_cables,
                m.design_time_s,
                m.assembly_time_s,
            );
        }
    }
    s
}

/// `v` with `digits` significant digits, or nothing when it is not finite.
fn finite(v: f64, digits: usize) -> String {
    if v.is_finite() {
        readable(v, digits)
    } else {
        String::new()
    }
}

/// `relaxation,iteration,…`: one row per outer iteration of every run.
pub fn convergence_csv(runs: &[LoopRun]) -> String {
    let mut s = String::from(
        "relaxation,iteration,boundary_change_max_m,boundary_change_rms_m,xi_change_m,ratio,\
         relaxation_factor,oracle_newton_iterations,design_time_s,truss_time_s,elapsed_s\n",
    );
    for run in runs {
        for r in &run.history {
            let _ = writeln!(
                s,
                "{},{},{},{},{},{},{},{},{},{},{}",
                run.relaxation.name(),
                r.iteration,
                readable(r.boundary_change_max_m, 7),
                readable(r.boundary_change_rms_m, 7),
                r.xi_change_m.map_or(String::new(), |v| readable(v, 7)),
                readable(r.ratio, 13),
                readable(r.relaxation_factor, 7),
                r.oracle_newton_iterations,
                readable(r.design_time_s, 7),
                readable(r.truss_time_s, 7),
                readable(r.elapsed_s, 7)
            );
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::status::Termination;

    #[test]
    fn study_rows_read_back_as_written() {
        let row = StudyRow {
            knob: Knob::Solver,
            value: "least-squares".into(),
            settings: RunSettings {
                tolerance_m: 1e-6,
                elements_per_rod: 4,
                rings: 3,
                truss: TrussModel::Exact,
                solver: SolverKind::LeastSquares,
            },
            time_s: 0.25,
            summary: Some(LoopSummary {
                termination: Termination::MaxIterations,
                outer_iterations: 4,
                boundary_residual_m: 2.5e-8,
                time_s: 0.125,
            }),
            ratio: 1.25,
            built_ratio: 1.5,
            ratio_error: 0.125,
            rms_mm: 1e-6,
            max_deviation_mm: 2e-6,
            facet_rms_mm: 3.0,
            tension_change_pct: 0.5,
            cut_length_error_mm: f64::NAN,
            error: Some("outer iteration 2: a \"quoted\", comma\nand a line".into()),
        };
        let line = study_row(&row);
        assert!(!line.contains('\n'));
        let back = parse_study_row(&line).unwrap();
        assert_eq!(study_row(&back), line);
        assert_eq!(back.knob, Knob::Solver);
        assert_eq!(back.settings, row.settings);
        let summary = back.summary.expect("the loop's summary read back");
        assert_eq!(summary.termination, Termination::MaxIterations);
        assert_eq!(summary.outer_iterations, 4);
        assert_eq!(summary.boundary_residual_m, 2.5e-8);
        assert!(
            summary.time_s.is_nan(),
            "the file holds the design's time only"
        );
        assert!(back.cut_length_error_mm.is_nan());
        assert_eq!(
            back.error.as_deref(),
            Some("outer iteration 2: a \"quoted\", comma and a line")
        );
        assert_eq!(STUDY_COLUMNS.split(',').count(), 20);

        // A point that failed before its loop ended: no summary, either way.
        let failed = StudyRow {
            summary: None,
            ratio: f64::NAN,
            ..row.clone()
        };
        let line = study_row(&failed);
        let back = parse_study_row(&line).unwrap();
        assert_eq!(back.summary, None);
        assert_eq!(study_row(&back), line);
        // Iterations without a termination is no row of ours.
        let whole_row = study_row(&row);
        let mut torn: Vec<&str> = whole_row.splitn(11, ',').collect();
        torn[9] = "";
        assert!(parse_study_row(&torn.join(",")).is_err());
    }

    #[test]
    fn front_rows_read_back_as_written() {
        let row = FrontRow {
            solver: "bisection".into(),
            knob: 0.07,
            ratio: 1.2345678901234,
            rms_mm: 1.5e-3,
            time_s: 0.01,
        };
        let line = front_row(&row);
        assert_eq!(front_row(&parse_front_row(&line).unwrap()), line);
        assert!(parse_front_row("bisection,1,2").is_err());
    }
}
