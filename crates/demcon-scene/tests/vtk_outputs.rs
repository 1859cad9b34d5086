//! The VTK files of a run, read back by VTK's own readers (`scripts/vtk_read.py`): the
//! particles' time series of a transient (`particles.pvd`: one file per output time and the
//! end, each with that time's fields), the contact network (`contacts.vtp` / `contacts.pvd`:
//! one line per contact and wall link with its values, which must add up to the run's own
//! totals) and the Laguerre cells (`cells.vtu`: polyhedra whose volumes fill the box).

#[path = "../../demcon-post/tests/common/vtk_reader.rs"]
mod vtk_reader;

use std::path::{Path, PathBuf};

use demcon_scene::{RunOptions, RunResult, Scene, run, write_outputs};
use serde_json::Value;
use vtk_reader::{values, vtk_read};

/// A 1 cm steel cube of 600 particles with Laguerre cells, a steady or transient heat problem
/// (YMin at 20 °C, YMax at 30 °C) and a one-way electric one (0.01 V across z).
fn scene(solver: &str, times: &str) -> Scene {
    scene_with(solver, times, "")
}

/// [`scene`] with extra top-level fields (cracks, damage…).
fn scene_with(solver: &str, times: &str, extra: &str) -> Scene {
    let text = format!(
        r#"(
    name: "vtk-outputs",
    seed: 3,
    packing: Generate(container: Box(size: (0.01, 0.01, 0.01)), count: 600, phi: 0.55, radius_cov: 0.3),
    surface: Laguerre,
    {extra}
    materials: [(name: "steel", conductivity: 15.0, density: 7900.0, specific_heat: 500.0, resistivity: 0.73e-6)],
    thermal: (
        initial_temperature: 20.0,
        bcs: [WallTemperature(face: YMin, value: 20.0), WallTemperature(face: YMax, value: 30.0)],
        solver: {solver},
    ),
    electric: (
        electrodes: [(face: ZMin, potential: 0.0), (face: ZMax, potential: 0.01)],
        eta: 1.0,
        surface: Laguerre,
    ),
    outputs: (
        times: {times},
        flux: true,
        halo: Some(3.0),
        vtk: true,
        contacts_vtk: true,
        cells_vtk: true,
    ),
)"#
    );
    Scene::parse(&text, Path::new("vtk-outputs.ron"), PathBuf::from(".")).unwrap()
}

fn out_dir(test: &str) -> PathBuf {
    std::env::temp_dir().join(format!("demcon-vtk-outputs-{}-{test}", std::process::id()))
}

fn run_and_write(s: &Scene, test: &str) -> (RunResult, PathBuf) {
    let r = run(s, &RunOptions::default()).unwrap();
    let dir = out_dir(test);
    write_outputs("vtk-outputs", &s.config().outputs, &r, &dir).unwrap();
    (r, dir)
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * b.abs().max(1e-300)
}

/// Checks one `contacts.vtp` read by VTK against the run: lines and kinds, heat flow = G ΔT,
/// Σ Joule power = the electric solve's, the electrodes' current = the current in.
fn check_contacts(c: &Value, r: &RunResult) {
    let m = &r.model;
    let s = r.thermal_setup.as_ref().unwrap();
    let e = r.electric.as_ref().unwrap();
    let contacts = m.graph.pairs.len();
    let lines = contacts + s.walls.len() + e.walls.len() + m.cut_contacts().len();
    assert_eq!(c["cells"], lines);
    assert_eq!(c["cell_types"], serde_json::json!([3]));
    let cd = &c["cell_data"];
    let kind = values(cd, "kind");
    assert_eq!(kind.iter().filter(|&&k| k == 0.0).count(), contacts);
    assert_eq!(kind.iter().filter(|&&k| k == 1.0).count(), s.walls.len());
    assert_eq!(kind.iter().filter(|&&k| k == 2.0).count(), e.walls.len());
    let (g, flow, drop) = (
        values(cd, "thermal_conductance"),
        values(cd, "heat_flow"),
        values(cd, "temperature_drop"),
    );
    for k in 0..lines {
        assert!(
            close(flow[k], g[k] * drop[k], 1e-12),
            "line {k}: heat flow {} ≠ G ΔT",
            flow[k]
        );
    }
    assert_eq!(&g[..contacts], s.contact_conductances());
    let area = values(cd, "surface");
    assert_eq!(&area[..contacts], s.areas(m));
    let joule: f64 = values(cd, "joule_power").iter().sum();
    assert!(
        close(joule, e.report.joule_w, 1e-9),
        "Σ joule {joule} vs {}",
        e.report.joule_w
    );
    let current = values(cd, "current");
    let electrodes: f64 = current
        .iter()
        .zip(&kind)
        .filter(|(_, k)| **k == 2.0)
        .map(|(i, _)| i.abs())
        .sum();
    assert!(
        close(electrodes, 2.0 * e.report.current_in, 1e-6),
        "electrode links carry {electrodes} A, twice the current in {}",
        e.report.current_in
    );
    // Every line has two points, and a contact's points are its particles' centres.
    let pts = c["cell_points"].as_array().unwrap();
    for (k, &[p, q]) in m.graph.pairs.iter().enumerate().step_by(37) {
        assert_eq!(pts[k], serde_json::json!([p, q]), "contact {k}");
    }
}

