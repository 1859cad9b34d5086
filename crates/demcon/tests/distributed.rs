//! `mpirun -n K demcon run SCENE --distributed` (built with `--features petsc`) against the
//! serial run of the same scene: effective conductivity, resistance and every particle's
//! temperature (and potential) within 1e-8 relative, both solved to 1e-10, on 1, 2 and 4 ranks,
//! for a steady thermal, a steady electric with the ρ_e(T) fixed point, and an implicit
//! transient with Joule re-solves. Then the bad launches: a rank count above the unknowns, a
//! solve that does not converge, mpirun without --distributed, --resume — one clear error on
//! rank 0, every rank non-zero, no output folder.
//!
//! Needs `mpirun` (Open MPI's, from `openmpi-bin`) on PATH; runs as root allowed.
#![cfg(feature = "petsc")]

mod common;
#[path = "../../demcon-post/tests/common/vtk_reader.rs"]
mod vtk_reader;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::scratch;

const STEADY: &str = r#"(
    name: "steady",
    seed: 3,
    packing: Generate(container: Box(size: (0.1, 0.1, 0.1)), count: 3000, phi: 0.6, radius_cov: 0.3),
    contacts: (coordination: 7.5),
    surface: TerrerosAlpha,
    linear_solver: (rel_tol: 1e-10, max_iter: MAX_ITER),
    materials: [(name: "steel", conductivity: 33.0, density: 7800.0, specific_heat: 500.0)],
    thermal: (
        initial_temperature: 25.0,
        bcs: [WallTemperature(face: YMin, value: 25.0), WallTemperature(face: YMax, value: 35.0)],
        solver: Steady,
    ),
    outputs: (etc_axis: Some(Y), particles_csv: true, vtk: false),
)"#;

/// Steady Joule heating of a cylinder with ρ_e(T) (β = 4e-3 1/K) solved to a fixed point.
const ELECTRIC: &str = r#"(
    name: "electric",
    seed: 2,
    packing: Generate(container: Cylinder(radius: 1.0e-3, length: 5.0e-3), count: 3000, phi: 0.64,
                      radius_cov: 0.3, allow_short: true),
    contacts: (coordination: 7.5),
    surface: TerrerosAlpha,
    linear_solver: (rel_tol: 1e-10),
    materials: [(name: "AISI 304L", conductivity: 15.0, density: 7900.0, specific_heat: 500.0,
                 resistivity: 0.73e-6, resistivity_temp_coeff: 4.0e-3, resistivity_ref_temp: 20.0)],
    thermal: (
        initial_temperature: 20.0,
        bcs: [WallTemperature(face: ZMin, value: 20.0), WallTemperature(face: ZMax, value: 20.0)],
        solver: Steady,
    ),
    electric: (
        electrodes: [(face: ZMin, potential: 0.0), (face: ZMax, potential: 0.05)],
        eta: 1.0,
        surface: TerrerosAlpha,
        recouple_tolerance: 1e-6,
    ),
    outputs: (particles_csv: true, vtk: false),
)"#;

/// Implicit transient (20 steps of one Δt) with the potential re-solved as ρ_e(T) moves.
const IMPLICIT: &str = r#"(
    name: "implicit",
    seed: 4,
    packing: Generate(container: Cylinder(radius: 1.0e-3, length: 5.0e-3), count: 2000, phi: 0.64,
                      radius_cov: 0.3, allow_short: true),
    contacts: (coordination: 7.5),
    surface: TerrerosAlpha,
    linear_solver: (rel_tol: 1e-10),
    materials: [(name: "AISI 304L", conductivity: 15.0, density: 7900.0, specific_heat: 500.0,
                 resistivity: 0.73e-6, resistivity_temp_coeff: 4.0e-3, resistivity_ref_temp: 20.0)],
    thermal: (
        initial_temperature: 20.0,
        bcs: [WallTemperature(face: ZMin, value: 20.0)],
        solver: Implicit(t_end: 13.0, dt: 0.65),
    ),
    electric: (
        electrodes: [(face: ZMin, potential: 0.0), (face: ZMax, potential: 0.01)],
        eta: 1.0,
        surface: TerrerosAlpha,
        recouple_tolerance: 0.05,
    ),
    outputs: (particles_csv: true, vtk: false),
)"#;

