//! Imports from other DEM codes: each format written here from a known demcon packing, read
//! back, and compared with it (bit for bit, or to 1e-15 relative where a diameter is rescaled);
//! bad input gives an error naming the file and what is missing.

use std::fmt::Write as _;
use std::path::PathBuf;

use demcon_core::{Container, ParticleSet};
use demcon_packing::{
    ImportFormat, PackingError, PackingParams, RadiusDistribution, check_imported, import_packing, pack,
};

/// A small periodic packing from demcon's own packer (polydisperse, so radii differ).
fn known() -> (ParticleSet, [f64; 3]) {
    let size = [1.0e-3, 1.2e-3, 0.9e-3];
    let params = PackingParams::new(
        Container::Periodic { size },
        60,
        0.45,
        RadiusDistribution::gaussian(0.2),
    );
    let (p, _) = pack(&params, 7, None).unwrap();
    (p, size)
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("demcon-import-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Writes a PackingGeneration folder: `packing.xyzd` with diameters `2r / factor`, a
/// `packing.nfo` whose porosities give that factor, a `generation.conf` with the box.
fn write_packing_generation(dir: &std::path::Path, p: &ParticleSet, size: [f64; 3], porosities: (f64, f64)) {
    let (theoretical, final_porosity) = porosities;
    let factor = ((1.0 - final_porosity) / (1.0 - theoretical)).cbrt();
    let mut bytes = Vec::new();
    for (c, r) in p.centres.iter().zip(&p.radii) {
        for v in [c.x, c.y, c.z, 2.0 * r / factor] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    std::fs::write(dir.join("packing.xyzd"), bytes).unwrap();
    std::fs::write(
        dir.join("packing.nfo"),
        format!(
            "N: {}\n Dimensions: {:.6} {:.6} {:.6}\n Theoretical Porosity: {theoretical}\n\
             Final Porosity: {final_porosity} (Tolerance: 1.000100)\nTotal Simulation Time: 12.0\n\
             Total Iterations: 393\nRuns count: 1",
            p.len(),
            size[0],
            size[1],
            size[2]
        ),
    )
    .unwrap();
    std::fs::write(
        dir.join("generation.conf"),
        format!(
            "Particles count: {}\nPacking size: {} {} {}\nGeneration start: 0\nSeed: 341\n\
             Steps to write: 1000\nBoundaries mode: 1\nContraction rate: 1.328910e-005\n",
            p.len(),
            size[0],
            size[1],
            size[2]
        ),
    )
    .unwrap();
}

#[test]
fn packing_generation_round_trip_bit_for_bit() {
    let (p, size) = known();
    let d = scratch("pg");
    // Equal porosities: the rescaling factor is exactly 1, so r = d/2 bit for bit.
    write_packing_generation(&d, &p, size, (0.36, 0.36));
    let imp = import_packing(ImportFormat::PackingGeneration, &d).unwrap();
    assert_eq!(imp.particles, p);
    assert_eq!(imp.container, Some(Container::Periodic { size }));
    check_imported(&imp.particles, &imp.container.unwrap()).unwrap();
}

#[test]
fn packing_generation_diameters_rescaled_by_the_nfo_porosities() {
    let (p, size) = known();
    let d = scratch("pg-rescaled");
    write_packing_generation(&d, &p, size, (0.5, 0.4));
    let imp = import_packing(ImportFormat::PackingGeneration, &d).unwrap();
    assert_eq!(imp.particles.centres, p.centres);
    for (a, b) in imp.particles.radii.iter().zip(&p.radii) {
        assert!((a - b).abs() <= 1e-15 * b, "{a} vs {b}");
    }
    assert!(
        imp.notes.iter().any(|n| n.contains("scaled by")),
        "{:?}",
        imp.notes
    );
}

#[test]
fn packing_generation_missing_or_truncated_files_are_named() {
    let (p, size) = known();
    let d = scratch("pg-bad");
    write_packing_generation(&d, &p, size, (0.36, 0.36));
    std::fs::remove_file(d.join("packing.nfo")).unwrap();
    let e = import_packing(ImportFormat::PackingGeneration, &d)
        .unwrap_err()
        .to_string();
    assert!(e.contains("packing.nfo") && e.contains("missing"), "{e}");

    write_packing_generation(&d, &p, size, (0.36, 0.36));
    let mut bytes = std::fs::read(d.join("packing.xyzd")).unwrap();
    bytes.pop();
    std::fs::write(d.join("packing.xyzd"), &bytes).unwrap();
    let e = import_packing(ImportFormat::PackingGeneration, &d)
        .unwrap_err()
        .to_string();
    assert!(e.contains("packing.xyzd") && e.contains("32-byte records"), "{e}");

    std::fs::remove_file(d.join("packing.xyzd")).unwrap();
    let e = import_packing(ImportFormat::PackingGeneration, &d)
        .unwrap_err()
        .to_string();
    assert!(e.contains("packing.xyzd") && e.contains("missing"), "{e}");
}

/// A `dump custom` with an earlier snapshot (other values) before the last one; columns in
/// an unusual order and rows reversed (ids give the order back); coordinates offset by `lo`.
fn write_dump(p: &ParticleSet, size: [f64; 3], lo: f64, flags: &str, columns: &str) -> String {
    let mut s = String::new();
    for (step, scale) in [(0, 0.5), (1000, 1.0)] {
        let _ = write!(
            s,
            "ITEM: TIMESTEP\n{step}\nITEM: NUMBER OF ATOMS\n{}\nITEM: BOX BOUNDS {flags}\n",
            p.len()
        );
        for l in size {
            let _ = writeln!(s, "{lo} {}", lo + l);
        }
        let _ = writeln!(s, "ITEM: ATOMS {columns}");
        for i in (0..p.len()).rev() {
            let c = p.centres[i];
            let row: Vec<String> = columns
                .split_whitespace()
                .map(|col| match col {
                    "id" => (i + 1).to_string(),
                    "type" => "1".into(),
                    "x" => (c.x + lo).to_string(),
                    "y" => (c.y + lo).to_string(),
                    "z" => (c.z + lo).to_string(),
                    "radius" => (p.radii[i] * scale).to_string(),
                    _ => "0".into(),
                })
                .collect();
            let _ = writeln!(s, "{}", row.join(" "));
        }
    }
    s
}

#[test]
fn liggghts_dump_round_trip_last_snapshot() {
    let (p, size) = known();
    let d = scratch("dump");
    let f = d.join("dump.liggghts");
    std::fs::write(
        &f,
        write_dump(&p, size, 0.0, "pp pp pp", "id type vx radius z x y"),
    )
    .unwrap();
    let imp = import_packing(ImportFormat::LiggghtsDump, &f).unwrap();
    assert_eq!(imp.particles, p);
    assert_eq!(imp.container, Some(Container::Periodic { size }));
}

#[test]
fn liggghts_dump_walled_box_is_shifted_to_start_at_zero() {
    let (p, size) = known();
    let d = scratch("dump-ff");
    let f = d.join("dump.liggghts");
    let lo = -0.5e-3;
    std::fs::write(&f, write_dump(&p, size, lo, "ff ff ff", "id type x y z radius")).unwrap();
    let imp = import_packing(ImportFormat::LiggghtsDump, &f).unwrap();
    let Some(Container::Box { size: got }) = imp.container else {
        panic!("{:?}", imp.container)
    };
    for k in 0..3 {
        assert!((got[k] - size[k]).abs() <= 1e-15 * size[k]);
    }
    assert_eq!(imp.particles.radii, p.radii);
    for (a, b) in imp.particles.centres.iter().zip(&p.centres) {
        assert!((a - b).norm() <= 4e-16 * 2e-3, "{a} vs {b}");
    }
    assert!(imp.notes.iter().any(|n| n.contains("shifted")), "{:?}", imp.notes);
}

#[test]
fn liggghts_dump_without_radius_is_an_error_naming_the_file() {
    let (p, size) = known();
    let d = scratch("dump-bad");
    let f = d.join("dump.noradius");
    std::fs::write(&f, write_dump(&p, size, 0.0, "pp pp pp", "id type x y z")).unwrap();
    let e = import_packing(ImportFormat::LiggghtsDump, &f).unwrap_err();
    assert!(matches!(e, PackingError::Import { .. }), "{e:?}");
    let e = e.to_string();
    assert!(
        e.contains("dump.noradius") && e.contains("no `radius` column"),
        "{e}"
    );
}

#[test]
fn yade_text_round_trip_bit_for_bit() {
    let (p, _) = known();
    let d = scratch("yade");
    let f = d.join("export.txt");
    let mut s = String::from("#format x_y_z_r\n# a comment\n");
    for (c, r) in p.centres.iter().zip(&p.radii) {
        let _ = writeln!(s, "{}\t{}\t{}\t{}", c.x, c.y, c.z, r);
    }
    std::fs::write(&f, s).unwrap();
    let imp = import_packing(ImportFormat::YadeText, &f).unwrap();
    assert_eq!(imp.particles, p);
    assert_eq!(imp.container, None);
}

#[test]
fn a_container_too_small_is_the_check_inside_error() {
    let (p, size) = known();
    let small = Container::Box {
        size: [0.5 * size[0], size[1], size[2]],
    };
    let e = check_imported(&p, &small).unwrap_err();
    assert!(matches!(e, PackingError::Outside { .. }), "{e:?}");
}
