//! Validation cases of the two papers (Haddad 2021, Hubert 2017): each case builds its scene,
//! runs it and returns named comparisons against analytic, FEM or FFT references.
#![warn(missing_docs)]
