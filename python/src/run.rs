//! `Scene.run` and `demcon.RunResult`: the run on a worker thread with the GIL released, the
//! calling thread relaying progress and checking for Ctrl-C; the fields moved into numpy arrays.
//!
//! Stopping: the library has no cancel flag, but it calls back between stages and during the
//! packing and the time march. On Ctrl-C the calling thread sets `stop`; the worker's next
//! callback unwinds with [`Cancelled`] (`resume_unwind`: no panic message), caught at the top of
//! the worker. Nothing is written: the outputs are written only after a complete run (a
//! transient's checkpoint, when the scene schedules one and `out` is given, stays for `resume`).

use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError, Sender};
use std::time::Duration;

use demcon_core::{StageObserver, StageRecord, Vec3};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

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
    progress: ProgressArg<'_>,
    resume: bool,
) -> PyResult<PyRunResult> {
    if let Some(dir) = out {
        demcon_scene::output::check_output_dir(dir).map_err(scene_err)?;
    }
    let checkpoint = checkpoint_of(scene, out, resume)?;
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
    let checkpoint_at = checkpoint.as_deref();
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
                    checkpoint: checkpoint_at.map(|path| demcon_scene::CheckpointOptions {
                        path: path.to_path_buf(),
                        resume,
                        after_write: None,
                    }),
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
                Ok(Event::Stage(stage)) => report.call(stage, 0, 0),
                Ok(Event::Steps(done, total)) => report.call("solve", done, total),
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
    });
    report.close();
    let result = outcome?;
    if let Some(dir) = out {
        demcon_scene::write_outputs(&scene.name, &scene.scene.config().outputs, &result, dir)
            .map_err(scene_err)?;
    }
    if let Some(path) = &checkpoint {
        demcon_scene::checkpoint::remove_checkpoint(path).map_err(scene_err)?;
    }
    PyRunResult::new(py, &scene.name, result)
}

/// The checkpoint file of a run, as `demcon run --out OUT` has it: `OUT.checkpoint` when `out`
/// is given and the scene schedules checkpoints (`thermal.checkpoint`), else none — and then
/// `resume` is refused.
fn checkpoint_of(scene: &PyScene, out: Option<&Path>, resume: bool) -> PyResult<Option<PathBuf>> {
    let scheduled = scene
        .scene
        .config()
        .thermal
        .as_ref()
        .is_some_and(|t| t.checkpoint.is_some());
    let checkpoint = match out {
        Some(dir) if scheduled => Some(demcon_scene::checkpoint::checkpoint_path(dir).map_err(scene_err)?),
        _ => None,
    };
    if resume && checkpoint.is_none() {
        return Err(PyValueError::new_err(
            "resume = True: a run continues from the checkpoint beside its output folder; give out= \
             (the interrupted run's) and a scene with thermal.checkpoint",
        ));
    }
    Ok(checkpoint)
}

/// Runs `f` on this thread with the GIL released, handing it a packing-progress callback that
/// takes the GIL back at most every [`POLL`] to look for Ctrl-C; on Ctrl-C `f` is unwound
/// (nothing it made is kept) and `KeyboardInterrupt` raised.
pub(crate) fn checking_signals<R: Send>(
    py: Python<'_>,
    f: impl FnOnce(&(dyn Fn(&demcon_packing::PackProgress) + Sync)) -> R + Send,
) -> PyResult<R> {
    let interrupted: Mutex<Option<PyErr>> = Mutex::new(None);
    let last = Mutex::new(std::time::Instant::now());
    let check = |_: &demcon_packing::PackProgress| {
        let mut last = last.lock().unwrap_or_else(|p| p.into_inner());
        if last.elapsed() < POLL {
            return;
        }
        *last = std::time::Instant::now();
        if let Err(e) = Python::attach(|py| py.check_signals()) {
            *interrupted.lock().unwrap_or_else(|p| p.into_inner()) = Some(e);
            resume_unwind(Box::new(Cancelled));
        }
    };
    let caught = py.detach(|| catch_unwind(AssertUnwindSafe(|| f(&check))));
    match caught {
        Ok(r) => Ok(r),
        Err(payload) if payload.is::<Cancelled>() => Err(interrupted
            .into_inner()
            .unwrap_or_else(|p| p.into_inner())
            .unwrap_or_else(|| PyRuntimeError::new_err("stopped"))),
        Err(payload) => Err(PyRuntimeError::new_err(format!(
            "demcon failed (an internal error, please report it): {}",
            panic_text(payload.as_ref())
        ))),
    }
}

