//! PNG charts of demcon results, drawn with plotters' bitmap backend and an embedded DejaVu
//! Sans font (no system font library needed): line charts ([`Chart`], [`draw`]) for probes
//! against time, profiles and the validation report's curves, and rasters ([`Raster`],
//! [`draw_raster`]) for slices, with a colour bar, axes in mm and the field's unit.
//!
//! Everything takes plain data (points, cells); what the values mean — field names and units —
//! is the caller's. Every file is written to a temporary name and renamed.
//!
//! ```no_run
//! use demcon_plot::{Chart, Scale, Series, draw};
//!
//! let chart = Chart {
//!     title: "probe centre".into(),
//!     x_label: "t (s)".into(),
//!     y_label: "temperature (°C)".into(),
//!     x_scale: Scale::Linear,
//!     y_scale: Scale::Linear,
//!     series: vec![Series::line("centre", vec![(0.0, 25.0), (0.1, 27.5), (0.2, 29.0)])],
//! };
//! draw(&chart, std::path::Path::new("probe.png")).unwrap();
//! ```
#![warn(missing_docs)]

mod chart;
mod raster;
mod ticks;

pub use chart::{Chart, Scale, Series, draw};
pub use raster::{Raster, RasterReport, colormap, draw_raster};
pub use ticks::{MAX_DIGITS, nice_ticks, tick_labels};

use std::path::{Path, PathBuf};

use plotters::style::{FontStyle, register_font};

/// Failures of drawing a chart.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// Nothing to draw, or inconsistent inputs (e.g. a raster whose cells do not match its shape).
    #[error("{what}: {why}")]
    Invalid {
        /// What was wrong.
        what: String,
        /// Why, or what is expected.
        why: String,
    },
    /// The drawing backend failed (plotters' message).
    #[error("drawing {path}: {message}")]
    Draw {
        /// The PNG being drawn.
        path: PathBuf,
        /// The backend's message.
        message: String,
    },
    /// A file-system failure.
    #[error("writing {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
}

impl PlotError {
    fn invalid(what: impl Into<String>, why: impl Into<String>) -> Self {
        Self::Invalid {
            what: what.into(),
            why: why.into(),
        }
    }
}

static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// Registers the embedded font as "sans-serif" once (plotters panics on text without a font).
fn ensure_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // The font is compiled in; registration fails only if it is not a valid TTF.
        let _ = register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// Draws into a temporary PNG beside `path` with `body`, then renames it to `path`; a
/// failure leaves no file behind.
fn with_png<T>(
    path: &Path,
    body: impl FnOnce(&Path) -> Result<T, Box<dyn std::error::Error>>,
) -> Result<T, PlotError> {
    ensure_font();
    // The image encoder picks the format from the last extension.
    let tmp = path.with_extension("tmp.png");
    let out = body(&tmp).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        PlotError::Draw {
            path: path.into(),
            message: e.to_string(),
        }
    })?;
    std::fs::rename(&tmp, path).map_err(|source| {
        let _ = std::fs::remove_file(&tmp);
        PlotError::Io {
            path: path.into(),
            source,
        }
    })?;
    Ok(out)
}

/// A tick label: up to four significant digits, no trailing zeros (`0.25`, `12`, `1.5e-4`).
pub fn fmt_tick(v: f64) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e5).contains(&a) {
        let s = format!("{v:.3e}");
        let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
        return format!("{}e{e}", trim_zeros(m));
    }
    let digits = if a == 0.0 {
        0
    } else {
        (3 - a.log10().floor() as i32).max(0)
    } as usize;
    let s = trim_zeros(&format!("{v:.digits$}")).to_string();
    if s == "-0" { "0".into() } else { s }
}

fn trim_zeros(s: &str) -> &str {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_short() {
        assert_eq!(fmt_tick(0.25), "0.25");
        assert_eq!(fmt_tick(12.0), "12");
        assert_eq!(fmt_tick(0.0), "0");
        assert_eq!(fmt_tick(-0.0001234), "-1.234e-4");
        assert_eq!(fmt_tick(1.5e6), "1.5e6");
        assert_eq!(fmt_tick(35.0), "35");
    }
}
