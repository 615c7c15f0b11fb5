//! `granular_mpm._native`: the Python extension over the `mpm-run` library. It only parses,
//! drives and reports: scenes are loaded and validated by `mpm-scene`, runs are `run_scene` and
//! `resume`, and the stepping API is `mpm_run::Simulation`. The Python package around it
//! (`python/granular_mpm`) turns the summaries into dicts and the series into NumPy arrays or
//! pandas DataFrames.
//!
//! While a run or a step works, the GIL is released and the calling thread only waits, every
//! `mpm_run::POLL`, looking for a Python signal (Ctrl-C) and calling the progress callback; a
//! signal stops the work after its current step, then raises `KeyboardInterrupt` with the state
//! consistent (a run writes its checkpoint, as `mpm` does on Ctrl-C).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use mpm_run::{
    Limit, Progress, ProgressSink, RunError, RunOptions, RunStatus, SceneError as NativeSceneError,
};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1};
use pyo3::exceptions::{PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

pyo3::create_exception!(
    granular_mpm._native,
    SceneError,
    PyValueError,
    "A scene was refused: `str(e)` is the located message (file, line, field, value, \
     admissible range and fix), and `e.origin`, `e.line`, `e.column`, `e.path`, `e.value`, \
     `e.problem`, `e.admissible`, `e.fix` its parts."
);
pyo3::create_exception!(
    granular_mpm._native,
    SolverError,
    PyRuntimeError,
    "The solver stopped with an instability (the step, the particle and the cause in the \
     message); `e.summary_json` is the run's summary at that step, and what was written stays \
     readable."
);

/// the located scene error as a Python `SceneError` with its parts as attributes.
fn scene_error(py: Python<'_>, e: &NativeSceneError) -> PyErr {
    let err = SceneError::new_err(e.to_string());
    let v = err.value(py);
    let _ = v.setattr("origin", &e.origin);
    let _ = v.setattr("line", e.line);
    let _ = v.setattr("column", e.column);
    let _ = v.setattr("path", &e.path);
    let _ = v.setattr("value", e.value.as_deref());
    let _ = v.setattr("problem", &e.problem);
    let _ = v.setattr("admissible", &e.admissible);
    let _ = v.setattr("fix", &e.fix);
    err
}

/// a run's error as the Python exception a user expects.
fn run_error(py: Python<'_>, e: RunError) -> PyErr {
    match e {
        RunError::Scene(s) => scene_error(py, &s),
        RunError::Solver { message, summary } => {
            let err = SolverError::new_err(message);
            let json = serde_json::to_string(&summary).unwrap_or_default();
            let _ = err.value(py).setattr("summary_json", json);
            err
        }
        RunError::Output(o) => PyOSError::new_err(o.to_string()),
        RunError::Arguments(a) => PyValueError::new_err(a),
        RunError::Setup(s) => PyRuntimeError::new_err(s),
    }
}

/// A validated scene (the TOML scene format of `docs/scene-format.md`).
#[pyclass(module = "granular_mpm._native", name = "Scene", frozen)]
#[derive(Clone)]
struct Scene {
    inner: mpm_run::AnyScene,
}

#[pymethods]
impl Scene {
    /// loads and validates a scene file; files it names (DEMs, polylines) are relative to it.
    #[staticmethod]
    fn from_file(py: Python<'_>, path: PathBuf) -> PyResult<Scene> {
        mpm_run::load_any_scene_file(&path)
            .map(|inner| Scene { inner })
            .map_err(|e| scene_error(py, &e))
    }

    /// validates a scene given as TOML text; `name` is how messages call it.
    #[staticmethod]
    #[pyo3(signature = (text, name = "<string>"))]
    fn from_str(py: Python<'_>, text: &str, name: &str) -> PyResult<Scene> {
        mpm_run::AnyScene::from_str(text, name)
            .map(|inner| Scene { inner })
            .map_err(|e| scene_error(py, &e))
    }

    /// validates a scene given as TOML text whose named files are relative to `dir`.
    #[staticmethod]
    fn from_str_in(py: Python<'_>, text: &str, name: &str, dir: PathBuf) -> PyResult<Scene> {
        mpm_run::AnyScene::from_str_in(text, name, &dir)
            .map(|inner| Scene { inner })
            .map_err(|e| scene_error(py, &e))
    }

    /// the folder the scene's named files were found in (`None` if it names none from a file).
    #[getter]
    fn files_dir(&self) -> Option<&str> {
        self.inner.files_dir()
    }

    /// an embedded scene (`granular_mpm.scenes()` lists them; the default is the paper's flume).
    #[staticmethod]
    #[pyo3(signature = (name = "flume"))]
    fn embedded(py: Python<'_>, name: &str) -> PyResult<Scene> {
        let Some(text) = mpm_run::embedded_scene(name) else {
            // a SceneError (a ValueError) with its parts, as a refused scene file has them
            let err = SceneError::new_err(mpm_run::unknown_scene_message(name));
            let v = err.value(py);
            let names: Vec<&str> = mpm_run::SCENES.iter().map(|(n, _)| *n).collect();
            let _ = v.setattr("origin", format!("embedded:{name}"));
            let _ = v.setattr("line", py.None());
            let _ = v.setattr("column", py.None());
            let _ = v.setattr("path", "name");
            let _ = v.setattr("value", name);
            let _ = v.setattr("problem", "no embedded scene has this name");
            let _ = v.setattr("admissible", names.join(", "));
            let fix = mpm_run::nearest_scene(name)
                .map_or("choose one of granular_mpm.scenes()".to_string(), |n| format!("`{n}`"));
            let _ = v.setattr("fix", fix);
            return Err(err);
        };
        mpm_run::AnyScene::from_str(text, &format!("embedded:{name}"))
            .map(|inner| Scene { inner })
            .map_err(|e| scene_error(py, &e))
    }

    /// this scene with the field at `path` set to `value`, a TOML value as text (`"35.0"`,
    /// `"\"musl\""`, `"[0.0, 1.2]"`), validated again.
    fn with_value(&self, py: Python<'_>, path: &str, value: &str) -> PyResult<Scene> {
        self.inner
            .with_value(path, value)
            .map(|inner| Scene { inner })
            .map_err(|e| scene_error(py, &e))
    }

    /// this scene without the field at `path` (its default applies), validated again.
    fn without_value(&self, py: Python<'_>, path: &str) -> PyResult<Scene> {
        self.inner.without_value(path).map(|inner| Scene { inner }).map_err(|e| scene_error(py, &e))
    }

    /// the value the scene gives at `path` as JSON text, or `None` when it gives none (its
    /// default applies).
    fn value_json(&self, py: Python<'_>, path: &str) -> PyResult<Option<String>> {
        let v = self.inner.value_at(path).map_err(|e| scene_error(py, &e))?;
        v.map(|v| serde_json::to_string(&v).map_err(|e| PyRuntimeError::new_err(e.to_string())))
            .transpose()
    }

    /// the scene's TOML text.
    #[getter]
    fn text(&self) -> &str {
        self.inner.text()
    }

    /// where the scene came from (a path, `embedded:NAME` or the name given).
    #[getter]
    fn origin(&self) -> &str {
        self.inner.origin()
    }

    /// the hash `summary.json` names the scene by.
    #[getter]
    fn hash(&self) -> String {
        self.inner.hash()
    }

    /// particles the scene generates.
    #[getter]
    fn particle_count(&self) -> usize {
        self.inner.particle_count()
    }

    /// simulated time the run ends at (s).
    #[getter]
    fn end_time(&self) -> f64 {
        self.inner.end_time()
    }

    /// the first step's Δt (s).
    #[getter]
    fn initial_dt(&self) -> f64 {
        self.inner.initial_dt()
    }

    /// the materials' names, in the order particles' `material` numbers them.
    #[getter]
    fn materials(&self) -> Vec<String> {
        self.inner.material_names().to_vec()
    }

    /// `mpm check`: the full validation and estimates, as JSON text.
    fn check_json(&self, py: Python<'_>) -> PyResult<String> {
        let report = mpm_run::check(&self.inner).map_err(|e| run_error(py, e))?.report;
        serde_json::to_string(&report).map_err(|e| PyRuntimeError::new_err(e.to_string()))
    }

    /// 2 for a plane-strain scene, 3 for a 3D one (`[grid] dimension`).
    #[getter]
    fn dimension(&self) -> u8 {
        self.inner.dimension()
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene({:?}, {}D, {} particles, end_time {} s)",
            self.inner.origin(),
            self.inner.dimension(),
            self.inner.particle_count(),
            self.inner.end_time()
        )
    }
}

