//! The registry: the one list of validation cases, in report order. One file per paper case.

pub mod common;
pub mod haddad2021_ct_calibration;
pub mod haddad2021_slab_transient;
pub mod haddad2021_sphere_transient;
pub mod haddad2021_stability;

use crate::Case;

/// Every case, in the order of the report.
pub fn registry() -> Vec<Case> {
    vec![
        Case {
            id: "ct-calibration",
            about: "Haddad 2021 §2.1: C_t on our packings against N, 4 realisations",
            run: haddad2021_ct_calibration::run,
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
    ]
}
