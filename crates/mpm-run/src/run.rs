//! The run driver: builds the solver for a scene, steps it to the end time with an observer
//! that records time series, writes frames and checkpoints and draws progress, and writes the
//! final files — also when the solver stops with an instability or the user interrupts.
//!
//! Output timing never changes the steps: frames, series rows and checkpoints are taken after
//! the first step that reaches their time, so a resumed run takes exactly the steps of an
//! uninterrupted one (Δt depends only on the particle state, and only the end time shortens a
//! step).

use std::path::{Path, PathBuf};
use std::time::Instant;

use mpm_grid::ShapeFunctions;
use mpm_scene::dispatch::{self, Job, SavedState, SceneModel};
use mpm_scene::summary::RunSummary;
use mpm_scene::{GridBuilt, InitialState, Scene, SceneError, load_scene_str};
use mpm_solver::{Solver, SolverError};
use serde::{Deserialize, Serialize};

use mpm_output::checkpoint::{self, CheckpointFile, History};
use mpm_output::dir::{DirLock, prepare_dir};
use mpm_output::{OutputError, atomic};

use crate::driver::{Driver, initial_state};
use crate::error::RunError;
pub use crate::options::RunOptions;

/// what a message about a particle that left the grid adds: how to let it leave, or keep it.
pub(crate) const OUTSIDE_HINT: &str = " (material may leave through a side of the grid that \
    `[boundaries]` declares `\"outflow\"`; otherwise widen the grid or give the side a wall)";

/// What `mpm check` reports.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CheckReport {
    /// particles generated.
    pub particles: usize,
    /// grid cells (columns × rows, or nx × ny, or nx × ny × nz in 3D).
    pub cells: Vec<usize>,
    /// active grid nodes at t = 0.
    pub active_nodes: usize,
    /// Δt of the first step (s).
    pub initial_dt: f64,
    /// end time / initial Δt (the real count varies as speeds change).
    pub estimated_steps: u64,
    /// steps of an explicit initial state before t = 0 (`[initial_state] method =
    /// "gravity_ramp"`: ramp and settling time / initial Δt), if the scene asks one.
    pub initial_state_steps: Option<u64>,
    /// heap memory of particles and per-step scratch after locating, and of the implicit initial
    /// state's solve if the scene asks one (bytes).
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
                    setup_error(scene.origin(), &format!("particle {i} at {}: {e}", seed.position))
                })?;
                active.extend(stencil.nodes);
            }
            let cells = match &r.grid {
                GridBuilt::Terrain(t) => vec![t.columns(), t.rows()],
                GridBuilt::Regular(g) => g.cells().to_vec(),
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
                initial_state_steps: match r.initial_state {
                    mpm_scene::InitialState::GravityRamp { ramp, hold } => {
                        Some(((ramp + hold) / r.initial_dt).ceil() as u64)
                    }
                    _ => None,
                },
                memory_bytes: mpm_solver::estimated_bytes(
                    r.seeds.len(),
                    active.len(),
                    N,
                    state,
                    apic,
                ) as usize
                    // a checkpoint's two copies of the particles
                    + 2 * r.seeds.len() * mpm_scene::checkpoint_copy(state, apic)
                    + match r.initial_state {
                        mpm_scene::InitialState::Implicit(_) => {
                            mpm_solver::geostatic::estimated_bytes(r.seeds.len(), N) as usize
                        }
                        _ => 0,
                    },
                frames,
                frame_bytes: frames * per_frame,
            })
        }
    }
    dispatch::dispatch(scene, CheckJob)?
}

