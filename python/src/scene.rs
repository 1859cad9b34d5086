//! `demcon.Scene`: a RON scene read and checked by `demcon-scene` (the CLI's parser, checks and
//! messages), and its `run`.

use std::path::PathBuf;

use pyo3::exceptions::{PyFileNotFoundError, PyValueError};
use pyo3::prelude::*;

use crate::SceneError as PySceneError;

/// A scene error as a Python exception: a missing file is `FileNotFoundError`, everything else
/// `demcon.SceneError` (a `ValueError`), both with the CLI's message.
pub(crate) fn scene_err(e: demcon_scene::SceneError) -> PyErr {
    if let demcon_scene::SceneError::Io { source, .. } = &e
        && source.kind() == std::io::ErrorKind::NotFound
    {
        return PyFileNotFoundError::new_err(e.to_string());
    }
    PySceneError::new_err(e.to_string())
}

/// A scene: the RON file format of `demcon run`, parsed and checked (every value, before any
/// heavy work) once. Build it with `Scene.from_file(path)` or `Scene.from_str(text)`.
#[pyclass(name = "Scene", module = "demcon", frozen)]
pub struct PyScene {
    pub(crate) scene: demcon_scene::Scene,
    /// The name outputs carry: the scene's `name`, else the file's stem, else "scene".
    pub(crate) name: String,
}

#[pymethods]
impl PyScene {
    /// Reads a RON scene file (relative paths in it are resolved against its folder).
    ///
    /// Raises `FileNotFoundError` when the file does not exist, `demcon.SceneError` (with the
    /// file, line, column or field path) when it cannot be parsed or a value is not allowed.
    #[staticmethod]
    fn from_file(path: PathBuf) -> PyResult<Self> {
        let scene = demcon_scene::Scene::load(&path).map_err(scene_err)?;
        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("scene");
        Ok(Self::named(scene, stem))
    }

    /// Parses RON scene text. `base_dir` (default: the current folder) resolves the relative
    /// paths in it (packing files, label images); `path` is the name messages give the text.
    #[staticmethod]
    #[pyo3(signature = (text, base_dir=None, path=None))]
    fn from_str(text: &str, base_dir: Option<PathBuf>, path: Option<PathBuf>) -> PyResult<Self> {
        let path = path.unwrap_or_else(|| PathBuf::from("<string>"));
        let scene =
            demcon_scene::Scene::parse(text, &path, base_dir.unwrap_or_default()).map_err(scene_err)?;
        Ok(Self::named(scene, "scene"))
    }

    /// The scene's name (its `name` field, else the file's stem, else "scene").
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    /// Warnings about values that are allowed but probably not meant.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.scene.warnings().to_vec()
    }

    /// Runs the scene: packing, network, solves, post-processing; the GIL is released meanwhile.
    ///
    /// - `out`: a folder to write the outputs `demcon run --out` writes (summary.json, CSV,
    ///   VTK, plots); None writes nothing.
    /// - `threads`: worker threads of the run (a pool of its own); None uses rayon's global
    ///   pool (all cores, or `RAYON_NUM_THREADS`).
    /// - `progress`: False/None says nothing; True prints stages and transient steps to
    ///   `sys.stderr`; a callable is called as `progress(stage: str, done: int, total: int)`
    ///   (`done`/`total` are time steps in stage "solve" of a transient, else 0).
    ///
    /// Ctrl-C (`KeyboardInterrupt`) stops the run at its next stage or progress report and
    /// writes no output. Errors raise `demcon.SceneError`.
    #[pyo3(signature = (out=None, threads=None, progress=None))]
    fn run(
        &self,
        py: Python<'_>,
        out: Option<PathBuf>,
        threads: Option<usize>,
        progress: Option<Bound<'_, PyAny>>,
    ) -> PyResult<crate::run::PyRunResult> {
        if threads == Some(0) {
            return Err(PyValueError::new_err(
                "threads = 0: the number of worker threads must be at least 1 (or None for all cores)",
            ));
        }
        crate::run::run(py, self, out.as_deref(), threads, progress)
    }

    fn __repr__(&self) -> String {
        format!("Scene(name={:?})", self.name)
    }
}

impl PyScene {
    fn named(scene: demcon_scene::Scene, fallback: &str) -> Self {
        let name = if scene.config().name.is_empty() {
            fallback.to_string()
        } else {
            scene.config().name.clone()
        };
        PyScene { scene, name }
    }
}
