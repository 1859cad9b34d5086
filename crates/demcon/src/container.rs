//! The container flags shared by `pack`, `import` and `info`: `--container KIND` with
//! `--size` or `--radius`/`--length`.

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use demcon_core::Container;

/// Container kinds accepted by `--container`.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum ContainerKind {
    /// Box with hard walls spanning [0, LX]×[0, LY]×[0, LZ] (`--size`).
    Box,
    /// Cylinder along z, hard walls (`--radius`, `--length`).
    Cylinder,
    /// Sphere centred at the origin, hard wall (`--radius`).
    Sphere,
    /// Periodic box [0, LX]×[0, LY]×[0, LZ] (`--size`).
    Periodic,
}

/// The container flags of `pack`, optional: `--container KIND` with `--size` or
/// `--radius`/`--length`.
#[derive(Debug, Args)]
pub struct ContainerFlags {
    /// Container kind (box and periodic span [0, L]; cylinder along z, axis at x = y = 0;
    /// sphere centred at the origin).
    #[arg(long, value_enum)]
    container: Option<ContainerKind>,
    /// Box or periodic box edge lengths LX,LY,LZ (m).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    size: Option<Vec<f64>>,
    /// Cylinder or sphere radius (m).
    #[arg(long, allow_negative_numbers = true)]
    radius: Option<f64>,
    /// Cylinder length along z (m).
    #[arg(long, allow_negative_numbers = true)]
    length: Option<f64>,
}

impl ContainerFlags {
    /// The container the flags give, `None` without `--container`.
    pub fn container(&self) -> anyhow::Result<Option<Container>> {
        let Some(kind) = self.container else {
            if self.size.is_some() || self.radius.is_some() || self.length.is_some() {
                bail!("--size, --radius and --length need --container box|cylinder|sphere|periodic");
            }
            return Ok(None);
        };
        let size = || -> anyhow::Result<[f64; 3]> {
            match &self.size {
                Some(s) if s.len() == 3 => Ok([s[0], s[1], s[2]]),
                Some(s) => bail!("--size needs three lengths LX,LY,LZ (m), got {}", s.len()),
                None => bail!("--container {kind:?} needs --size LX,LY,LZ (m)"),
            }
        };
        let need = |v: Option<f64>, flag: &str| {
            v.with_context(|| format!("--container {kind:?} needs {flag}").to_lowercase())
        };
        let c = match kind {
            ContainerKind::Box => Container::Box { size: size()? },
            ContainerKind::Periodic => Container::Periodic { size: size()? },
            ContainerKind::Cylinder => Container::Cylinder {
                radius: need(self.radius, "--radius R (m)")?,
                length: need(self.length, "--length L (m)")?,
            },
            ContainerKind::Sphere => Container::Sphere {
                radius: need(self.radius, "--radius R (m)")?,
            },
        };
        c.validate().context("--container")?;
        Ok(Some(c))
    }
}
