//! The run driver of 3D scenes (`[grid] dimension = 3`): the 3D build of the solver
//! (`mpm-solver3d`) stepped to the end time by an observer that records the energy ledger and
//! the runout measures, writes frames and watches for alarms, rest, limits and interrupts, then
//! `summary.json` in the 2D runs' format.
//!
//! The runout measures are the 2D ones taken in the vertical plane of the runout direction
//! (`SpaceScene::runout_direction`): a particle at x counts at station x·d and height y, so
//! the front, tail, thickness (over the whole width) and travel angle follow that direction;
//! the centre of mass's travel is its 3D distance. Checkpoints (every
//! `output.checkpoint_interval` and on an interrupt) are the 2D runs' files, whose state is a 3D
//! variant of [`SavedState`]; `mpm resume` continues them bit-identically ([`crate::resume()`]
//! routes a 3D scene here). Probes write `probes.csv` with three components; not yet in 3D:
//! envelopes along a section and the analytic reference curves. The plots
//! are the energy, the runout and the deposit in plan; `hazard_maps` adds the maps of `maps/`.
//! The 3D worker of [`crate::Simulation`] (`simulation/space.rs`) records through this driver.

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use glam::DVec2;
use mpm_grid3d::ShapeFunctions;
use mpm_output::checkpoint::{self, CheckpointFile, History, state_hash};
use mpm_output::csv::{self, EnergyRow, ProbeRow};
use mpm_output::dir::prepare_dir;
use mpm_output::loads::{self, LoadSample, WallSeries};
use mpm_output::{OutputError, atomic, maps, report, vtk};
use mpm_scene::dispatch::SceneModel;
use mpm_scene::edges::{EdgeContact, EdgeWatch, Grain};
use mpm_scene::plan::PlanEnvelope;
use mpm_scene::space::{SpaceJob, space_particles};
use mpm_scene::summary::{
    self, DtStats, EnergyReport, OutflowReport, RunStatus, RunSummary, RunoutMetrics, RunoutReport,
};
use mpm_scene::{SavedState, SpaceGrid, SpaceScene, dispatch_space, fnv1a};
use mpm_solver3d::{EnergyCheck, Observer, RunEnd, Solver, StepReport, Vector};

use crate::common::{CheckReport, setup_error, with_pool};
use crate::driver::{next_mark, on_mark, slot};
use crate::error::RunError;
use crate::options::RunOptions;
use crate::progress::ProgressSink;

mod record;

/// The main mass of a 3D run in plan: the particles (indices into `positions`) of the heaviest
/// set of plan cells of side `column` (in x and z) joined by an edge or a corner; the first such
/// set in cell order on a tie. Empty without a finite position.
fn main_mass_in_plan(positions: &[Vector], mass: &[f64], column: f64) -> Vec<usize> {
    use std::collections::{HashMap, HashSet};
    let key = |p: &Vector| ((p.x / column).floor() as i64, (p.z / column).floor() as i64);
    let mut cells: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (q, p) in positions.iter().enumerate().filter(|(_, p)| p.is_finite()) {
        cells.entry(key(p)).or_default().push(q);
    }
    let mut order: Vec<(i64, i64)> = cells.keys().copied().collect();
    order.sort_unstable();
    let mut seen = HashSet::new();
    let mut best: (f64, Vec<usize>) = (f64::NEG_INFINITY, Vec::new());
    for start in order {
        if !seen.insert(start) {
            continue;
        }
        let (mut stack, mut members, mut total) = (vec![start], Vec::new(), 0.0);
        while let Some((i, k)) = stack.pop() {
            for &q in &cells[&(i, k)] {
                members.push(q);
                total += mass[q];
            }
            for di in -1..=1 {
                for dk in -1..=1 {
                    let next = (i + di, k + dk);
                    if cells.contains_key(&next) && seen.insert(next) {
                        stack.push(next);
                    }
                }
            }
        }
        if total > best.0 {
            best = (total, members);
        }
    }
    best.1.sort_unstable();
    best.1
}

