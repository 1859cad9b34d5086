//! Phases from a labelled 3-D image: the same image as `.raw`, `.npy` and multi-page `.tif`
//! gives the same bits; a slab of voxels conducts as the same slab given as a box region (its
//! faces are voxel faces); laminate images under conforming cells are exact; and every bad
//! image is refused by name before packing.

use std::path::{Path, PathBuf};

use demcon_scene::{RunOptions, Scene, run, summary_json};

/// 20³ voxels of 0.05 m in the periodic unit cell: label 7 for 0.25 ≤ x < 0.65 (a slab clear
/// of the periodic faces, which a box region would not wrap round), 2 elsewhere.
const N: usize = 20;

fn label(x: usize) -> u8 {
    if (5..13).contains(&x) { 7 } else { 2 }
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("demcon-images-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// x fastest.
fn raw_bytes() -> Vec<u8> {
    (0..N * N * N).map(|i| label(i % N)).collect()
}

/// numpy `.npy` v1.0, C order, axes (x, y, z): z fastest.
fn npy_bytes() -> Vec<u8> {
    npy_of(|x, _| label(x))
}

/// The `.npy` of an image whose label depends on x and y alone.
fn npy_of(label: impl Fn(usize, usize) -> u8) -> Vec<u8> {
    let mut header = format!("{{'descr': '|u1', 'fortran_order': False, 'shape': ({N}, {N}, {N}), }}");
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut b = b"\x93NUMPY\x01\x00".to_vec();
    b.extend((header.len() as u16).to_le_bytes());
    b.extend(header.as_bytes());
    for x in 0..N {
        for y in 0..N {
            for _z in 0..N {
                b.push(label(x, y));
            }
        }
    }
    b
}

fn write_tiff(path: &Path, rgb: bool) {
    use tiff::encoder::{TiffEncoder, colortype};
    let mut enc = TiffEncoder::new(std::fs::File::create(path).unwrap()).unwrap();
    let page: Vec<u8> = (0..N * N).map(|i| label(i % N)).collect();
    for _ in 0..N {
        if rgb {
            let p: Vec<u8> = page.iter().flat_map(|&v| [v, v, v]).collect();
            enc.write_image::<colortype::RGB8>(N as u32, N as u32, &p)
                .unwrap();
        } else {
            enc.write_image::<colortype::Gray8>(N as u32, N as u32, &page)
                .unwrap();
        }
    }
}

fn scene(phases: &str, extra: &str) -> String {
    format!(
        r#"(
    seed: 2,
    packing: Generate(container: Periodic(size: (1.0, 1.0, 1.0)), count: 4000, phi: 0.6, radius_cov: 0.3),
    surface: Laguerre,
    materials: [
        (name: "m", conductivity: 1.0, density: 1000.0, specific_heat: 500.0),
        (name: "g", conductivity: 10.0, density: 1000.0, specific_heat: 500.0),
    ],
    phases: [{phases}],
    thermal: Some((bcs: [], solver: Homogenize)),
    outputs: (vtk: false),
    {extra}
)"#
    )
}

fn image(file: &str, extra: &str) -> String {
    scene(
        &format!(r#"Image(path: "{file}", voxel: 0.05, labels: [(2, "m"), (7, "g")]{extra})"#),
        "",
    )
}

fn tensor(text: &str, base: &Path) -> serde_json::Value {
    let s = Scene::parse(text, Path::new("images.ron"), base.to_path_buf()).unwrap();
    summary_json("i", &run(&s, &RunOptions::default()).unwrap())["etc_tensor"].clone()
}

#[test]
fn one_image_in_three_formats_and_as_a_box_region() {
    let d = dir("formats");
    std::fs::write(d.join("slab.raw"), raw_bytes()).unwrap();
    std::fs::write(d.join("slab.npy"), npy_bytes()).unwrap();
    write_tiff(&d.join("slab.tif"), false);
    let raw = tensor(
        &image("slab.raw", r#", dims: Some((20, 20, 20)), dtype: Some("u8")"#),
        &d,
    );
    assert_eq!(raw, tensor(&image("slab.npy", ""), &d));
    assert_eq!(raw, tensor(&image("slab.tif", ""), &d));
    // The same slab as a box region under the same (segment) rule: the image's level set is
    // the slab's own signed distance along x, so the two agree to round-off.
    let region = tensor(
        &scene(
            r#"Region(material: "g", region: Box(min: (0.25, -1.0, -1.0), max: (0.65, 2.0, 2.0)))"#,
            "phase_rule: Some(Segment),",
        ),
        &d,
    );
    for i in 0..3 {
        let (a, b) = (raw[i][i].as_f64().unwrap(), region[i][i].as_f64().unwrap());
        assert!((a - b).abs() < 1e-6 * b, "axis {i}: image {a}, box {b}");
    }
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn laminate_images_under_conforming_cells_are_exact_in_series_and_in_parallel() {
    // Conforming seeds on the voxel faces: every cell is of one layer, so the network is exact
    // for a laminate — across the layers the series value, along them the parallel one —
    // also for a layer that crosses the periodic face (which a box region would not wrap).
    let d = dir("laminate");
    std::fs::write(d.join("slab.npy"), npy_bytes()).unwrap();
    std::fs::write(
        d.join("wrap.npy"),
        npy_of(|x, _| if (3..15).contains(&x) { 2 } else { 7 }),
    )
    .unwrap();
    for (file, t) in [("slab.npy", 0.4), ("wrap.npy", 0.4)] {
        let phase = format!(r#"Image(path: "{file}", voxel: 0.05, labels: [(2, "m"), (7, "g")])"#);
        let k = tensor(&scene(&phase, "phase_rule: Some(Conforming),"), &d);
        let series = 1.0 / (t / 10.0 + (1.0 - t) / 1.0);
        let parallel = t * 10.0 + (1.0 - t) * 1.0;
        for (i, want) in [(0, series), (1, parallel), (2, parallel)] {
            let got = k[i][i].as_f64().unwrap();
            assert!(
                (got / want - 1.0).abs() < 1e-6,
                "{file} axis {i}: {got} vs {want}"
            );
        }
    }
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn bad_images_are_refused_by_name_before_packing() {
    let d = dir("bad");
    std::fs::write(
        d.join("post.npy"),
        npy_of(|x, y| if x == 4 && y == 4 { 7 } else { 2 }),
    )
    .unwrap();
    std::fs::write(d.join("slab.raw"), raw_bytes()).unwrap();
    std::fs::write(d.join("short.raw"), &raw_bytes()[..N * N * N - 3]).unwrap();
    std::fs::write(d.join("slab.npy"), npy_bytes()).unwrap();
    std::fs::write(d.join("slab.png"), b"not an image").unwrap();
    write_tiff(&d.join("rgb.tif"), true);
    let raw = r#", dims: Some((20, 20, 20)), dtype: Some("u8")"#;
    let cases = [
        (
            scene(r#"Image(path: "slab.npy", voxel: 0.05, labels: [(2, "m")])"#, ""),
            "labels 7 in the image have no material",
        ),
        (
            scene(
                r#"Image(path: "slab.npy", voxel: 0.0, labels: [(2, "m"), (7, "g")])"#,
                "",
            ),
            "phases[0].voxel",
        ),
        (
            scene(
                r#"Image(path: "slab.npy", voxel: 0.04, labels: [(2, "m"), (7, "g")])"#,
                "",
            ),
            "phases[0].origin",
        ),
        (image("short.raw", raw), "truncated"),
        (image("slab.raw", ""), "phases[0].dims"),
        (
            image("slab.raw", r#", dims: Some((20, 20, 20)), dtype: Some("f32")"#),
            "phases[0].dtype",
        ),
        (image("slab.png", ""), "phases[0].path"),
        (image("rgb.tif", ""), "grey"),
        (image("nowhere.npy", ""), "nowhere.npy"),
        (
            scene(
                r#"Image(path: "slab.npy", voxel: 0.05, labels: [(2, "m"), (7, "glass")])"#,
                "",
            ),
            "phases[0].labels[1]",
        ),
        (
            // A post one voxel (0.05 m) wide under conforming cells at h = 0.063 m.
            scene(
                r#"Image(path: "post.npy", voxel: 0.05, labels: [(2, "m"), (7, "g")])"#,
                "phase_rule: Some(Conforming),",
            ),
            "narrower than the mean site spacing",
        ),
    ];
    for (text, want) in cases {
        let e = Scene::parse(&text, Path::new("images.ron"), d.clone())
            .err()
            .map(|e| e.to_string())
            .expect("refused at parse");
        assert!(e.contains(want), "expected `{want}` in: {e}");
    }
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn a_region_across_a_periodic_face_is_repeated_round_the_period() {
    // The box x ∈ [0.75, 1.15] of the periodic unit cell is the layer x ∈ [0, 0.15) ∪ [0.75, 1)
    // of the `wrap` image: the same conductivity under each rule that reads a level set.
    let d = dir("wrap");
    std::fs::write(
        d.join("wrap.npy"),
        npy_of(|x, _| if (3..15).contains(&x) { 2 } else { 7 }),
    )
    .unwrap();
    let across = r#"Region(material: "g", region: Box(min: (0.75, -1.0, -1.0), max: (1.15, 2.0, 2.0)))"#;
    let wrap = r#"Image(path: "wrap.npy", voxel: 0.05, labels: [(2, "m"), (7, "g")])"#;
    for rule in ["Segment", "Laminate"] {
        let extra = format!("phase_rule: Some({rule}),");
        let (a, b) = (
            tensor(&scene(across, &extra), &d),
            tensor(&scene(wrap, &extra), &d),
        );
        for i in 0..3 {
            let (a, b) = (a[i][i].as_f64().unwrap(), b[i][i].as_f64().unwrap());
            assert!((a - b).abs() < 1e-6 * b, "{rule} axis {i}: box {a}, image {b}");
        }
    }
    std::fs::remove_dir_all(&d).ok();
}
