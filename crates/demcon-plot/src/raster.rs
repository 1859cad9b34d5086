//! Rasters: a field sampled on a plane (a slice) drawn as square cells in a viridis-like
//! colour map, with axes in mm, a colour bar labelled with the field and its unit, and grey
//! where no value is given.

use std::path::Path;

use plotters::prelude::*;

use crate::ticks::Ticked;
use crate::{PlotError, fmt_tick, with_png};

/// A raster to draw: `nx` × `ny` square cells, row-major (`cells[j · nx + i]`), row 0 at the
/// lowest `v` coordinate (drawn at the bottom).
#[derive(Debug, Clone)]
pub struct Raster<'a> {
    /// Title (drawn above the picture).
    pub title: String,
    /// Cells along the horizontal axis.
    pub nx: usize,
    /// Cells along the vertical axis.
    pub ny: usize,
    /// Value of each cell (unit of the field); `None` where nothing is there (drawn grey).
    pub cells: &'a [Option<f64>],
    /// Coordinates (horizontal, vertical) of the lower-left corner of cell (0, 0) (m).
    pub origin: [f64; 2],
    /// Cell edge (m).
    pub cell: f64,
    /// Names of the horizontal and vertical axes (`"x"`, `"z"`); the axes are labelled
    /// `x (mm)`, `z (mm)`.
    pub axes: [&'a str; 2],
    /// Label of the colour bar: the field and its unit, e.g. `temperature (°C)`.
    pub bar_label: String,
    /// The colour bar's range (lo, hi) in the field's unit; `None`: the least and greatest
    /// finite cell values.
    pub range: Option<(f64, f64)>,
}

/// What [`draw_raster`] drew.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RasterReport {
    /// The colour bar's range (lo, hi), unit of the field.
    pub range: (f64, f64),
    /// Size of the PNG (width, height) in pixels.
    pub size: (u32, u32),
}

/// A colour map (viridis-like, 5 stops) from t ∈ [0, 1] to RGB; t outside is clamped, NaN
/// is the low end.
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

/// Grey of the cells without a value.
const EMPTY: RGBColor = RGBColor(200, 200, 200);
/// The longer side of the picture's plotting area (pixels).
const SIDE: f64 = 640.0;
/// The least width of the picture's plotting area (pixels).
const MIN_WIDTH: u32 = 420;
/// Width of the colour-bar panel (pixels), with labels of up to 6 characters.
const BAR_PANEL: u32 = 150;
/// Width of the colour bar's label area (tick labels and the field's name, pixels), grown
/// for longer labels.
const BAR_LABEL_AREA: u32 = 75;

