//! The bar of the face-condition cases (`surroundings`, `time-tables`): L × L/10 × L/10
//! (L = 0.1 m), λ = 10 W/(m·K), ρc = 10⁶ J/(m³·K) (a = 10⁻⁵ m²/s), Laguerre cells.

use demcon_scene::config::*;

use super::common::{material, thermal_scene};

/// The bar's length (m).
pub const L: f64 = 0.1;
/// Its conductivity (W/(m·K)).
pub const LAMBDA: f64 = 10.0;
/// ρ (kg/m³) and c (J/(kg·K)): ρc = 10⁶ J/(m³·K).
const RHO: f64 = 1000.0;
const C: f64 = 1000.0;
/// Its diffusivity (m²/s).
pub const DIFFUSIVITY: f64 = LAMBDA / (RHO * C);

/// The bar's scene (`n` sites, packing `seed`) with `bcs` and `solver`, initially at 0 °C.
pub fn bar_scene(n: usize, seed: u64, bcs: Vec<ThermalBcConfig>, solver: ThermalSolverConfig) -> SceneConfig {
    let mut s = thermal_scene(
        "bar",
        seed,
        PackingConfig::Generate {
            // A long thin box jams below the cube's density: φ = 0.55 packs fast, and the
            // Laguerre network needs no particular density.
            container: ContainerConfig::Box {
                size: (L, 0.1 * L, 0.1 * L),
            },
            count: n,
            phi: 0.55,
            radius_cov: 0.3,
            radius_range: None,
            allow_short: false,
        },
        vec![material("bar", LAMBDA, RHO, C)],
        ThermalConfig {
            initial_temperature: 0.0,
            bcs,
            sources: Vec::new(),
            solver,
            checkpoint: None,
        },
    );
    s.surface = SurfaceConfig::Laguerre;
    s
}
