//! The registry: the one list of validation cases, in report order. One file per paper case;
//! cases import the shared modules below, never each other.

// Shared machinery (not cases).
pub mod bar;
pub mod common;
pub mod composite;
pub mod cylinder;
pub mod multi_inclusion_interface_periodic;
pub mod multi_inclusion_periodic;
pub mod study;
pub mod transient;

// The cases.
pub mod anisotropy;
pub mod crack_density;
pub mod crack_penny;
pub mod current_control;
pub mod grain_boundaries;
pub mod haddad2021_cost_accuracy;
pub mod haddad2021_ct_calibration;
pub mod haddad2021_halo_cov;
pub mod haddad2021_inclusion_etc;
pub mod haddad2021_inclusion_fields;
pub mod haddad2021_multi_inclusion_etc;
pub mod haddad2021_multi_inclusion_fields;
pub mod haddad2021_slab_transient;
pub mod haddad2021_sphere_transient;
pub mod haddad2021_stability;
pub mod homogeneous_exactness;
pub mod hubert2017_cylinder_resistance;
pub mod hubert2017_notch_joule;
pub mod hubert2017_solver_timing;
pub mod images;
pub mod inclusion_interface;
pub mod joule_transient;
pub mod lambda_t;
pub mod layered_interface;
pub mod ligament_holm;
pub mod multi_inclusion_interface;
pub mod packing_stress;
pub mod shapes_aligned;
pub mod shapes_dilute;
pub mod shapes_generator;
pub mod sphere_arrays;
pub mod surroundings;
pub mod time_tables;

use crate::Case;

/// Every case, in the order of the report.
pub fn registry() -> Vec<Case> {
    CASES.to_vec()
}

