//! An image's phases under the conforming rule: the voxel faces between voxels of different
//! phases become plane patches for the conforming seeds (each plane of faces merged into
//! rectangles), and every cell takes the phase of the voxel holding its site. The cells then
//! follow the staircase of voxel faces itself, where the other rules read its smoothed level
//! set ([`demcon_core::Voxels`]).

use demcon_core::{Container, ParticleSet, Voxels};
use demcon_graph::PlanePatch;

use crate::ModelError;

/// The phase of every voxel of the image the labels share (x fastest), `None` where no
/// label maps it to a material; the image's voxel geometry is that of the first label.
fn phase_grid(labels: &[(u16, Voxels)]) -> Option<(&Voxels, Vec<Option<u16>>)> {
    let (_, first) = labels.first()?;
    let [nx, ny, nz] = first.dims();
    let mut grid = vec![None; nx * ny * nz];
    for (phase, voxels) in labels {
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    if voxels.holds([i, j, k]) {
                        grid[(k * ny + j) * nx + i] = Some(*phase);
                    }
                }
            }
        }
    }
    Some((first, grid))
}

/// The rectangles (corner `(u, v)` and size `(w, h)`, in cells) that cover the true cells of
/// the `nu × nv` mask (u fastest), merged greedily: each rectangle grows along u, then along v
/// while the whole row is true and not yet covered.
fn rectangles(mask: &[bool], nu: usize, nv: usize) -> Vec<([usize; 2], [usize; 2])> {
    let mut used = vec![false; mask.len()];
    let free = |used: &[bool], u: usize, v: usize| mask[v * nu + u] && !used[v * nu + u];
    let mut out = Vec::new();
    for v in 0..nv {
        for u in 0..nu {
            if !free(&used, u, v) {
                continue;
            }
            let w = (u..nu).take_while(|&x| free(&used, x, v)).count();
            let h = (v..nv)
                .take_while(|&y| (u..u + w).all(|x| free(&used, x, y)))
                .count();
            for y in v..v + h {
                used[y * nu + u..y * nu + u + w].fill(true);
            }
            out.push(([u, v], [w, h]));
        }
    }
    out
}

/// The voxel faces between voxels of different phases (a voxel no label maps counts as a
/// phase of its own), as rectangles clipped to the container. A walled image: its inner
/// planes, those strictly inside the container. A periodic image (one period of the box):
/// every plane, the one at its lower face between its last and first voxels.
pub(crate) fn voxel_faces(labels: &[(u16, Voxels)], container: &Container) -> Vec<PlanePatch> {
    let Some((image, grid)) = phase_grid(labels) else {
        return Vec::new();
    };
    let dims = image.dims();
    let (origin, size) = (image.origin(), image.voxel());
    let periodic = image.is_periodic();
    let b = container.bounds();
    let at_voxel = |c: [usize; 3]| grid[(c[2] * dims[1] + c[1]) * dims[0] + c[0]];
    let mut faces = Vec::new();
    for axis in 0..3 {
        let [u, v] = [(axis + 1) % 3, (axis + 2) % 3];
        let (n, nu, nv) = (dims[axis], dims[u], dims[v]);
        let planes = if periodic { 0..n } else { 1..n };
        for k in planes {
            let at = origin[axis] + k as f64 * size;
            if !periodic && (at <= b.min[axis] || at >= b.max[axis]) {
                continue;
            }
            let mut mask = vec![false; nu * nv];
            for jv in 0..nv {
                for iu in 0..nu {
                    let mut below = [0usize; 3];
                    below[axis] = (k + n - 1) % n;
                    below[u] = iu;
                    below[v] = jv;
                    let mut above = below;
                    above[axis] = k;
                    mask[jv * nu + iu] = at_voxel(below) != at_voxel(above);
                }
            }
            for ([iu, jv], [w, h]) in rectangles(&mask, nu, nv) {
                let corner = |i: usize, axis: usize| origin[axis] + i as f64 * size;
                let mut lo = [corner(iu, u), corner(jv, v)];
                let mut hi = [corner(iu + w, u), corner(jv + h, v)];
                if !periodic {
                    lo = [lo[0].max(b.min[u]), lo[1].max(b.min[v])];
                    hi = [hi[0].min(b.max[u]), hi[1].min(b.max[v])];
                    if !(hi[0] > lo[0] && hi[1] > lo[1]) {
                        continue;
                    }
                }
                faces.push(PlanePatch::Rect { axis, at, lo, hi });
            }
        }
    }
    faces
}

/// Refuses conforming cells on the image of phase entry `entry` (its `labels`) when a
/// rectangle of its voxel faces ([`voxel_faces`]) is narrower than the mean site spacing `h`
/// (m): the conforming seeds, about 0.8 h apart, cannot follow steps finer than that (a sphere
/// of 32³ voxels under conforming cells at h = 1.2 voxels measured +5 % on its conductivity,
/// where the segment rule reads it within 1.5 %). Laminates and coarse images pass: their
/// faces are wide.
///
/// # Errors
/// [`ModelError::Invalid`] naming `rule_field` (the phase rule) and the entry.
pub fn check_conformable(
    labels: &[(u16, Voxels)],
    container: &Container,
    h: f64,
    (rule_field, entry): (&str, &str),
) -> Result<(), ModelError> {
    let narrowest = voxel_faces(labels, container)
        .iter()
        .filter_map(|f| match f {
            PlanePatch::Rect { lo, hi, .. } => Some((hi[0] - lo[0]).min(hi[1] - lo[1])),
            PlanePatch::Crack(_) => None,
        })
        .fold(f64::INFINITY, f64::min);
    if narrowest < h {
        return Err(ModelError::invalid(
            rule_field,
            "Conforming",
            format!(
                "the voxel faces of {entry} make steps {narrowest:.3e} m wide, narrower than the mean site spacing \
                 h = {h:.3e} m: conforming seeds (about 0.8 h apart) cannot follow them; use the Segment rule (the \
                 default with images, which reads the image's smoothed level set), or fewer, larger voxels"
            ),
        ));
    }
    Ok(())
}

