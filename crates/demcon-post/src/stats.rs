//! Field statistics: coefficient of variation, effective conductivity from a steady run, and
//! small helpers to turn vector fields into scalars.

use demcon_core::check::check_len;
use demcon_core::{Axis, Vec3};

use crate::error::PostError;

/// Coefficient of variation of `values` (fraction): population standard deviation divided by
/// the absolute mean, over the entries where `mask` is true (all entries when `mask` is
/// `None`).
///
/// Errors: mask of the wrong length, no entry selected, a non-finite selected value, or a
/// mean of zero (the CoV is then undefined — it is never returned as NaN or ∞).
pub fn coefficient_of_variation(values: &[f64], mask: Option<&[bool]>) -> Result<f64, PostError> {
    if let Some(m) = mask {
        check_len("mask", m.len(), values.len())?;
    }
    let selected = |i: usize| mask.is_none_or(|m| m[i]);
    let mut n = 0usize;
    let mut sum = 0.0;
    for (i, &v) in values.iter().enumerate().filter(|&(i, _)| selected(i)) {
        if !v.is_finite() {
            return Err(PostError::invalid(format!("values[{i}]"), v, "must be finite"));
        }
        n += 1;
        sum += v;
    }
    if n == 0 {
        return Err(PostError::Undefined {
            what: "coefficient of variation",
            why: "no value selected".into(),
        });
    }
    let mean = sum / n as f64;
    let var = values
        .iter()
        .enumerate()
        .filter(|&(i, _)| selected(i))
        .map(|(_, v)| (v - mean).powi(2))
        .sum::<f64>()
        / n as f64;
    let cov = var.sqrt() / mean.abs();
    if mean == 0.0 || !cov.is_finite() {
        return Err(PostError::Undefined {
            what: "coefficient of variation",
            why: format!("mean = {mean:e} over {n} values"),
        });
    }
    Ok(cov)
}

/// Effective conductivity from a steady run, `λ_e = (Q/A)·L/ΔT` (W/(m·K); S/m with a current
/// and a potential difference).
///
/// - `heat_flow_w`: heat flow through the section (W), e.g. from
///   [`flow_across_plane`](crate::flow_across_plane) or the reaction at a fixed-temperature face;
/// - `area_m2`: section crossed by the flow (m²), > 0;
/// - `length_m`: distance between the two faces held at different temperatures (m), > 0;
/// - `delta_t`: temperature difference between these faces (K), ≠ 0, same sign convention as
///   the flow (a flow from hot to cold and `ΔT = T_hot − T_cold` give `λ_e > 0`).
pub fn effective_conductivity(
    heat_flow_w: f64,
    area_m2: f64,
    length_m: f64,
    delta_t: f64,
) -> Result<f64, PostError> {
    if !heat_flow_w.is_finite() {
        return Err(PostError::invalid(
            "heat_flow_w",
            heat_flow_w,
            "must be finite (W)",
        ));
    }
    for (field, v, unit) in [("area_m2", area_m2, "m²"), ("length_m", length_m, "m")] {
        if !(v.is_finite() && v > 0.0) {
            return Err(PostError::invalid(
                field,
                v,
                format!("must be a finite number > 0 ({unit})"),
            ));
        }
    }
    if !(delta_t.is_finite() && delta_t != 0.0) {
        return Err(PostError::invalid(
            "delta_t",
            delta_t,
            "must be a finite, non-zero temperature difference (K)",
        ));
    }
    Ok(heat_flow_w / area_m2 * length_m / delta_t)
}

/// Euclidean norm of every vector (same unit as the vectors, e.g. W/m²).
pub fn magnitudes(vectors: &[Vec3]) -> Vec<f64> {
    vectors.iter().map(|v| v.norm()).collect()
}

/// One Cartesian component of every vector (same unit as the vectors).
pub fn components(vectors: &[Vec3], axis: Axis) -> Vec<f64> {
    let k = axis.index();
    vectors.iter().map(|v| v[k]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cov_of_a_constant_is_zero_and_of_a_known_set_is_exact() {
        assert_eq!(coefficient_of_variation(&[3.5; 10], None).unwrap(), 0.0);
        // {1, 3}: mean 2, population std 1.
        let c = coefficient_of_variation(&[1.0, 3.0, 100.0], Some(&[true, true, false])).unwrap();
        assert!((c - 0.5).abs() < 1e-15);
        let c = coefficient_of_variation(&[-1.0, -3.0], None).unwrap();
        assert!((c - 0.5).abs() < 1e-15);
    }

    #[test]
    fn cov_errors() {
        assert!(matches!(
            coefficient_of_variation(&[1.0, -1.0], None),
            Err(PostError::Undefined { .. })
        ));
        assert!(coefficient_of_variation(&[], None).is_err());
        assert!(coefficient_of_variation(&[1.0], Some(&[false])).is_err());
        let e = coefficient_of_variation(&[1.0], Some(&[true, true])).unwrap_err();
        assert!(e.to_string().contains("mask"), "{e}");
        let e = coefficient_of_variation(&[1.0, f64::INFINITY], None).unwrap_err();
        assert!(e.to_string().contains("values[1]"), "{e}");
    }

    #[test]
    fn etc() {
        let l = effective_conductivity(50.0, 0.01, 0.1, 10.0).unwrap();
        assert!((l - 50.0).abs() < 1e-12);
        let e = effective_conductivity(50.0, 0.0, 0.1, 10.0).unwrap_err();
        assert!(e.to_string().contains("area_m2"), "{e}");
        assert!(effective_conductivity(50.0, 1.0, 0.1, 0.0).is_err());
        assert!(effective_conductivity(f64::NAN, 1.0, 0.1, 1.0).is_err());
    }

    #[test]
    fn vector_helpers() {
        let v = [Vec3::new(3.0, 4.0, 0.0)];
        assert_eq!(magnitudes(&v), vec![5.0]);
        assert_eq!(components(&v, Axis::Y), vec![4.0]);
    }
}
