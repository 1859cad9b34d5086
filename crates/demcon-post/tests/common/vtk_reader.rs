//! Reads a VTK file back through VTK's own readers (`scripts/vtk_read.py`, VTK's Python
//! package, the library ParaView is built on) and returns what it found as JSON. `.ci/run`
//! installs the package; elsewhere, without it, the caller is told to skip (and CI, where
//! `CI` is set, fails instead: the check cannot silently vanish there).
#![allow(dead_code)]

use std::path::Path;
use std::process::Command;

/// The JSON `scripts/vtk_read.py` prints for `path`, or `None` when VTK's Python package is
/// missing outside CI (a message says so).
pub fn vtk_read(path: &Path) -> Option<serde_json::Value> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scripts/vtk_read.py");
    let have_vtk = Command::new("python3")
        .args(["-c", "import vtk"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !have_vtk {
        assert!(
            std::env::var_os("CI").is_none(),
            "VTK's Python package is needed to read the files back (pip install vtk)"
        );
        eprintln!(
            "SKIPPED: VTK's Python package is missing (pip install vtk): {} not read back",
            path.display()
        );
        return None;
    }
    let out = Command::new("python3")
        .arg(&script)
        .arg(path)
        .output()
        .expect("python3 runs");
    assert!(
        out.status.success(),
        "VTK could not read {}: {}",
        path.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    Some(serde_json::from_slice(&out.stdout).expect("vtk_read.py prints JSON"))
}

/// The values of array `name` of `data` (a `point_data` or `cell_data` object) as f64.
pub fn values(data: &serde_json::Value, name: &str) -> Vec<f64> {
    data[name]["values"]
        .as_array()
        .unwrap_or_else(|| panic!("array {name} in {data}"))
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect()
}

/// The names of the arrays of `data`, in file order.
pub fn names(data: &serde_json::Value) -> Vec<String> {
    data.as_object()
        .map_or(Vec::new(), |m| m.keys().cloned().collect())
}
