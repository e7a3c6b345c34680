//! `ringmesh cantilever`: the paper's cantilever under a tip moment (§3.4,
//! Tables 1–2) beside the closed form and the paper's figures.

use std::path::Path;

use serde::Serialize;

use super::Summary;
use crate::frame::cantilever::{self, CantileverRow};
use crate::frame::FrameFileError;
use crate::mechanics::ElementKind;
use crate::report::{json_bytes, OutputPath, OutputSet};
use crate::Error;

/// One row of `ringmesh cantilever`: the engine's row and the paper's result
/// where the paper gives one.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CantileverTableRow {
    /// Ours, the closed form, the error and the solver's statistics.
    #[serde(flatten)]
    pub row: CantileverRow,
    /// The paper's tip axial displacement (Tables 1–2, 10 elements), m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub paper_axial_m: Option<f64>,
    /// The paper's tip vertical displacement, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub paper_vertical_m: Option<f64>,
}

/// The output of `ringmesh cantilever`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CantileverTable {
    /// Elements along the cantilever.
    pub elements: usize,
    /// The element type.
    pub element: String,
    /// One row per load `ML/(πEI)` of [`cantilever::M_RATIOS`].
    pub rows: Vec<CantileverTableRow>,
}

impl CantileverTable {
    /// What `ringmesh cantilever` prints: the table as pretty JSON when
    /// `as_json`, else as text, one load per line.
    pub fn summary(&self, as_json: bool) -> Summary {
        let mut s = Summary::default();
        if as_json {
            say!(
                s,
                "{}",
                serde_json::to_string_pretty(self).expect("a table serialises")
            );
        } else {
            self.text(&mut s);
        }
        s
    }

    /// The table as text, one load per line.
    fn text(&self, s: &mut Summary) {
        say!(
            s,
            "cantilever L = 10, EI = 100 under a tip moment: {} {} elements (paper §3.4, Tables 1-2)",
            self.elements,
            self.element
        );
        say!(
            s,
            "{:>9} | {:>9} {:>9} | {:>9} {:>9} | {:>9} {:>9} | {:>9} | {:>6} {:>5} {:>9}",
            "ML/(πEI)",
            "analytic",
            "",
            "paper",
            "",
            "ours",
            "",
            "rel. err",
            "Newton",
            "steps",
            "time ms"
        );
        say!(
            s,
            "{:>9} | {:>9} {:>9} | {:>9} {:>9} | {:>9} {:>9} | {:>9} | {:>6} {:>5} {:>9}",
            "",
            "axial",
            "vertical",
            "axial",
            "vertical",
            "axial",
            "vertical",
            "",
            "",
            "",
            ""
        );
        for r in &self.rows {
            let paper = |v: Option<f64>| v.map_or_else(|| "—".to_string(), |v| format!("{v:.5}"));
            let row = &r.row;
            say!(
                s,
                "{:>9.1} | {:>9.5} {:>9.5} | {:>9} {:>9} | {:>9.5} {:>9.5} | {:>9.2e} | {:>6} {:>5} {:>9.3}{}",
                row.m_ratio,
                row.analytic_axial_m,
                row.analytic_vertical_m,
                paper(r.paper_axial_m),
                paper(r.paper_vertical_m),
                row.axial_m,
                row.vertical_m,
                row.relative_error,
                row.newton_iterations,
                row.load_steps,
                1e3 * row.time_s,
                if row.converged { "" } else { "  NOT CONVERGED" }
            );
        }
    }
}

/// `ringmesh cantilever`: the paper's Tables 1–2 (§3.4) with `elements`
/// elements of `kind`, every load from 0.2 to the full circle; with
/// `output`, also written there: a folder receives `cantilever.json`, a
/// path ending in `.json` is the file ([`OutputPath`]); its folder is
/// checked before computing.
///
/// # Errors
/// The engine's, and the writer's.
pub fn cantilever(
    elements: usize,
    kind: ElementKind,
    output: Option<&Path>,
) -> Result<CantileverTable, Error> {
    crate::resources::check_frame(&format!("--elements {elements}"), elements)?;
    let target = output
        .map(|o| OutputPath::resolve(o).map(|t| t.folder_and_name("cantilever.json")))
        .transpose()?;
    if let Some((dir, _)) = &target {
        OutputSet::check_folder(dir)?;
    }
    let rows = cantilever::table(elements, kind)
        .map_err(FrameFileError::from)?
        .into_iter()
        .map(|row| {
            let paper = cantilever::PAPER.iter().find(|p| p.0 == row.m_ratio);
            CantileverTableRow {
                paper_axial_m: paper.map(|p| p.1),
                paper_vertical_m: paper.map(|p| p.2),
                row,
            }
        })
        .collect();
    let table = CantileverTable {
        elements,
        element: kind.name().to_string(),
        rows,
    };
    if let Some((dir, name)) = target {
        let bytes = json_bytes(&dir.join(&name), &table)?;
        OutputSet::write_one(&dir, &name, &bytes)?;
    }
    Ok(table)
}
