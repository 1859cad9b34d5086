//! Reference data files (FEM, FFT): copies of `shared/refs/` kept in `validation/data/` and
//! compiled in (`include_str!`), so a clean clone validates without `shared/`.

use serde_json::Value;

/// Single-inclusion FEM reference (`single-inclusion-fem.json`).
pub fn single_inclusion_fem() -> Value {
    serde_json::from_str(include_str!("../data/single-inclusion-fem.json")).expect("bundled JSON is valid")
}

/// Epoxy/silica FFT reference (`multi-inclusion-fft.json`).
pub fn multi_inclusion_fft() -> Value {
    serde_json::from_str(include_str!("../data/multi-inclusion-fft.json")).expect("bundled JSON is valid")
}

/// The same composites realisation by realisation, with exact sphere centres
/// (`multi-inclusion-fft-realisations.json`).
pub fn multi_inclusion_fft_realisations() -> Value {
    serde_json::from_str(include_str!("../data/multi-inclusion-fft-realisations.json"))
        .expect("bundled JSON is valid")
}

/// Grooved-cylinder FEM reference (`notch-electric-fem.json`).
pub fn notch_electric_fem() -> Value {
    serde_json::from_str(include_str!("../data/notch-electric-fem.json")).expect("bundled JSON is valid")
}
