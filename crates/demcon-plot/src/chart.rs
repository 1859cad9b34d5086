//! Line charts: curves (lines with markers, or markers only) on linear or log axes, with a
//! legend — probes against time, profiles along their lines, the report's comparisons.

use std::path::Path;

use plotters::prelude::*;

use crate::{PlotError, with_png};

/// One curve of a chart.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend label.
    pub label: String,
    /// Points (x, y).
    pub points: Vec<(f64, f64)>,
    /// Draw as markers only (references), or as a line with markers.
    pub markers_only: bool,
}

impl Series {
    /// A line with markers.
    pub fn line(label: &str, points: Vec<(f64, f64)>) -> Self {
        Self {
            label: label.into(),
            points,
            markers_only: false,
        }
    }

    /// Markers only.
    pub fn markers(label: &str, points: Vec<(f64, f64)>) -> Self {
        Self {
            label: label.into(),
            points,
            markers_only: true,
        }
    }
}

/// Axis scale.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Scale {
    /// Linear axis.
    Linear,
    /// Base-10 logarithmic axis (values must be > 0).
    Log,
}

/// A 2-D chart description.
#[derive(Debug, Clone)]
pub struct Chart {
    /// Title.
    pub title: String,
    /// X-axis label (with unit).
    pub x_label: String,
    /// Y-axis label (with unit).
    pub y_label: String,
    /// X scale.
    pub x_scale: Scale,
    /// Y scale.
    pub y_scale: Scale,
    /// Curves.
    pub series: Vec<Series>,
}

const COLORS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

fn range(vals: impl Iterator<Item = f64>, scale: Scale) -> (f64, f64) {
    let v: Vec<f64> = vals
        .filter(|x| x.is_finite() && (scale == Scale::Linear || *x > 0.0))
        .collect();
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    match scale {
        Scale::Linear => {
            let pad = if hi > lo {
                0.05 * (hi - lo)
            } else {
                0.5 * lo.abs().max(1.0)
            };
            (lo - pad, hi + pad)
        }
        Scale::Log => {
            let (a, b) = if hi > lo { (lo, hi) } else { (lo / 2.0, hi * 2.0) };
            (a / 1.3, b * 1.3)
        }
    }
}

/// Draws `chart` to a PNG file of 900 × 600 pixels. Non-finite points are left out (as are
/// points ≤ 0 on a log axis).
pub fn draw(chart: &Chart, path: &Path) -> Result<(), PlotError> {
    if chart.series.iter().all(|s| s.points.is_empty()) {
        return Err(PlotError::invalid(
            format!("chart `{}`", chart.title),
            "no points to draw",
        ));
    }
    let (x0, x1) = range(
        chart.series.iter().flat_map(|s| s.points.iter().map(|p| p.0)),
        chart.x_scale,
    );
    let (y0, y1) = range(
        chart.series.iter().flat_map(|s| s.points.iter().map(|p| p.1)),
        chart.y_scale,
    );
    with_png(path, |tmp| {
        let root = BitMapBackend::new(&tmp, (900, 600)).into_drawing_area();
        root.fill(&WHITE)?;
        macro_rules! body {
            ($ctx:expr) => {{
                let mut ctx = $ctx;
                ctx.configure_mesh()
                    .x_label_formatter(&|v: &f64| crate::fmt_tick(*v))
                    .y_label_formatter(&|v: &f64| crate::fmt_tick(*v))
                    .x_desc(chart.x_label.as_str())
                    .y_desc(chart.y_label.as_str())
                    .label_style(("sans-serif", 14))
                    .draw()?;
                for (i, s) in chart.series.iter().enumerate() {
                    let c = COLORS[i % COLORS.len()];
                    let pts: Vec<(f64, f64)> = s
                        .points
                        .iter()
                        .copied()
                        .filter(|p| p.0.is_finite() && p.1.is_finite())
                        .collect();
                    if s.markers_only {
                        ctx.draw_series(pts.iter().map(|&p| Cross::new(p, 6, c.stroke_width(2))))?
                            .label(s.label.as_str())
                            .legend(move |(x, y)| Cross::new((x + 10, y), 5, c.stroke_width(2)));
                    } else {
                        ctx.draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))?
                            .label(s.label.as_str())
                            .legend(move |(x, y)| {
                                PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                            });
                        ctx.draw_series(pts.iter().map(|&p| Circle::new(p, 3, c.filled())))?;
                    }
                }
                ctx.configure_series_labels()
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .label_font(("sans-serif", 14))
                    .draw()?;
            }};
        }
        let mut builder = ChartBuilder::on(&root);
        builder
            .caption(chart.title.as_str(), ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(70);
        match (chart.x_scale, chart.y_scale) {
            (Scale::Linear, Scale::Linear) => body!(builder.build_cartesian_2d(x0..x1, y0..y1)?),
            (Scale::Log, Scale::Linear) => body!(builder.build_cartesian_2d((x0..x1).log_scale(), y0..y1)?),
            (Scale::Linear, Scale::Log) => body!(builder.build_cartesian_2d(x0..x1, (y0..y1).log_scale())?),
            (Scale::Log, Scale::Log) => {
                body!(builder.build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?)
            }
        }
        root.present()?;
        Ok(())
    })
}
