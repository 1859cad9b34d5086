//! Analytic references, independent of any DEM code: slab and sphere Fourier series
//! (the heat paper's sphere formula corrected), effective-medium estimates, uniform-conductor
//! resistance and the Kohlrausch temperature of steady Joule heating.
//!
//! Source of the corrected forms: `shared/refs/analytic.md` §1, §2, §4, §6.

use std::f64::consts::PI;

/// Transient slab (Haddad 2021 eq. 17, correct as printed): temperature (°C) at height `y` (m)
/// and time `t` (s) in a slab of thickness `l` (m) held at `t1` (y = 0) and `t2` (y = l),
/// initially at `t0`, diffusivity `a` (m²/s). Terms are summed until they fall below 1e-15.
pub fn slab_temperature(y: f64, t: f64, l: f64, t1: f64, t2: f64, t0: f64, a: f64) -> f64 {
    let dt = t2 - t1;
    let theta0 = (t0 - t1) / dt;
    let mut sum = 0.0;
    for n in 1..100_000 {
        let nf = n as f64;
        let decay = (-(nf * PI / l).powi(2) * a * t).exp();
        let sign = if n % 2 == 0 { 1.0 } else { -1.0 };
        let c_n = 2.0 * (sign * (1.0 - theta0) + theta0) / (nf * PI);
        sum += c_n * (nf * PI * y / l).sin() * decay;
        if decay < 1e-16 && n > 3 {
            break;
        }
    }
    t1 + dt * y / l + dt * sum
}

/// Sphere of radius `r_s` (m), initially at `t0`, surface held at `ti` from t = 0: temperature
/// (°C) at radius `r` (m) and time `t` (s), diffusivity `a` (m²/s). This is the CORRECTED form
/// of Haddad 2021 eq. 18 (the paper swaps T0 and Ti and misses a factor R).
pub fn sphere_temperature(r: f64, t: f64, r_s: f64, t0: f64, ti: f64, a: f64) -> f64 {
    if r < 1e-9 * r_s {
        return sphere_centre_temperature(t, r_s, t0, ti, a);
    }
    let mut sum = 0.0;
    for n in 1..2_000_000 {
        let nf = n as f64;
        let decay = (-a * nf * nf * PI * PI * t / (r_s * r_s)).exp();
        let sign = if n % 2 == 1 { 1.0 } else { -1.0 };
        sum += sign / nf * (nf * PI * r / r_s).sin() * decay;
        if decay < 1e-16 {
            break;
        }
    }
    ti + (t0 - ti) * 2.0 * r_s / (PI * r) * sum
}

/// Centre temperature (°C) of the sphere of [`sphere_temperature`] (corrected Haddad eq. 19).
/// At small Fourier numbers (Fo < 0.02) the slowly converging alternating series is replaced
/// by its exact short-time (Jacobi-transformed) form.
pub fn sphere_centre_temperature(t: f64, r_s: f64, t0: f64, ti: f64, a: f64) -> f64 {
    let fo = a * t / (r_s * r_s);
    if fo < 0.02 {
        // Jacobi's imaginary transformation of the theta series gives the exact short-time
        // form T* = 1 − (2/√(πFo)) Σ_{k≥0} exp(−(2k+1)²/(4Fo)), which converges fast here.
        let s: f64 = (0..20)
            .map(|k| {
                let m = 2.0 * k as f64 + 1.0;
                2.0 * (-(m * m) / (4.0 * fo)).exp() / (PI * fo).sqrt()
            })
            .sum();
        return ti + (t0 - ti) * (1.0 - s);
    }
    let mut sum = 0.0;
    for n in 1..1_000_000 {
        let nf = n as f64;
        let decay = (-nf * nf * PI * PI * fo).exp();
        let sign = if n % 2 == 1 { 1.0 } else { -1.0 };
        sum += sign * decay;
        if decay < 1e-16 {
            break;
        }
    }
    ti + 2.0 * (t0 - ti) * sum
}

/// Maxwell(-Garnett) estimate λ_e/λ_m for spheres of conductivity `li` at volume fraction `f`
/// in a matrix `lm` (the Hashin–Shtrikman lower bound when li > lm).
pub fn maxwell(lm: f64, li: f64, f: f64) -> f64 {
    let b = (li - lm) / (li + 2.0 * lm);
    (1.0 + 2.0 * b * f) / (1.0 - b * f)
}

/// Hasselman & Johnson (J. Compos. Mater. 21, 1987) λ_e/λ_m for spheres of conductivity `li`
/// at volume fraction `f` in a matrix `lm`, with an interface conductance h written as the
/// Kapitza radius over the sphere radius, α = λ_m/(h a):
/// [li(1 + 2α) + 2lm + 2f(li(1 − α) − lm)] / [li(1 + 2α) + 2lm − f(li(1 − α) − lm)].
/// α = 0 is [`maxwell`]; it equals Maxwell with li replaced by li/(1 + α li/lm).
pub fn hasselman_johnson(lm: f64, li: f64, f: f64, alpha: f64) -> f64 {
    let a = li * (1.0 + 2.0 * alpha) + 2.0 * lm;
    let b = li * (1.0 - alpha) - lm;
    (a + 2.0 * f * b) / (a - f * b)
}

