//! The design front: `Tmax/Tmin` against the surface RMS of a forward
//! solve, or the total with the net's facet RMS, one curve per solver, each
//! point labelled with its knob.

use std::path::Path;

use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

use super::canvas::{png_and_svg, titled_with_legend};
use super::labels::{label_font, place_labels};
use super::{total_rms_mm, RMS_FLOOR_MM};
use crate::report::{readable, DrawError, FrontRow, ReportError};
use crate::uniformity::SolverKind;

/// The surface RMS the front's points are drawn at (`--rms`,
/// [`super::RmsAxis`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrontRms {
    /// Each point's RMS from its forward solve.
    Design,
    /// The total `√(facets_mm² + forward-solve RMS²)` ([`total_rms_mm`]).
    Total {
        /// Facet RMS of the net's design surface, mm: one number for the
        /// front, whose points all design one net.
        facets_mm: f64,
    },
}

impl FrontRms {
    /// The RMS `row` is drawn at, mm.
    pub fn of(&self, row: &FrontRow) -> f64 {
        match self {
            FrontRms::Design => row.rms_mm,
            FrontRms::Total { facets_mm } => total_rms_mm(*facets_mm, row.rms_mm),
        }
    }

    /// The axis's caption.
    fn caption(&self) -> String {
        match self {
            FrontRms::Design => "surface RMS from a forward solve (mm)".to_string(),
            FrontRms::Total { facets_mm } => format!(
                "total surface RMS √(facets² + forward solve²) (mm); facets: facet RMS of \
                 the design surface, {} mm",
                readable(*facets_mm, 4)
            ),
        }
    }
}

pub(super) fn draw_front<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    points: &[FrontRow],
    failed: Option<&[(String, f64)]>,
    rms: &FrontRms,
    title: &str,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let ok: Vec<&FrontRow> = points.iter().filter(|p| p.ratio.is_finite()).collect();
    let (plot, legend) = titled_with_legend(&root, title, 72)?;
    let x = |p: &FrontRow| rms.of(p).max(RMS_FLOOR_MM);
    let (mut x_lo, mut x_hi, mut y_lo, mut y_hi) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for p in &ok {
        x_lo = x_lo.min(x(p));
        x_hi = x_hi.max(x(p));
        y_lo = y_lo.min(p.ratio);
        y_hi = y_hi.max(p.ratio);
    }
    if ok.is_empty() {
        (x_lo, x_hi, y_lo, y_hi) = (RMS_FLOOR_MM, 1.0, 1.0, 2.0);
    }
    let (y_lo, y_hi) = ((y_lo * 0.95).max(1.0 - 1e-9), y_hi * 1.05 + 1e-9);
    let mut solvers: Vec<&str> = Vec::new();
    let failures = failed.unwrap_or_default();
    for p in ok
        .iter()
        .map(|p| p.solver.as_str())
        .chain(failures.iter().map(|f| f.0.as_str()))
    {
        if !solvers.contains(&p) {
            solvers.push(p);
        }
    }
    let colour = |solver: &str| {
        Palette99::pick(solvers.iter().position(|s| *s == solver).unwrap_or(0)).to_rgba()
    };
    let mut builder = ChartBuilder::on(&plot);
    builder
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(60);
    // The design's RMS spans decades: a logarithmic axis. The total, led by
    // the facets, rarely spans one: a linear axis fitted to it.
    match rms {
        FrontRms::Design => {
            let x_range = (x_lo / 2.0)..(x_hi * 4.0).max(x_lo * 10.0);
            let mut chart = builder.build_cartesian_2d(x_range.log_scale(), y_lo..y_hi)?;
            chart
                .configure_mesh()
                .x_desc(rms.caption())
                .x_label_formatter(&|v| format!("{v:.0e}"))
                .y_desc("Tmax / Tmin")
                .label_style(("sans-serif", 14))
                .draw()?;
            draw_front_points(&mut chart, &ok, &solvers, &colour, rms)?;
        }
        FrontRms::Total { .. } => {
            let span = (x_hi - x_lo).max(0.05 * x_hi);
            let x_range = (x_lo - 0.15 * span)..(x_hi + 0.25 * span);
            let mut chart = builder.build_cartesian_2d(x_range, y_lo..y_hi)?;
            chart
                .configure_mesh()
                .x_desc(rms.caption())
                .x_label_formatter(&|v| readable(*v, 4))
                .y_desc("Tmax / Tmin")
                .label_style(("sans-serif", 14))
                .draw()?;
            draw_front_points(&mut chart, &ok, &solvers, &colour, rms)?;
        }
    }
    // The legend below the plot: the solvers, the floor, the failures.
    let font = ("sans-serif", 14).into_font();
    let mut at = 70;
    for solver in &solvers {
        let c = colour(solver);
        legend.draw(&PathElement::new(
            vec![(at, 14), (at + 22, 14)],
            c.stroke_width(2),
        ))?;
        legend.draw(&Text::new(solver.to_string(), (at + 28, 6), font.clone()))?;
        at += 50 + 8 * solver.len() as i32;
    }
    match rms {
        FrontRms::Design => {
            legend.draw(&Circle::new((at, 14), 4, BLACK.stroke_width(2)))?;
            legend.draw(&Text::new(
                format!("RMS below {RMS_FLOOR_MM:e} mm (an exact 0 among them), drawn at it"),
                (at + 10, 6),
                font.clone(),
            ))?;
        }
        // The total is at least the facet RMS: never below the floor.
        FrontRms::Total { .. } => {}
    }
    legend.draw(&Text::new(knobs_caption(&solvers), (70, 52), font.clone()))?;
    let failures = match failed {
        None => "failed points: not recorded in shards (see each shard's run)".to_string(),
        Some([]) => "no failed point".to_string(),
        Some(failed) => {
            let list: Vec<String> = failed
                .iter()
                .map(|(solver, knob)| match solver_kind(solver) {
                    Some(kind) => format!("{solver} {}", kind.knob_text(&readable(*knob, 3))),
                    None => format!("{solver} at {}", readable(*knob, 3)),
                })
                .collect();
            format!("failed, no design (not drawn): {}", list.join(", "))
        }
    };
    legend.draw(&Text::new(failures, (70, 32), font))?;
    Ok(root.present()?)
}

