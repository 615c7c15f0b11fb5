//! The run driver: builds the solver for a scene, steps it to the end time with an observer
//! that records time series, writes frames and checkpoints and draws progress, and writes the
//! final files — also when the solver stops with an instability or the user interrupts.
//!
//! Output timing never changes the steps: frames, series rows and checkpoints are taken after
//! the first step that reaches their time, so a resumed run takes exactly the steps of an
//! uninterrupted one (Δt depends only on the particle state, and only the end time shortens a
//! step).

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use mpm_grid::ShapeFunctions;
use mpm_scene::dispatch::{self, Job, SavedState, SceneModel};
use mpm_scene::envelope::{self, Envelope};
use mpm_scene::observed;
use mpm_scene::summary::{
    self, DtStats, EnergyReport, RunStatus, RunSummary, RunoutMetrics, RunoutReport,
};
use mpm_scene::{
    GridBuilt, InitialState, InitialStateSummary, Resolved, Scene, SceneError, ground_height,
    load_scene_str,
};
use mpm_solver::{EnergyCheck, Observer, RunEnd, Solver, SolverError, StepReport, Vector};
use serde::{Deserialize, Serialize};

use mpm_output::checkpoint::{self, CheckpointFile, History};
use mpm_output::csv::{self, EnergyRow, ProbeRow};
use mpm_output::dir::{DirLock, prepare_dir};
use mpm_output::report::{self, Deposit};
use mpm_output::{OutputError, atomic, vtk};

use crate::error::RunError;
use crate::progress::ProgressSink;

/// How to run a scene.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// output directory; `None` writes nothing (the summary is still returned).
    pub out_dir: Option<PathBuf>,
    /// rayon threads; `None` uses rayon's default (one per core).
    pub threads: Option<usize>,
    /// where progress, warnings and reports go; the default reports nothing.
    pub progress: ProgressSink,
    /// overwrite an existing, non-empty output directory.
    pub force: bool,
    /// stop (as on Ctrl-C, writing a checkpoint) after the first step that reaches this
    /// simulated time (s).
    pub stop_after: Option<f64>,
    /// set to true (e.g. by a Ctrl-C handler) to stop after the current step with a checkpoint.
    pub interrupt: Option<Arc<AtomicBool>>,
}

/// What `mpm check` reports.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CheckReport {
    /// particles generated.
    pub particles: usize,
    /// grid cells (columns × rows, or nx × ny).
    pub cells: [usize; 2],
    /// active grid nodes at t = 0.
    pub active_nodes: usize,
    /// Δt of the first step (s).
    pub initial_dt: f64,
    /// end time / initial Δt (the real count varies as speeds change).
    pub estimated_steps: u64,
    /// heap memory of particles and per-step scratch after locating (bytes).
    pub memory_bytes: usize,
    /// particle frames that would be written.
    pub frames: u64,
    /// approximate size of all frames on disk (bytes).
    pub frame_bytes: u64,
}

/// Validates a scene fully without building the solver's state: every particle is located on
/// the grid (its stencil exists), and particles, active nodes, steps, memory and disk are
/// estimated. Validation has already refused a scene that does not fit in memory or whose
/// initial Δt needs more than `max_steps` steps.
pub fn check_scene(scene: &Scene) -> Result<CheckReport, RunError> {
    struct CheckJob;
    impl Job for CheckJob {
        type Output = Result<CheckReport, RunError>;
        fn run<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
            self,
            scene: &Scene,
            shape: S,
            _materials: Vec<M>,
        ) -> Self::Output {
            let r = scene.resolved();
            let mut active = std::collections::HashSet::new();
            for (i, seed) in r.seeds.iter().enumerate() {
                let stencil = shape.stencil(seed.position).map_err(|e| {
                    setup_error(scene, &format!("particle {i} at {}: {e}", seed.position))
                })?;
                active.extend(stencil.nodes);
            }
            let cells = match &r.grid {
                GridBuilt::Terrain(t) => [t.columns(), t.rows()],
                GridBuilt::Regular(g) => g.cells(),
            };
            let frames =
                if r.output.vtk { (r.end_time / r.output.interval).ceil() as u64 + 1 } else { 0 };
            let per_frame = r.output.vtk_format.frame_bytes(r.seeds.len(), &r.output.fields);
            let apic = r.config.transfer == mpm_solver::Transfer::Apic;
            let state = std::mem::size_of::<M::State>();
            Ok(CheckReport {
                particles: r.seeds.len(),
                cells,
                active_nodes: active.len(),
                initial_dt: r.initial_dt,
                estimated_steps: (r.end_time / r.initial_dt).ceil() as u64,
                memory_bytes: mpm_solver::estimated_bytes(
                    r.seeds.len(),
                    active.len(),
                    N,
                    state,
                    apic,
                ) as usize,
                frames,
                frame_bytes: frames * per_frame,
            })
        }
    }
    dispatch::dispatch(scene, CheckJob)?
}

