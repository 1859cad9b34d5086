//! PNG charts for the report (plotters, bitmap backend, embedded DejaVu Sans font so no
//! system font library is needed).

use std::path::Path;

use anyhow::{Context, Result};
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};

static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

fn ensure_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // The font is compiled in; registration fails only if it is not a valid TTF.
        let _ = register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

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

/// Draws `chart` to a PNG file of 900 × 600 pixels.
pub fn draw(chart: &Chart, path: &Path) -> Result<()> {
    ensure_font();
    let (x0, x1) = range(
        chart.series.iter().flat_map(|s| s.points.iter().map(|p| p.0)),
        chart.x_scale,
    );
    let (y0, y1) = range(
        chart.series.iter().flat_map(|s| s.points.iter().map(|p| p.1)),
        chart.y_scale,
    );
    let tmp = path.with_extension("tmp.png"); // the image encoder picks the format from the last extension
    {
        let root = BitMapBackend::new(&tmp, (900, 600)).into_drawing_area();
        root.fill(&WHITE)?;
        macro_rules! body {
            ($ctx:expr) => {{
                let mut ctx = $ctx;
                ctx.configure_mesh()
                    .x_label_formatter(&|v: &f64| crate::outcome::fmt_sig(*v))
                    .y_label_formatter(&|v: &f64| crate::outcome::fmt_sig(*v))
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
    }
    std::fs::rename(&tmp, path).with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

/// A colour map (viridis-like, 5 stops) from t ∈ [0, 1] to RGB.
pub fn colormap(t: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (253.0, 231.0, 37.0),
    ];
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 } * 4.0;
    let i = (t.floor() as usize).min(3);
    let f = t - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    let lerp = |x: f64, y: f64| (x + (y - x) * f).round() as u8;
    RGBColor(lerp(a.0, b.0), lerp(a.1, b.1), lerp(a.2, b.2))
}

/// Draws a raster (row-major, `nx` × `ny`, `None` = not covered, drawn grey) as a colour
/// image with a title and the value range, e.g. a slice of T or |q|.
pub fn draw_raster(
    title: &str,
    nx: usize,
    ny: usize,
    cells: &[Option<f64>],
    unit: &str,
    path: &Path,
) -> Result<()> {
    ensure_font();
    let vals = cells.iter().flatten().copied().filter(|v| v.is_finite());
    let (lo, hi) = vals.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    let tmp = path.with_extension("tmp.png"); // the image encoder picks the format from the last extension
    {
        let px = 4u32;
        let w = nx as u32 * px + 40;
        let h = ny as u32 * px + 90;
        let root = BitMapBackend::new(&tmp, (w, h)).into_drawing_area();
        root.fill(&WHITE)?;
        root.draw(&Text::new(title.to_string(), (20, 10), ("sans-serif", 16)))?;
        root.draw(&Text::new(
            format!(
                "range {} … {} {unit}",
                crate::outcome::fmt_sig(lo),
                crate::outcome::fmt_sig(hi)
            ),
            (20, 32),
            ("sans-serif", 13),
        ))?;
        for j in 0..ny {
            for i in 0..nx {
                let c = match cells[j * nx + i] {
                    Some(v) if hi > lo => colormap((v - lo) / (hi - lo)),
                    Some(_) => colormap(0.5),
                    None => RGBColor(200, 200, 200),
                };
                let x = 20 + i as i32 * px as i32;
                // Row 0 is the lowest coordinate: draw it at the bottom.
                let y = 55 + (ny - 1 - j) as i32 * px as i32;
                root.draw(&Rectangle::new(
                    [(x, y), (x + px as i32, y + px as i32)],
                    c.filled(),
                ))?;
            }
        }
        root.present()?;
    }
    std::fs::rename(&tmp, path).with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}
