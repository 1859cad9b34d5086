//! Calibrated transmission surface (Haddad et al. 2021, §2.1): S_pq = C_t·π·R_m².

/// Transmission surface of a contact (m²): S_pq = C_t·π·R_m², with C_t the calibration
/// constant (dimensionless, from a calibration run on the same kind of packing) and
/// R_m = (R_p + R_q)/2 the mean radius (m).
pub fn surface_calibrated(c_t: f64, r_m: f64) -> f64 {
    c_t * std::f64::consts::PI * r_m * r_m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_constant_gives_the_disc_of_mean_radius() {
        assert!((surface_calibrated(1.0, 2.0) - 4.0 * std::f64::consts::PI).abs() < 1e-15);
        assert!((surface_calibrated(0.8, 1.0) - 0.8 * std::f64::consts::PI).abs() < 1e-15);
    }
}
