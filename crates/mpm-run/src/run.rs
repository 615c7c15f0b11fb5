//! The run driver: builds the solver for a scene, steps it to the end time with an observer
//! that records time series, writes frames and checkpoints and draws progress, and writes the
//! final files — also when the solver stops with an instability or the user interrupts.
//!
//! Output timing never changes the steps: frames, series rows and checkpoints are taken after
//! the first step that reaches their time, so a resumed run takes exactly the steps of an
//! uninterrupted one (Δt depends only on the particle state, and only the end time shortens a
//! step).

use std::path::PathBuf;

use mpm_grid::ShapeFunctions;
use mpm_scene::dispatch::{self, Job, SavedState, SceneModel};
use mpm_scene::summary::RunSummary;
use mpm_scene::{GridBuilt, InitialState, Scene};
use mpm_solver::{Solver, SolverError};

use mpm_output::OutputError;
use mpm_output::checkpoint::{self, History};

use crate::common::{CheckReport, new_run, setup_error};
use crate::driver::plane::{Plane, initial_state};
use crate::driver::{Driver, describe};
use crate::error::RunError;
pub use crate::options::RunOptions;

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

/// Runs `scene` to its end time (see [`RunOptions`]).
///
/// Returns the summary of a completed or interrupted run; a solver instability returns
/// [`RunError::Solver`] after writing the files reached so far (including a frame of the
/// failing state and the summary with the error).
pub fn run_scene(scene: &Scene, opts: &RunOptions) -> Result<RunSummary, RunError> {
    let r = scene.resolved();
    new_run(opts, scene.text(), &r.warnings, r.seeds.len(), |threads| {
        let out_dir = opts.out_dir.clone();
        dispatch::dispatch(scene, RunJob { opts, resume: None, threads, out_dir })?
    })
}

pub(crate) struct RunJob<'a> {
    pub(crate) opts: &'a RunOptions,
    pub(crate) resume: Option<(SavedState, History)>,
    pub(crate) threads: usize,
    pub(crate) out_dir: Option<PathBuf>,
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
        let driver =
            Driver::begin(Plane::new(scene, initial), self.out_dir.as_deref(), history, self.opts);
        // An error of the initial state's explicit ramp names a step of the ramp, not of the run.
        let during_ramp =
            initial_error.is_some() && matches!(r.initial_state, InitialState::GravityRamp { .. });
        let describe = |e: &SolverError| {
            let said = describe::<Solver<M, S, N>>(e);
            if during_ramp {
                format!("initial state (gravity ramp, before the run): {said}")
            } else {
                said
            }
        };
        driver.drive(&mut solver, fresh, initial_error, &describe, self.threads)
    }
}