fn setup_error(scene: &Scene, message: &str) -> RunError {
    RunError::from(SceneError {
        origin: scene.origin().to_string(),
        line: None,
        column: None,
        path: "bodies".into(),
        value: None,
        problem: format!("the solver refused the scene: {message}"),
        admissible: String::new(),
        fix: "check the bodies' positions and materials".into(),
    })
}

/// Runs `scene` to its end time (see [`RunOptions`]).
///
/// Returns the summary of a completed or interrupted run; a solver instability returns
/// [`RunError::Solver`] after writing the files reached so far (including a frame of the
/// failing state and the summary with the error).
pub fn run_scene(scene: &Scene, opts: &RunOptions) -> Result<RunSummary, RunError> {
    // Held until the run returns: a second run into the directory is refused meanwhile.
    let _lock = match &opts.out_dir {
        Some(dir) => {
            let lock = prepare_dir(dir, opts.force)?;
            atomic::write(&dir.join("scene.toml"), scene.text().as_bytes())?;
            Some(lock)
        }
        None => None,
    };
    with_pool(opts, scene.resolved().seeds.len(), |threads| {
        dispatch::dispatch(
            scene,
            RunJob { opts, resume: None, threads, out_dir: opts.out_dir.clone() },
        )?
    })
}

/// Continues the run in `dir` from its last checkpoint to the scene's end time, writing into
/// the same directory (`opts.out_dir` and `opts.force` are ignored).
pub fn resume(dir: &Path, opts: &RunOptions) -> Result<RunSummary, RunError> {
    let path = dir.join(checkpoint::FILE_NAME);
    if !path.exists() {
        return Err(RunError::Output(OutputError::Checkpoint {
            path,
            reason: "no checkpoint in this directory (a run writes one on Ctrl-C and every \
                     output.checkpoint_interval)"
                .into(),
        }));
    }
    let _lock = DirLock::acquire(dir)?;
    let c = checkpoint::read(&path)?;
    // files the scene names (DEMs, CSV polylines) are relative to the scene file's directory
    let scene = match Path::new(&c.origin).parent() {
        Some(d) if !c.origin.starts_with("embedded:") => {
            mpm_scene::load_scene_str_in(&c.scene_text, &c.origin, d)?
        }
        _ => load_scene_str(&c.scene_text, &c.origin)?,
    };
    fits_its_scene(&c, &scene).map_err(|reason| OutputError::Checkpoint { path, reason })?;
    with_pool(opts, scene.resolved().seeds.len(), |threads| {
        dispatch::dispatch(
            &scene,
            RunJob {
                opts,
                resume: Some((c.state, c.history)),
                threads,
                out_dir: Some(dir.to_path_buf()),
            },
        )?
    })
}

/// why a decoded checkpoint cannot continue its scene (its clock, counts and history must be
/// those of a run of it), if it cannot.
fn fits_its_scene(c: &CheckpointFile, scene: &Scene) -> Result<(), String> {
    let r = scene.resolved();
    let (time, step, particles) = c.state.clock();
    if !(time.is_finite() && (0.0..=r.end_time).contains(&time)) {
        return Err(format!("time {time:e} s is not between 0 and end_time = {} s", r.end_time));
    }
    if step > r.max_steps {
        return Err(format!("step {step} is above max_steps = {}", r.max_steps));
    }
    if particles != r.seeds.len() {
        return Err(format!("{particles} particles, but its scene generates {}", r.seeds.len()));
    }
    // At most one row and one frame per step, besides those of t = 0.
    let h = &c.history;
    let rows = step.saturating_add(1);
    let probes = rows.saturating_mul(r.output.probes.len() as u64);
    for (what, n, most) in [
        ("energy rows", h.energy.len() as u64, rows),
        ("runout rows", h.runout.len() as u64, rows),
        ("frames", h.frames.len() as u64, rows),
        ("probe rows", h.probes.len() as u64, probes),
    ] {
        if n > most {
            return Err(format!("{n} {what} after {step} steps (at most {most})"));
        }
    }
    Ok(())
}