/// Draws `r` to a PNG: the raster with its axes in mm (cells square, the longer side 640
/// pixels, a narrow raster centred in a plotting area 420 pixels wide), and a colour bar on the right spanning `r.range` (or the cells' range).
/// Errors: a shape that does not match the cells, no finite value to colour, a bad range or
/// cell size, or a drawing or file failure.
pub fn draw_raster(r: &Raster, path: &Path) -> Result<RasterReport, PlotError> {
    let (lo, hi) = colour_range(r)?;
    // The picture: cells square, the longer side SIDE pixels, plus label areas.
    let scale = SIDE / r.nx.max(r.ny) as f64;
    let (mut pw, ph) = (
        (r.nx as f64 * scale).round() as u32,
        (r.ny as f64 * scale).round() as u32,
    );
    // A narrow raster is widened with empty margins (cells stay square) so its title fits.
    let widen = MIN_WIDTH.saturating_sub(pw);
    pw += widen;
    let (margin, left, bottom, caption) = (15u32, 75u32, 55u32, 25u32);
    // The colour bar's ticks, labelled with the digits that tell them apart; the bar's label
    // area widens for long labels (a value in full before offsets: `262.939177`, `+2e-8`).
    let (blo, bhi) = if hi > lo { (lo, hi) } else { (lo - 0.5, hi + 0.5) };
    let bar_ticks = if hi > lo {
        crate::nice_ticks(blo, bhi, (ph / 60).clamp(3, 10) as usize)
    } else {
        vec![lo]
    };
    let bar_labels = crate::tick_labels(&bar_ticks);
    let longest = bar_labels.iter().map(|l| l.chars().count()).max().unwrap_or(0) as u32;
    let bar_label_area = BAR_LABEL_AREA.max(longest * 8 + 20);
    let bar_panel = BAR_PANEL + (bar_label_area - BAR_LABEL_AREA);
    let width = margin + left + pw + margin + bar_panel;
    let height = margin + caption + ph + bottom + margin;
    let mm = |m: f64| m * 1e3;
    let (u0, v0) = (mm(r.origin[0]), mm(r.origin[1]));
    let (u1, v1) = (u0 + mm(r.cell) * r.nx as f64, v0 + mm(r.cell) * r.ny as f64);
    let margin_mm = 0.5 * widen as f64 / scale * mm(r.cell);
    let (left_mm, right_mm) = (u0 - margin_mm, u1 + margin_mm);
    let colour = |v: f64| {
        if hi > lo {
            colormap((v - lo) / (hi - lo))
        } else {
            colormap(0.5)
        }
    };
    with_png(path, |tmp| {
        let root = BitMapBackend::new(tmp, (width, height)).into_drawing_area();
        root.fill(&WHITE)?;
        let (main, bar) = root.split_horizontally(width - bar_panel);
        let mut chart = ChartBuilder::on(&main)
            .caption(r.title.as_str(), ("sans-serif", 20))
            .margin(margin)
            .x_label_area_size(bottom)
            .y_label_area_size(left)
            .build_cartesian_2d(left_mm..right_mm, v0..v1)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_labels((pw / 70).max(3) as usize)
            .y_labels((ph / 50).max(3) as usize)
            .x_label_formatter(&|v: &f64| fmt_tick(*v))
            .y_label_formatter(&|v: &f64| fmt_tick(*v))
            .x_desc(format!("{} (mm)", r.axes[0]))
            .y_desc(format!("{} (mm)", r.axes[1]))
            .label_style(("sans-serif", 14))
            .draw()?;
        let d = mm(r.cell);
        chart.draw_series((0..r.ny).flat_map(|j| {
            (0..r.nx).map(move |i| {
                let c = match r.cells[j * r.nx + i] {
                    Some(v) if v.is_finite() => colour(v),
                    _ => EMPTY,
                };
                let (x, y) = (u0 + i as f64 * d, v0 + j as f64 * d);
                Rectangle::new([(x, y), (x + d, y + d)], c.filled())
            })
        }))?;

        // The colour bar, level with the picture: a column of 256 bands from lo to hi.
        let mut cb = ChartBuilder::on(&bar)
            .margin_top(margin + caption)
            .margin_bottom(margin + bottom)
            .margin_left(10)
            .margin_right(20)
            .set_label_area_size(LabelAreaPosition::Right, bar_label_area)
            .build_cartesian_2d(0f64..1f64, Ticked::new(blo..bhi, bar_ticks.clone(), Vec::new()))?;
        let bar_label = |v: &f64| {
            bar_ticks
                .iter()
                .position(|t| t == v)
                .map_or_else(|| fmt_tick(*v), |k| bar_labels[k].clone())
        };
        cb.configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_label_formatter(&bar_label)
            .y_desc(r.bar_label.as_str())
            .label_style(("sans-serif", 14))
            .draw()?;
        let bands = 256;
        cb.draw_series((0..bands).map(|k| {
            let a = blo + (bhi - blo) * k as f64 / bands as f64;
            let b = blo + (bhi - blo) * (k + 1) as f64 / bands as f64;
            Rectangle::new([(0.0, a), (1.0, b)], colour(0.5 * (a + b)).filled())
        }))?;
        cb.draw_series(std::iter::once(Rectangle::new([(0.0, blo), (1.0, bhi)], BLACK)))?;
        root.present()?;
        Ok(())
    })?;
    Ok(RasterReport {
        range: (lo, hi),
        size: (width, height),
    })
}