/// Torquato third-order estimate λ_e/λ_m for impenetrable spheres, with
/// ζ₂ = 0.21068 f − 0.04693 f² (Miller & Torquato 1990, equilibrium hard spheres).
pub fn third_order(lm: f64, li: f64, f: f64) -> f64 {
    let b = (li - lm) / (li + 2.0 * lm);
    let z2 = 0.21068 * f - 0.04693 * f * f;
    let c = 2.0 * (1.0 - f) * z2 * b * b;
    (1.0 + 2.0 * b * f - c) / (1.0 - b * f - c)
}

/// Resistance (Ω) of a uniform conductor of resistivity `rho_e` (Ω·m), length `l` (m) and
/// cross-section `area` (m²).
pub fn uniform_resistance(rho_e: f64, l: f64, area: f64) -> f64 {
    rho_e * l / area
}

/// Kohlrausch: maximum steady temperature rise (K) of a conductor whose ends are held at the
/// same temperature and at potentials differing by `v0` (V), other surfaces insulating and
/// adiabatic: V0² / (8 ρ_e λ), for any geometry.
pub fn kohlrausch_max_rise(v0: f64, rho_e: f64, lambda: f64) -> f64 {
    v0 * v0 / (8.0 * rho_e * lambda)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hasselman_johnson_is_maxwell_of_the_equivalent_sphere() {
        let (lm, f) = (2.0, 0.155);
        for li in [0.2, 10.0] {
            assert!((hasselman_johnson(lm, li, f, 0.0) - maxwell(lm, li, f)).abs() < 1e-14);
            for alpha in [0.1, 1.0, 10.0] {
                let eq = li / (1.0 + alpha * li / lm);
                assert!((hasselman_johnson(lm, li, f, alpha) - maxwell(lm, eq, f)).abs() < 1e-14);
            }
        }
    }
    use approx::assert_abs_diff_eq;

    const A_SLAB: f64 = 33.0 / (7800.0 * 0.9);
    const A_AL: f64 = 185.0 / (2700.0 * 900.0);

    #[test]
    fn slab_matches_the_reference_table() {
        // shared/refs/analytic.md §1, t = 0.1 s row.
        let want = [
            25.000, 25.030, 25.090, 25.224, 25.504, 26.030, 26.921, 28.279, 30.142, 32.443, 35.000,
        ];
        for (i, w) in want.iter().enumerate() {
            let y = 0.01 * i as f64;
            assert_abs_diff_eq!(
                slab_temperature(y, 0.1, 0.1, 25.0, 35.0, 25.0, A_SLAB),
                *w,
                epsilon = 1.5e-3
            );
        }
    }

    #[test]
    fn sphere_centre_matches_the_corrected_series() {
        let want = [
            (1.0, 20.317),
            (2.0, 33.575),
            (5.0, 120.778),
            (10.0, 182.178),
            (20.0, 199.118),
            (30.0, 199.956),
        ];
        for (t, w) in want {
            assert_abs_diff_eq!(
                sphere_centre_temperature(t, 0.05, 20.0, 200.0, A_AL),
                w,
                epsilon = 1.5e-3
            );
        }
        assert_abs_diff_eq!(
            sphere_centre_temperature(0.5, 0.05, 20.0, 200.0, A_AL),
            20.0,
            epsilon = 1e-3
        );
    }

    #[test]
    fn sphere_profile_at_10_s() {
        let want = [
            182.178, 182.470, 183.327, 184.701, 186.511, 188.653, 191.007, 193.442, 195.831, 198.052, 200.000,
        ];
        for (i, w) in want.iter().enumerate() {
            let r = 0.005 * i as f64;
            assert_abs_diff_eq!(
                sphere_temperature(r, 10.0, 0.05, 20.0, 200.0, A_AL),
                *w,
                epsilon = 1.5e-3
            );
        }
    }

    #[test]
    fn effective_medium_values() {
        // analytic.md §4 epoxy/silica table.
        assert_abs_diff_eq!(0.195 * maxwell(0.195, 1.5, 0.3), 0.3478, epsilon = 1e-4);
        assert_abs_diff_eq!(0.195 * third_order(0.195, 1.5, 0.3), 0.3558, epsilon = 1e-4);
        assert_abs_diff_eq!(maxwell(1.0, 5.0, 0.1551403779550515), 1.29183, epsilon = 1e-5);
    }

    #[test]
    fn electric_references() {
        let r = uniform_resistance(0.73e-6, 5e-3, PI * 1e-6);
        assert_abs_diff_eq!(r, 1.16183e-3, epsilon = 1e-8);
        assert_abs_diff_eq!(
            20.0 + kohlrausch_max_rise(0.01, 7.3e-7, 15.0),
            21.1416,
            epsilon = 1e-4
        );
    }
}
