//! Terreros α transmission surfaces (Hubert et al. 2017 §2.1, after Terreros, Iordanoff &
//! Charles 2013): a particle with n neighbours is a polyhedron with n faces circumscribing
//! its sphere; it offers each neighbour S_i = α(n)·R_i² and stands for the volume V_i/f_v(n).

/// Neighbour counts of the Platonic solids used as nodes: tetrahedron, cube, octahedron,
/// dodecahedron, icosahedron.
pub const TERREROS_NODES: [u32; 5] = [4, 6, 8, 12, 20];

/// α = (area of one face)/R² of the Platonic solid with inradius R, at each node
/// (dimensionless): 6√3, 4, 3√3/2, √(25 + 10√5)/(5/2 + 11√5/10), 12√3/(3 + √5)².
pub const TERREROS_ALPHA: [f64; 5] = [
    10.392304845413264,
    4.0,
    2.598076211353316,
    1.3875727571288774,
    0.7581084215398356,
];

/// f_v = (4/3 π R³)/(solid volume) at each node (dimensionless); equal to 4π/(n·α) because
/// the solid is n pyramids of height R.
pub const TERREROS_VOLUME_FRACTION: [f64; 5] = [
    0.3022998940390363,
    0.5235987755982988,
    0.6045997880780726,
    0.7546973993374059,
    0.8287977192520121,
];

/// α and f_v for one neighbour count.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TerrerosValue {
    /// Surface factor α: S_i = α·R_i² (dimensionless).
    pub alpha: f64,
    /// Volume fraction f_v: representative volume V_i/f_v (dimensionless).
    pub volume_fraction: f64,
    /// Whether the count was outside [4, 20] and the end value was used.
    pub clamped: bool,
}

/// α(n) and f_v(n) for a particle with `n_neighbours` contacts: exact at the Platonic nodes
/// n = 4, 6, 8, 12, 20, linear in n between them (as the electric paper states), clamped to
/// the end values outside [4, 20] (where the paper is silent) with `clamped` set.
pub fn terreros_alpha(n_neighbours: u32) -> TerrerosValue {
    let last = TERREROS_NODES.len() - 1;
    if n_neighbours <= TERREROS_NODES[0] || n_neighbours >= TERREROS_NODES[last] {
        let k = if n_neighbours <= TERREROS_NODES[0] {
            0
        } else {
            last
        };
        return TerrerosValue {
            alpha: TERREROS_ALPHA[k],
            volume_fraction: TERREROS_VOLUME_FRACTION[k],
            clamped: n_neighbours < TERREROS_NODES[0] || n_neighbours > TERREROS_NODES[last],
        };
    }
    let k = TERREROS_NODES.partition_point(|&m| m <= n_neighbours) - 1;
    let (n0, n1) = (TERREROS_NODES[k] as f64, TERREROS_NODES[k + 1] as f64);
    let t = (n_neighbours as f64 - n0) / (n1 - n0);
    let lerp = |a: &[f64; 5]| a[k] + t * (a[k + 1] - a[k]);
    TerrerosValue {
        alpha: lerp(&TERREROS_ALPHA),
        volume_fraction: lerp(&TERREROS_VOLUME_FRACTION),
        clamped: false,
    }
}

/// Transmission surface of a contact (m²): S_pq = √(S_p S_q) = √(α(n_p) α(n_q))·R_p·R_q,
/// with n the particles' neighbour counts and R their radii (m).
pub fn surface_terreros(n_p: u32, r_p: f64, n_q: u32, r_q: f64) -> f64 {
    (terreros_alpha(n_p).alpha * terreros_alpha(n_q).alpha).sqrt() * (r_p * r_q)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nodes_are_exact_and_interpolation_is_linear() {
        for k in 0..5 {
            let v = terreros_alpha(TERREROS_NODES[k]);
            assert_eq!(
                (v.alpha, v.volume_fraction, v.clamped),
                (TERREROS_ALPHA[k], TERREROS_VOLUME_FRACTION[k], false)
            );
        }
        let v = terreros_alpha(10);
        assert!((v.alpha - 0.5 * (TERREROS_ALPHA[2] + TERREROS_ALPHA[3])).abs() < 1e-15);
        let v = terreros_alpha(7);
        assert!(
            (v.volume_fraction - 0.5 * (TERREROS_VOLUME_FRACTION[1] + TERREROS_VOLUME_FRACTION[2])).abs()
                < 1e-15
        );
        assert!(terreros_alpha(3).clamped && terreros_alpha(0).clamped && terreros_alpha(21).clamped);
        assert_eq!(terreros_alpha(25).alpha, TERREROS_ALPHA[4]);
        // α decreases and f_v increases with n.
        for n in 4..20 {
            assert!(terreros_alpha(n + 1).alpha < terreros_alpha(n).alpha);
            assert!(terreros_alpha(n + 1).volume_fraction > terreros_alpha(n).volume_fraction);
        }
    }

    #[test]
    fn cube_surface_is_four_r_squared() {
        assert_eq!(surface_terreros(6, 0.5, 6, 0.5), 1.0);
        // Geometric mean: symmetric.
        assert_eq!(surface_terreros(5, 0.3, 9, 0.7), surface_terreros(9, 0.7, 5, 0.3));
    }
}