/// The `progress` argument of `Scene.run`: on (its default), or what the caller passed.
pub(crate) enum ProgressArg<'py> {
    On,
    Given(Bound<'py, PyAny>),
}

impl<'a, 'py> FromPyObject<'a, 'py> for ProgressArg<'py> {
    type Error = PyErr;

    fn extract(obj: pyo3::Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        Ok(ProgressArg::Given(obj.to_owned()))
    }
}

/// The run's progress reports: to a callable, or nowhere. `True` is `demcon._progress`'s
/// reporter (a tqdm bar when tqdm is installed, else lines on `sys.stderr`).
enum Progress<'py> {
    None,
    Call(Bound<'py, PyAny>),
}

impl<'py> Progress<'py> {
    fn new(py: Python<'py>, progress: ProgressArg<'py>) -> PyResult<Self> {
        let p = match progress {
            ProgressArg::On => pyo3::types::PyBool::new(py, true).to_owned().into_any(),
            ProgressArg::Given(p) if p.is_none() => return Ok(Progress::None),
            ProgressArg::Given(p) => p,
        };
        if p.is_callable() {
            return Ok(Progress::Call(p));
        }
        match p.extract::<bool>() {
            Ok(true) => Ok(Progress::Call(
                py.import("demcon._progress")?.call_method0("Reporter")?,
            )),
            Ok(false) => Ok(Progress::None),
            Err(_) => Err(PyValueError::new_err(format!(
                "progress = {}: allowed are True, False, None or a callable progress(stage, done, total)",
                p.repr().map(|r| r.to_string()).unwrap_or_default()
            ))),
        }
    }

    fn call(&self, stage: &str, done: u64, total: u64) -> PyResult<()> {
        match self {
            Progress::None => Ok(()),
            Progress::Call(f) => f.call1((stage, done, total)).map(|_| ()),
        }
    }