/// the embedded scenes' names (the first is the default).
#[pyfunction]
fn scenes() -> Vec<&'static str> {
    mpm_run::SCENES.iter().map(|(n, _)| *n).collect()
}

/// What the worker reported last and the messages it sent, read by the waiting thread.
#[derive(Default)]
struct Watch {
    state: Mutex<(f64, f64, u64)>,
    messages: Mutex<Vec<(bool, String)>>,
}

impl Progress for Watch {
    fn start(&self, end_time: f64, time: f64, steps: u64) {
        if let Ok(mut s) = self.state.lock() {
            *s = (end_time, time, steps);
        }
    }
    fn update(&self, time: f64, steps: u64) {
        if let Ok(mut s) = self.state.lock() {
            (s.1, s.2) = (time, steps);
        }
    }
    fn warn(&self, message: &str) {
        if let Ok(mut m) = self.messages.lock() {
            m.push((true, message.to_string()));
        }
    }
    fn note(&self, message: &str) {
        if let Ok(mut m) = self.messages.lock() {
            m.push((false, message.to_string()));
        }
    }
    fn finish(&self) {}
}

/// How often a progress callback is called at most.
const PROGRESS_EVERY: Duration = Duration::from_millis(250);

/// The waiting thread's side: signals, progress, and the first Python error they raised.
struct Waiter {
    progress: Option<Py<PyAny>>,
    watch: Arc<Watch>,
    pending: Option<PyErr>,
    last: Instant,
}