/// runs `f` in a pool of the requested threads (default: one per core), but no more than a
/// scene of `particles` particles can use (`mpm_solver::useful_threads`): a small scene on two
/// threads would only pay for the hand-offs. The results are the same for any count.
fn with_pool<T>(
    opts: &RunOptions,
    particles: usize,
    f: impl FnOnce(usize) -> Result<T, RunError> + Send,
) -> Result<T, RunError>
where
    T: Send,
{
    // rayon's global pool size follows RAYON_NUM_THREADS, else one thread per core.
    let available = opts.threads.unwrap_or_else(rayon::current_num_threads);
    let b = rayon::ThreadPoolBuilder::new()
        .num_threads(mpm_solver::useful_threads(particles, available.max(1)));
    let pool = b.build().map_err(|e| RunError::Setup(format!("cannot start threads: {e}")))?;
    pool.install(|| f(rayon::current_num_threads()))
}

struct RunJob<'a> {
    opts: &'a RunOptions,
    resume: Option<(SavedState, History)>,
    threads: usize,
    out_dir: Option<PathBuf>,
}

impl Job for RunJob<'_> {
    type Output = Result<RunSummary, RunError>;

    fn run<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        self,
        scene: &Scene,
        shape: S,
        materials: Vec<M>,
    ) -> Self::Output {
        let r = scene.resolved();
        let (mut solver, history, fresh) = match self.resume {
            None => {
                let particles = dispatch::particles(&r.seeds, &materials);
                let s = Solver::new(shape, materials, particles, r.config.clone())
                    .map_err(|e| setup_error(scene, &e.to_string()))?;
                (s, History { dt_min: f64::INFINITY, ..History::default() }, true)
            }
            Some((state, history)) => {
                let dir = self.out_dir.clone().unwrap_or_default();
                let Some(c) = M::unwrap(state) else {
                    return Err(RunError::Output(OutputError::Checkpoint {
                        path: dir.join(checkpoint::FILE_NAME),
                        reason: "its material model does not match its scene".into(),
                    }));
                };
                let s = Solver::from_checkpoint(shape, materials, r.config.clone(), c)
                    .map_err(|e| setup_error(scene, &e.to_string()))?;
                (s, history, false)
            }
        };
        let (initial, initial_error) = if fresh {
            match initial_state(&mut solver, &r.initial_state, &self.opts.progress) {
                Ok(summary) => (summary, None),
                Err(e) => (None, Some(e)),
            }
        } else {
            (None, None)
        };
        let mut driver = Driver {
            initial,
            scene,
            dir: self.out_dir.as_deref(),
            history,
            flushed: Flushed::default(),
            progress: self.opts.progress.clone(),
            interrupt: self.opts.interrupt.clone(),
            stop_after: self.opts.stop_after,
            io_error: None,
            stop: None,
            rest: RestWatch::default(),
        };
        driver.progress.start(r.end_time, solver.time(), solver.step_count());
        if let Some(rest) = r.stop_at_rest {
            driver.rest = RestWatch::over(&driver.history.energy, rest.kinetic_fraction);
        }
        if fresh {
            if r.output.envelope {
                let column = r.grid.column_width();
                let mut e = Envelope::new(&r.ground, column);
                observe(&mut e, r, &solver);
                driver.history.envelope = Some(e);
            }
            let m0 = driver.metrics(&solver);
            driver.history.initial = Some(m0);
            let p = solver.particles();
            driver.history.energy_check = Some(EnergyCheck::new(
                &solver.energy(),
                &p.position,
                &p.mass,
                r.config.gravity.length(),
                |x| ground_height(&r.ground, x),
            ));
            driver.record_series(&solver);
            driver.write_frame(&solver)?;
            driver.flush_series()?;
        } else {
            driver.rewrite_outputs()?;
        }
        let session_steps0 = solver.step_count();
        let start = Instant::now();
        // An error of the initial state's explicit ramp names a step of the ramp, not of the run.
        let during_ramp =
            initial_error.is_some() && matches!(r.initial_state, InitialState::GravityRamp { .. });
        let describe = |e: &SolverError| {
            if during_ramp {
                format!("initial state (gravity ramp, before the run): {e}")
            } else {
                e.to_string()
            }
        };
        let result = match initial_error {
            Some(e) => Err(e),
            None => solver.run_until(r.end_time, &mut driver),
        };
        let elapsed = start.elapsed().as_secs_f64();
        driver.progress.finish();
        driver.history.wall_time += elapsed;
        driver.history.particle_steps +=
            (solver.step_count() - session_steps0) as f64 * solver.particles().len() as f64;
        if let Some(e) = driver.io_error.take() {
            return Err(e);
        }
        let (status, error) = match (&result, driver.stop) {
            (Err(e), _) => (RunStatus::Failed, Some(describe(e))),
            (Ok(RunEnd::Stopped), Some(Stop::StepLimit)) => (
                RunStatus::StepLimit,
                Some(format!(
                    "step limit: {} steps reached at t = {:.6e} s before end_time = {} s (Δt \
                     {:.3e} s); no checkpoint is written: if the run is sound, run the scene \
                     again with a higher `[solver] max_steps`",
                    solver.step_count(),
                    solver.time(),
                    r.end_time,
                    solver.last_report().dt
                )),
            ),
            (Ok(RunEnd::Stopped), Some(Stop::AtRest)) => (RunStatus::AtRest, None),
            (Ok(RunEnd::Stopped), Some(Stop::EnergyAlarm)) => {
                (RunStatus::EnergyAlarm, alarm_message(&driver.history, r.alarm.threshold))
            }
            (Ok(RunEnd::Stopped), None) => (RunStatus::Interrupted, None),
            // (judged below, once the final row is in)
            (Ok(RunEnd::EndTime), _) => (RunStatus::Completed, None),
        };
        // The checkpoint holds the history as an uninterrupted run has it at this step (the
        // extra row and frame of the stop below are not part of it).
        if status == RunStatus::Interrupted {
            driver.write_checkpoint(&solver)?;
        }
        // the final state: a last series row and frame unless this very step was recorded.
        let t = solver.time();
        if driver.history.energy.last().is_none_or(|row| row.time < t) {
            driver.record_series(&solver);
        }
        if driver.history.frames.last().is_none_or(|f| f.0 < t) {
            driver.write_frame(&solver)?;
        }
        // The final row may trip the alarm: a run is judged on its last state too.
        let (status, error) = match status {
            RunStatus::Completed | RunStatus::AtRest if driver.history.alarm_time.is_some() => {
                (RunStatus::EnergyAlarm, alarm_message(&driver.history, r.alarm.threshold))
            }
            _ => (status, error),
        };
        driver.flush_series()?;
        let summary = driver.summary(&solver, status, error, self.threads);
        if let Some(dir) = driver.dir {
            driver.envelope_files(&solver)?;
            driver.plots(&solver)?;
            let json = serde_json::to_string_pretty(&summary)
                .map_err(|e| RunError::Setup(format!("cannot encode summary.json: {e}")))?;
            atomic::write(&dir.join("summary.json"), json.as_bytes())?;
        }
        match result {
            Err(e) => Err(RunError::Solver { message: describe(&e), summary: Box::new(summary) }),
            Ok(_) => Ok(summary),
        }
    }
}