/// the solver's boundary loads as the output's samples.
fn load_samples(loads: &[mpm_solver3d::BoundaryLoad]) -> Vec<LoadSample> {
    loads
        .iter()
        .map(|l| LoadSample {
            impulse: l.impulse.to_array(),
            normal: l.normal,
            tangential: l.tangential.to_array(),
        })
        .collect()
}

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
    // the arguments before the folder: a refused one leaves an earlier run's files as they are
    crate::options::available_threads(opts.threads)?;
    let _lock = match &opts.out_dir {
        Some(dir) => {
            let lock = prepare_dir(dir, opts.force)?;
            atomic::write(&dir.join("scene.toml"), scene.text().as_bytes())?;
            Some(lock)
        }
        None => None,
    };
    for w in &scene.warnings {
        opts.progress.warn(&w.to_string());
    }
    with_pool(opts, scene.seeds.len(), |threads| {
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
        let resumed = history.is_some();
        let mut d = SpaceDriver::begin(scene, self.dir.as_deref(), self.opts, &solver, history);
        d.progress.start(scene.end_time, solver.time(), solver.step_count());
        if resumed {
            // the rows and frames a stopped session wrote past its checkpoint give way to the
            // checkpoint's
            d.rewrite_outputs()?;
        } else {
            d.record(&solver);
            d.write_frame(&solver)?;
            d.flush()?;
        }
        let start = Instant::now();
        let result = solver.run_until(scene.end_time, &mut d);
        d.wall_time = start.elapsed().as_secs_f64();
        d.progress.finish();
        if let Some(e) = d.io_error.take() {
            return Err(e);
        }
        let (status, error) = match (&result, d.stop) {
            (Err(e), _) => (RunStatus::Failed, Some(describe(e))),
            (Ok(RunEnd::EndTime), _) => (RunStatus::Completed, None),
            (Ok(RunEnd::Stopped), Some(Stop::StepLimit)) => (
                RunStatus::StepLimit,
                Some(format!(
                    "step limit: {} steps reached at t = {:.6e} s before end_time = {} s",
                    solver.step_count(),
                    solver.time(),
                    scene.end_time
                )),
            ),
            (Ok(RunEnd::Stopped), Some(Stop::AtRest)) => (RunStatus::AtRest, None),
            (Ok(RunEnd::Stopped), Some(Stop::EnergyAlarm)) => {
                (RunStatus::EnergyAlarm, d.alarm_message())
            }
            // (as in 2D: the front end says where to resume)
            (Ok(RunEnd::Stopped), None) => (RunStatus::Interrupted, None),
        };
        let summary = d.finish(&solver, status, error, self.threads)?;
        match result {
            Err(e) => Err(RunError::Solver { message: describe(&e), summary: Box::new(summary) }),
            Ok(_) => Ok(summary),
        }
    }
}

/// Why the driver stopped a run before its end time (other than an interrupt).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Stop {
    EnergyAlarm,
    StepLimit,
    AtRest,
}