/// The front's points on `chart` (x: the RMS `rms` draws them at, floored
/// at [`RMS_FLOOR_MM`]): one line per solver, each point labelled with its
/// knob where the label has room.
fn draw_front_points<DB, X>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, RangedCoordf64>>,
    ok: &[&FrontRow],
    solvers: &[&str],
    colour: &dyn Fn(&str) -> RGBAColor,
    rms: &FrontRms,
) -> Result<(), DrawError>
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
    X: Ranged<ValueType = f64>,
{
    let x = |p: &FrontRow| rms.of(p).max(RMS_FLOOR_MM);
    let mut anchors = Vec::new();
    for solver in solvers {
        let c = colour(solver);
        let mut series: Vec<&FrontRow> =
            ok.iter().copied().filter(|p| p.solver == *solver).collect();
        series.sort_by(|a, b| x(a).total_cmp(&x(b)));
        chart.draw_series(LineSeries::new(
            series.iter().map(|p| (x(p), p.ratio)),
            c.stroke_width(2),
        ))?;
        // A point below the axis floor is drawn at it, hollow.
        chart.draw_series(series.iter().map(|p| {
            let style = if rms.of(p) < RMS_FLOOR_MM {
                c.stroke_width(2)
            } else {
                c.filled()
            };
            Circle::new((x(p), p.ratio), 4, style)
        }))?;
        anchors.extend(series.iter().map(|p| ((x(p), p.ratio), knob_label(p.knob))));
    }
    // Each point labelled with its knob, where the label has room.
    let pixels: Vec<((i32, i32), Option<&str>)> = anchors
        .iter()
        .map(|(p, label)| (chart.backend_coord(p), Some(label.as_str())))
        .collect();
    let offsets = place_labels(&pixels);
    chart.draw_series(
        anchors
            .iter()
            .zip(offsets)
            .filter_map(|((p, label), offset)| {
                let offset = offset?;
                Some(EmptyElement::at(*p) + Text::new(label.clone(), offset, label_font()))
            }),
    )?;
    Ok(())
}

/// Draws the design front (ratio against actual surface RMS — the forward
/// solve's, or the total with the net's facet RMS: `rms` —, one curve per
/// solver, each point labelled with its knob where there is room; a point
/// below the RMS floor drawn hollow at it) as PNG and SVG, each written
/// atomically; the legend, below the plot, lists the `failed` points
/// (solver, knob), or says they are unknown (`None`: a merged front).
pub fn front_plot(
    points: &[FrontRow],
    failed: Option<&[(String, f64)]>,
    rms: &FrontRms,
    title: &str,
    png: &Path,
    svg: &Path,
) -> Result<(), ReportError> {
    png_and_svg!(
        draw_front,
        (1000, 680),
        png,
        svg,
        points,
        failed,
        rms,
        title
    )
}

/// A solver by its name in a front's rows.
fn solver_kind(name: &str) -> Option<SolverKind> {
    <SolverKind as clap::ValueEnum>::from_str(name, false).ok()
}

/// What the points' labels are: each solver's knob named, with its unit.
fn knobs_caption(solvers: &[&str]) -> String {
    let named: Vec<String> = solvers
        .iter()
        .filter_map(|s| Some(format!("{s}: {}", solver_kind(s)?.knob_label()?)))
        .collect();
    format!("point labels: each solver's knob — {}", named.join("; "))
}

/// A knob value as a point's label: one significant digit.
fn knob_label(knob: f64) -> String {
    if knob == 0.0 {
        "0".into()
    } else {
        format!("{knob:.0e}")
    }
}
