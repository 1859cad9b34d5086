//! `demcon.Scene`: a RON scene read and checked by `demcon-scene` (the CLI's parser, checks and
//! messages), and its `run`.

use std::path::PathBuf;

use demcon_scene::config::PackingConfig;
use pyo3::exceptions::{PyFileNotFoundError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::packing::PyPacking;
use crate::values::{repr, to_py, to_value};

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
    /// A scene from a dict in the RON schema's shape (docs/python.md "Scenes as dicts"): a
    /// struct is a dict, an enum variant `{"Variant": {...}}` (or `"Variant"` without fields),
    /// a tuple a list or tuple, `None` is None; numpy numbers and arrays are taken as their
    /// values. `base_dir` (default: the current folder) resolves relative paths in it.
    ///
    /// `packing` (a `demcon.Packing`) replaces the scene's `packing` section, which the dict
    /// may then leave out.
    ///
    /// Raises `demcon.SceneError` naming the field path (`thermal.bcs[0].value`) of an unknown
    /// key, a missing one, a wrong type or a value that is not allowed.
    #[new]
    #[pyo3(signature = (spec, base_dir=None, packing=None))]
    fn new(
        spec: &Bound<'_, PyAny>,
        base_dir: Option<PathBuf>,
        packing: Option<PyRef<'_, PyPacking>>,
    ) -> PyResult<Self> {
        if !spec.is_instance_of::<PyDict>() {
            return Err(PyTypeError::new_err(format!(
                "spec = {}: a dict in the scene schema (or use Scene.from_file / Scene.from_str for RON)",
                repr(spec)
            )));
        }
        let mut value = to_value(spec, "")?;
        if let (Some(p), serde_json::Value::Object(map)) = (&packing, &mut value) {
            // a placeholder the particles then replace (`Scene::with_particles`)
            let given = PackingConfig::Given {
                count: p.particles.len(),
                container: p.container,
            };
            map.insert(
                "packing".into(),
                serde_json::to_value(given).map_err(|e| PyValueError::new_err(e.to_string()))?,
            );
        }
        let config = demcon_scene::Scene::config_of_value(value).map_err(scene_err)?;
        Self::build(config, base_dir.unwrap_or_default(), packing, "scene")
    }

    /// Reads a RON scene file (relative paths in it are resolved against its folder);
    /// `packing` (a `demcon.Packing`) replaces its `packing` section.
    ///
    /// Raises `FileNotFoundError` when the file does not exist, `demcon.SceneError` (with the
    /// file, line, column or field path) when it cannot be parsed or a value is not allowed.
    #[staticmethod]
    #[pyo3(signature = (path, packing=None))]
    fn from_file(path: PathBuf, packing: Option<PyRef<'_, PyPacking>>) -> PyResult<Self> {
        let scene = demcon_scene::Scene::load(&path).map_err(scene_err)?;
        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("scene");
        Self::with_packing(scene, packing, stem)
    }

    /// Parses RON scene text. `base_dir` (default: the current folder) resolves the relative
    /// paths in it (packing files, label images); `path` is the name messages give the text;
    /// `packing` (a `demcon.Packing`) replaces its `packing` section.
    #[staticmethod]
    #[pyo3(signature = (text, base_dir=None, path=None, packing=None))]
    fn from_str(
        text: &str,
        base_dir: Option<PathBuf>,
        path: Option<PathBuf>,
        packing: Option<PyRef<'_, PyPacking>>,
    ) -> PyResult<Self> {
        let path = path.unwrap_or_else(|| PathBuf::from("<string>"));
        let scene =
            demcon_scene::Scene::parse(text, &path, base_dir.unwrap_or_default()).map_err(scene_err)?;
        Self::with_packing(scene, packing, "scene")
    }

    /// The scene as a dict in the schema `Scene(dict)` takes: `Scene(s.to_dict())` is `s`
    /// (defaults filled in).
    fn to_dict(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let value =
            serde_json::to_value(self.scene.config()).map_err(|e| PyValueError::new_err(e.to_string()))?;
        to_py(py, &value)
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
    /// - `progress`: True (the default) reports the stages on `sys.stderr` and a transient's
    ///   steps as a tqdm bar (when tqdm is installed, else a counter); False/None says
    ///   nothing; a callable is called as `progress(stage: str, done: int, total: int)`
    ///   (`done`/`total` are time steps in stage "solve" of a transient, else 0).
    /// - `resume`: continue the interrupted run whose checkpoint lies beside `out` (a
    ///   transient with `thermal.checkpoint` writes `OUT.checkpoint` as it goes, as
    ///   `demcon run --out OUT` does); the result equals the uninterrupted run's.
    ///
    /// Ctrl-C (`KeyboardInterrupt`) stops the run at its next stage or progress report and
    /// writes no output (a checkpoint stays). Errors raise `demcon.SceneError`.
    #[pyo3(signature = (out=None, threads=None, progress=crate::run::ProgressArg::On, resume=false))]
    fn run(
        &self,
        py: Python<'_>,
        out: Option<PathBuf>,
        threads: Option<usize>,
        progress: crate::run::ProgressArg<'_>,
        resume: bool,
    ) -> PyResult<crate::run::PyRunResult> {
        if threads == Some(0) {
            return Err(PyValueError::new_err(
                "threads = 0: the number of worker threads must be at least 1 (or None for all cores)",
            ));
        }
        crate::run::run(py, self, out.as_deref(), threads, progress, resume)
    }

    fn __repr__(&self) -> String {
        format!("Scene(name={:?})", self.name)
    }
}

impl PyScene {
    /// `scene`, with its packing replaced by `packing` when one is given.
    fn with_packing(
        scene: demcon_scene::Scene,
        packing: Option<PyRef<'_, PyPacking>>,
        fallback: &str,
    ) -> PyResult<Self> {
        match packing {
            None => Ok(Self::named(scene, fallback)),
            Some(p) => {
                let base_dir = scene.base_dir.clone();
                Self::build(scene.config().clone(), base_dir, Some(p), fallback)
            }
        }
    }

    /// A checked scene of `config`, on `packing`'s particles when one is given.
    fn build(
        config: demcon_scene::SceneConfig,
        base_dir: PathBuf,
        packing: Option<PyRef<'_, PyPacking>>,
        fallback: &str,
    ) -> PyResult<Self> {
        let scene = match packing {
            None => demcon_scene::Scene::from_config(config, base_dir),
            Some(p) => {
                demcon_scene::Scene::with_particles(config, base_dir, p.particles.clone(), p.container)
            }
        }
        .map_err(scene_err)?;
        Ok(Self::named(scene, fallback))
    }

    fn named(scene: demcon_scene::Scene, fallback: &str) -> Self {
        let name = if scene.config().name.is_empty() {
            fallback.to_string()
        } else {
            scene.config().name.clone()
        };
        PyScene { scene, name }
    }
}