/// the solver's refusal of a scene (from `origin`, a path or `embedded:NAME`) at set-up.
pub(crate) fn setup_error(origin: &str, message: &str) -> RunError {
    RunError::from(SceneError {
        origin: origin.to_string(),
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
    // the arguments before the folder: a refused one leaves an earlier run's files as they are
    crate::options::available_threads(opts.threads)?;
    // Held until the run returns: a second run into the directory is refused meanwhile.
    let _lock = match &opts.out_dir {
        Some(dir) => {
            let lock = prepare_dir(dir, opts.force)?;
            atomic::write(&dir.join("scene.toml"), scene.text().as_bytes())?;
            Some(lock)
        }
        None => None,
    };
    for w in &scene.resolved().warnings {
        opts.progress.warn(&w.to_string());
    }
    with_pool(opts, scene.resolved().seeds.len(), |threads| {
        dispatch::dispatch(
            scene,
            RunJob { opts, resume: None, threads, out_dir: opts.out_dir.clone() },
        )?
    })
}

/// The summary of a run whose checkpoint is its last state and which ended (not interrupted):
/// resuming it would only rewrite its files with a session of no steps.
fn finished(dir: &Path, c: &checkpoint::CheckpointFile) -> Option<RunSummary> {
    let s: RunSummary = serde_json::from_str(&summary_text(dir)?).ok()?;
    let (time, steps, _) = c.state.clock();
    let last = s.steps == steps && s.simulated_time == time;
    (last && s.status != mpm_scene::RunStatus::Interrupted).then_some(s)
}

/// the text of the folder's `summary.json`, if it is a regular file that reads.
fn summary_text(dir: &Path) -> Option<String> {
    use std::io::Read;
    let mut text = String::new();
    let path = dir.join("summary.json");
    // (a FIFO would block the open for ever)
    if !std::fs::metadata(&path).is_ok_and(|m| m.file_type().is_file()) {
        return None;
    }
    std::fs::File::open(path).and_then(|f| f.take(SUMMARY_LIMIT).read_to_string(&mut text)).ok()?;
    Some(text)
}

/// the folder of a checkpoint's scene's named files: the absolute one it recorded (R3-04: a
/// relative path no longer resolved from another working directory) while it exists, else (a
/// project folder moved or mounted elsewhere) the scene file's directory as it was typed; the
/// files' fingerprints still refuse other files.
pub(crate) fn files_dir(c: &checkpoint::CheckpointFile) -> Option<std::path::PathBuf> {
    if let Some(d) = c.scene_dir.as_ref().map(std::path::PathBuf::from).filter(|d| d.is_dir()) {
        return Some(d);
    }
    if c.origin.starts_with("embedded:") {
        return None;
    }
    Some(Path::new(&c.origin).parent().unwrap_or(Path::new("")).to_path_buf())
}

/// the `scene_hash` of the folder's `summary.json`, if it has one that reads.
fn summary_scene_hash(dir: &Path) -> Option<String> {
    let v: serde_json::Value = serde_json::from_str(&summary_text(dir)?).ok()?;
    v.get("scene_hash")?.as_str().map(str::to_string)
}

/// The most of `summary.json` [`finished`] reads (its size is a few kilobytes).
const SUMMARY_LIMIT: u64 = 16 << 20;

/// Continues the run in `dir` from its last checkpoint to the scene's end time, writing into
/// the same directory (`opts.out_dir` and `opts.force` are ignored).
/// A run that has already ended and whose checkpoint is its last state is not run again: its
/// summary is returned and nothing is written. (From an earlier checkpoint, the run is run again
/// from there, to the same bits.)
pub fn resume(dir: &Path, opts: &RunOptions) -> Result<RunSummary, RunError> {
    crate::options::available_threads(opts.threads)?;
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
    // the folder's own run, as its summary names it (R3-18: with scene.toml deleted, a 2D
    // checkpoint copied into a 3D run's folder continued there, beside the 3D run's maps)
    if let Some(theirs) = summary_scene_hash(dir) {
        let ours = format!("{:016x}", mpm_scene::fnv1a(c.scene_text.as_bytes()));
        if theirs != ours {
            return Err(RunError::Output(OutputError::Checkpoint {
                path,
                reason: format!(
                    "its scene ({}, hash {ours}) is not the run this folder's summary.json \
                     describes (scene hash {theirs}): a checkpoint copied from another run. \
                     Resume the folder the checkpoint came from, or run the scene again",
                    c.origin
                ),
            }));
        }
    }
    // the folder's own scene: a checkpoint copied in from another run would continue that run
    // here and leave a folder of two runs' files
    let written = dir.join("scene.toml");
    // (line endings and trailing blanks an editor or git may change do not count)
    let same = |a: &str, b: &str| a.lines().map(str::trim_end).eq(b.lines().map(str::trim_end));
    match std::fs::metadata(&written).map(|m| m.file_type().is_file()) {
        Ok(true) => {
            let text = std::fs::read_to_string(&written)
                .map_err(|source| OutputError::Io { path: written.clone(), source })?;
            if !same(&text, &c.scene_text) {
                return Err(RunError::Output(OutputError::Checkpoint {
                    path,
                    reason: format!(
                        "its scene ({}) is not this folder's {}: a checkpoint copied from \
                         another run, or an edited scene.toml. Resume the folder the checkpoint \
                         came from, run the scene again, or, if only scene.toml was edited, \
                         delete it (resume writes it again from the checkpoint)",
                        c.origin,
                        written.display()
                    ),
                }));
            }
        }
        Ok(false) => {
            return Err(RunError::Output(OutputError::Checkpoint {
                path,
                reason: format!("{} is not a regular file", written.display()),
            }));
        }
        // a deleted scene.toml is written again from the checkpoint
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            atomic::write(&written, c.scene_text.as_bytes())?;
        }
        Err(source) => return Err(RunError::Output(OutputError::Io { path: written, source })),
    }
    if let Some(done) = finished(dir, &c) {
        opts.progress.note(&format!(
            "{}: the run has already ended ({:?} at t = {} s after {} steps); nothing to resume, \
             its files are left as they are (run the scene again with --force, or force=True in Python, to redo it)",
            dir.display(),
            done.status,
            done.simulated_time,
            done.steps
        ));
        return Ok(done);
    }
    mpm_output::dir::layout(dir)?;
    if mpm_scene::declared_dimension(&c.scene_text) == 3 {
        return crate::space::resume_space(dir, c, opts);
    }
    if c.state.dimension() != 2 {
        return Err(RunError::Output(OutputError::Checkpoint {
            path,
            reason: "its scene is a 2D scene but its state is a 3D run's".into(),
        }));
    }
    // files the scene names (DEMs, CSV polylines) are relative to the scene file's directory
    let scene = match files_dir(&c) {
        Some(d) => mpm_scene::load_scene_str_in(&c.scene_text, &c.origin, &d)?,
        None => load_scene_str(&c.scene_text, &c.origin)?,
    };
    fits_its_scene(&c, &scene)
        .map_err(|reason| OutputError::Checkpoint { path: path.clone(), reason })?;
    if let Some(reason) = mpm_scene::inputs::changed(&c.inputs, scene.inputs()) {
        return Err(RunError::Output(OutputError::Checkpoint { path, reason }));
    }
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
    fits(c, r.end_time, r.max_steps, r.seeds.len(), r.output.probes.len())
}

/// why checkpoint `c` cannot continue a run of a scene of this end time, step limit, particle
/// count and number of probes, if it cannot (2D and 3D runs alike).
pub(crate) fn fits(
    c: &CheckpointFile,
    end_time: f64,
    max_steps: u64,
    seeds: usize,
    probes: usize,
) -> Result<(), String> {
    let (time, step, particles) = c.state.clock();
    if !(time.is_finite() && (0.0..=end_time).contains(&time)) {
        return Err(format!("time {time:e} s is not between 0 and end_time = {end_time} s"));
    }
    if step > max_steps {
        return Err(format!("step {step} is above max_steps = {max_steps}"));
    }
    if particles != seeds as u64 {
        return Err(format!("{particles} particles, but its scene generates {seeds}"));
    }
    // At most one row and one frame per step, besides those of t = 0.
    let h = &c.history;
    let rows = step.saturating_add(1);
    let probes = rows.saturating_mul(probes as u64);
    for (what, n, most) in [
        ("energy rows", h.energy.len() as u64, rows),
        ("runout rows", h.runout.len() as u64, rows),
        ("frames", h.frames.len() as u64, rows),
        ("probe rows", h.probes.len() as u64, probes),
        ("wall-load rows", h.walls.as_ref().map_or(0, |w| w.rows.len() as u64), rows),
    ] {
        if n > most {
            return Err(format!("{n} {what} after {step} steps (at most {most})"));
        }
    }
    if let Some(why) = h.walls.as_ref().and_then(|w| w.malformed()) {
        return Err(why);
    }
    Ok(())
}

/// runs `f` in a pool of the requested threads (default: one per core), but no more than a
/// scene of `particles` particles can use (`mpm_solver::useful_threads`): a small scene on two
/// threads would only pay for the hand-offs. The results are the same for any count.
pub(crate) fn with_pool<T>(
    opts: &RunOptions,
    particles: usize,
    f: impl FnOnce(usize) -> Result<T, RunError> + Send,
) -> Result<T, RunError>
where
    T: Send,
{
    // rayon's global pool size follows RAYON_NUM_THREADS, else one thread per core.
    let available = crate::options::available_threads(opts.threads)?;
    let b = rayon::ThreadPoolBuilder::new()
        .num_threads(mpm_solver::useful_threads(particles, available));
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
                    .map_err(|e| setup_error(scene.origin(), &e.to_string()))?;
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
                    .map_err(|e| setup_error(scene.origin(), &e.to_string()))?;
                (s, history, false)
            }
        };
        let (initial, initial_error) = if fresh {
            // a signal stops the initial state too (within a Newton iteration or a ramp step)
            solver.set_interrupt(self.opts.interrupt.clone());
            let found = initial_state(&mut solver, &r.initial_state, &self.opts.progress);
            solver.set_interrupt(None);
            match found {
                Ok(summary) => (summary, None),
                Err(e) => (None, Some(e)),
            }
        } else {
            (None, None)
        };
        let mut driver = Driver::begin(scene, self.out_dir.as_deref(), history, initial, self.opts);
        driver.progress.start(r.end_time, solver.time(), solver.step_count());
        if fresh {
            driver.record_start(&solver)?;
        } else {
            driver.rewrite_outputs()?;
        }
        let start = Instant::now();
        // An error of the initial state's explicit ramp names a step of the ramp, not of the run.
        let during_ramp =
            initial_error.is_some() && matches!(r.initial_state, InitialState::GravityRamp { .. });
        let describe = |e: &SolverError| {
            let hint = if matches!(e, SolverError::OutsideGrid { .. }) { OUTSIDE_HINT } else { "" };
            if during_ramp {
                format!("initial state (gravity ramp, before the run): {e}{hint}")
            } else {
                format!("{e}{hint}")
            }
        };
        let result = match initial_error {
            Some(e) => Err(e),
            None => solver.run_until(r.end_time, &mut driver),
        };
        let elapsed = start.elapsed().as_secs_f64();
        driver.progress.finish();
        driver.history.wall_time += elapsed;
        driver.history.particle_steps += std::mem::take(&mut driver.session_particle_steps);
        if let Some(e) = driver.io_error.take() {
            return Err(e);
        }
        let (status, error) = driver.status(&result, &solver, &describe);
        let summary = driver.finish(&solver, status, error, self.threads)?;
        match result {
            Err(e) => Err(RunError::Solver { message: describe(&e), summary: Box::new(summary) }),
            Ok(_) => Ok(summary),
        }
    }
}
