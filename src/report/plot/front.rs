//! The design front: `Tmax/Tmin` against the surface RMS of a forward
//! solve, or the total with the net's facet RMS, one curve per solver, each
//! point labelled with its knob — and the same points with their wall time
//! for `Tmax/Tmin` ([`FrontY::Time`]): what each strategy's accuracy costs
//! in time, every solver on one axis pair.

use std::path::Path;

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

/// What a front figure's vertical axis shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrontY {
    /// `Tmax/Tmin` (linear): the design front.
    Ratio,
    /// The point's wall time, s (logarithmic): the strategies' cost.
    Time,
}

impl FrontY {
    /// The value `row` is drawn at.
    fn of(self, row: &FrontRow) -> f64 {
        match self {
            FrontY::Ratio => row.ratio,
            FrontY::Time => row.time_s,
        }
    }
}

pub(super) fn draw_front<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    points: &[FrontRow],
    failed: Option<&[(String, f64)]>,
    (rms, y_axis): (&FrontRms, FrontY),
    title: &str,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let ok: Vec<&FrontRow> = points
        .iter()
        .filter(|p| p.ratio.is_finite() && (y_axis == FrontY::Ratio || p.time_s > 0.0))
        .collect();
    let (plot, legend) = titled_with_legend(&root, title, 72)?;
    let x = |p: &FrontRow| rms.of(p).max(RMS_FLOOR_MM);
    let (mut x_lo, mut x_hi, mut y_lo, mut y_hi) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for p in &ok {
        x_lo = x_lo.min(x(p));
        x_hi = x_hi.max(x(p));
        y_lo = y_lo.min(y_axis.of(p));
        y_hi = y_hi.max(y_axis.of(p));
    }
    if ok.is_empty() {
        (x_lo, x_hi, y_lo, y_hi) = (RMS_FLOOR_MM, 1.0, 1.0, 2.0);
    }
    let (y_lo, y_hi) = match y_axis {
        FrontY::Ratio => ((y_lo * 0.95).max(1.0 - 1e-9), y_hi * 1.05 + 1e-9),
        FrontY::Time => (y_lo / 2.0, (y_hi * 2.0).max(y_lo * 10.0)),
    };
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
    // the facets, rarely spans one: a linear axis fitted to it. Times span
    // decades too.
    let x_range = match rms {
        FrontRms::Design => (x_lo / 2.0)..(x_hi * 4.0).max(x_lo * 10.0),
        FrontRms::Total { .. } => {
            let span = (x_hi - x_lo).max(0.05 * x_hi);
            (x_lo - 0.15 * span)..(x_hi + 0.25 * span)
        }
    };
    let x_log = matches!(rms, FrontRms::Design);
    let points = FrontPoints {
        ok: &ok,
        solvers: &solvers,
        colour: &colour,
        rms,
        y_axis,
    };
    match (x_log, y_axis) {
        (true, FrontY::Ratio) => {
            let chart = builder.build_cartesian_2d(x_range.log_scale(), y_lo..y_hi)?;
            points.draw(chart, true)?;
        }
        (true, FrontY::Time) => {
            let chart =
                builder.build_cartesian_2d(x_range.log_scale(), (y_lo..y_hi).log_scale())?;
            points.draw(chart, true)?;
        }
        (false, FrontY::Ratio) => {
            let chart = builder.build_cartesian_2d(x_range, y_lo..y_hi)?;
            points.draw(chart, false)?;
        }
        (false, FrontY::Time) => {
            let chart = builder.build_cartesian_2d(x_range, (y_lo..y_hi).log_scale())?;
            points.draw(chart, false)?;
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

/// The front's points to draw: those with a value, their solvers and
/// colours, and the axes they are drawn against.
struct FrontPoints<'a> {
    ok: &'a [&'a FrontRow],
    solvers: &'a [&'a str],
    colour: &'a dyn Fn(&str) -> RGBAColor,
    rms: &'a FrontRms,
    y_axis: FrontY,
}

impl FrontPoints<'_> {
    /// The mesh of `chart` (x logarithmic when `x_log`) and the points on
    /// it (x: the RMS `rms` draws them at, floored at [`RMS_FLOOR_MM`]):
    /// one line per solver, each point labelled with its knob where the
    /// label has room.
    fn draw<DB, X, Y>(
        &self,
        mut chart: ChartContext<'_, DB, Cartesian2d<X, Y>>,
        x_log: bool,
    ) -> Result<(), DrawError>
    where
        DB: DrawingBackend,
        DB::ErrorType: 'static,
        X: Ranged<ValueType = f64> + plotters::coord::ranged1d::ValueFormatter<f64>,
        Y: Ranged<ValueType = f64> + plotters::coord::ranged1d::ValueFormatter<f64>,
    {
        let (rms, y_axis) = (self.rms, self.y_axis);
        let x_format = |v: &f64| match x_log {
            true => format!("{v:.0e}"),
            false => readable(*v, 4),
        };
        let y_format = |v: &f64| match y_axis {
            FrontY::Ratio => readable(*v, 4),
            FrontY::Time => readable(*v, 2),
        };
        chart
            .configure_mesh()
            .x_desc(rms.caption())
            .x_label_formatter(&x_format)
            .y_desc(match y_axis {
                FrontY::Ratio => "Tmax / Tmin",
                FrontY::Time => "wall time of the design (s)",
            })
            .y_label_formatter(&y_format)
            .label_style(("sans-serif", 14))
            .draw()?;
        let x = |p: &FrontRow| rms.of(p).max(RMS_FLOOR_MM);
        let mut anchors = Vec::new();
        for solver in self.solvers {
            let c = (self.colour)(solver);
            let mut series: Vec<&FrontRow> = self
                .ok
                .iter()
                .copied()
                .filter(|p| p.solver == *solver)
                .collect();
            series.sort_by(|a, b| x(a).total_cmp(&x(b)));
            chart.draw_series(LineSeries::new(
                series.iter().map(|p| (x(p), y_axis.of(p))),
                c.stroke_width(2),
            ))?;
            // A point below the axis floor is drawn at it, hollow.
            chart.draw_series(series.iter().map(|p| {
                let style = if rms.of(p) < RMS_FLOOR_MM {
                    c.stroke_width(2)
                } else {
                    c.filled()
                };
                Circle::new((x(p), y_axis.of(p)), 4, style)
            }))?;
            anchors.extend(
                series
                    .iter()
                    .map(|p| ((x(p), y_axis.of(p)), knob_label(p.knob))),
            );
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
    axes: (&FrontRms, FrontY),
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
        axes,
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
