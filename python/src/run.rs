//! `Scene.run` and `demcon.RunResult`: the run on a worker thread with the GIL released, the
//! calling thread relaying progress and checking for Ctrl-C; the fields moved into numpy arrays.
//!
//! Stopping: the library has no cancel flag, but it calls back between stages and during the
//! packing and the time march. On Ctrl-C the calling thread sets `stop`; the worker's next
//! callback unwinds with [`Cancelled`] (`resume_unwind`: no panic message), caught at the top of
//! the worker. Nothing is written: the outputs are written only after a complete run.

use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::path::Path;
use std::sync::Arc;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError, Sender};
use std::time::Duration;

use demcon_core::{StageObserver, StageRecord, Vec3};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

use crate::scene::{PyScene, scene_err};

/// How often the calling thread looks for Ctrl-C while the run goes (s).
const POLL: Duration = Duration::from_millis(50);

/// The payload a stopped run unwinds with.
struct Cancelled;

/// What the worker tells the calling thread.
enum Event {
    /// A stage began.
    Stage(&'static str),
    /// Transient steps done of total.
    Steps(u64, u64),
    /// The run ended (or failed, or was stopped).
    Done(Outcome),
}

/// The end of a run on the worker.
enum Outcome {
    Ok(Box<demcon_scene::RunResult>),
    Err(demcon_scene::SceneError),
    Stopped,
    Panicked(String),
}

/// Stops the run (unwinding) when `stop` is set; otherwise passes the event on.
struct Relay {
    stop: Arc<AtomicBool>,
    tx: Sender<Event>,
}

impl Relay {
    fn check(&self) {
        if self.stop.load(Ordering::Relaxed) {
            resume_unwind(Box::new(Cancelled));
        }
    }
    fn send(&self, e: Event) {
        self.check();
        // The receiver outlives the worker; a failed send only means nobody listens.
        let _ = self.tx.send(e);
    }
}

impl StageObserver for Relay {
    fn started(&self, stage: &'static str) {
        self.send(Event::Stage(stage));
    }
    fn finished(&self, _record: &StageRecord) {
        self.check();
    }
}

/// Runs `scene` (see `Scene.run`).
pub(crate) fn run(
    py: Python<'_>,
    scene: &PyScene,
    out: Option<&Path>,
    threads: Option<usize>,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<PyRunResult> {
    if let Some(dir) = out {
        demcon_scene::output::check_output_dir(dir).map_err(scene_err)?;
    }
    let pool = match threads {
        Some(n) => Some(
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| PyRuntimeError::new_err(format!("threads = {n}: {e}")))?,
        ),
        None => None,
    };
    let report = Progress::new(py, progress)?;
    let stop = Arc::new(AtomicBool::new(false));
    let (tx, rx) = mpsc::channel::<Event>();
    // Shared with the GIL-free waits (`detach` wants `Send` closures; a receiver is not `Sync`).
    let rx = Mutex::new(rx);
    let recv = |timeout: Option<Duration>| {
        let rx = rx.lock().unwrap_or_else(|p| p.into_inner());
        match timeout {
            Some(t) => rx.recv_timeout(t),
            None => rx.recv().map_err(|_| RecvTimeoutError::Disconnected),
        }
    };
    let relay = Arc::new(Relay {
        stop: stop.clone(),
        tx: tx.clone(),
    });
    let inner = &scene.scene;
    let outcome = std::thread::scope(|s| -> PyResult<demcon_scene::RunResult> {
        s.spawn(move || {
            let work = || {
                let packing = |_: &demcon_packing::PackProgress| relay.check();
                let steps = relay.clone();
                let opts = demcon_scene::RunOptions {
                    progress: Some(&packing),
                    transient_progress: Some(demcon_scene::ProgressFn::new(move |done, total| {
                        steps.send(Event::Steps(done, total))
                    })),
                    stages: Some(relay.clone() as Arc<dyn StageObserver>),
                    checkpoint: None,
                };
                demcon_scene::run(inner, &opts)
            };
            let caught = catch_unwind(AssertUnwindSafe(|| match &pool {
                Some(p) => p.install(work),
                None => work(),
            }));
            let outcome = match caught {
                Ok(Ok(r)) => Outcome::Ok(Box::new(r)),
                Ok(Err(e)) => Outcome::Err(e),
                Err(payload) if payload.is::<Cancelled>() => Outcome::Stopped,
                Err(payload) => Outcome::Panicked(panic_text(payload.as_ref())),
            };
            let _ = tx.send(Event::Done(outcome));
        });
        loop {
            match py.detach(|| recv(Some(POLL))) {
                Ok(Event::Done(o)) => {
                    return match o {
                        Outcome::Ok(r) => Ok(*r),
                        Outcome::Err(e) => Err(scene_err(e)),
                        Outcome::Stopped => Err(PyRuntimeError::new_err("the run was stopped")),
                        Outcome::Panicked(m) => Err(PyRuntimeError::new_err(format!(
                            "demcon failed (an internal error, please report it): {m}"
                        ))),
                    };
                }
                Ok(Event::Stage(stage)) => report.call(py, stage, 0, 0),
                Ok(Event::Steps(done, total)) => report.call(py, "solve", done, total),
                Err(RecvTimeoutError::Timeout) => Ok(()),
                Err(RecvTimeoutError::Disconnected) => Err(PyRuntimeError::new_err(
                    "the run's worker thread ended without a result",
                )),
            }
            .and_then(|()| py.check_signals())
            .inspect_err(|_| {
                // Ctrl-C (or an error in the progress callback): stop the worker at its next
                // callback and wait for it, the GIL released.
                stop.store(true, Ordering::Relaxed);
                py.detach(|| while !matches!(recv(None), Ok(Event::Done(_)) | Err(_)) {});
            })?;
        }
    })?;
    let result = outcome;
    if let Some(dir) = out {
        demcon_scene::write_outputs(&scene.name, &scene.scene.config().outputs, &result, dir)
            .map_err(scene_err)?;
    }
    PyRunResult::new(py, &scene.name, result)
}

/// The run's progress reports: to a callable, to `sys.stderr`, or nowhere.
enum Progress<'py> {
    None,
    Print(Bound<'py, PyAny>),
    Call(Bound<'py, PyAny>),
}

impl<'py> Progress<'py> {
    fn new(py: Python<'py>, progress: Option<Bound<'py, PyAny>>) -> PyResult<Self> {
        let Some(p) = progress else {
            return Ok(Progress::None);
        };
        if p.is_callable() {
            return Ok(Progress::Call(p));
        }
        match p.extract::<bool>() {
            Ok(true) => Ok(Progress::Print(py.import("sys")?.getattr("stderr")?)),
            Ok(false) => Ok(Progress::None),
            Err(_) => Err(PyValueError::new_err(format!(
                "progress = {}: allowed are True, False, None or a callable progress(stage, done, total)",
                p.repr().map(|r| r.to_string()).unwrap_or_default()
            ))),
        }
    }

    fn call(&self, _py: Python<'py>, stage: &str, done: u64, total: u64) -> PyResult<()> {
        match self {
            Progress::None => Ok(()),
            Progress::Call(f) => f.call1((stage, done, total)).map(|_| ()),
            Progress::Print(stderr) => {
                let line = if total > 0 {
                    format!("\rdemcon: {stage} {done}/{total} steps")
                } else {
                    format!("\ndemcon: {stage}")
                };
                stderr.call_method1("write", (line,))?;
                stderr.call_method0("flush").map(|_| ())
            }
        }
    }
}

/// A panic's message.
fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "panic".into())
}

