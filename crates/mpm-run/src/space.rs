//! The entry points of 3D scenes (`[grid] dimension = 3`): check, run and resume with the 3D
//! build of the solver (`mpm-solver3d`), recorded by the run driver ([`crate::driver`]) with its
//! 3D wing (runout in the vertical plane of the runout direction, hazard maps). Checkpoints are
//! the 2D runs' files, whose state is a 3D variant of [`SavedState`]; `mpm resume` continues
//! them bit-identically ([`crate::resume()`] routes a 3D scene here).

use std::path::{Path, PathBuf};

use mpm_grid3d::ShapeFunctions;
use mpm_output::OutputError;
use mpm_output::checkpoint::{self, CheckpointFile, History};
use mpm_scene::dispatch::SceneModel;
use mpm_scene::space::{SpaceJob, space_particles};
use mpm_scene::summary::RunSummary;
use mpm_scene::{SavedState, SpaceScene, dispatch_space};
use mpm_solver3d::Solver;

use crate::common::{CheckReport, new_run, setup_error, with_pool};
use crate::driver::space::Space;
use crate::driver::{Driver, describe};
use crate::error::RunError;
use crate::options::RunOptions;

/// Validates a 3D scene fully without stepping: every particle located, and particles, active
/// nodes, steps, memory and frames estimated (as [`crate::check_scene`]).
pub fn check_space_scene(scene: &SpaceScene) -> Result<CheckReport, RunError> {
    struct CheckJob;
    impl SpaceJob for CheckJob {
        type Output = Result<CheckReport, RunError>;
        fn run<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
            self,
            scene: &SpaceScene,
            shape: S,
            _materials: Vec<M>,
        ) -> Self::Output {
            let mut active = std::collections::HashSet::new();
            for (i, seed) in scene.seeds.iter().enumerate() {
                let stencil = shape.stencil(seed.position).map_err(|e| {
                    setup_error(scene.origin(), &format!("particle {i} at {}: {e}", seed.position))
                })?;
                active.extend(stencil.nodes);
            }
            let o = &scene.output;
            let frames = if o.vtk { (scene.end_time / o.interval).ceil() as u64 + 1 } else { 0 };
            let n = scene.seeds.len();
            Ok(CheckReport {
                particles: n,
                cells: scene.grid.cells().to_vec(),
                active_nodes: active.len(),
                initial_dt: scene.initial_dt,
                estimated_steps: (scene.end_time / scene.initial_dt).ceil() as u64,
                initial_state_steps: None,
                // (the run's peak: the solver, the seeds, a checkpoint's copies, a frame)
                memory_bytes: scene.peak_bytes(size_of::<M::State>()) as usize,
                frames,
                frame_bytes: frames * o.vtk_format.frame_bytes(n, &o.fields),
            })
        }
    }
    dispatch_space(scene, CheckJob)?
}

/// Runs a 3D scene to its end time (see [`RunOptions`]; `stop_after` and `interrupt` stop it
/// after a step with a checkpoint that `mpm resume` continues). Returns the summary of a completed, stopped or interrupted run; a
/// solver instability returns [`RunError::Solver`] after writing the files reached so far.
pub fn run_space_scene(scene: &SpaceScene, opts: &RunOptions) -> Result<RunSummary, RunError> {
    new_run(opts, scene.text(), &scene.warnings, scene.seeds.len(), |threads| {
        let run = SpaceRun { opts, threads, resume: None, dir: opts.out_dir.clone() };
        dispatch_space(scene, run)?
    })
}

/// Continues the 3D run of checkpoint `c` (read from `dir`, its scene checked against the
/// folder's by [`crate::resume()`]) to its end time, writing into `dir`.
pub(crate) fn resume_space(
    dir: &Path,
    c: CheckpointFile,
    opts: &RunOptions,
) -> Result<RunSummary, RunError> {
    let path = dir.join(checkpoint::FILE_NAME);
    let refuse =
        |reason: String| RunError::Output(OutputError::Checkpoint { path: path.clone(), reason });
    // (a terrain grid's DEM is relative to the scene file's directory, as when it started)
    let scene = match crate::common::files_dir(&c) {
        Some(d) => mpm_scene::load_space_str_in(&c.scene_text, &c.origin, &d)?,
        None => mpm_scene::load_space_str(&c.scene_text, &c.origin)?,
    };
    if let Some(reason) = mpm_scene::inputs::changed(&c.inputs, scene.inputs()) {
        return Err(refuse(reason));
    }
    if c.state.dimension() != 3 {
        return Err(refuse("its scene is a 3D scene but its state is a 2D run's".into()));
    }
    crate::common::fits(
        &c,
        scene.end_time,
        scene.max_steps,
        scene.seeds.len(),
        scene.output.probes.len(),
    )
    .map_err(refuse)?;
    let resume = Some((c.state, c.history));
    with_pool(opts, scene.seeds.len(), |threads| {
        let run = SpaceRun { opts, threads, resume, dir: Some(dir.to_path_buf()) };
        dispatch_space(&scene, run)?
    })
}

struct SpaceRun<'a> {
    opts: &'a RunOptions,
    threads: usize,
    /// the state and output history of the run to continue, if resumed.
    resume: Option<(SavedState, History)>,
    /// where the run writes (`opts.out_dir`, or a resumed run's folder).
    dir: Option<PathBuf>,
}

impl SpaceJob for SpaceRun<'_> {
    type Output = Result<RunSummary, RunError>;

    fn run<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        self,
        scene: &SpaceScene,
        shape: S,
        materials: Vec<M>,
    ) -> Self::Output {
        let (mut solver, history) = match self.resume {
            None => {
                let particles = space_particles(&scene.seeds, &materials);
                let solver = Solver::new(shape, materials, particles, scene.config.clone());
                (solver.map_err(|e| setup_error(scene.origin(), &e.to_string()))?, None)
            }
            Some((state, history)) => {
                let Some(c) = M::unwrap_space(state) else {
                    return Err(setup_error(
                        scene.origin(),
                        "the checkpoint holds the state of other material models than its \
                         scene's: run the scene again",
                    ));
                };
                let solver = Solver::from_checkpoint(shape, materials, scene.config.clone(), c);
                (solver.map_err(|e| setup_error(scene.origin(), &e.to_string()))?, Some(history))
            }
        };
        let fresh = history.is_none();
        let history =
            history.unwrap_or_else(|| History { dt_min: f64::INFINITY, ..History::default() });
        let wing = Space::new(scene, &history, &solver);
        let driver = Driver::begin(wing, self.dir.as_deref(), history, self.opts);
        driver.drive(&mut solver, fresh, None, &describe::<Solver<M, S, N>>, self.threads)
    }
}