    /// Tells the reporter the run ended (closes a tqdm bar), when it listens for that.
    fn close(&self) {
        if let Progress::Call(f) = self
            && f.hasattr("close").unwrap_or(false)
        {
            let _ = f.call_method0("close");
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
#[pyclass(name = "RunResult", module = "demcon", frozen)]
pub struct PyRunResult {
    /// `summary.json` of the run, as a dict.
    #[pyo3(get)]
    summary: Py<PyAny>,
    /// Particle centres (m), shape (N, 3).
    #[pyo3(get)]
    centres: Py<PyAny>,
    /// Particle radii (m), shape (N,).
    #[pyo3(get)]
    radii: Py<PyAny>,
    /// Phase index of each particle (into the scene's `phases`, or 0), uint16, shape (N,).
    #[pyo3(get)]
    phase: Py<PyAny>,
    /// Volume each particle stands for (m³): the Laguerre cell's, or the representative volume
    /// of the network, shape (N,).
    #[pyo3(get)]
    volume: Py<PyAny>,
    /// End temperature (K or °C as the scene's values), shape (N,); None without thermal physics
    /// or in a periodic homogenisation.
    #[pyo3(get)]
    temperature: Py<PyAny>,
    /// Heat flux density (W/m²), shape (N, 3), when the scene's outputs ask for it.
    #[pyo3(get)]
    heat_flux: Py<PyAny>,
    /// Halo-smoothed heat flux density (W/m²), shape (N, 3), when the outputs ask for it.
    #[pyo3(get)]
    halo_flux: Py<PyAny>,
    /// Whether each particle's Halo is cut by the boundary (its `halo_flux` is biased), bool (N,).
    #[pyo3(get)]
    halo_cut: Py<PyAny>,
    /// Electric potential (V), shape (N,); None without electric physics.
    #[pyo3(get)]
    potential: Py<PyAny>,
    /// Current density (A/m²), shape (N, 3); None without electric physics.
    #[pyo3(get)]
    current_density: Py<PyAny>,
    /// Joule power of each particle (W), shape (N,); None without electric physics.
    #[pyo3(get)]
    joule_power: Py<PyAny>,
    /// Effective thermal conductivity along the scene's `etc_axis` (W/(m·K)), a float, or None.
    #[pyo3(get)]
    etc: Option<f64>,
    /// Effective conductivity tensor of a periodic homogenisation (W/(m·K)), shape (3, 3), or None.
    #[pyo3(get)]
    etc_tensor: Py<PyAny>,
    /// Electric conductivity tensor of a periodic homogenisation (S/m), shape (3, 3), or None.
    #[pyo3(get)]
    electric_tensor: Py<PyAny>,
    /// Probe readings: {name: {"t": (K,) s, one (K,) array per field read (`temperature`,
    /// `flux_magnitude`, …), "solved": (K,) bool}}.
    #[pyo3(get)]
    probes: Py<PyAny>,
    /// Profiles: {name: {"t": (K,) s, "distance": (P,) m, one (K, P) array per field read,
    /// "solved": (K, P) bool}}.
    #[pyo3(get)]
    profiles: Py<PyAny>,
    /// Where a resumed run continued from: {"steps": int, "t": float (s)}, or None.
    #[pyo3(get)]
    resumed: Py<PyAny>,
    /// Wall time of the run (s).
    #[pyo3(get)]
    wall_s: f64,
    /// What `contacts()` builds its arrays from.
    contacts: ContactData,
}

/// What `RunResult.contacts()` builds its arrays from, moved out of the run: the arrays are made
/// only when asked for (at 10⁶ particles, 7·10⁶ contacts, they take a few hundred ms).
struct ContactData {
    pairs: Vec<[u32; 2]>,
    geometry: Vec<demcon_graph::ContactGeometry>,
    /// Thermal conductances (W/K): the contacts, then the wall links.
    thermal: Option<Vec<f64>>,
    /// Electric conductances (S) and currents (A): the contacts, then the electrode links.
    electric: Option<(Vec<f64>, Vec<f64>)>,
}

impl PyRunResult {
    fn new(py: Python<'_>, name: &str, mut r: demcon_scene::RunResult) -> PyResult<Self> {
        let summary_text = demcon_scene::summary_json(name, &r).to_string();
        let summary = py
            .import("json")?
            .call_method1("loads", (summary_text,))?
            .unbind();
        let n = r.model.particles.len();
        let volume: Vec<f64> = match (&mut r.thermal_setup, &mut r.electric) {
            (Some(s), _) => std::mem::take(&mut s.rep_volumes),
            (None, Some(e)) => std::mem::take(&mut e.rep_volumes),
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
        let probes = probe_arrays(py, &r.probes)?;
        let profiles = profile_arrays(py, &r.profiles)?;
        let wall_s = r.wall_s;
        let resumed = match &r.resumed {
            Some(x) => {
                let d = PyDict::new(py);
                d.set_item("steps", x.steps)?;
                d.set_item("t", x.t)?;
                d.into_any().unbind()
            }
            None => py.None(),
        };
        let graph = &mut r.model.graph;
        let contacts = ContactData {
            geometry: std::mem::take(&mut graph.geometry),
            pairs: std::mem::take(&mut graph.pairs),
            thermal: r
                .thermal_setup
                .as_mut()
                .map(|s| std::mem::take(&mut s.conductances)),
            electric: r.electric.as_mut().map(|e| {
                (
                    std::mem::take(&mut e.conductances),
                    std::mem::take(&mut e.branch_currents),
                )
            }),
        };
        let particles = std::mem::take(&mut r.model.particles);
        let (potential, joule_power) = match r.electric.as_mut() {
            Some(e) => (
                scalars(py, Some(std::mem::take(&mut e.potentials))),
                scalars(py, Some(std::mem::take(&mut e.joule))),
            ),
            None => (py.None(), py.None()),
        };
        let (halo_flux, halo_cut) = match r.halo.take() {
            Some((f, cut, _)) => (vectors(py, f)?, PyArray1::from_vec(py, cut).into_any().unbind()),
            None => (py.None(), py.None()),
        };
        let temperature = scalars(
            py,
            r.thermal.as_mut().map(|t| std::mem::take(&mut t.temperatures)),
        );
        let heat_flux = r.flux.take().map_or_else(|| Ok(py.None()), |f| vectors(py, f))?;
        // The rest (the network, cells, solver state: most of the run's memory) is freed on a
        // thread of its own: at 10⁶ particles that takes longer than making every array here.
        std::thread::spawn(move || drop(r));
        Ok(PyRunResult {
            summary,
            centres: vectors(py, particles.centres)?,
            radii: scalars(py, Some(particles.radii)),
            phase: PyArray1::from_vec(py, particles.phases).into_any().unbind(),
            volume: scalars(py, Some(volume)),
            temperature,
            heat_flux,
            halo_flux,
            halo_cut,
            potential,
            current_density: current_density.map_or_else(|| Ok(py.None()), |j| vectors(py, j))?,
            joule_power,
            etc,
            etc_tensor,
            electric_tensor,
            probes,
            profiles,
            resumed,
            wall_s,
            contacts,
        })
    }
}

#[pymethods]
impl PyRunResult {
    /// The contacts between particles (the network's edges; wall and electrode links are not
    /// included) as a dict of arrays, one row per contact: `pairs` (M, 2) uint32 particle
    /// indices; `distance` (M,) centre to centre (m; the periodic image's across a period);
    /// with thermal physics `thermal_conductance` (M,) (W/K) and, unless homogenised,
    /// `heat_flow` (M,) (W, from the first particle to the second); with electric physics
    /// `electric_conductance` (M,) (S) and `current` (M,) (A, first to second).
    fn contacts(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        contact_arrays(py, &self.contacts, self.temperature.bind(py))
    }

    /// The run as a `pyvista.PolyData` of the particle centres, every per-particle array as
    /// point data (needs PyVista: `pip install pyvista`).
    fn to_pyvista(slf: &Bound<'_, Self>) -> PyResult<Py<PyAny>> {
        let helper = slf.py().import("demcon._pyvista")?;
        Ok(helper.call_method1("to_pyvista", (slf,))?.unbind())
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let n = self.radii.bind(py).len().unwrap_or(0);
        let etc = self.etc.map_or_else(|| "None".to_string(), |x| x.to_string());
        format!("RunResult(particles={n}, etc={etc}, wall_s={:.3})", self.wall_s)
    }
}

/// The contact arrays of `RunResult.contacts()` (`temperature`: the run's, or None).
fn contact_arrays(py: Python<'_>, c: &ContactData, temperature: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
    let m = c.pairs.len();
    let d = PyDict::new(py);
    let flat: Vec<u32> = bytemuck::cast_slice(&c.pairs).to_vec();
    d.set_item("pairs", PyArray1::from_vec(py, flat).reshape([m, 2])?)?;
    let distance = c.geometry.iter().map(|g| g.distance);
    d.set_item("distance", PyArray1::from_iter(py, distance))?;
    if let Some(g) = &c.thermal {
        let g = &g[..m];
        d.set_item("thermal_conductance", PyArray1::from_slice(py, g))?;
        if let Ok(t) = temperature.cast::<PyArray1<f64>>() {
            let t = t.readonly();
            let temps = t.as_slice()?;
            let flow: Vec<f64> = c
                .pairs
                .iter()
                .zip(g)
                .map(|(&[p, q], gk)| gk * (temps[p as usize] - temps[q as usize]))
                .collect();
            d.set_item("heat_flow", PyArray1::from_vec(py, flow))?;
        }
    }
    if let Some((g, i)) = &c.electric {
        d.set_item("electric_conductance", PyArray1::from_slice(py, &g[..m]))?;
        d.set_item("current", PyArray1::from_slice(py, &i[..m]))?;
    }
    Ok(d.into_any().unbind())
}

/// The names in order of first appearance.
fn names_of<'a>(names: impl Iterator<Item = &'a str>) -> Vec<&'a str> {
    let mut out: Vec<&str> = Vec::new();
    for n in names {
        if !out.contains(&n) {
            out.push(n);
        }
    }
    out
}

/// `RunResult.probes`: per probe, its output times `t` (K,), one (K,) array per field it reads
/// (`temperature`, `potential`, `flux_magnitude`, …) and `solved` (K,) (every reading from
/// solved particles).
fn probe_arrays(py: Python<'_>, probes: &[demcon_scene::run::ProbeValue]) -> PyResult<Py<PyAny>> {
    let d = PyDict::new(py);
    for name in names_of(probes.iter().map(|p| p.name.as_str())) {
        let of: Vec<_> = probes.iter().filter(|p| p.name == name).collect();
        let fields = names_of(of.iter().map(|p| p.field.as_str()));
        let first: Vec<_> = of.iter().filter(|p| p.field == fields[0]).collect();
        let e = PyDict::new(py);
        e.set_item("t", PyArray1::from_iter(py, first.iter().map(|p| p.t)))?;
        for field in &fields {
            let values = of.iter().filter(|p| p.field == *field).map(|p| p.value);
            e.set_item(*field, PyArray1::from_iter(py, values))?;
        }
        let solved = (0..first.len()).map(|k| {
            fields.iter().all(|f| {
                of.iter()
                    .filter(|p| p.field == *f)
                    .nth(k)
                    .is_some_and(|p| p.solved)
            })
        });
        e.set_item("solved", PyArray1::from_iter(py, solved))?;
        d.set_item(name, e)?;
    }
    Ok(d.into_any().unbind())
}

/// `RunResult.profiles`: per profile, its output times `t` (K,), the points' `distance` (P,)
/// from its start (m), one (K, P) array per field it reads and `solved` (K, P).
fn profile_arrays(py: Python<'_>, profiles: &[demcon_scene::run::ProfileValues]) -> PyResult<Py<PyAny>> {
    let d = PyDict::new(py);
    for name in names_of(profiles.iter().map(|p| p.name.as_str())) {
        let of: Vec<_> = profiles.iter().filter(|p| p.name == name).collect();
        let fields = names_of(of.iter().map(|p| p.field.as_str()));
        let first: Vec<_> = of.iter().filter(|p| p.field == fields[0]).collect();
        let points = first[0].points.len();
        let grid = |rows: &[&&demcon_scene::run::ProfileValues],
                    f: &dyn Fn(&demcon_scene::run::ProfileValues, usize) -> f64|
         -> PyResult<Bound<'_, PyAny>> {
            let flat: Vec<f64> = rows
                .iter()
                .flat_map(|p| (0..points).map(move |i| if i < p.points.len() { f(p, i) } else { f64::NAN }))
                .collect();
            let a = Array2::from_shape_vec((rows.len(), points), flat)
                .map_err(|e| PyRuntimeError::new_err(format!("profile {name}: {e}")))?;
            Ok(a.into_pyarray(py).into_any())
        };
        let e = PyDict::new(py);
        e.set_item("t", PyArray1::from_iter(py, first.iter().map(|p| p.t)))?;
        e.set_item(
            "distance",
            PyArray1::from_iter(py, first[0].points.iter().map(|x| x.0)),
        )?;
        let mut solved = vec![true; first.len() * points];
        for field in &fields {
            let rows: Vec<_> = of.iter().filter(|p| p.field == *field).collect();
            e.set_item(*field, grid(&rows, &|p, i| p.points[i].1)?)?;
            for (k, p) in rows.iter().enumerate() {
                for (i, &ok) in p.solved.iter().enumerate().take(points) {
                    if let Some(s) = solved.get_mut(k * points + i) {
                        *s &= ok;
                    }
                }
            }
        }
        let solved = Array2::from_shape_vec((first.len(), points), solved)
            .map_err(|e| PyRuntimeError::new_err(format!("profile {name}: {e}")))?;
        e.set_item("solved", solved.into_pyarray(py))?;
        d.set_item(name, e)?;
    }
    Ok(d.into_any().unbind())
}

/// A float64 array (N,) moved into numpy without a copy, or None.
fn scalars(py: Python<'_>, v: Option<Vec<f64>>) -> Py<PyAny> {
    match v {
        Some(v) => PyArray1::from_vec(py, v).into_any().unbind(),
        None => py.None(),
    }
}

/// Vectors as a float64 array (N, 3), moved into numpy without a copy (nalgebra's `Vec3` is
/// three contiguous f64, so the buffer is already (N, 3) row-major).
pub(crate) fn vectors(py: Python<'_>, v: Vec<Vec3>) -> PyResult<Py<PyAny>> {
    let n = v.len();
    let flat: Vec<f64> = bytemuck::allocation::try_cast_vec(v)
        .unwrap_or_else(|(_, v)| v.iter().flat_map(|x| [x.x, x.y, x.z]).collect());
    Ok(PyArray1::from_vec(py, flat).reshape([n, 3])?.into_any().unbind())
}
