//! The error budget's figure (`ringmesh budget`): a bar chart of every term
//! (raw and about the best fit, log scale) and the Monte Carlo's
//! distribution of the best-fit RMS, nonlinear and linearised.

use std::path::Path;

use plotters::prelude::*;

use super::canvas::{png_and_svg, titled_with_legend};
use crate::budget::BudgetTable;
use crate::report::{DrawError, ReportError};

/// Floor of the bar chart's logarithmic axis, mm.
const FLOOR_MM: f64 = 1e-9;

/// Bins of the histogram.
const BINS: usize = 20;

fn draw_bars<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    table: &BudgetTable,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let terms = &table.terms;
    let hi = terms
        .iter()
        .flat_map(|t| [t.raw_mm, t.best_fit_mm])
        .filter(|v| v.is_finite())
        .fold(FLOOR_MM, f64::max)
        * 3.0;
    let n = terms.len() as f64;
    let mut chart = ChartBuilder::on(area)
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(150)
        .build_cartesian_2d((FLOOR_MM..hi).log_scale(), 0.0..n)?;
    let names: Vec<String> = terms.iter().map(|t| t.term.clone()).collect();
    chart
        .configure_mesh()
        .disable_y_mesh()
        .x_desc("axial RMS (mm)")
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_labels(terms.len() * 2 + 1)
        .y_label_formatter(&|y| {
            let k = y.floor();
            if (y - k - 0.5).abs() < 0.01 && k >= 0.0 && (k as usize) < names.len() {
                names[names.len() - 1 - k as usize].clone()
            } else {
                String::new()
            }
        })
        .label_style(("sans-serif", 13))
        .draw()?;
    for (i, t) in terms.iter().enumerate() {
        let y = n - 1.0 - i as f64;
        for (value, offset, colour) in [
            (t.raw_mm, 0.5, RGBColor(170, 170, 170)),
            (t.best_fit_mm, 0.15, RGBColor(30, 90, 200)),
        ] {
            if value.is_finite() {
                chart.draw_series(std::iter::once(Rectangle::new(
                    [
                        (FLOOR_MM, y + offset),
                        (value.max(FLOOR_MM), y + offset + 0.33),
                    ],
                    colour.filled(),
                )))?;
            }
        }
    }
    Ok(())
}

fn draw_histogram<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    nonlinear: &[f64],
    linear: &[f64],
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let all = nonlinear.iter().chain(linear).filter(|v| v.is_finite());
    let (lo, hi) = all.fold((f64::INFINITY, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
    let (lo, hi) = if lo.is_finite() && hi > lo {
        (lo, hi)
    } else {
        (0.0, hi.max(1e-9) * 2.0)
    };
    let width = (hi - lo) / BINS as f64;
    let counts = |values: &[f64]| {
        let mut c = vec![0usize; BINS];
        for &v in values.iter().filter(|v| v.is_finite()) {
            c[(((v - lo) / width) as usize).min(BINS - 1)] += 1;
        }
        c
    };
    let (cn, cl) = (counts(nonlinear), counts(linear));
    let top = cn.iter().chain(&cl).copied().max().unwrap_or(1).max(1) as f64 * 1.1;
    let mut chart = ChartBuilder::on(area)
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d(lo..hi, 0.0..top)?;
    chart
        .configure_mesh()
        .x_desc("tolerances: best-fit RMS of a sample (mm)")
        .y_desc("samples")
        .x_label_formatter(&|v| format!("{v:.2e}"))
        .label_style(("sans-serif", 14))
        .draw()?;
    for (c, colour, filled) in [(&cn, RGBColor(30, 90, 200), true), (&cl, BLACK, false)] {
        chart.draw_series(c.iter().enumerate().map(|(b, &k)| {
            let x0 = lo + b as f64 * width;
            let style = if filled {
                colour.mix(0.5).filled()
            } else {
                colour.stroke_width(2)
            };
            Rectangle::new([(x0, 0.0), (x0 + width, k as f64)], style)
        }))?;
    }
    Ok(())
}

pub(super) fn draw_budget<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    table: &BudgetTable,
    samples: &[(f64, f64)],
    title: &str,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let (charts, legend) = titled_with_legend(&root, title, 35)?;
    let panels = charts.split_evenly((1, 2));
    let font = ("sans-serif", 15).into_font();
    let mut x = 90;
    for (name, colour) in [
        ("raw (design paraboloid)", RGBColor(170, 170, 170)),
        ("best fit; histogram: nonlinear", RGBColor(30, 90, 200)),
        ("histogram: linearised", BLACK),
    ] {
        legend.draw(&Rectangle::new([(x, 8), (x + 25, 22)], colour.filled()))?;
        legend.draw(&Text::new(name, (x + 32, 7), font.clone()))?;
        x += 60 + 9 * name.len() as i32;
    }
    draw_bars(&panels[0], table)?;
    let nonlinear: Vec<f64> = samples.iter().map(|s| s.0).collect();
    let linear: Vec<f64> = samples.iter().map(|s| s.1).collect();
    draw_histogram(&panels[1], &nonlinear, &linear)?;
    Ok(root.present()?)
}

/// Draws the budget as PNG and SVG, each written atomically: the terms of
/// `table` as bars (raw and best fit, log scale, values below 1e-9 mm at
/// that floor) and the samples' best-fit RMS, `(nonlinear, linearised)` mm,
/// as histograms.
pub fn budget_plot(
    table: &BudgetTable,
    samples: &[(f64, f64)],
    title: &str,
    png: &Path,
    svg: &Path,
) -> Result<(), ReportError> {
    png_and_svg!(draw_budget, (1600, 700), png, svg, table, samples, title)
}
