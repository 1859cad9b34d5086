//! Our VTK files read back by an independent reader, VTK's own (through
//! `scripts/vtk_read.py`): point and cell counts, cell types, array names, types and values;
//! the `.pvd` collection with the files it names.

mod common;

use std::path::PathBuf;

use common::jittered;
use common::vtk_reader::{names, values, vtk_read};
use demcon_core::Vec3;
use demcon_post::*;

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("demcon-vtk-reader-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn flat(v: &[Vec3]) -> Vec<f64> {
    v.iter().flat_map(|x| x.iter().copied()).collect()
}

#[test]
fn particles_vtu_reads_back_in_vtk() {
    let mut p = jittered(4, 3);
    for (i, ph) in p.phases.iter_mut().enumerate() {
        *ph = (i % 2) as u16;
    }
    let t: Vec<f64> = p.centres.iter().map(|c| 20.0 + c.x).collect();
    let q: Vec<Vec3> = p.centres.iter().map(|c| Vec3::new(c.y, -c.z, 1.5)).collect();
    let flag: Vec<i32> = (0..p.len() as i32).map(|i| i % 3).collect();
    let path = tmp("p.vtu");
    let fields = [
        Field::scalars("temperature", &t),
        Field::vectors("heat_flux", &q),
        Field::ints("solved", &flag),
    ];
    write_vtu(&path, &p, &fields).unwrap();
    let Some(r) = vtk_read(&path) else { return };
    assert_eq!(r["points"], p.len());
    assert_eq!(r["cells"], p.len());
    assert_eq!(r["cell_types"], serde_json::json!([1]), "vertex cells");
    let xyz: Vec<f64> = r["xyz"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(xyz, flat(&p.centres));
    let pd = &r["point_data"];
    let mut got = names(pd);
    got.sort();
    let mut want = ["radius", "phase", "temperature", "heat_flux", "solved"];
    want.sort();
    assert_eq!(got, want);
    assert_eq!(values(pd, "radius"), p.radii);
    assert_eq!(values(pd, "temperature"), t);
    assert_eq!(pd["heat_flux"]["components"], 3);
    assert_eq!(values(pd, "heat_flux"), flat(&q));
    let ph: Vec<f64> = p.phases.iter().map(|&x| x as f64).collect();
    assert_eq!(values(pd, "phase"), ph);
    let fl: Vec<f64> = flag.iter().map(|&x| x as f64).collect();
    assert_eq!(values(pd, "solved"), fl);
}

#[test]
fn lines_vtp_reads_back_in_vtk() {
    let pts: Vec<Vec3> = (0..5).map(|i| Vec3::new(i as f64, (i * i) as f64, 0.5)).collect();
    let lines = [[0u32, 1], [1, 2], [2, 4], [3, 0]];
    let g = [1.0, 2.0, 3.5, -4.0];
    let kind = [0i32, 0, 1, 2];
    let path = tmp("c.vtp");
    write_lines_vtp(
        &path,
        &pts,
        &lines,
        &[Field::scalars("conductance", &g), Field::ints("kind", &kind)],
    )
    .unwrap();
    // A line naming a missing point is refused.
    let e = write_lines_vtp(tmp("bad.vtp"), &pts, &[[0, 5]], &[]).unwrap_err();
    assert!(e.to_string().contains("lines[0]"), "{e}");
    let Some(r) = vtk_read(&path) else { return };
    assert_eq!(r["points"], 5);
    assert_eq!(r["cells"], 4);
    assert_eq!(r["cell_types"], serde_json::json!([3]), "VTK_LINE cells");
    assert_eq!(
        r["cell_points"],
        serde_json::json!([[0, 1], [1, 2], [2, 4], [3, 0]])
    );
    let cd = &r["cell_data"];
    assert_eq!(values(cd, "conductance"), g);
    assert_eq!(values(cd, "kind"), [0.0, 0.0, 1.0, 2.0]);
}

#[test]
fn polyhedra_vtu_reads_back_in_vtk() {
    // Two unit cubes side by side, and a tetrahedron of volume 1/6.
    let cube = |x0: f64| -> Vec<Vec3> {
        (0..8)
            .map(|i| Vec3::new(x0 + (i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .collect()
    };
    let faces: Vec<Vec<u32>> = vec![
        vec![0, 2, 3, 1],
        vec![4, 5, 7, 6],
        vec![0, 1, 5, 4],
        vec![2, 6, 7, 3],
        vec![0, 4, 6, 2],
        vec![1, 3, 7, 5],
    ];
    let mut cells = Polyhedra::new();
    cells.push(cube(0.0), faces.clone());
    cells.push(cube(1.0), faces);
    let tet = [Vec3::zeros(), Vec3::x(), Vec3::y(), Vec3::z()].map(|v| v + Vec3::new(3.0, 0.0, 0.0));
    cells.push(
        tet,
        vec![vec![0, 2, 1], vec![0, 1, 3], vec![1, 2, 3], vec![0, 3, 2]],
    );
    let id = [0i32, 1, 2];
    let path = tmp("cells.vtu");
    write_polyhedra_vtu(&path, &cells, &[Field::ints("particle", &id)]).unwrap();
    let mut bad = Polyhedra::new();
    bad.push(cube(0.0), vec![vec![0, 1, 8]]);
    let e = write_polyhedra_vtu(tmp("bad.vtu"), &bad, &[]).unwrap_err();
    assert!(e.to_string().contains("cells[0]"), "{e}");
    let Some(r) = vtk_read(&path) else { return };
    assert_eq!(r["points"], 20);
    assert_eq!(r["cells"], 3);
    assert_eq!(r["cell_types"], serde_json::json!([42]), "VTK_POLYHEDRON cells");
    assert_eq!(r["cell_faces"], serde_json::json!([6, 6, 4]));
    let vol: Vec<f64> = r["cell_volumes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    for (v, want) in vol.iter().zip([1.0, 1.0, 1.0 / 6.0]) {
        assert!((v - want).abs() < 1e-12, "volume {v}, expected {want}");
    }
    assert_eq!(values(&r["cell_data"], "particle"), [0.0, 1.0, 2.0]);
}

#[test]
fn pvd_names_each_file_at_its_time() {
    let p = jittered(3, 5);
    let mut entries = Vec::new();
    for (k, t) in [0.5, 1.25, 3.0].into_iter().enumerate() {
        let temp: Vec<f64> = vec![t; p.len()];
        let file = format!("s_{k:04}.vtu");
        write_vtu(tmp(&file), &p, &[Field::scalars("temperature", &temp)]).unwrap();
        entries.push((t, file));
    }
    let path = tmp("series.pvd");
    write_pvd(&path, &entries).unwrap();
    let e = write_pvd(tmp("bad.pvd"), &[(1.0, "a".into()), (1.0, "b".into())]).unwrap_err();
    assert!(e.to_string().contains("entries[1].t"), "{e}");
    let Some(r) = vtk_read(&path) else { return };
    let got = r["entries"].as_array().unwrap();
    assert_eq!(got.len(), 3);
    for (g, (t, file)) in got.iter().zip(&entries) {
        assert_eq!(g["t"].as_f64().unwrap(), *t);
        assert_eq!(g["file"], file.as_str());
        assert_eq!(values(&g["data"]["point_data"], "temperature"), vec![*t; p.len()]);
    }
}
