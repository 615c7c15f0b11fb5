//! What the 2D and 3D runs share: the check's report, the thread pool, the set-up refusal, the
//! hint for a particle outside the grid, and whether a checkpoint fits a scene — kept apart
//! from both so that neither depends on the other.

use std::path::Path;

use mpm_output::checkpoint::CheckpointFile;
use mpm_scene::SceneError;
use serde::{Deserialize, Serialize};

use crate::error::RunError;
use crate::options::RunOptions;

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

/// the folder of a checkpoint's scene's named files: the absolute one it recorded (R3-04: a
/// relative path no longer resolved from another working directory) while it exists, else (a
/// project folder moved or mounted elsewhere) the scene file's directory as it was typed; the
/// files' fingerprints still refuse other files.
pub(crate) fn files_dir(c: &CheckpointFile) -> Option<std::path::PathBuf> {
    if let Some(d) = c.scene_dir.as_ref().map(std::path::PathBuf::from).filter(|d| d.is_dir()) {
        return Some(d);
    }
    if c.origin.starts_with("embedded:") {
        return None;
    }
    Some(Path::new(&c.origin).parent().unwrap_or(Path::new("")).to_path_buf())
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

/// a new run of a scene whose text is `text`, with its plausibility `warnings` and `particles`
/// particles, of either dimension: the arguments checked before the folder (a refused one
/// leaves an earlier run's files as they are), the folder prepared and locked until the run
/// returns (a second run into it is refused meanwhile) with `scene.toml` in it, the warnings
/// reported, and `run` called in the run's thread pool with its thread count.
pub(crate) fn new_run<T: Send>(
    opts: &RunOptions,
    text: &str,
    warnings: &[mpm_scene::Warning],
    particles: usize,
    run: impl FnOnce(usize) -> Result<T, RunError> + Send,
) -> Result<T, RunError> {
    crate::options::available_threads(opts.threads)?;
    let _lock = match &opts.out_dir {
        Some(dir) => {
            let lock = mpm_output::dir::prepare_dir(dir, opts.force)?;
            mpm_output::atomic::write(&dir.join("scene.toml"), text.as_bytes())?;
            Some(lock)
        }
        None => None,
    };
    for w in warnings {
        opts.progress.warn(&w.to_string());
    }
    with_pool(opts, particles, run)
}