/// the summary's message for a tripped energy alarm (`None` if it did not trip).
fn alarm_message(h: &History, threshold: f64) -> Option<String> {
    let t = h.alarm_time?;
    let worst = h.energy_check.unwrap_or_default();
    Some(format!(
        "energy alarm: at t = {t:.4} s the energy residual exceeded {:.1} % of the run's energy \
         scale (`[solver] energy_alarm`); the worst was {:+.1} % at t = {:.4} s. The results are \
         suspect: check the time step, the material's stiffness and the contact settings",
        100.0 * threshold,
        100.0 * worst.worst,
        worst.worst_time
    ))
}

struct Driver<'a> {
    /// what the initial-state stage did (a new run with `[initial_state]`).
    initial: Option<InitialStateSummary>,
    scene: &'a Scene,
    dir: Option<&'a Path>,
    history: History,
    flushed: Flushed,
    progress: ProgressSink,
    interrupt: Option<Arc<AtomicBool>>,
    stop_after: Option<f64>,
    io_error: Option<RunError>,
    /// why the driver stopped the run, when not on request.
    stop: Option<Stop>,
    /// the kinetic energy's course for `stop_at_rest`, kept as the rows come.
    rest: RestWatch,
}

/// The peak of the kinetic energy over the series rows so far, and the time of the first row of
/// the trailing run of rows at or below `fraction` of it (`None` when the last row is above).
/// Updated row by row; rebuilt from the rows on resume, so a resumed run decides as the
/// uninterrupted one does.
#[derive(Clone, Copy, Debug, Default)]
struct RestWatch {
    peak: f64,
    since: Option<f64>,
}

impl RestWatch {
    /// the watch after the rows of a history.
    fn over(rows: &[EnergyRow], fraction: f64) -> Self {
        let mut w = Self::default();
        for r in rows {
            w.push(r.time, r.ledger.kinetic, fraction);
        }
        w
    }