pub(crate) struct SpaceDriver<'a> {
    scene: &'a SpaceScene,
    /// the hazard maps so far (`[output] hazard_maps`), observed every step.
    plan: Option<PlanEnvelope>,
    /// the rows of `walls.csv` so far (a scene with a boundary).
    walls: Option<WallSeries>,
    /// the watch over the grid's undeclared side faces.
    edges: Option<EdgeWatch>,
    /// when this session started, and at which step.
    session: (Instant, u64),
    /// particle-steps of this session: the particles of each step (fewer once some left through
    /// outflow sides).
    session_particle_steps: f64,
    /// wall time (s) and particle-steps of earlier sessions (a resumed run's).
    earlier: (f64, f64),
    checkpoint_slot: u64,
    dir: Option<&'a Path>,
    progress: ProgressSink,
    interrupt: Option<Arc<AtomicBool>>,
    stop_after: Option<f64>,
    io_error: Option<RunError>,
    pub(crate) stop: Option<Stop>,
    /// the floor as a polyline in the runout plane (station along the runout direction, y).
    ground: Vec<DVec2>,
    /// the particle spacing (m).
    spacing: f64,
    /// the centre of mass at t = 0 (m).
    com0: mpm_solver3d::Vector,
    /// the highest particle at t = 0 (m).
    crown: mpm_solver3d::Vector,
    energy: Vec<EnergyRow>,
    runout: Vec<RunoutMetrics>,
    /// the rows of `probes.csv` (a scene with `output.probes`).
    probes: Vec<ProbeRow>,
    frames: Vec<(f64, String)>,
    flushed: [usize; 4],
    check: EnergyCheck,
    alarm_time: Option<f64>,
    rest_peak: f64,
    rest_since: Option<f64>,
    series_slot: u64,
    frame_slot: u64,
    dt: DtStats,
    output_time: f64,
    wall_time: f64,
}

impl<M: SceneModel, S: ShapeFunctions<N>, const N: usize> Observer<M, S, N> for SpaceDriver<'_> {
    fn after_step(&mut self, solver: &Solver<M, S, N>, report: &StepReport) -> ControlFlow<()> {
        let scene = self.scene;
        let landed = on_mark(report.time, scene.output.exact_times, &self.marks());
        // (a step shortened to land on the end time or an output mark is not the smallest)
        if (!landed && !mpm_solver3d::reached(report.time, scene.end_time)) || self.dt.max == 0.0 {
            self.dt.min = self.dt.min.min(report.dt);
        }
        self.dt.max = self.dt.max.max(report.dt);
        if self.dt.first == 0.0 {
            self.dt.first = report.dt;
        }
        self.session_particle_steps += solver.particles().len() as f64;
        let t = report.time;
        if let Some(e) = &mut self.plan {
            observe(e, scene, self.spacing, solver);
        }
        let series = slot(t, scene.output.series_interval);
        if series > self.series_slot {
            self.series_slot = series;
            self.record(solver);
        }
        let frame = slot(t, scene.output.interval);
        if frame > self.frame_slot {
            self.frame_slot = frame;
            if let Err(e) = self.write_frame(solver).and_then(|()| self.flush()) {
                self.io_error = Some(e);
                return ControlFlow::Break(());
            }
        }
        self.progress.update(t, report.step);
        if report.step >= scene.max_steps && !mpm_solver3d::reached(t, scene.end_time) {
            self.stop.get_or_insert(Stop::StepLimit);
        }
        if let Some(every) = scene.output.checkpoint_interval {
            let c = slot(t, every);
            if c > self.checkpoint_slot {
                self.checkpoint_slot = c;
                if let Err(e) = self.write_checkpoint(solver) {
                    self.io_error = Some(e);
                    return ControlFlow::Break(());
                }
            }
        }
        let interrupted = self.interrupt.as_ref().is_some_and(|f| f.load(Ordering::Relaxed));
        if interrupted {
            self.progress.warn("interrupted: writing a checkpoint after this step");
        }
        if self.stop.is_some() || interrupted || self.stop_after.is_some_and(|s| t >= s) {
            return ControlFlow::Break(());
        }
        ControlFlow::Continue(())
    }

    fn landing(&self, time: f64) -> f64 {
        next_mark(time, self.scene.output.exact_times, &self.marks())
    }
}

/// a 3D solver error as the run reports it: a particle out of the grid with what to do.
pub(crate) fn describe(e: &mpm_solver3d::SolverError) -> String {
    match e {
        mpm_solver3d::SolverError::OutsideGrid { .. } => {
            format!("{e}{}", crate::common::OUTSIDE_HINT)
        }
        _ => e.to_string(),
    }
}