/// Gives every particle whose centre lies in a voxel of a label that label's phase (voxel
/// lookup, no smoothing). Returns how many particles the labels claim.
pub(crate) fn assign_voxels(particles: &mut ParticleSet, labels: &[(u16, Voxels)]) -> usize {
    let mut claimed = 0;
    for i in 0..particles.len() {
        let c = particles.centres[i];
        if let Some(&(phase, _)) = labels.iter().find(|(_, v)| v.holds_point(&c)) {
            particles.phases[i] = phase;
            claimed += 1;
        }
    }
    claimed
}

#[cfg(test)]
mod tests {
    use super::*;
    use demcon_core::Vec3;

    fn image(dims: [usize; 3], voxel: f64, periodic: bool, inside: impl Fn([usize; 3]) -> bool) -> Voxels {
        let mask: Vec<bool> = (0..dims.iter().product())
            .map(|i| inside([i % dims[0], (i / dims[0]) % dims[1], i / (dims[0] * dims[1])]))
            .collect();
        Voxels::from_mask(dims, voxel, Vec3::zeros(), &mask, periodic, "image").unwrap()
    }

    #[test]
    fn rectangles_cover_the_mask_once() {
        // An L of 5 cells and a lone cell in a 4 × 3 mask.
        let mask = [
            true, true, false, false, //
            true, false, false, true, //
            true, true, false, false,
        ];
        let rects = rectangles(&mask, 4, 3);
        let mut covered = [0; 12];
        for ([u, v], [w, h]) in &rects {
            for y in *v..v + h {
                for x in *u..u + w {
                    covered[y * 4 + x] += 1;
                }
            }
        }
        let want: Vec<i32> = mask.iter().map(|&m| i32::from(m)).collect();
        assert_eq!(covered.to_vec(), want);
        assert_eq!(rects.len(), 4); // [0..2)×{0}, {0}×[1..3), {3}×{1}, {1}×{2}
    }

    #[test]
    fn a_periodic_layer_has_two_whole_faces() {
        // Layer z ∈ [0.25, 0.5) of a periodic 4³ image of 0.25 m voxels: faces at z = 0.25, 0.5.
        let layer = image([4, 4, 4], 0.25, true, |c| c[2] == 1);
        let rest = image([4, 4, 4], 0.25, true, |c| c[2] != 1);
        let container = Container::Periodic { size: [1.0; 3] };
        let faces = voxel_faces(&[(0, rest), (1, layer.clone())], &container);
        let want = |at: f64| PlanePatch::Rect {
            axis: 2,
            at,
            lo: [0.0, 0.0],
            hi: [1.0, 1.0],
        };
        assert_eq!(faces, vec![want(0.25), want(0.5)]);
        // A label alone: the unmapped voxels are a phase of their own.
        assert_eq!(voxel_faces(&[(1, layer)], &container).len(), 2);
    }

    #[test]
    fn steps_narrower_than_the_site_spacing_are_refused() {
        let container = Container::Periodic { size: [1.0; 3] };
        let layer = image([4, 4, 4], 0.25, true, |c| c[2] == 1);
        let post = image([4, 4, 4], 0.25, true, |c| c[0] == 1 && c[1] == 1);
        let fields = ("phase_rule", "phases[0]");
        assert!(check_conformable(&[(1, layer)], &container, 0.3, fields).is_ok());
        assert!(check_conformable(&[(1, post.clone())], &container, 0.2, fields).is_ok());
        let e = check_conformable(&[(1, post)], &container, 0.3, fields)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("phase_rule") && e.contains("phases[0]") && e.contains("2.500e-1"),
            "{e}"
        );
    }

    #[test]
    fn a_walled_cube_has_six_faces_clipped_to_the_container() {
        // Voxel (1, 1, 1) of a 3³ image of 1 m voxels, in a box that cuts the image at x = 2.5.
        let cube = image([3, 3, 3], 1.0, false, |c| c == [1, 1, 1]);
        let container = Container::Box {
            size: [2.5, 3.0, 3.0],
        };
        let faces = voxel_faces(&[(1, cube.clone())], &container);
        assert_eq!(faces.len(), 6);
        for f in &faces {
            let PlanePatch::Rect { axis, at, lo, hi } = f else {
                panic!("a rectangle")
            };
            assert!(*at == 1.0 || *at == 2.0, "axis {axis} at {at}");
            assert_eq!((*lo, *hi), ([1.0, 1.0], [2.0, 2.0]));
        }
        let centres = [0.5, 1.5, 2.5].map(|x| Vec3::new(x, 1.5, 1.5)).to_vec();
        let mut particles = ParticleSet::new(centres, vec![0.1; 3]).unwrap();
        assert_eq!(assign_voxels(&mut particles, &[(3, cube)]), 1);
        assert_eq!(particles.phases, vec![0, 3, 0]);
    }
}