    /// takes one row. A rise to a new peak ends any rest; a run that has not moved (zero
    /// peak) is not at rest: it has not started.
    fn push(&mut self, time: f64, kinetic: f64, fraction: f64) {
        self.peak = self.peak.max(kinetic);
        if self.peak > 0.0 && kinetic <= fraction * self.peak {
            self.since.get_or_insert(time);
        } else {
            self.since = None;
        }
    }

    /// whether the kinetic energy has stayed at or below the fraction for `duration` up to `now`.
    fn at_rest(&self, now: f64, duration: f64) -> bool {
        self.since.is_some_and(|t| now - t >= duration)
    }
}

/// finds a new run's initial stresses as the scene asks (`[initial_state]`), timed and reported
/// to `progress`; `Ok(None)` for a stress-free start.
fn initial_state<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
    solver: &mut Solver<M, S, N>,
    how: &InitialState,
    progress: &ProgressSink,
) -> Result<Option<InitialStateSummary>, SolverError> {
    let start = Instant::now();
    let summary = match *how {
        InitialState::None => return Ok(None),
        InitialState::Implicit(settings) => {
            let g = solver.solve_geostatic(&settings)?;
            InitialStateSummary {
                method: "implicit".into(),
                load_steps: Some(g.load_steps),
                iterations: Some(g.iterations),
                residual: Some(g.residual),
                residual_history: g.history.iter().map(|h| h.residual).collect(),
                plastic_particles: Some(g.plastic_particles),
                tied_nodes: Some(g.tied_nodes),
                released_planes: Some(g.released_planes),
                max_displacement: Some(g.max_displacement),
                base_friction_ratio: Some(g.base_friction_ratio),
                ..InitialStateSummary::default()
            }
        }
        InitialState::GravityRamp { ramp, hold } => {
            let r = solver.settle(ramp, hold)?;
            InitialStateSummary {
                method: "gravity_ramp".into(),
                steps: Some(r.steps),
                kinetic_energy: Some(r.kinetic_energy),
                ..InitialStateSummary::default()
            }
        }
    };
    let summary = InitialStateSummary { wall_time_s: start.elapsed().as_secs_f64(), ..summary };
    {
        let s = &summary;
        progress.note(&match s.method.as_str() {
            "implicit" => format!(
                "initial state (implicit): {} load step(s), {} Newton iterations, residual \
                 {:.2e}, {} particles plastic, {} surface nodes tied, largest displacement \
                 {:.3e} m, {:.2} s",
                s.load_steps.unwrap_or(0),
                s.iterations.unwrap_or(0),
                s.residual.unwrap_or(0.0),
                s.plastic_particles.unwrap_or(0),
                s.tied_nodes.unwrap_or(0),
                s.max_displacement.unwrap_or(0.0),
                s.wall_time_s
            ),
            _ => format!(
                "initial state (gravity ramp): {} steps, kinetic energy left {:.3e} J/m \
                 (dropped), {:.2} s",
                s.steps.unwrap_or(0),
                s.kinetic_energy.unwrap_or(0.0),
                s.wall_time_s
            ),
        });
    }
    Ok(Some(summary))
}

/// takes the solver's current state into the envelopes.
fn observe<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
    e: &mut Envelope,
    r: &Resolved,
    solver: &Solver<M, S, N>,
) {
    let p = solver.particles();
    e.observe(solver.time(), r.spacing, [&p.position, &p.velocity], [&p.mass, &p.volume]);
}

/// Why the driver stopped a run before its end time (other than an interrupt).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stop {
    /// the energy alarm tripped with `energy_alarm_stop = true`.
    EnergyAlarm,
    /// `max_steps` was reached.
    StepLimit,
    /// `stop_at_rest`: the material has come to rest.
    AtRest,
}

/// Rows of each series this session has on disk.
#[derive(Clone, Copy, Debug, Default)]
struct Flushed {
    energy: usize,
    probes: usize,
    runout: usize,
}

/// A slot time counts as reached when the clock is within this fraction of the interval of it
/// (round-off of summed steps, never a physical time difference).
const SLOT_SLACK: f64 = 1e-9;

/// index of the last slot k·interval reached at time t.
fn slot(t: f64, interval: f64) -> u64 {
    (t / interval + SLOT_SLACK).floor().max(0.0) as u64
}