#[test]
fn transient_writes_a_time_series_of_particles_and_contacts() {
    let s = scene("Explicit(t_end: 2.0, dt: Auto(safety: 0.9))", "[0.5, 1.0, 2.0]");
    let (r, dir) = run_and_write(&s, "transient");
    assert!(
        !dir.join("particles.vtu").exists(),
        "a transient writes the series, not one file"
    );
    let th = r.thermal.as_ref().unwrap();
    let Some(series) = vtk_read(&dir.join("particles.pvd")) else {
        return;
    };
    let entries = series["entries"].as_array().unwrap();
    let times: Vec<f64> = entries.iter().map(|e| e["t"].as_f64().unwrap()).collect();
    assert_eq!(times, [0.5, 1.0, 2.0], "the output times, the last being the end");
    for (k, e) in entries.iter().enumerate() {
        let d = &e["data"];
        assert_eq!(d["points"], r.model.particles.len());
        let pd = &d["point_data"];
        let t = values(pd, "temperature");
        let want = if k + 1 < entries.len() {
            &th.snapshots[k].1
        } else {
            &th.temperatures
        };
        assert_eq!(&t, want, "entry {k}: that time's temperatures");
        // One-way electric: the potential holds at every time.
        assert_eq!(values(pd, "potential"), r.electric.as_ref().unwrap().potentials);
        for f in [
            "heat_flux",
            "halo_flux",
            "halo_truncated",
            "solved",
            "radius",
            "phase",
        ] {
            assert!(pd.get(f).is_some(), "entry {k} lacks {f}");
        }
    }
    // The temperatures rise from 20 °C towards the hot face: the entries differ.
    assert_ne!(
        values(&entries[0]["data"]["point_data"], "temperature"),
        th.temperatures
    );
    // The flux of an earlier time is that time's, not the end's.
    let early = values(&entries[0]["data"]["point_data"], "heat_flux");
    let end: Vec<f64> = r
        .flux
        .as_ref()
        .unwrap()
        .iter()
        .flat_map(|v| v.iter().copied())
        .collect();
    assert_ne!(early, end);
    assert_eq!(values(&entries[2]["data"]["point_data"], "heat_flux"), end);

    let Some(contacts) = vtk_read(&dir.join("contacts.pvd")) else {
        return;
    };
    let entries = contacts["entries"].as_array().unwrap();
    assert_eq!(entries.len(), 3);
    for e in entries {
        check_contacts(&e["data"], &r);
    }
    let drop0 = values(&entries[0]["data"]["cell_data"], "temperature_drop");
    let drop2 = values(&entries[2]["data"]["cell_data"], "temperature_drop");
    assert_ne!(drop0, drop2, "each time has its own temperature drops");
}

