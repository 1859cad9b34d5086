//! End-to-end tests of `demcon plot` and of `outputs.plots`: the PNGs a small run gives (valid,
//! of the expected size, the slice's colour bar spanning the field), read from the CSV or the
//! VTU, and the refusals of folders that lack what a plot needs.

mod common;

use std::path::Path;

use common::{demcon, scratch, text};

const SCENE: &str = r#"(
    packing: Generate(container: Box(size: (1.0, 1.0, 1.0)), count: 300, phi: 0.5, radius_cov: 0.0),
    surface: TerrerosAlpha,
    materials: [(name: "steel", conductivity: 33.0, density: 7800.0, specific_heat: 500.0)],
    thermal: (bcs: [WallTemperature(face: YMin, value: 20.0), WallTemperature(face: YMax, value: 30.0)],
              solver: Steady),
    outputs: (OUTPUTS),
)"#;

const FULL: &str = r#"probes: [(name: "low", point: (0.5, 0.25, 0.5)), (name: "high", point: (0.5, 0.75, 0.5))],
    profiles: [(name: "y", from: (0.5, 0.05, 0.5), to: (0.5, 0.95, 0.5), points: 5)],
    halo: 2.0, particles_csv: true, vtk: true, plots: PLOTS"#;

/// Runs the scene with `outputs` into `dir/out`; returns the output folder.
fn run(dir: &Path, outputs: &str) -> std::path::PathBuf {
    run_with_output(dir, outputs).0
}

/// Runs the scene with `outputs` into `dir/out`; returns the output folder and what it printed.
fn run_with_output(dir: &Path, outputs: &str) -> (std::path::PathBuf, String) {
    let scene = dir.join("s.ron");
    std::fs::write(&scene, SCENE.replace("OUTPUTS", outputs)).unwrap();
    let out = dir.join("out");
    let o = demcon(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    (out, text(&o))
}

/// Width and height of a PNG (decoding it whole: a damaged file fails).
fn png_size(path: &Path) -> (u32, u32) {
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    (info.width, info.height)
}

/// The colour-bar range `demcon plot` printed for the file `name`.
fn printed_range(stdout: &str, name: &str) -> (f64, f64) {
    let line = stdout
        .lines()
        .find(|l| l.contains(name))
        .unwrap_or_else(|| panic!("no line for {name} in:\n{stdout}"));
    let range = line.rsplit("colour bar ").next().unwrap();
    let (lo, hi) = range.split_once(" … ").unwrap();
    (lo.trim().parse().unwrap(), hi.trim().parse().unwrap())
}

/// Least and greatest of a column of `particles.csv`.
fn csv_range(out: &Path, column: &str) -> (f64, f64) {
    let text = std::fs::read_to_string(out.join("particles.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines
        .next()
        .unwrap()
        .split(',')
        .map(|h| h.trim_matches('"'))
        .collect();
    let k = header.iter().position(|h| *h == column).unwrap();
    lines
        .map(|l| l.split(',').nth(k).unwrap().parse::<f64>().unwrap())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        })
}

fn close(a: (f64, f64), b: (f64, f64)) -> bool {
    let tol = 1e-6 * (b.1 - b.0).abs().max(1e-12);
    (a.0 - b.0).abs() <= tol && (a.1 - b.1).abs() <= tol
}

#[test]
fn a_run_plots_itself_and_demcon_plot_draws_its_folder() {
    let d = scratch("cli-plot", "full");
    let out = run(&d, &FULL.replace("PLOTS", "true"));
    // `outputs.plots`: the PNGs are in the run's folder.
    let charts = [
        "probes_temperature.png",
        "profile_y_temperature.png",
        "slice_temperature_z.png",
        "slice_halo_flux_z.png",
    ];
    for name in charts {
        let (w, h) = png_size(&out.join("plots").join(name));
        assert!(w >= 600 && h >= 400, "{name}: {w} × {h}");
    }
    assert_eq!(png_size(&out.join("plots/probes_temperature.png")), (900, 600));
    // A slice of the cube: 200 × 200 square cells on 640 × 640 pixels, the axes and the colour bar.
    assert_eq!(png_size(&out.join("plots/slice_temperature_z.png")), (895, 750));

    // `demcon plot` from the CSV files into another folder: the same charts.
    let other = d.join("charts");
    let o = demcon(&["plot", out.to_str().unwrap(), "--out", other.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let stdout = String::from_utf8_lossy(&o.stdout).to_string();
    for name in charts {
        assert_eq!(
            png_size(&other.join(name)),
            png_size(&out.join("plots").join(name)),
            "{name}"
        );
    }
    // The colour bar spans the field over the particles.
    let t = csv_range(&out, "temperature");
    assert!(
        t.0 >= 20.0 - 1e-9 && t.1 <= 30.0 + 1e-9 && t.1 - t.0 > 5.0,
        "{t:?}"
    );
    assert!(
        close(printed_range(&stdout, "slice_temperature_z.png"), t),
        "{stdout}"
    );

    // Without particles.csv the fields come from particles.vtu: same range; another plane.
    std::fs::remove_file(out.join("particles.csv")).unwrap();
    let o = demcon(&[
        "plot",
        out.to_str().unwrap(),
        "--out",
        other.to_str().unwrap(),
        "--slice",
        "temperature",
        "--slice",
        "coordination",
        "--axis",
        "x",
        "--at",
        "0.4",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let stdout = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(
        close(printed_range(&stdout, "slice_temperature_x.png"), t),
        "{stdout}"
    );
    assert!(stdout.contains("plane x = 400 mm"), "{stdout}");
    assert!(png_size(&other.join("slice_coordination_x.png")).0 > 0);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn plots_refuse_folders_without_what_they_need() {
    let d = scratch("cli-plot", "refuse");
    // Not a run's folder.
    let empty = d.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let o = demcon(&["plot", empty.to_str().unwrap()]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("no summary.json") && err.contains("empty"), "{err}");
    assert!(!empty.join("plots").exists());

    // A run with no probes, no profiles, no particle files: asked to plot itself, it slices
    // its fields in memory; its folder has nothing `demcon plot` can draw.
    let (out, said) = run_with_output(&d, "vtk: false, plots: true");
    assert!(said.contains("plots/"), "{said}");
    assert!(png_size(&out.join("plots/slice_temperature_z.png")).0 > 0);
    let o = demcon(&["plot", out.to_str().unwrap()]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("nothing to plot") && err.contains("probes.csv"),
        "{err}"
    );
    // A slice asked of it: the missing files are named.
    let o = demcon(&["plot", out.to_str().unwrap(), "--slice", "temperature"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("no particles.csv or particles.vtu"),
        "{err}"
    );

    // An unknown field: the file is named, and the fields it has.
    let out = run(&d, &FULL.replace("PLOTS", "false"));
    let o = demcon(&["plot", out.to_str().unwrap(), "--slice", "pressure"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("particles.csv") && err.contains("no field `pressure`") && err.contains("temperature"),
        "{err}"
    );
    // A plane outside the particles.
    let o = demcon(&["plot", out.to_str().unwrap(), "--at", "7.0"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("outside"), "{err}");
    let _ = std::fs::remove_dir_all(&d);
}