impl Driver<'_> {
    fn metrics<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &self,
        solver: &Solver<M, S, N>,
    ) -> RunoutMetrics {
        let r = self.scene.resolved();
        let p = solver.particles();
        let column = r.grid.column_width();
        summary::runout(
            solver.time(),
            [&p.position, &p.velocity],
            &p.mass,
            &r.ground,
            r.spacing,
            column,
            self.history.initial.as_ref(),
        )
    }

    fn record_series<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &mut self,
        solver: &Solver<M, S, N>,
    ) {
        let r = self.scene.resolved();
        let t = solver.time();
        let ledger = solver.energy();
        if let Some(check) = &mut self.history.energy_check {
            let relative = check.observe(t, &ledger);
            if self.history.alarm_time.is_none() && relative.abs() > r.alarm.threshold {
                self.history.alarm_time = Some(t);
                self.progress.warn(&format!(
                    "energy alarm at t = {t:.4} s: |energy residual| is {:.1} % of the energy \
                     scale (threshold {:.1} %)",
                    100.0 * relative.abs(),
                    100.0 * r.alarm.threshold
                ));
                if r.alarm.stop {
                    self.stop = Some(Stop::EnergyAlarm);
                }
            }
        }
        self.history.energy.push(EnergyRow {
            time: t,
            step: solver.step_count(),
            dt: solver.last_report().dt,
            ledger,
        });
        if let Some(rest) = r.stop_at_rest {
            self.rest.push(t, ledger.kinetic, rest.kinetic_fraction);
            if self.rest.at_rest(t, rest.duration) {
                self.stop.get_or_insert(Stop::AtRest);
            }
        }
        let p = solver.particles();
        let direction = r.output.reference.map_or(Vector::X, |rf| rf.direction);
        for (k, &i) in r.output.probes.iter().enumerate() {
            let Some(&x) = p.position.get(i) else { continue };
            let u = x - p.initial_position[i];
            let v = p.velocity[i];
            self.history.probes.push(ProbeRow {
                time: t,
                probe: k,
                particle: i,
                position: [x.x, x.y],
                displacement: [u.x, u.y],
                velocity: [v.x, v.y],
                along: u.dot(direction),
                reference: r.output.reference.map(|rf| rf.displacement(t)),
            });
        }
        let m = self.metrics(solver);
        self.history.runout.push(m);
    }

    fn write_frame<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &mut self,
        solver: &Solver<M, S, N>,
    ) -> Result<(), RunError> {
        let r = self.scene.resolved();
        let Some(dir) = self.dir else { return Ok(()) };
        if !r.output.vtk {
            return Ok(());
        }
        let clock = Instant::now();
        let name = format!("frames/particles_{:06}.vtp", self.history.frames.len());
        let path = dir.join(&name);
        let frame = vtk::frame(
            solver.particles(),
            solver.materials(),
            &r.output.fields,
            r.output.vtk_format,
            solver.time(),
        )
        .map_err(|source| RunError::from(OutputError::Io { path: path.clone(), source }))?;
        atomic::write_parts(&path, &frame.parts())?;
        self.history.frames.push((solver.time(), name));
        // The collection is small (a line per frame): rewritten whole, atomically.
        atomic::write(&dir.join("particles.pvd"), vtk::pvd(&self.history.frames).as_bytes())?;
        self.history.output_time += clock.elapsed().as_secs_f64();
        Ok(())
    }

    /// rewrites the files a killed or stopped session may have written past its checkpoint
    /// (rows, a torn last line, frames in the collection) from the history, before a resumed
    /// run continues them.
    fn rewrite_outputs(&mut self) -> Result<(), RunError> {
        let Some(dir) = self.dir else { return Ok(()) };
        self.flushed = Flushed::default();
        self.flush_series()?;
        if self.scene.resolved().output.vtk {
            atomic::write(&dir.join("particles.pvd"), vtk::pvd(&self.history.frames).as_bytes())?;
        }
        Ok(())
    }

    fn flush_series(&mut self) -> Result<(), RunError> {
        let Some(dir) = self.dir else { return Ok(()) };
        let clock = Instant::now();
        let (h, f) = (&self.history, &mut self.flushed);
        csv::flush(
            &dir.join("energy.csv"),
            csv::ENERGY_HEADER,
            &h.energy,
            &mut f.energy,
            csv::energy,
        )?;
        csv::flush(
            &dir.join("runout.csv"),
            csv::RUNOUT_HEADER,
            &h.runout,
            &mut f.runout,
            csv::runout,
        )?;
        if !self.scene.resolved().output.probes.is_empty() {
            csv::flush(
                &dir.join("probes.csv"),
                csv::PROBES_HEADER,
                &h.probes,
                &mut f.probes,
                csv::probes,
            )?;
        }
        self.history.output_time += clock.elapsed().as_secs_f64();
        Ok(())
    }

    fn write_checkpoint<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &self,
        solver: &Solver<M, S, N>,
    ) -> Result<(), RunError> {
        let Some(dir) = self.dir else { return Ok(()) };
        let file = CheckpointFile {
            format: checkpoint::FORMAT,
            code_version: env!("CARGO_PKG_VERSION").to_string(),
            origin: self.scene.origin().to_string(),
            scene_text: self.scene.text().to_string(),
            state: M::wrap(solver.checkpoint()),
            history: self.history.clone(),
        };
        Ok(checkpoint::write(&dir.join(checkpoint::FILE_NAME), &file)?)
    }

    fn summary<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &self,
        solver: &Solver<M, S, N>,
        status: RunStatus,
        error: Option<String>,
        threads: usize,
    ) -> RunSummary {
        let r = self.scene.resolved();
        let h = &self.history;
        let steps = solver.step_count();
        RunSummary {
            code_version: env!("CARGO_PKG_VERSION").to_string(),
            scene_origin: self.scene.origin().to_string(),
            scene_hash: self.scene.hash(),
            status,
            error,
            particles: solver.particles().len(),
            scheme: r.config.scheme.name().to_string(),
            shape_function: r.shape_function.name().to_string(),
            steps,
            simulated_time: solver.time(),
            end_time: r.end_time,
            dt: DtStats {
                min: if h.dt_min.is_finite() { h.dt_min } else { 0.0 },
                max: h.dt_max,
                mean: if steps > 0 { solver.time() / steps as f64 } else { 0.0 },
                first: h.dt_first,
            },
            wall_time_s: h.wall_time,
            particle_steps_per_s: if h.wall_time > 0.0 {
                h.particle_steps / h.wall_time
            } else {
                0.0
            },
            output_time_s: h.output_time,
            threads,
            energy: solver.energy(),
            energy_check: {
                let mut c = h.energy_check.unwrap_or_default();
                EnergyReport {
                    relative_residual: c.observe(solver.time(), &solver.energy()),
                    worst_relative_residual: c.worst,
                    worst_time: c.worst_time,
                    alarm_threshold: r.alarm.threshold,
                    alarm_time: h.alarm_time,
                }
            },
            runout: RunoutReport {
                last: h.runout.last().copied().unwrap_or_default(),
                indicators: {
                    let p = solver.particles();
                    // the source's top: the highest initial particle's top
                    let crown = p
                        .initial_position
                        .iter()
                        .copied()
                        .max_by(|a, b| a.y.total_cmp(&b.y))
                        .map_or(Vector::ZERO, |c| c + Vector::new(0.0, 0.5 * r.spacing));
                    let kinetic: Vec<(f64, f64)> =
                        h.energy.iter().map(|e| (e.time, e.ledger.kinetic)).collect();
                    summary::indicators(&h.runout, &kinetic, crown, &r.ground)
                },
            },
            observed: r.output.observed.as_ref().and_then(|o| {
                let p = solver.particles();
                let sim =
                    observed::simulated(&r.ground, r.grid.column_width(), r.spacing, &p.position);
                let last = h.runout.last()?;
                observed::compare(o, &sim, last.front_x, last.tail_x)
            }),
            state_hash: checkpoint::state_hash(&solver.checkpoint()),
            initial_state: self.initial.clone(),
        }
    }

    /// `envelope.csv`, `deposit.csv` and `plots/envelope.png`, when the scene asks for them.
    fn envelope_files<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &self,
        solver: &Solver<M, S, N>,
    ) -> Result<(), RunError> {
        let (Some(dir), Some(e)) = (self.dir, &self.history.envelope) else { return Ok(()) };
        let r = self.scene.resolved();
        let deposit = envelope::deposit(e, r.spacing, &solver.particles().position);
        let mut s = csv::ENVELOPE_HEADER.to_string();
        csv::envelope(&mut s, e);
        atomic::write(&dir.join("envelope.csv"), s.as_bytes())?;
        let mut s = csv::DEPOSIT_HEADER.to_string();
        csv::deposit(&mut s, &deposit);
        atomic::write(&dir.join("deposit.csv"), s.as_bytes())?;
        if r.output.plots {
            report::envelope(&dir.join("plots"), e, &deposit)?;
        }
        Ok(())
    }

    fn plots<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &self,
        solver: &Solver<M, S, N>,
    ) -> Result<(), RunError> {
        let Some(dir) = self.dir else { return Ok(()) };
        if !self.scene.resolved().output.plots {
            return Ok(());
        }
        let p = solver.particles();
        let deposit =
            Deposit { positions: &p.position, initial: &p.initial_position, time: solver.time() };
        Ok(report::plots(&dir.join("plots"), self.scene, &self.history, &deposit)?)
    }
}

