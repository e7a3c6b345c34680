//! The sizing's figure: each tube section tried, its limit margin against
//! the truss's mass, the margin asked for as a line and the chosen section
//! marked.

use std::path::Path;

use plotters::prelude::*;

use super::canvas::{png_and_svg, titled_with_legend};
use super::labels::{label_font, place_labels};
use crate::report::{DrawError, ReportError};
use crate::sizing::SectionTrial;

/// A section's label: its outer/inner diameters, mm.
fn section_label(t: &SectionTrial) -> String {
    format!(
        "{:.1}/{:.1} mm",
        1e3 * t.section.outer_diameter_m,
        1e3 * t.section.inner_diameter_m
    )
}

pub(super) fn draw_sizing<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    trials: &[SectionTrial],
    chosen: usize,
    margin: f64,
    title: &str,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let (chart_area, legend) = titled_with_legend(&root, title, 35)?;
    let (m0, m1) = trials.iter().fold((f64::INFINITY, 0.0f64), |(a, b), t| {
        (a.min(t.mass_kg), b.max(t.mass_kg))
    });
    let pad = 0.08 * (m1 - m0).max(0.1 * m1).max(1e-3);
    let top = trials
        .iter()
        .map(|t| t.margin)
        .fold(margin, f64::max)
        .max(1.0)
        * 1.15;
    let mut chart = ChartBuilder::on(&chart_area)
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(65)
        .build_cartesian_2d((m0 - pad)..(m1 + pad), 0.0..top)?;
    chart
        .configure_mesh()
        .x_desc("mass of the truss's tubes (kg)")
        .y_desc("limit margin (multiple of the design's pull)")
        .label_style(("sans-serif", 14))
        .draw()?;
    chart.draw_series(LineSeries::new(
        [(m0 - pad, margin), (m1 + pad, margin)],
        BLACK.stroke_width(1),
    ))?;
    let colour = |t: &SectionTrial| if t.carries { BLUE } else { RED };
    chart.draw_series(
        trials
            .iter()
            .map(|t| Circle::new((t.mass_kg, t.margin), 4, colour(t).filled())),
    )?;
    let c = &trials[chosen];
    chart.draw_series(std::iter::once(Circle::new(
        (c.mass_kg, c.margin),
        9,
        BLACK.stroke_width(2),
    )))?;
    let labels: Vec<String> = trials
        .iter()
        .enumerate()
        .map(|(k, t)| {
            let name = section_label(t);
            if k == chosen {
                format!("{name} (chosen)")
            } else {
                name
            }
        })
        .collect();
    let anchors: Vec<((i32, i32), Option<&str>)> = trials
        .iter()
        .zip(&labels)
        .map(|(t, l)| {
            (
                chart.backend_coord(&(t.mass_kg, t.margin)),
                Some(l.as_str()),
            )
        })
        .collect();
    let font = label_font();
    for ((point, label), offset) in anchors.iter().zip(place_labels(&anchors)) {
        if let (Some(label), Some((dx, dy))) = (label, offset) {
            root.draw(&Text::new(
                label.to_string(),
                (point.0 + dx, point.1 + dy),
                font.clone(),
            ))?;
        }
    }
    let font = ("sans-serif", 15).into_font();
    let mut x = 90;
    for (text, colour) in [("carries", BLUE), ("does not carry", RED)] {
        legend.draw(&Circle::new((x, 15), 4, colour.filled()))?;
        legend.draw(&Text::new(text, (x + 10, 7), font.clone()))?;
        x += 40 + 9 * text.len() as i32;
    }
    legend.draw(&PathElement::new(vec![(x, 15), (x + 25, 15)], BLACK))?;
    let asked = format!("margin asked for: {margin}");
    legend.draw(&Text::new(asked.as_str(), (x + 32, 7), font.clone()))?;
    x += 60 + 9 * asked.len() as i32;
    legend.draw(&Circle::new((x, 15), 9, BLACK.stroke_width(2)))?;
    legend.draw(&Text::new(
        "the chosen section: the lightest that carries",
        (x + 15, 7),
        font,
    ))?;
    Ok(root.present()?)
}

/// Draws the sizing as PNG and SVG, each written atomically: the limit
/// margin of every section tried against the mass of its tubes, those that
/// carry the net in blue, the margin asked for as a line, the chosen section
/// ringed.
///
/// # Panics
/// If `chosen` is not an index of `trials`.
#[track_caller]
pub fn sizing_plot(
    trials: &[SectionTrial],
    chosen: usize,
    margin: f64,
    title: &str,
    png: &Path,
    svg: &Path,
) -> Result<(), ReportError> {
    assert!(chosen < trials.len(), "chosen section out of range");
    png_and_svg!(
        draw_sizing,
        (1100, 700),
        png,
        svg,
        trials,
        chosen,
        margin,
        title
    )
}