/// The result of `Scene.run`: `summary` (summary.json as a dict) and the per-particle fields as
/// numpy arrays (float64 unless said), each None when the run does not compute it.
#[pyclass(name = "RunResult", module = "demcon", frozen, get_all)]
pub struct PyRunResult {
    /// `summary.json` of the run, as a dict.
    summary: Py<PyAny>,
    /// Particle centres (m), shape (N, 3).
    centres: Py<PyAny>,
    /// Particle radii (m), shape (N,).
    radii: Py<PyAny>,
    /// Phase index of each particle (into the scene's `phases`, or 0), uint16, shape (N,).
    phase: Py<PyAny>,
    /// Volume each particle stands for (m³): the Laguerre cell's, or the representative volume
    /// of the network, shape (N,).
    volume: Py<PyAny>,
    /// End temperature (K or °C as the scene's values), shape (N,); None without thermal physics
    /// or in a periodic homogenisation.
    temperature: Py<PyAny>,
    /// Heat flux density (W/m²), shape (N, 3), when the scene's outputs ask for it.
    heat_flux: Py<PyAny>,
    /// Electric potential (V), shape (N,); None without electric physics.
    potential: Py<PyAny>,
    /// Current density (A/m²), shape (N, 3); None without electric physics.
    current_density: Py<PyAny>,
    /// Joule power of each particle (W), shape (N,); None without electric physics.
    joule_power: Py<PyAny>,
    /// Effective thermal conductivity along the scene's `etc_axis` (W/(m·K)), a float, or None.
    etc: Option<f64>,
    /// Effective conductivity tensor of a periodic homogenisation (W/(m·K)), shape (3, 3), or None.
    etc_tensor: Py<PyAny>,
    /// Electric conductivity tensor of a periodic homogenisation (S/m), shape (3, 3), or None.
    electric_tensor: Py<PyAny>,
    /// Wall time of the run (s).
    wall_s: f64,
}