/// `mpirun -n ranks demcon run scene --out out --distributed --quiet --threads 1 extra…`.
/// A composite on a tiled packing: by blocks under `--distributed` (every rank its own part of
/// the model).
const TILED: &str = r#"(
    name: "tiled",
    seed: 7,
    packing: Tile(
        packing: Generate(container: Periodic(size: (0.002, 0.002, 0.002)), count: 500, phi: 0.62, radius_cov: 0.3),
        repeat: REPEAT,
        walls: true,
    ),
    surface: Laguerre,
    phase_rule: Centre,
    materials: [
        (name: "epoxy", conductivity: 0.195, density: 1200.0, specific_heat: 1000.0),
        (name: "silica", conductivity: 1.5, density: 2200.0, specific_heat: 740.0),
    ],
    phases: [Inclusions(material: "silica", fraction: 0.2, size_ratio: 4.0)],
    interface: Harmonic,
    linear_solver: (rel_tol: 1e-10),
    thermal: (
        initial_temperature: 25.0,
        bcs: [WallTemperature(face: YMin, value: 25.0), WallTemperature(face: YMax, value: 35.0)],
        solver: Steady,
    ),
    outputs: (
        etc_axis: Y,
        particles_csv: true,
        vtk: true,
        flux: true,
        halo: 4.0,
        probes: [
            (name: "centre", point: (0.002, 0.002, 0.002)),
            (name: "ball", point: (0.001, 0.003, 0.002), method: Ball(0.0003)),
        ],
    ),
)"#;

fn mpirun(ranks: usize, scene: &Path, out: &Path, extra: &[&str]) -> Output {
    Command::new("mpirun")
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        // The method under test, not a user's override.
        .env_remove("PETSC_OPTIONS")
        .args(["--oversubscribe", "-n", &ranks.to_string()])
        .arg(env!("CARGO_BIN_EXE_demcon"))
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .args(["--threads", "1"])
        .args(extra)
        .output()
        .expect("mpirun on PATH (apt-get install openmpi-bin)")
}

