//! The Python module `demcon._demcon`: scenes read through `demcon-scene` (RON text or files,
//! the CLI's checks and messages), runs with the GIL released, stopped by Ctrl-C, and their
//! per-particle fields as numpy arrays (SI units, one copy at most).
//!
//! The package `demcon` (python/demcon/) re-exports everything here; docs/python.md is the
//! user's page.

mod packing;
mod run;
mod scene;
mod values;

use pyo3::prelude::*;

pyo3::create_exception!(
    demcon,
    SceneError,
    pyo3::exceptions::PyValueError,
    "A scene that cannot be read or run: the CLI's message, with the file, line and column or the \
     field path (`thermal.bcs[0].value`), the value and what is allowed."
);

/// The compiled part of the `demcon` package.
#[pymodule]
fn _demcon(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("SceneError", m.py().get_type::<SceneError>())?;
    m.add_class::<scene::PyScene>()?;
    m.add_class::<run::PyRunResult>()?;
    m.add_class::<packing::PyPacking>()?;
    m.add_function(wrap_pyfunction!(packing::pack, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