impl PyRunResult {
    fn new(py: Python<'_>, name: &str, r: demcon_scene::RunResult) -> PyResult<Self> {
        let summary_text = demcon_scene::summary_json(name, &r).to_string();
        let summary = py
            .import("json")?
            .call_method1("loads", (summary_text,))?
            .unbind();
        let n = r.model.particles.len();
        let volume: Vec<f64> = match (&r.thermal_setup, &r.electric) {
            (Some(s), _) => s.rep_volumes.clone(),
            (None, Some(e)) => e.rep_volumes.clone(),
            (None, None) => (0..n).map(|p| r.model.solid_volume_of(p)).collect(),
        };
        let current_density = r.electric.as_ref().map(|e| e.current_density(&r.model));
        let tensor = |t: Option<&[[f64; 3]; 3]>| -> PyResult<Py<PyAny>> {
            match t {
                Some(t) => vectors(
                    py,
                    t.iter().map(|row| Vec3::new(row[0], row[1], row[2])).collect(),
                ),
                None => Ok(py.None()),
            }
        };
        let h = r.homogenization.as_ref();
        let etc_tensor = tensor(h.and_then(|h| h.thermal.as_ref()).map(|t| &t.report.tensor))?;
        let electric_tensor = tensor(h.and_then(|h| h.electric.as_ref()).map(|t| &t.report.tensor))?;
        let etc = r.etc.as_ref().map(|e| e.lambda_e);
        let wall_s = r.wall_s;
        let demcon_scene::RunResult {
            model,
            thermal,
            electric,
            flux,
            ..
        } = r;
        let particles = model.particles;
        let (potential, joule_power) = match electric {
            Some(e) => (scalars(py, Some(e.potentials)), scalars(py, Some(e.joule))),
            None => (py.None(), py.None()),
        };
        Ok(PyRunResult {
            summary,
            centres: vectors(py, particles.centres)?,
            radii: scalars(py, Some(particles.radii)),
            phase: PyArray1::from_vec(py, particles.phases).into_any().unbind(),
            volume: scalars(py, Some(volume)),
            temperature: scalars(py, thermal.map(|t| t.temperatures)),
            heat_flux: flux.map_or_else(|| Ok(py.None()), |f| vectors(py, f))?,
            potential,
            current_density: current_density.map_or_else(|| Ok(py.None()), |j| vectors(py, j))?,
            joule_power,
            etc,
            etc_tensor,
            electric_tensor,
            wall_s,
        })
    }
}

#[pymethods]
impl PyRunResult {
    fn __repr__(&self, py: Python<'_>) -> String {
        let n = self.radii.bind(py).len().unwrap_or(0);
        format!(
            "RunResult(particles={n}, etc={:?}, wall_s={:.3})",
            self.etc, self.wall_s
        )
    }
}

/// A float64 array (N,) moved into numpy without a copy, or None.
fn scalars(py: Python<'_>, v: Option<Vec<f64>>) -> Py<PyAny> {
    match v {
        Some(v) => PyArray1::from_vec(py, v).into_any().unbind(),
        None => py.None(),
    }
}

/// Vectors as a float64 array (N, 3) (one copy: nalgebra's vectors into one flat buffer).
fn vectors(py: Python<'_>, v: Vec<Vec3>) -> PyResult<Py<PyAny>> {
    let n = v.len();
    let flat: Vec<f64> = v.iter().flat_map(|x| [x.x, x.y, x.z]).collect();
    let a = Array2::from_shape_vec((n, 3), flat)
        .map_err(|e| PyRuntimeError::new_err(format!("an (N, 3) array of {n} rows: {e}")))?;
    Ok(a.into_pyarray(py).into_any().unbind())
}