impl Waiter {
    fn new(progress: Option<Py<PyAny>>) -> Self {
        Waiter { progress, watch: Arc::default(), pending: None, last: Instant::now() }
    }

    /// true when the work should stop after its current step.
    fn poll(&mut self) -> bool {
        if self.pending.is_some() {
            return true;
        }
        Python::attach(|py| {
            if let Err(e) = py.check_signals() {
                self.pending = Some(e);
                return true;
            }
            if let Some(cb) = &self.progress {
                if self.last.elapsed() >= PROGRESS_EVERY {
                    self.last = Instant::now();
                    let (end, time, steps) = self.watch.state.lock().map_or((0.0, 0.0, 0), |s| *s);
                    if let Err(e) = cb.call1(py, (time, end, steps)) {
                        self.pending = Some(e);
                        return true;
                    }
                }
            }
            false
        })
    }

    /// the messages the run sent, as (is_warning, text).
    fn messages(&self) -> Vec<(bool, String)> {
        self.watch.messages.lock().map(|m| m.clone()).unwrap_or_default()
    }
}

/// runs `work` on its own thread with the GIL released, polling `waiter` meanwhile and setting
/// `flag` when it asks to stop.
fn detached<T: Send>(
    py: Python<'_>,
    waiter: &mut Waiter,
    flag: &AtomicBool,
    work: impl FnOnce() -> Result<T, RunError> + Send,
) -> Result<T, RunError> {
    py.detach(|| {
        std::thread::scope(|s| {
            let handle = s.spawn(work);
            while !handle.is_finished() {
                std::thread::sleep(mpm_run::POLL);
                if waiter.poll() {
                    flag.store(true, Ordering::Relaxed);
                }
            }
            handle.join().unwrap_or_else(|_| {
                Err(RunError::Setup(
                    "the run's thread panicked (a defect: please report it)".into(),
                ))
            })
        })
    })
}

/// the summary as JSON text and the run's messages.
type Ran = (String, Vec<(bool, String)>);

/// runs `work` (a run or a resume) with options that report to the waiting thread and stop on
/// its signal, and hands the result to Python.
fn drive(
    py: Python<'_>,
    progress: Option<Py<PyAny>>,
    options: RunOptions,
    work: impl FnOnce(&RunOptions) -> Result<mpm_run::RunSummary, RunError> + Send,
) -> PyResult<Ran> {
    let mut waiter = Waiter::new(progress);
    let flag = Arc::new(AtomicBool::new(false));
    let opts = RunOptions {
        progress: ProgressSink(Some(waiter.watch.clone())),
        interrupt: Some(flag.clone()),
        ..options
    };
    let result = detached(py, &mut waiter, &flag, || work(&opts));
    finish(py, waiter, result)
}

/// runs `scene` into `out` (see `granular_mpm.run`).
#[pyfunction]
#[pyo3(signature = (scene, out, threads = None, force = false, progress = None))]
fn run(
    py: Python<'_>,
    scene: &Scene,
    out: Option<PathBuf>,
    threads: Option<usize>,
    force: bool,
    progress: Option<Py<PyAny>>,
) -> PyResult<Ran> {
    let options = RunOptions { out_dir: out, threads, force, ..Default::default() };
    let scene = &scene.inner;
    drive(py, progress, options, |opts| match scene {
        mpm_run::AnyScene::Plane(s) => mpm_run::run_scene(s, opts),
        mpm_run::AnyScene::Space(s) => mpm_run::run_space_scene(s, opts),
    })
}