impl<M: SceneModel, S: ShapeFunctions<N>, const N: usize> Observer<M, S, N> for Driver<'_> {
    fn after_step(&mut self, solver: &Solver<M, S, N>, report: &StepReport) -> ControlFlow<()> {
        let r = self.scene.resolved();
        let h = &mut self.history;
        // The step that lands on the end time is shortened; it does not count as the smallest.
        if report.time < r.end_time * (1.0 - 1e-12) || h.dt_max == 0.0 {
            h.dt_min = h.dt_min.min(report.dt);
        }
        h.dt_max = h.dt_max.max(report.dt);
        if h.dt_first == 0.0 {
            h.dt_first = report.dt;
        }
        if let Some(e) = &mut h.envelope {
            observe(e, r, solver);
        }
        let t = report.time;
        let series = slot(t, r.output.series_interval);
        let frame = slot(t, r.output.interval);
        if series > self.history.series_slot {
            self.history.series_slot = series;
            self.record_series(solver);
        }
        if frame > self.history.frame_slot {
            self.history.frame_slot = frame;
            if let Err(e) = self.write_frame(solver).and_then(|()| self.flush_series()) {
                self.io_error = Some(e);
                return ControlFlow::Break(());
            }
        }
        if let Some(every) = r.output.checkpoint_interval {
            let c = slot(t, every);
            if c > self.history.checkpoint_slot {
                self.history.checkpoint_slot = c;
                if let Err(e) = self.write_checkpoint(solver) {
                    self.io_error = Some(e);
                    return ControlFlow::Break(());
                }
            }
        }
        self.progress.update(t, report.step);
        if report.step >= r.max_steps && t < r.end_time * (1.0 - 1e-12) {
            self.stop.get_or_insert(Stop::StepLimit);
        }
        let interrupted = self.interrupt.as_ref().is_some_and(|f| f.load(Ordering::Relaxed));
        if interrupted {
            self.progress
                .warn("interrupted: writing a checkpoint after this step (a second signal aborts)");
        }
        if self.stop.is_some() || interrupted || self.stop_after.is_some_and(|s| t >= s) {
            return ControlFlow::Break(());
        }
        ControlFlow::Continue(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A checkpoint whose checksum holds but whose content cannot belong to its scene (a time of
    /// −1.9e305 s made `resume` run forever; another particle count) is refused before the solver
    /// takes it.
    #[test]
    fn a_checksummed_checkpoint_that_does_not_fit_its_scene_is_refused() {
        let text = crate::embedded_scene("free_fall")
            .unwrap()
            .replace("end_time = 1.0", "end_time = 0.02");
        let scene = load_scene_str(&text, "free_fall").unwrap();
        let dir = std::env::temp_dir().join(format!("mpm-fits-{}", std::process::id()));
        let opts =
            RunOptions { out_dir: Some(dir.clone()), stop_after: Some(0.01), ..Default::default() };
        run_scene(&scene, &opts).unwrap();
        let path = dir.join(checkpoint::FILE_NAME);
        let good = checkpoint::read(&path).unwrap();
        type Edit = fn(&mut CheckpointFile);
        let edits: [(&str, Edit); 3] = [
            ("time -1.9e305", |c| {
                if let SavedState::Elastic(s) = &mut c.state {
                    s.time = -1.9e305;
                }
            }),
            ("particles, but its scene generates", |c| {
                if let SavedState::Elastic(s) = &mut c.state {
                    s.particles.position.pop();
                }
            }),
            ("energy rows after", |c| {
                let row = c.history.energy[0];
                c.history.energy.extend(std::iter::repeat_n(row, 10_000));
            }),
        ];
        for (expect, edit) in edits {
            let mut bad = good.clone();
            edit(&mut bad);
            checkpoint::write(&path, &bad).unwrap();
            let e = resume(&dir, &RunOptions { threads: opts.threads, ..Default::default() })
                .unwrap_err();
            assert!(matches!(e, RunError::Output(OutputError::Checkpoint { .. })), "{expect}: {e}");
            assert!(e.to_string().contains(expect), "{expect}: {e}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
