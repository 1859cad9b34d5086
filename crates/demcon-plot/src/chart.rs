//! Line charts: curves (lines with markers, or markers only) on linear or log axes, with a
//! legend — probes against time, profiles along their lines, the report's comparisons.

use std::path::Path;

use plotters::prelude::*;

use crate::ticks::Ticked;
use crate::{PlotError, nice_ticks, tick_labels, with_png};

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
    /// For x only: the series are categories at x = 1, 2, …, each named under its points
    /// by its label (no legend); e.g. one value per probe at a single time.
    Categories,
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
        .filter(|x| x.is_finite() && (scale != Scale::Log || *x > 0.0))
        .collect();
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    match scale {
        Scale::Linear | Scale::Categories => {
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
    check(chart)?;
    let (x0, x1) = match chart.x_scale {
        Scale::Categories => (0.5, chart.series.len() as f64 + 0.5),
        _ => range(
            chart.series.iter().flat_map(|s| s.points.iter().map(|p| p.0)),
            chart.x_scale,
        ),
    };
    let names: Vec<&str> = chart.series.iter().map(|s| s.label.as_str()).collect();
    let x_tick = |v: &f64| match chart.x_scale {
        Scale::Categories => {
            let k = v.round();
            if (v - k).abs() < 1e-6 && k >= 1.0 && k as usize <= names.len() {
                names[k as usize - 1].to_string()
            } else {
                String::new()
            }
        }
        _ => crate::fmt_tick(*v),
    };
    let (y0, y1) = range(
        chart.series.iter().flat_map(|s| s.points.iter().map(|p| p.1)),
        chart.y_scale,
    );
    let legend = legend_position(chart, (x0, x1), (y0, y1));
    // A linear y axis gets our ticks, labelled with the digits that tell them apart (a probe
    // over a millikelvin at 263 °C reads 262.9392, 262.9394, …), light lines at fifths.
    let y_ticks = nice_ticks(y0, y1, 10);
    let y_labels = tick_labels(&y_ticks);
    let y_light = fifths(&y_ticks, y0, y1);
    let y_tick = |v: &f64| {
        y_ticks
            .iter()
            .position(|t| t == v)
            .map_or_else(|| crate::fmt_tick(*v), |k| y_labels[k].clone())
    };
    let y_linear = || Ticked::new(y0..y1, y_ticks.clone(), y_light.clone());
    // Categories: one tick per category (0.5 … n + 0.5 with n ticks puts them at 1 … n).
    let x_ticks = match chart.x_scale {
        Scale::Categories => chart.series.len(),
        _ => 10,
    };
    with_png(path, |tmp| {
        let root = BitMapBackend::new(&tmp, (900, 600)).into_drawing_area();
        root.fill(&WHITE)?;
        macro_rules! body {
            ($ctx:expr) => {{
                let mut ctx = $ctx;
                ctx.configure_mesh()
                    .x_labels(x_ticks)
                    .x_label_formatter(&x_tick)
                    .y_label_formatter(&y_tick)
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
                if chart.x_scale != Scale::Categories {
                    ctx.configure_series_labels()
                        .position(legend)
                        .background_style(WHITE.mix(0.85))
                        .border_style(BLACK)
                        .label_font(("sans-serif", 14))
                        .draw()?;
                }
            }};
        }
        let mut builder = ChartBuilder::on(&root);
        builder
            .caption(chart.title.as_str(), ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(70);
        match (chart.x_scale, chart.y_scale) {
            (Scale::Linear | Scale::Categories, Scale::Linear | Scale::Categories) => {
                body!(builder.build_cartesian_2d(x0..x1, y_linear())?)
            }
            (Scale::Log, Scale::Linear | Scale::Categories) => {
                body!(builder.build_cartesian_2d((x0..x1).log_scale(), y_linear())?)
            }
            (Scale::Linear | Scale::Categories, Scale::Log) => {
                body!(builder.build_cartesian_2d(x0..x1, (y0..y1).log_scale())?)
            }
            (Scale::Log, Scale::Log) => {
                body!(builder.build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?)
            }
        }
        root.present()?;
        Ok(())
    })
}

/// Refuses a chart with no point, or categories on the y axis.
fn check(chart: &Chart) -> Result<(), PlotError> {
    let what = || format!("chart `{}`", chart.title);
    if chart.series.iter().all(|s| s.points.is_empty()) {
        return Err(PlotError::invalid(what(), "no points to draw"));
    }
    if chart.y_scale == Scale::Categories {
        return Err(PlotError::invalid(what(), "categories are for the x axis only"));
    }
    Ok(())
}

/// The light grid lines: every fifth of the step of `ticks` within [lo, hi].
fn fifths(ticks: &[f64], lo: f64, hi: f64) -> Vec<f64> {
    match ticks {
        [a, b, ..] => {
            let fifth = (b - a) / 5.0;
            let first = (lo / fifth).ceil() as i64;
            let last = (hi / fifth).floor() as i64;
            (first..=last).map(|k| k as f64 * fifth).collect()
        }
        _ => Vec::new(),
    }
}

/// The corner (or side) of the plot where the legend covers the fewest points of the curves
/// (lines sampled between their points), for a legend of the chart's labels.
fn legend_position(chart: &Chart, (x0, x1): (f64, f64), (y0, y1): (f64, f64)) -> SeriesLabelPosition {
    let norm = |v: f64, lo: f64, hi: f64, scale: Scale| match scale {
        Scale::Log => (v.ln() - lo.ln()) / (hi.ln() - lo.ln()),
        _ => (v - lo) / (hi - lo),
    };
    let mut pts: Vec<(f64, f64)> = Vec::new();
    for s in &chart.series {
        let p: Vec<(f64, f64)> = s
            .points
            .iter()
            .map(|&(x, y)| (norm(x, x0, x1, chart.x_scale), norm(y, y0, y1, chart.y_scale)))
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .collect();
        pts.extend(&p);
        if !s.markers_only {
            for w in p.windows(2) {
                pts.extend((1..20).map(|k| {
                    let f = k as f64 / 20.0;
                    (w[0].0 + f * (w[1].0 - w[0].0), w[0].1 + f * (w[1].1 - w[0].1))
                }));
            }
        }
    }
    // The legend's size as a fraction of the plotting area (about 800 × 490 pixels).
    let longest = chart
        .series
        .iter()
        .map(|s| s.label.chars().count())
        .max()
        .unwrap_or(0);
    let w = ((longest as f64 * 7.5 + 50.0) / 800.0).min(0.6);
    let h = ((chart.series.len() as f64 * 19.0 + 14.0) / 490.0).min(0.9);
    use SeriesLabelPosition::*;
    let candidates = [
        (UpperRight, 1.0 - w, 1.0 - h),
        (UpperLeft, 0.0, 1.0 - h),
        (LowerRight, 1.0 - w, 0.0),
        (LowerLeft, 0.0, 0.0),
        (MiddleRight, 1.0 - w, 0.5 - h / 2.0),
        (MiddleLeft, 0.0, 0.5 - h / 2.0),
    ];
    let covered = |&(_, bx, by): &(SeriesLabelPosition, f64, f64)| {
        pts.iter()
            .filter(|p| p.0 >= bx - 0.02 && p.0 <= bx + w + 0.02 && p.1 >= by - 0.02 && p.1 <= by + h + 0.02)
            .count()
    };
    let best = candidates
        .iter()
        .min_by_key(|c| covered(c))
        .expect("six candidates");
    best.0.clone()
}