#[test]
fn steady_writes_contacts_whose_wall_flows_carry_the_joule_heat_and_cells_that_fill_the_box() {
    let s = scene("Steady", "[]");
    let (r, dir) = run_and_write(&s, "steady");
    assert!(dir.join("particles.vtu").exists() && !dir.join("particles.pvd").exists());
    let Some(c) = vtk_read(&dir.join("contacts.vtp")) else {
        return;
    };
    check_contacts(&c, &r);
    // Steady: the heat leaving through the walls' links (particle → face) is the Joule heat
    // made inside (η = 1).
    let cd = &c["cell_data"];
    let (kind, flow) = (values(cd, "kind"), values(cd, "heat_flow"));
    let walls: f64 = kind
        .iter()
        .zip(&flow)
        .filter(|(k, _)| **k == 1.0)
        .map(|(_, f)| f)
        .sum();
    let joule = r.electric.as_ref().unwrap().report.joule_w;
    assert!(
        close(walls, joule, 1e-6),
        "the walls take {walls} W, the Joule heat is {joule} W"
    );

    let Some(cells) = vtk_read(&dir.join("cells.vtu")) else {
        return;
    };
    let n = r.model.particles.len();
    assert_eq!(cells["cells"], n);
    assert_eq!(cells["cell_types"], serde_json::json!([42]));
    let vol: Vec<f64> = cells["cell_volumes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let ours = &r.model.graph.cells.as_ref().unwrap().volume;
    for (p, (v, w)) in vol.iter().zip(ours).enumerate() {
        assert!(
            close(*v, *w, 1e-9),
            "cell {p}: VTK's faces enclose {v} m³, the tessellation's {w}"
        );
    }
    let total: f64 = vol.iter().sum();
    assert!(close(total, 1e-6, 1e-9), "cells fill the 1 cm cube: {total} m³");
    assert_eq!(
        values(&cells["cell_data"], "temperature"),
        r.thermal.as_ref().unwrap().temperatures
    );
}

#[test]
fn with_eta_one_half_the_lines_still_add_up_to_the_power_dissipated() {
    // `joule_power` of contacts.vtp is I²/G, before η; `electric.joule_w` is the power the
    // current dissipates, whatever η; the particles (and so the walls, in steady state) get
    // η of it (`joule_heat_w`).
    let s = scene("Steady", "[]")
        .edit(|c| c.electric.as_mut().unwrap().eta = 0.5)
        .unwrap();
    let (r, dir) = run_and_write(&s, "eta-half");
    let e = &r.electric.as_ref().unwrap().report;
    let heat: f64 = r.electric.as_ref().unwrap().joule.iter().sum();
    assert!(
        close(heat, 0.5 * e.joule_w, 1e-9) && close(e.joule_heat_w, heat, 1e-12),
        "{e:?}"
    );
    let Some(c) = vtk_read(&dir.join("contacts.vtp")) else {
        return;
    };
    check_contacts(&c, &r);
    let cd = &c["cell_data"];
    let (kind, flow) = (values(cd, "kind"), values(cd, "heat_flow"));
    let walls: f64 = kind
        .iter()
        .zip(&flow)
        .filter(|(k, _)| **k == 1.0)
        .map(|(_, f)| f)
        .sum();
    assert!(
        close(walls, e.joule_heat_w, 1e-6),
        "the walls take {walls} W, the Joule heat is {} W",
        e.joule_heat_w
    );
}

#[test]
fn cells_need_laguerre_cells() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenes/slab-steady.ron"
    ))
    .unwrap();
    let contacts = text
        .replace("surface: Laguerre,", "surface: TerrerosAlpha,")
        .replace("vtk: true,", "vtk: true, cells_vtk: true,");
    let e = Scene::parse(&contacts, Path::new("x.ron"), PathBuf::from(".")).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("outputs.cells_vtk") && msg.contains("Laguerre"),
        "{msg}"
    );
}

#[test]
fn cracks_and_damage_are_marked_in_the_network_and_on_the_particles() {
    let s = scene_with(
        "Steady",
        "[]",
        "cracks: [Disc(centre: (0.005, 0.005, 0.005), normal: (0.0, 1.0, 0.0), radius: 0.003)],\n    \
         damage: [(region: Sphere(centre: (0.005, 0.005, 0.002), radius: 0.002), factor: 0.5)],",
    );
    let (r, dir) = run_and_write(&s, "cracked");
    let m = &r.model;
    let cut = m.cut_contacts().len();
    assert!(cut > 0, "the disc cuts contacts");
    let Some(c) = vtk_read(&dir.join("contacts.vtp")) else {
        return;
    };
    check_contacts(&c, &r);
    let cd = &c["cell_data"];
    let (kind, marks) = (values(cd, "kind"), values(cd, "marks"));
    assert_eq!(kind.iter().filter(|&&k| k == 3.0).count(), cut, "cut lines");
    let damaged = m.contact_marks().iter().filter(|&&b| b & 2 != 0).count();
    assert!(damaged > 0);
    assert_eq!(marks.iter().filter(|&&b| b as i32 & 2 != 0).count(), damaged);
    // A cut line conducts nothing; its temperature drop is the jump across the crack, hot
    // (y = L) side above: from the lower particle to the upper one the drop is negative.
    let (flow, drop) = (values(cd, "heat_flow"), values(cd, "temperature_drop"));
    let n_lines = kind.len();
    let cut_lines = n_lines - cut..n_lines;
    assert!(flow[cut_lines.clone()].iter().all(|&f| f == 0.0));
    let jump: f64 = m
        .cut_contacts()
        .iter()
        .zip(&drop[cut_lines])
        .map(|(c, d)| {
            let dy = m.particles.centres[c.pair[1] as usize].y - m.particles.centres[c.pair[0] as usize].y;
            if dy > 0.0 { -d } else { *d }
        })
        .sum::<f64>()
        / cut as f64;
    assert!(
        jump > 0.0,
        "the mean jump across the crack, upper minus lower: {jump} K"
    );
    let Some(p) = vtk_read(&dir.join("particles.vtu")) else {
        return;
    };
    let face = values(&p["point_data"], "crack_face");
    assert_eq!(
        face.iter().filter(|&&f| f == 1.0).count(),
        m.crack_face_particles().len()
    );
}