/// The cases, in the order of the report.
const CASES: &[Case] = &[
    Case {
        id: "packing-stress",
        about: "the packer on 200 (full: 1000) small packings: no overlap above 1e-9 R, every run finishes",
        run: packing_stress::run,
    },
    Case {
        id: "ct-calibration",
        about: "Haddad 2021 §2.1: C_t on our packings against N, 4 realisations",
        run: haddad2021_ct_calibration::run,
    },
    Case {
        id: "homogeneous-exactness",
        about: "λ_e/λ − 1 of a homogeneous box and cylinder (walls), calibrated C_t, Terreros α and Laguerre, 3 packings",
        run: homogeneous_exactness::run,
    },
    Case {
        id: "slab-transient",
        about: "Haddad 2021 §2.2: cube slab T(y, t) vs eq. 17, explicit and implicit",
        run: haddad2021_slab_transient::run,
    },
    Case {
        id: "sphere-transient",
        about: "Haddad 2021 §2.2: aluminium sphere centre T(t) vs corrected eq. 19",
        run: haddad2021_sphere_transient::run,
    },
    Case {
        id: "stability",
        about: "Haddad 2021 eq. 16 vs the exact explicit bound; implicit/steady do not fail",
        run: haddad2021_stability::run,
    },
    Case {
        id: "cost-accuracy-thermal",
        about: "Haddad 2021 §2.2: slab and sphere error against N and wall time, explicit vs implicit",
        run: haddad2021_cost_accuracy::run,
    },
    Case {
        id: "cylinder-resistance",
        about: "Hubert 2017 §3.1: cylinder R vs ρ_e l/A, N = 1e3…2e4, 3 packings, Terreros and C_t",
        run: hubert2017_cylinder_resistance::run,
    },
    Case {
        id: "halo-cov",
        about: "Haddad 2021 §3: CoV of the flux in a homogeneous slab against the Halo ratio k",
        run: haddad2021_halo_cov::run,
    },
    Case {
        id: "inclusion-etc",
        about: "Haddad 2021 §4.1: single inclusion, λ_e/λ_m against the contrast vs FEM and Maxwell",
        run: haddad2021_inclusion_etc::run,
    },
    Case {
        id: "inclusion-fields",
        about: "Haddad 2021 §4.2: single inclusion, T and Halo |q| at A, B, C vs FEM; slices",
        run: haddad2021_inclusion_fields::run,
    },
    Case {
        id: "multi-inclusion-etc",
        about: "Haddad 2021 §5.1: epoxy/silica ETC against f vs FFT, Maxwell, third order; N ladder",
        run: haddad2021_multi_inclusion_etc::run,
    },
    Case {
        id: "sphere-arrays",
        about: "issue 32: SC, BCC, FCC sphere arrays (f = 0.3 and nearly touching) vs a multipole solution; conforming cells, centre, segment",
        run: sphere_arrays::run,
    },
    Case {
        id: "multi-inclusion-fields",
        about: "Haddad 2021 §5.2: f = 0.2, T and Halo |q| at A–D beside Table 3; flux slice",
        run: haddad2021_multi_inclusion_fields::run,
    },
    Case {
        id: "shapes-generator",
        about: "issue 34: random placement of fibres, platelets and cylinders over 10 seeds: fraction, smallest gap and orientation tensor against what was asked; an unreachable fraction refused",
        run: shapes_generator::run,
    },
    Case {
        id: "shapes-aligned",
        about: "issue 34: aligned prolate (a/b = 3) and oblate (1/3) spheroids, f ≈ 0.15, contrasts 10 and 0.1, periodic, tensor diagonal vs a voxel FFT on the identical microstructure",
        run: shapes_aligned::run,
    },
    Case {
        id: "images",
        about: "issue 34: phases from labelled voxel images: a laminate image exact in series and parallel; 60 spheres as a list and as 32³–256³ images against a voxel FFT on the identical images (error and time)",
        run: images::run,
    },
    Case {
        id: "shapes-dilute",
        about: "issue 34: one aligned spheroid (a/b = 3, 1/3; full: also 5, 1/10) in periodic cells at f = 0.01 and 0.005, contrasts 10 and 0.1: the increment per fraction extrapolated to f → 0 vs the exact dilute (depolarisation-factor) result",
        run: shapes_dilute::run,
    },
    Case {
        id: "surroundings",
        about: "issue 35: a bar held at one end, convecting and/or radiating at the other: steady (exact, linear) and transient convection (Biot-eigenvalue series), 3 packings; the Robin face's cost beside a held face",
        run: surroundings::run,
    },
    Case {
        id: "time-tables",
        about: "issue 35: a bar whose end is held at a step then a ramp (a time table) vs Duhamel's superposition, forward and backward Euler, 3 packings",
        run: time_tables::run,
    },
    Case {
        id: "grain-boundaries",
        about: "issue 35: a boundary conductance on every facet between grains of one material: a cubic lattice vs its exact series value; a random Laguerre polycrystal's λ_e against h D/λ (3 packings, no exact reference)",
        run: grain_boundaries::run,
    },
    Case {
        id: "current-control",
        about: "issue 35: a current imposed between two face electrodes: the potential found vs I ρ_e L/A, and a ρ_e(T) bar heated at constant current vs its exact θ(t), 3 packings",
        run: current_control::run,
    },
    Case {
        id: "lambda-t",
        about: "issue 35: λ(T) = λ0 (1 + β T) bar: steady vs the Kirchhoff-transform profile (with the solve count), transient vs our fine 1-D reference, 3 packings",
        run: lambda_t::run,
    },
    Case {
        id: "anisotropy",
        about: "issue 35: conductivity tensors: a cubic lattice (K-orthogonal cells) exact along and across the axis; random periodic Laguerre cells (K about z, tilted, four anisotropic layers) against the exact tensor, error measured",
        run: anisotropy::run,
    },
    Case {
        id: "layered-interface",
        about: "issue 14: layered cube with interface conductance h (10 %, 50 % of the resistance) vs L/(Σ t/λ + n/h); error against N",
        run: layered_interface::run,
    },
    Case {
        id: "inclusion-interface",
        about: "issue 14: Haddad §4 single inclusion with an interface conductance (a_K/a = 0.1, 1, 10; contrasts 5, 0.1) vs Hasselman–Johnson",
        run: inclusion_interface::run,
    },
    Case {
        id: "multi-inclusion-interface",
        about: "issue 14: epoxy/silica ETC against f with an interface conductance (a_K/a = 0.01…1) vs the equivalent-sphere third order; how much of the paper's 7 % a barrier explains",
        run: multi_inclusion_interface::run,
    },
    Case {
        id: "crack-penny",
        about: "issue 14: insulating penny crack (a/L = 1/8, 1/6, 1/4) in a cube, jump profile vs (4q/πλ)√(a² − r²); a through-section crack passes no heat",
        run: crack_penny::run,
    },
    Case {
        id: "crack-density",
        about: "issue 14: periodic cells with 8 and 27 penny cracks, aligned and random, λ against 1 − (8/3)ρ and 1 − (8/9)ρ (reported)",
        run: crack_density::run,
    },
    Case {
        id: "ligament-holm",
        about: "issue 14: cylinder cut at mid-length leaving a ligament (a/b = 1/4, 1/2), constriction R vs Holm ρ_e/(2a) (reported)",
        run: ligament_holm::run,
    },
    Case {
        id: "notch-joule",
        about: "Hubert 2017 §3.2: grooved cylinder, R vs FEM and steady Joule ΔT_max vs Kohlrausch",
        run: hubert2017_notch_joule::run,
    },
    Case {
        id: "joule-transient",
        about: "ρ_e(T) two-way coupling in transients: uniform Joule heating vs the exact θ(t), explicit and implicit",
        run: joule_transient::run,
    },
    Case {
        id: "electric-solver-timing",
        about: "Hubert 2017 Table 1: one potential solve at 5000 particles, CG vs Cholesky",
        run: hubert2017_solver_timing::run,
    },
];