/// Runs `scene` serially into `out`; its summary.
fn serial_run(scene: &Path, out: &Path) -> serde_json::Value {
    let o = common::demcon(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", common::text(&o));
    summary(out)
}

/// Writes `text` as `name.ron` in `dir`.
fn scene(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(format!("{name}.ron"));
    std::fs::write(&p, text).unwrap();
    p
}

fn summary(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// The named numeric columns of particles.csv, one vector each.
fn columns(out: &Path, names: &[&str]) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(out.join("particles.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let idx: Vec<usize> = names
        .iter()
        .map(|n| {
            header
                .iter()
                .position(|h| h == n)
                .unwrap_or_else(|| panic!("no column {n}"))
        })
        .collect();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    idx.iter()
        .map(|&i| {
            rows.iter()
                .map(|r| r[i].parse::<f64>().unwrap_or(f64::NAN))
                .collect()
        })
        .collect()
}

fn close(what: &str, serial: f64, dist: f64) {
    close_to(what, serial, dist, 1e-8);
}

/// Within `tol` relative. Fluxes get 1e-7: a flux is a temperature difference across about a
/// hundredth of the span, so it carries ~100× the temperatures' relative error.
fn close_to(what: &str, serial: f64, dist: f64, tol: f64) {
    let rel = (serial - dist).abs() / serial.abs().max(f64::MIN_POSITIVE);
    assert!(
        rel <= tol,
        "{what}: serial {serial}, distributed {dist}, relative {rel:.2e}"
    );
}

/// Runs `text` serially and on 1, 2 and 4 ranks; compares the quantities at the JSON
/// pointers `values` and the particle columns `fields`.
fn distributed_equals_serial(tag: &str, text: &str, values: &[&str], fields: &[&str]) {
    let d = scratch("distributed", tag);
    let s = scene(&d, tag, text);
    let serial_out = d.join("serial");
    let serial = serial_run(&s, &serial_out);
    assert!(serial["distributed"].is_null());
    let serial_cols = columns(&serial_out, fields);
    for ranks in [1, 2, 4] {
        let out = d.join(format!("ranks-{ranks}"));
        let o = mpirun(ranks, &s, &out, &["--distributed"]);
        assert!(o.status.success(), "{ranks} ranks: {}", common::text(&o));
        let dist = summary(&out);
        assert_eq!(dist["distributed"]["ranks"], ranks, "{}", dist["distributed"]);
        assert_eq!(dist["distributed"]["method"], "petsc-cg-gamg");
        assert_eq!(dist["distributed"]["petsc_solver"], "cg + gamg");
        assert!(dist["distributed"]["iterations"].as_u64().unwrap() > 0);
        for v in values {
            let (a, b) = (serial.pointer(v), dist.pointer(v));
            let (Some(a), Some(b)) = (a.and_then(|x| x.as_f64()), b.and_then(|x| x.as_f64())) else {
                panic!("{v}: serial {a:?}, distributed {b:?}");
            };
            close(&format!("{ranks} ranks, {v}"), a, b);
        }
        for (name, (a, b)) in fields.iter().zip(serial_cols.iter().zip(columns(&out, fields))) {
            assert_eq!(a.len(), b.len());
            for (p, (x, y)) in a.iter().zip(&b).enumerate() {
                if x.is_nan() && y.is_nan() {
                    continue; // an excluded particle in both
                }
                close(&format!("{ranks} ranks, {name} of particle {p}"), *x, *y);
            }
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn steady_thermal_distributed_equals_serial() {
    distributed_equals_serial(
        "steady",
        &STEADY.replace("MAX_ITER", "200000"),
        &["/etc/lambda_e", "/etc/heat_flow_w"],
        &["temperature"],
    );
}

#[test]
fn electric_with_resistivity_of_temperature_distributed_equals_serial() {
    distributed_equals_serial(
        "electric",
        ELECTRIC,
        &[
            "/electric/resistance_ohm",
            "/electric/current_in",
            "/electric/joule_w",
        ],
        &["temperature", "potential"],
    );
}

#[test]
fn implicit_transient_distributed_equals_serial() {
    distributed_equals_serial(
        "implicit",
        IMPLICIT,
        &["/electric/resistance_ohm", "/electric/joule_w"],
        &["temperature", "potential"],
    );
}

/// The named columns of a block run's `particles_<r>.csv`, ranks in order (the serial order).
fn block_columns(out: &Path, ranks: usize, names: &[&str]) -> Vec<Vec<f64>> {
    let mut cols = vec![Vec::new(); names.len()];
    for r in 0..ranks {
        let piece = out.join(format!("piece-{r}"));
        std::fs::create_dir_all(&piece).unwrap();
        std::fs::copy(
            out.join(format!("particles_{r}.csv")),
            piece.join("particles.csv"),
        )
        .unwrap();
        for (c, part) in cols.iter_mut().zip(columns(&piece, names)) {
            c.extend(part);
        }
    }
    cols
}

#[test]
fn tiled_composite_by_blocks_equals_serial() {
    let d = scratch("distributed", "blocks");
    let s = scene(&d, "tiled", &TILED.replace("REPEAT", "(2, 2, 2)"));
    let serial_out = d.join("serial");
    let serial = serial_run(&s, &serial_out);
    let fields = [
        "x",
        "y",
        "z",
        "radius",
        "phase",
        "phase_fraction",
        "other_phase",
        "temperature",
        "volume",
    ];
    let serial_cols = columns(&serial_out, &fields);
    for ranks in [1, 2, 4] {
        let out = d.join(format!("ranks-{ranks}"));
        let o = mpirun(ranks, &s, &out, &["--distributed"]);
        assert!(o.status.success(), "{ranks} ranks: {}", common::text(&o));
        let dist = summary(&out);
        assert_eq!(dist["model"], "blocks");
        assert_eq!(dist["ranks"], ranks);
        assert_eq!(dist["n_particles"], 4000);
        let owned: u64 = dist["owned_per_rank"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap())
            .sum();
        assert_eq!(owned, 4000, "every particle owned once");
        for v in [
            "/etc/lambda_e",
            "/etc/heat_flow_w",
            "/etc/hot_flow_w",
            "/etc/cold_flow_w",
        ] {
            close(
                &format!("{ranks} ranks, {v}"),
                serial.pointer(v).and_then(|x| x.as_f64()).unwrap(),
                dist.pointer(v).and_then(|x| x.as_f64()).unwrap(),
            );
        }
        // Two probes × temperature, flux and Halo flux magnitudes, in the serial order.
        assert_eq!(dist["probes"].as_array().unwrap().len(), 6);
        for k in 0..6 {
            let field = &serial["probes"][k]["field"];
            assert_eq!(&dist["probes"][k]["field"], field);
            let v = format!("/probes/{k}/value");
            close_to(
                &format!("{ranks} ranks, probe {k} ({field})"),
                serial.pointer(&v).and_then(|x| x.as_f64()).unwrap(),
                dist.pointer(&v).and_then(|x| x.as_f64()).unwrap(),
                if field == "temperature" { 1e-8 } else { 1e-7 },
            );
        }
        // Every particle: the same place, size and phase, and its temperature and cell volume.
        let cols = block_columns(&out, ranks, &fields);
        for (name, (a, b)) in fields.iter().zip(serial_cols.iter().zip(&cols)) {
            assert_eq!(a.len(), b.len(), "{name}");
            for (p, (x, y)) in a.iter().zip(b).enumerate() {
                if ["x", "y", "z", "radius", "phase", "phase_fraction", "other_phase"].contains(name) {
                    assert_eq!(x, y, "{ranks} ranks, {name} of particle {p}");
                } else {
                    close(&format!("{ranks} ranks, {name} of particle {p}"), *x, *y);
                }
            }
        }
        // The `.pvtu` names one piece per rank and the serial file's point fields.
        let pvtu = std::fs::read_to_string(out.join("particles.pvtu")).unwrap();
        assert_eq!(pvtu.matches("<Piece ").count(), ranks);
        for r in 0..ranks {
            let piece = std::fs::read(out.join(format!("particles/particles_{r}.vtu"))).unwrap();
            assert!(piece.starts_with(b"<?xml"));
        }
        // VTK's own parallel reader joins the pieces: the serial file's points, fields and
        // field types, the same positions and phases, the temperatures to the tolerance.
        if let (Some(serial_vtk), Some(dist_vtk)) = (
            vtk_reader::vtk_read(&serial_out.join("particles.vtu")),
            vtk_reader::vtk_read(&out.join("particles.pvtu")),
        ) {
            assert_eq!(dist_vtk["points"], serial_vtk["points"]);
            assert_eq!(dist_vtk["cell_types"], serial_vtk["cell_types"]);
            assert_eq!(dist_vtk["xyz"], serial_vtk["xyz"], "{ranks} ranks: positions");
            let (a, b) = (&serial_vtk["point_data"], &dist_vtk["point_data"]);
            assert_eq!(
                vtk_reader::names(a),
                vtk_reader::names(b),
                "{ranks} ranks: point fields"
            );
            for name in vtk_reader::names(a) {
                assert_eq!(a[&name]["type"], b[&name]["type"], "{name}");
                let (x, y) = (vtk_reader::values(a, &name), vtk_reader::values(b, &name));
                // A flux component may be near zero: against the field's largest.
                let scale = x.iter().fold(0.0f64, |m, u| m.max(u.abs()));
                for (p, (u, v)) in x.iter().zip(&y).enumerate() {
                    if name == "heat_flux" || name == "halo_flux" {
                        assert!(
                            (u - v).abs() <= 1e-7 * scale,
                            "{ranks} ranks, VTK {name}[{p}]: {u} vs {v}"
                        );
                    } else if name == "temperature" || name == "volume" {
                        close(&format!("{ranks} ranks, VTK {name} of point {p}"), *u, *v);
                    } else {
                        assert_eq!(u, v, "{ranks} ranks, VTK {name} of point {p}");
                    }
                }
            }
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn explicit_transient_by_blocks_equals_serial_to_round_off() {
    let d = scratch("distributed", "blocks-explicit");
    let text = TILED
        .replace("REPEAT", "(2, 2, 2)")
        .replace(
            "solver: Steady,",
            "solver: Explicit(t_end: 0.5, dt: Auto(safety: 0.9)),",
        )
        .replace("etc_axis: Y,", "");
    let s = scene(&d, "explicit", &text);
    let serial_out = d.join("serial");
    let serial = serial_run(&s, &serial_out);
    let serial_t = &columns(&serial_out, &["temperature"])[0];
    for ranks in [1, 2, 4] {
        let out = d.join(format!("ranks-{ranks}"));
        let o = mpirun(ranks, &s, &out, &["--distributed"]);
        assert!(o.status.success(), "{ranks} ranks: {}", common::text(&o));
        let dist = summary(&out);
        assert_eq!(dist["model"], "blocks");
        // The serial step (the smallest bound over the ranks) and step count, bit for bit.
        assert_eq!(dist["solve"]["dt_s"], serial["thermal"]["dt"], "{ranks} ranks");
        assert_eq!(
            dist["solve"]["steps"], serial["thermal"]["steps"],
            "{ranks} ranks"
        );
        let t = &block_columns(&out, ranks, &["temperature"])[0];
        assert_eq!(t.len(), serial_t.len());
        let worst = serial_t
            .iter()
            .zip(t)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        if ranks == 1 {
            // One block is the serial network: the same sums in the same order.
            assert_eq!(worst, 0.0, "1 rank: bit for bit");
        } else {
            // A facet towards a ghost is measured from the owned side only, and a row sums its
            // ghosts after its owned neighbours: round-off (5e-13 K measured over 555 steps).
            assert!(worst <= 1e-10, "{ranks} ranks: |ΔT| up to {worst:e} K");
        }
        assert!(out.join("particles.pvd").exists());
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn convection_and_heat_flux_by_blocks_equal_serial() {
    let d = scratch("distributed", "blocks-conditions");
    let text = TILED
        .replace("REPEAT", "(2, 2, 2)")
        .replace(
            "bcs: [WallTemperature(face: YMin, value: 25.0), WallTemperature(face: YMax, value: 35.0)],",
            "bcs: [Convection(face: YMin, h: 50.0, t_inf: 20.0), HeatFlux(face: YMax, flux: 300.0), \
             WallTemperature(face: XMin, value: 30.0)],",
        )
        .replace("etc_axis: Y,", "");
    assert!(text.contains("Convection"));
    let s = scene(&d, "conditions", &text);
    let serial_out = d.join("serial");
    let serial = serial_run(&s, &serial_out);
    let serial_t = &columns(&serial_out, &["temperature"])[0];
    for ranks in [2, 4] {
        let out = d.join(format!("ranks-{ranks}"));
        let o = mpirun(ranks, &s, &out, &["--distributed"]);
        assert!(o.status.success(), "{ranks} ranks: {}", common::text(&o));
        assert_eq!(summary(&out)["model"], "blocks");
        let t = &block_columns(&out, ranks, &["temperature"])[0];
        for (p, (a, b)) in serial_t.iter().zip(t).enumerate() {
            close(&format!("{ranks} ranks, temperature of particle {p}"), *a, *b);
        }
        let dist = summary(&out);
        for k in 0..6 {
            let field = &serial["probes"][k]["field"];
            let v = format!("/probes/{k}/value");
            close_to(
                &format!("{ranks} ranks, probe {k} ({field})"),
                serial.pointer(&v).and_then(|x| x.as_f64()).unwrap(),
                dist.pointer(&v).and_then(|x| x.as_f64()).unwrap(),
                if field == "temperature" { 1e-8 } else { 1e-7 },
            );
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// A steel with 20 % carbide inclusions between two face electrodes, on a tiled packing.
const TILED_ELECTRIC: &str = r#"(
    name: "tiled-electric",
    seed: 7,
    packing: Tile(
        packing: Generate(container: Periodic(size: (0.002, 0.002, 0.002)), count: 500, phi: 0.62, radius_cov: 0.3),
        repeat: (2, 2, 2),
        walls: true,
    ),
    surface: Laguerre,
    phase_rule: Centre,
    materials: [
        (name: "steel", conductivity: 15.0, density: 7900.0, specific_heat: 500.0, resistivity: 0.73e-6),
        (name: "carbide", conductivity: 60.0, density: 15600.0, specific_heat: 200.0, resistivity: 0.2e-6),
    ],
    phases: [Inclusions(material: "carbide", fraction: 0.2, size_ratio: 4.0)],
    interface: Harmonic,
    linear_solver: (rel_tol: 1e-10),
    electric: (
        electrodes: [(face: YMin, potential: 0.0), (face: YMax, potential: 0.05)],
        eta: 1.0,
        surface: Laguerre,
    ),
    outputs: (
        particles_csv: true,
        vtk: false,
        probes: [
            (name: "centre", point: (0.002, 0.002, 0.002)),
            (name: "ball", point: (0.001, 0.003, 0.002), method: Ball(0.0003)),
        ],
    ),
)"#;

#[test]
fn electric_by_blocks_equals_serial() {
    let d = scratch("distributed", "blocks-electric");
    let s = scene(&d, "electric", TILED_ELECTRIC);
    let serial_out = d.join("serial");
    let serial = serial_run(&s, &serial_out);
    let fields = [
        "potential",
        "joule_power",
        "joule_power_density",
        "current_density_y",
    ];
    let serial_cols = columns(&serial_out, &fields);
    for ranks in [1, 2, 4] {
        let out = d.join(format!("ranks-{ranks}"));
        let o = mpirun(ranks, &s, &out, &["--distributed"]);
        assert!(o.status.success(), "{ranks} ranks: {}", common::text(&o));
        let dist = summary(&out);
        assert_eq!(dist["model"], "blocks");
        for v in [
            "/electric/resistance_ohm",
            "/electric/current_in",
            "/electric/current_out",
            "/electric/joule_w",
            "/electric/joule_heat_w",
            "/probes/0/value",
            "/probes/1/value",
        ] {
            close(
                &format!("{ranks} ranks, {v}"),
                serial.pointer(v).and_then(|x| x.as_f64()).unwrap(),
                dist.pointer(v).and_then(|x| x.as_f64()).unwrap(),
            );
        }
        // Potentials and Joule powers within 1e-8; the current density (a difference of
        // potentials) within 1e-7 of its largest.
        let cols = block_columns(&out, ranks, &fields);
        for (name, (a, b)) in fields.iter().zip(serial_cols.iter().zip(&cols)) {
            let scale = a.iter().fold(0.0f64, |m, u| m.max(u.abs()));
            for (p, (x, y)) in a.iter().zip(b).enumerate() {
                let tol = if name.starts_with("current") { 1e-7 } else { 1e-8 };
                assert!(
                    (x - y).abs() <= tol * scale,
                    "{ranks} ranks, {name} of particle {p}: {x} vs {y}"
                );
            }
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_tiled_scene_that_needs_the_whole_body_runs_replicated_and_says_so() {
    let d = scratch("distributed", "replicated-tile");
    // Conforming cells place their seeds over the whole body: not a block's job.
    let text = TILED
        .replace("REPEAT", "(2, 2, 2)")
        .replace("phase_rule: Centre,", "phase_rule: Conforming,");
    let s = scene(&d, "conforming", &text);
    let out = d.join("out");
    let o = mpirun(2, &s, &out, &["--distributed"]);
    assert!(o.status.success(), "{}", common::text(&o));
    let dist = summary(&out);
    assert!(dist["model"].is_object(), "the replicated run's summary");
    let said = dist["diagnostics"].to_string();
    assert!(
        said.contains("replicated on every rank") && said.contains("conforming cells"),
        "{said}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn blocks_thinner_than_the_ghost_layer_are_refused() {
    let d = scratch("distributed", "thin-blocks");
    // One copy of 500 particles on 4 ranks: blocks about 5 diameters across, ghost layer 3.4.
    let text = TILED
        .replace("REPEAT", "(1, 1, 1)")
        .replace("(0.001, 0.003, 0.002)", "(0.001, 0.001, 0.001)");
    let s = scene(&d, "tiled", &text);
    let out = d.join("out");
    let o = mpirun(4, &s, &out, &["--distributed"]);
    fails_once(&o, &out, "`MPI ranks` = 4: at most 1 for this tiling");
    let _ = std::fs::remove_dir_all(&d);
}

/// A failed launch: non-zero, the error once (rank 0 only), no output folder.
fn fails_once(o: &Output, out: &Path, expect: &str) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{}", common::text(o));
    assert!(err.contains(expect), "expected `{expect}` in: {err}");
    assert_eq!(
        err.matches("error: ").count(),
        1,
        "one error message, from rank 0: {err}"
    );
    assert!(!out.exists(), "no output of a failed run");
}

#[test]
fn more_ranks_than_unknowns_is_refused() {
    let d = scratch("distributed", "ranks");
    // Three particles between two walls held at fixed temperatures: 3 unknowns.
    let s = scene(
        &d,
        "tiny",
        &STEADY
            .replace("count: 3000, phi: 0.6", "count: 3, phi: 0.3")
            .replace("coordination: 7.5", "tolerance: 1.0")
            .replace("MAX_ITER", "1000"),
    );
    let out = d.join("out");
    let o = mpirun(4, &s, &out, &["--distributed"]);
    fails_once(&o, &out, "must be at most the number of unknown rows");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_solve_that_does_not_converge_fails_on_every_rank() {
    let d = scratch("distributed", "converge");
    let s = scene(&d, "starved", &STEADY.replace("MAX_ITER", "1"));
    let out = d.join("out");
    let o = mpirun(2, &s, &out, &["--distributed"]);
    fails_once(&o, &out, "petsc-cg-gamg did not converge");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn mpirun_without_distributed_and_resume_are_refused() {
    let d = scratch("distributed", "launch");
    let s = scene(&d, "steady", &STEADY.replace("MAX_ITER", "1000"));
    let out = d.join("out");
    let o = mpirun(2, &s, &out, &[]);
    fails_once(&o, &out, "without --distributed");
    let o = mpirun(2, &s, &out, &["--distributed", "--resume"]);
    fails_once(&o, &out, "--resume cannot be combined with --distributed");
    let _ = std::fs::remove_dir_all(&d);
}