/// Checks the raster's shape, cell and origin; returns the colour range: `r.range`, or the
/// finite cells' range.
fn colour_range(r: &Raster) -> Result<(f64, f64), PlotError> {
    if r.nx == 0 || r.ny == 0 || r.cells.len() != r.nx * r.ny {
        return Err(PlotError::invalid(
            format!("raster `{}`", r.title),
            format!("{} cells for a {} × {} raster", r.cells.len(), r.nx, r.ny),
        ));
    }
    if !(r.cell.is_finite() && r.cell > 0.0 && r.origin.iter().all(|o| o.is_finite())) {
        return Err(PlotError::invalid(
            format!("raster `{}`", r.title),
            format!(
                "cell {} m at {:?} m: a finite cell > 0 and a finite origin",
                r.cell, r.origin
            ),
        ));
    }
    let (lo, hi) = match r.range {
        Some(range) => range,
        None => r
            .cells
            .iter()
            .flatten()
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            }),
    };
    if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
        return Err(PlotError::invalid(
            format!("raster `{}`", r.title),
            "no finite value to colour (or a colour range with lo > hi)",
        ));
    }
    Ok((lo, hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode(path: &Path) -> (u32, u32, Vec<u8>) {
        let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
        let mut reader = dec.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        buf.truncate(info.buffer_size());
        (info.width, info.height, buf)
    }

    #[test]
    fn a_raster_is_a_png_with_its_range_and_size() {
        let dir = std::env::temp_dir().join(format!("demcon-plot-raster-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("slice.png");
        // 40 × 20 cells of 0.5 mm, a linear ramp along x with a hole.
        let cells: Vec<Option<f64>> = (0..20)
            .flat_map(|j| (0..40).map(move |i| (j != 10).then_some(20.0 + i as f64 * 0.5)))
            .collect();
        let r = Raster {
            title: "temperature (°C), z = 5 mm".into(),
            nx: 40,
            ny: 20,
            cells: &cells,
            origin: [0.0, 0.0],
            cell: 0.5e-3,
            axes: ["x", "y"],
            bar_label: "temperature (°C)".into(),
            range: None,
        };
        let rep = draw_raster(&r, &path).unwrap();
        assert_eq!(rep.range, (20.0, 39.5));
        let (w, h, _) = decode(&path);
        assert_eq!((w, h), rep.size);
        // Cells square: 640 × 320 pixels plus the label areas and the bar.
        assert_eq!(
            rep.size,
            (15 + 75 + 640 + 15 + BAR_PANEL, 15 + 25 + 320 + 55 + 15)
        );
        assert!(!dir.join("slice.tmp.png").exists());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn bad_rasters_are_refused() {
        let path = std::env::temp_dir().join("demcon-plot-never.png");
        let cells = vec![None; 4];
        let mut r = Raster {
            title: "t".into(),
            nx: 2,
            ny: 2,
            cells: &cells,
            origin: [0.0, 0.0],
            cell: 1e-3,
            axes: ["x", "y"],
            bar_label: "T".into(),
            range: None,
        };
        let e = draw_raster(&r, &path).unwrap_err().to_string();
        assert!(e.contains("no finite value"), "{e}");
        r.nx = 3;
        let e = draw_raster(&r, &path).unwrap_err().to_string();
        assert!(e.contains("4 cells for a 3 × 2"), "{e}");
        assert!(!path.exists());
    }

    #[test]
    fn colormap_ends() {
        assert_eq!(colormap(0.0), RGBColor(68, 1, 84));
        assert_eq!(colormap(1.0), RGBColor(253, 231, 37));
        assert_eq!(colormap(f64::NAN), colormap(0.0));
    }
}