/// the watch over the grid's side faces that the scene left undeclared (no wall law, not
/// outflow, not periodic); `None` when every side is declared.
fn edge_watch(scene: &SpaceScene) -> Option<EdgeWatch> {
    let (c, g) = (&scene.config, &scene.grid);
    let ([x0, z0], [x1, z1]) = (g.plan_origin(), g.plan_end());
    let (b, o) = (&c.boundaries, &c.outflow);
    let x_open = c.periodic.is_none();
    let faces = [
        ("left_wall", x_open && b.left_wall.is_none() && o.x_min.is_none(), 0, x0, -1.0),
        ("right_wall", x_open && b.right_wall.is_none() && o.x_max.is_none(), 0, x1, 1.0),
        ("back_wall", b.back_wall.is_none() && o.z_min.is_none(), 2, z0, -1.0),
        ("front_wall", b.front_wall.is_none() && o.z_max.is_none(), 2, z1, 1.0),
    ];
    let open = faces.into_iter().filter(|f| f.1).map(|(n, _, axis, at, out)| (n, axis, at, out));
    EdgeWatch::new(open.collect(), g.plan_cell())
}

/// the indices of the particles of flowing materials (not obstacles; as the runout measures).
fn flowing<'p, S>(
    scene: &SpaceScene,
    p: &'p mpm_solver3d::Particles<S>,
) -> impl Iterator<Item = usize> + 'p {
    let mask = scene.materials.flow_mask();
    (0..p.len()).filter(move |&q| {
        mask.as_ref().is_none_or(|m| m.get(usize::from(p.material[q])).copied().unwrap_or(true))
    })
}

/// takes the flowing particles' state now into the hazard maps `e`.
fn observe<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
    e: &mut PlanEnvelope,
    scene: &SpaceScene,
    spacing: f64,
    solver: &Solver<M, S, N>,
) {
    let p = solver.particles();
    if scene.materials.flow_mask().is_none() {
        let ground = |x, z| scene.grid.ground(x, z);
        e.observe(solver.time(), spacing, [&p.position, &p.velocity], [&p.mass, &p.volume], ground);
        return;
    }
    let keep: Vec<usize> = flowing(scene, p).collect();
    let pick = |v: &[mpm_solver3d::Vector]| -> Vec<mpm_solver3d::Vector> {
        keep.iter().map(|&q| v[q]).collect()
    };
    let pick_f = |v: &[f64]| -> Vec<f64> { keep.iter().map(|&q| v[q]).collect() };
    e.observe(
        solver.time(),
        spacing,
        [&pick(&p.position), &pick(&p.velocity)],
        [&pick_f(&p.mass), &pick_f(&p.volume)],
        |x, z| scene.grid.ground(x, z),
    );
}

#[cfg(test)]
mod plan_tests {
    use super::*;

    /// a block of 9 cells, a grain in the cell touching its corner (joined), a grain one empty
    /// cell ahead (not joined), and a lighter block elsewhere: the main mass is the block and
    /// the corner grain.
    #[test]
    fn the_main_mass_in_plan_joins_cells_by_edges_and_corners_only() {
        let at = |x: f64, z: f64| Vector::new(x, 0.0, z);
        let mut positions = Vec::new();
        for i in 0..3 {
            for k in 0..3 {
                positions.push(at(0.5 + f64::from(i), 0.5 + f64::from(k)));
            }
        }
        positions.push(at(3.5, 3.5)); // 9: the corner of cell (2, 2)
        positions.push(at(4.5, 1.5)); // 10: cell (4, 1), one empty column ahead of (2, 1)
        positions.push(at(10.5, 10.5)); // 11, 12: a lighter pair
        positions.push(at(10.5, 11.5));
        let mass = vec![1.0; positions.len()];
        let main = main_mass_in_plan(&positions, &mass, 1.0);
        assert_eq!(main, (0..10).collect::<Vec<_>>());
        assert!(main_mass_in_plan(&[at(f64::NAN, 0.0)], &[1.0], 1.0).is_empty());
    }
}