/// continues the run in `out` from its checkpoint (see `granular_mpm.resume`).
#[pyfunction]
#[pyo3(signature = (out, threads = None, progress = None))]
fn resume(
    py: Python<'_>,
    out: PathBuf,
    threads: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Ran> {
    let options = RunOptions { threads, ..Default::default() };
    drive(py, progress, options, |opts| mpm_run::resume(&out, opts))
}

/// a run's result for Python: a pending KeyboardInterrupt first, then the run's own error.
fn finish(
    py: Python<'_>,
    mut waiter: Waiter,
    result: Result<mpm_run::RunSummary, RunError>,
) -> PyResult<Ran> {
    if let Some(e) = waiter.pending.take() {
        return Err(e);
    }
    let summary = result.map_err(|e| run_error(py, e))?;
    let json =
        serde_json::to_string(&summary).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    Ok((json, waiter.messages()))
}

/// A run advanced step by step (see `granular_mpm.Simulation`).
#[pyclass(module = "granular_mpm._native", name = "Simulation")]
struct Simulation {
    inner: Mutex<mpm_run::Simulation>,
}

impl Simulation {
    fn advance(&self, py: Python<'_>, limit: Limit) -> PyResult<Option<String>> {
        let mut guard = self.lock()?;
        let sim = &mut *guard;
        let mut waiter = Waiter::new(None);
        let result = py.detach(|| sim.advance(limit, &mut || waiter.poll()));
        if let Some(e) = waiter.pending.take() {
            return Err(e);
        }
        let a = result.map_err(|e| run_error(py, e))?;
        Ok(a.stopped.map(status_name))
    }

    /// the simulation, if no other thread is using it: a thread that waited for the lock while
    /// holding the GIL would deadlock with an advance that takes the GIL back to poll.
    fn lock(&self) -> PyResult<std::sync::MutexGuard<'_, mpm_run::Simulation>> {
        self.inner.try_lock().map_err(|e| match e {
            std::sync::TryLockError::WouldBlock => PyRuntimeError::new_err(
                "the simulation is busy in another thread (one call at a time)",
            ),
            std::sync::TryLockError::Poisoned(_) => {
                PyRuntimeError::new_err("the simulation failed in another thread")
            }
        })
    }

    fn with<T>(
        &self,
        py: Python<'_>,
        f: impl FnOnce(&mut mpm_run::Simulation) -> Result<T, RunError>,
    ) -> PyResult<T> {
        let mut guard = self.lock()?;
        f(&mut guard).map_err(|e| run_error(py, e))
    }
}

/// a run's particle fields as a dict of NumPy arrays.
fn field_dict<'py, const D: usize, const C: usize>(
    py: Python<'py>,
    f: mpm_run::ParticleFields<D, C>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let n = f.mass.len();
    let flat = |v: &[[f64; D]]| v.iter().flatten().copied().collect::<Vec<f64>>();
    d.set_item("position", PyArray1::from_vec(py, flat(&f.position)).reshape([n, D])?)?;
    d.set_item("velocity", PyArray1::from_vec(py, flat(&f.velocity)).reshape([n, D])?)?;
    d.set_item(
        "initial_position",
        PyArray1::from_vec(py, flat(&f.initial_position)).reshape([n, D])?,
    )?;
    let stress: Vec<f64> = f.stress.iter().flatten().copied().collect();
    d.set_item("stress", PyArray1::from_vec(py, stress).reshape([n, C])?)?;
    d.set_item("mass", PyArray1::from_vec(py, f.mass))?;
    d.set_item("volume", PyArray1::from_vec(py, f.volume))?;
    d.set_item("body", PyArray1::from_vec(py, f.body))?;
    d.set_item("material", PyArray1::from_vec(py, f.material))?;
    d.set_item("plastic_strain", PyArray1::from_vec(py, f.plastic_strain))?;
    Ok(d)
}

fn status_name(s: RunStatus) -> String {
    serde_json::to_value(s)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_else(|| format!("{s:?}"))
}

#[pymethods]
impl Simulation {
    /// generates the scene's particles and its initial state.
    #[new]
    #[pyo3(signature = (scene, threads = None))]
    fn new(py: Python<'_>, scene: &Scene, threads: Option<usize>) -> PyResult<Simulation> {
        let mut waiter = Waiter::new(None);
        let result = py.detach(|| match &scene.inner {
            mpm_run::AnyScene::Plane(s) => {
                mpm_run::Simulation::new(s, threads, &mut || waiter.poll())
            }
            mpm_run::AnyScene::Space(s) => {
                mpm_run::Simulation::new_space(s, threads, &mut || waiter.poll())
            }
        });
        if let Some(e) = waiter.pending.take() {
            return Err(e);
        }
        let inner = result.map_err(|e| run_error(py, e))?;
        Ok(Simulation { inner: Mutex::new(inner) })
    }

    /// `n` more steps; returns `None`, or why the run stopped early (`"at_rest"`,
    /// `"energy_alarm"`, `"step_limit"`).
    #[pyo3(signature = (n = 1))]
    fn step(&self, py: Python<'_>, n: u64) -> PyResult<Option<String>> {
        self.advance(py, Limit::Steps(n))
    }

    /// steps until simulated time `t` (s), the last step shortened to land on it.
    fn advance_to(&self, py: Python<'_>, t: f64) -> PyResult<Option<String>> {
        self.advance(py, Limit::Time(t))
    }

    /// simulated time (s).
    #[getter]
    fn time(&self, py: Python<'_>) -> PyResult<f64> {
        self.with(py, |s| Ok(s.time()))
    }

    /// steps taken.
    #[getter]
    fn steps(&self, py: Python<'_>) -> PyResult<u64> {
        self.with(py, |s| Ok(s.steps()))
    }

    /// number of particles.
    #[getter]
    fn particle_count(&self, py: Python<'_>) -> PyResult<usize> {
        self.with(py, |s| Ok(s.particle_count()))
    }

    /// 2 or 3.
    #[getter]
    fn dimension(&self, py: Python<'_>) -> PyResult<u8> {
        self.with(py, |s| Ok(s.dimension()))
    }

    /// the particles' fields as NumPy arrays (copies): vectors N × 2 or N × 3, stresses N × 4
    /// (xx, yy, zz, xy) or N × 6 (xx, yy, zz, xy, yz, zx).
    fn fields<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        if self.with(py, |s| Ok(s.dimension()))? == 3 {
            let f = self.with(py, |s| s.space_fields())?;
            return field_dict(py, f);
        }
        let f = self.with(py, |s| s.fields())?;
        field_dict(py, f)
    }

    /// sets every particle's velocity before the next step: `v` holds the N × 2 values in a
    /// row (x0, y0, x1, y1, ...), checked by the Python wrapper.
    fn set_velocities(&self, py: Python<'_>, v: PyReadonlyArray1<'_, f64>) -> PyResult<()> {
        let v = v.as_slice()?.to_vec();
        self.with(py, |s| s.set_velocities(v))
    }

    /// prescribes a body force per unit mass on each particle from the next step (`None`
    /// removes it): `b` as `set_velocities`'s values.
    #[pyo3(signature = (b = None))]
    fn set_body_force(&self, py: Python<'_>, b: Option<PyReadonlyArray1<'_, f64>>) -> PyResult<()> {
        let b = b.map(|b| b.as_slice().map(<[f64]>::to_vec)).transpose()?;
        self.with(py, |s| s.set_body_force(b))
    }

    /// changes a material's parameter (`materials.<name>.<field>`, a TOML value as text).
    fn set_material(&self, py: Python<'_>, path: &str, value: &str) -> PyResult<()> {
        self.with(py, |s| s.set_material(path, value))
    }

    /// the energy ledger now, as JSON text.
    fn energy_json(&self, py: Python<'_>) -> PyResult<String> {
        let e = self.with(py, |s| s.energy())?;
        serde_json::to_string(&e).map_err(|e| PyRuntimeError::new_err(e.to_string()))
    }

    /// what a run would report if it ended now, as JSON text.
    fn summary_json(&self, py: Python<'_>) -> PyResult<String> {
        let s = self.with(py, |s| s.summary())?;
        serde_json::to_string(&s).map_err(|e| PyRuntimeError::new_err(e.to_string()))
    }

    /// writes `dir/checkpoint.bin` and `dir/scene.toml`; `granular_mpm.resume(dir)` or
    /// `mpm resume DIR` continues from here.
    fn checkpoint(&self, py: Python<'_>, dir: PathBuf) -> PyResult<()> {
        self.with(py, |s| s.checkpoint(&dir))
    }
}

/// The extension module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_class::<Scene>()?;
    m.add_class::<Simulation>()?;
    m.add_function(wrap_pyfunction!(scenes, m)?)?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(resume, m)?)?;
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add("SolverError", py.get_type::<SolverError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
