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
//! routes a 3D scene here). Not yet in 3D: probes and envelopes. The plots
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
use mpm_output::csv::{self, EnergyRow};
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
    crate::common::fits(&c, scene.end_time, scene.max_steps, scene.seeds.len(), 0)
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
    frames: Vec<(f64, String)>,
    flushed: [usize; 3],
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

impl<'a> SpaceDriver<'a> {
    pub(crate) fn begin<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        scene: &'a SpaceScene,
        dir: Option<&'a Path>,
        opts: &'a RunOptions,
        solver: &Solver<M, S, N>,
        history: Option<History>,
    ) -> Self {
        let g = &scene.grid;
        let d = scene.runout_direction;
        let ([x0, z0], [x1, z1]) = (g.plan_origin(), g.plan_end());
        let corners =
            [x0, x1].into_iter().flat_map(|x| [z0, z1].map(|z| Vector::new(x, 0.0, z).dot(d)));
        let (s0, s1) =
            corners.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), s| (a.min(s), b.max(s)));
        let p = solver.particles();
        let check = EnergyCheck::new(
            &solver.energy(),
            &p.position,
            &p.mass,
            scene.config.gravity.length(),
            |x| g.ground(x.x, x.z).0,
        );
        let mass: f64 = p.mass.iter().sum();
        // (from the generation positions: a resumed run's particles have moved; and kept by
        // the history, as particles may have left since)
        let com0 = match history.as_ref().and_then(|h| h.initial_centre) {
            Some(c) => Vector::from_array(c),
            None => {
                p.initial_position.iter().zip(&p.mass).map(|(x, m)| *x * *m).sum::<Vector>() / mass
            }
        };
        let crown = match history.as_ref().and_then(|h| h.crown) {
            Some(c) => Vector::from_array(c),
            None => p
                .initial_position
                .iter()
                .copied()
                .max_by(|a, b| a.y.total_cmp(&b.y))
                .unwrap_or(Vector::ZERO),
        };
        let spacing = g.plan_cell() / scene.gimp_ppc as f64;
        let plan = scene.output.hazard_maps.then(|| {
            let [nx, _, nz] = g.cells();
            let mut e = PlanEnvelope::new(g.plan_origin(), g.plan_cell(), [nx, nz]);
            observe(&mut e, scene, spacing, solver);
            e
        });
        // the ground in the runout plane: under the line through the initial centre of mass
        // along the runout direction, at the plan cells' spacing (the floor of a regular grid)
        let ground = match g {
            SpaceGrid::Regular(r) => {
                let y0 = r.origin().y;
                vec![DVec2::new(s0, y0), DVec2::new(s1, y0)]
            }
            SpaceGrid::Terrain(_) => {
                let along = com0.dot(d);
                let n = ((s1 - s0) / g.plan_cell()).ceil().max(1.0) as usize;
                (0..=n)
                    .map(|k| {
                        let s = s0 + (s1 - s0) * k as f64 / n as f64;
                        let x = com0 + (s - along) * d;
                        DVec2::new(s, g.ground(x.x, x.z).0)
                    })
                    .collect()
            }
        };
        let mut d = SpaceDriver {
            scene,
            plan,
            session: (Instant::now(), solver.step_count()),
            session_particle_steps: 0.0,
            earlier: (0.0, 0.0),
            checkpoint_slot: 0,
            dir,
            progress: opts.progress.clone(),
            interrupt: opts.interrupt.clone(),
            stop_after: opts.stop_after,
            io_error: None,
            stop: None,
            ground,
            spacing,
            com0,
            crown,
            energy: Vec::new(),
            runout: Vec::new(),
            frames: Vec::new(),
            flushed: [0; 3],
            walls: None,
            edges: edge_watch(scene),
            check,
            alarm_time: None,
            rest_peak: 0.0,
            rest_since: None,
            series_slot: 0,
            frame_slot: 0,
            dt: DtStats { min: f64::INFINITY, ..DtStats::default() },
            output_time: 0.0,
            wall_time: 0.0,
        };
        if let Some(h) = history {
            d.energy = h.energy;
            d.runout = h.runout;
            d.frames = h.frames;
            (d.frame_slot, d.series_slot, d.checkpoint_slot) =
                (h.frame_slot, h.series_slot, h.checkpoint_slot);
            d.dt = DtStats { min: h.dt_min, max: h.dt_max, first: h.dt_first, mean: 0.0 };
            d.output_time = h.output_time;
            d.earlier = (h.wall_time, h.particle_steps);
            if let Some(c) = h.energy_check {
                d.check = EnergyCheck {
                    initial_scale: c.initial_scale,
                    initial_potential: c.initial_potential,
                    released: c.released,
                    worst: c.worst,
                    worst_time: c.worst_time,
                };
            }
            d.alarm_time = h.alarm_time;
            d.walls = h.walls;
            d.edges = h.edges;
            if d.plan.is_some() {
                d.plan = h.plan;
            }
            // the rest watch as the rows left it
            let rows: Vec<(f64, f64)> =
                d.energy.iter().map(|e| (e.time, e.ledger.kinetic)).collect();
            for (t, kinetic) in rows {
                d.watch_rest(t, kinetic);
            }
        }
        d
    }

    /// the output history as a resumed run needs it, at this step.
    pub(crate) fn history(&self) -> History {
        let (start, _) = self.session;
        let c = &self.check;
        History {
            energy: self.energy.clone(),
            probes: Vec::new(),
            runout: self.runout.clone(),
            frames: self.frames.clone(),
            frame_slot: self.frame_slot,
            series_slot: self.series_slot,
            checkpoint_slot: self.checkpoint_slot,
            dt_min: self.dt.min,
            dt_max: self.dt.max,
            dt_first: self.dt.first,
            wall_time: self.earlier.0 + start.elapsed().as_secs_f64(),
            particle_steps: self.earlier.1 + self.session_particle_steps,
            output_time: self.output_time,
            initial: self.runout.first().copied(),
            energy_check: Some(mpm_solver::EnergyCheck {
                initial_scale: c.initial_scale,
                initial_potential: c.initial_potential,
                released: c.released,
                worst: c.worst,
                worst_time: c.worst_time,
            }),
            alarm_time: self.alarm_time,
            envelope: None,
            plan: self.plan.clone(),
            walls: self.walls.clone(),
            edges: self.edges.clone(),
            initial_centre: Some(self.com0.to_array()),
            crown: Some(self.crown.to_array()),
        }
    }

    /// the marks `[output] exact_times` lands on: series rows, frames, checkpoints.
    fn marks(&self) -> [Option<f64>; 3] {
        let o = &self.scene.output;
        [Some(o.series_interval), Some(o.interval), o.checkpoint_interval]
    }

    /// writes `checkpoint.bin` (atomically): the solver state, the scene and the history.
    fn write_checkpoint<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &self,
        solver: &Solver<M, S, N>,
    ) -> Result<(), RunError> {
        let Some(dir) = self.dir else { return Ok(()) };
        let file = CheckpointFile::new(
            self.scene.origin(),
            self.scene.text(),
            self.scene.files_dir(),
            self.scene.inputs(),
            M::wrap_space(solver.checkpoint()),
            self.history(),
        );
        Ok(checkpoint::write(&dir.join(checkpoint::FILE_NAME), &file)?)
    }

    /// rewrites the series and the frame collection from the history (a resumed run's).
    fn rewrite_outputs(&mut self) -> Result<(), RunError> {
        let Some(dir) = self.dir else { return Ok(()) };
        self.flushed = [0; 3];
        self.flush()?;
        if self.scene.output.vtk {
            atomic::write(&dir.join("particles.pvd"), vtk::pvd(&self.frames).as_bytes())?;
        }
        Ok(())
    }

    /// `stop_at_rest`: the kinetic energy `kinetic` at time `t` against the run's peak.
    fn watch_rest(&mut self, t: f64, kinetic: f64) {
        if let Some(rest) = self.scene.stop_at_rest {
            self.rest_peak = self.rest_peak.max(kinetic);
            if self.rest_peak > 0.0 && kinetic <= rest.kinetic_fraction * self.rest_peak {
                let since = *self.rest_since.get_or_insert(t);
                if t - since >= rest.duration {
                    self.stop.get_or_insert(Stop::AtRest);
                }
            } else {
                self.rest_since = None;
            }
        }
    }

    /// the runout measures now, in the vertical plane of the runout direction.
    fn metrics<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &self,
        solver: &Solver<M, S, N>,
    ) -> RunoutMetrics {
        let p = solver.particles();
        let d = self.scene.runout_direction;
        let keep: Vec<usize> = flowing(self.scene, p).collect();
        // every flowing particle has left through outflow sides: the measures stay where they
        // were last taken
        if keep.is_empty()
            && let Some(last) = self.runout.last()
        {
            return RunoutMetrics { time: solver.time(), front_speed: 0.0, ..*last };
        }
        let plane = |v: &[mpm_solver3d::Vector]| -> Vec<DVec2> {
            keep.iter().map(|&q| DVec2::new(v[q].dot(d), v[q].y)).collect()
        };
        // (with periodic sides, the positions the particles have had they never wrapped: the
        // runout of an endless slope; R3-15)
        let unwrapped: Vec<mpm_solver3d::Vector>;
        let at: &[mpm_solver3d::Vector] = if p.unwrap.is_empty() {
            &p.position
        } else {
            unwrapped = (0..p.len()).map(|q| p.unwrapped_position(q)).collect();
            &unwrapped
        };
        let (position, velocity) = (plane(at), plane(&p.velocity));
        let mass: Vec<f64> = keep.iter().map(|&q| p.mass[q]).collect();
        let mut m = summary::runout(
            solver.time(),
            [&position, &velocity],
            &mass,
            &self.ground,
            self.spacing,
            self.scene.grid.plan_cell(),
            self.runout.first(),
        );
        let total: f64 = mass.iter().sum();
        let com = keep.iter().map(|&q| at[q] * p.mass[q]).sum::<mpm_solver3d::Vector>() / total;
        m.com_travel = (com - self.com0).length();
        // The main mass in plan: the section rule above splits the particles sorted along d at
        // gaps wider than a column, but in 3D the grains beside those thrown ahead close such
        // gaps (the flume extruded: 4.19 m against 3.42 m in 2D). Its front, tail and front
        // speed are taken from the heaviest set of plan cells joined by an edge or a corner.
        let column = self.scene.grid.plan_cell();
        let plan: Vec<mpm_solver3d::Vector> = keep.iter().map(|&q| at[q]).collect();
        let main = main_mass_in_plan(&plan, &mass, column);
        if !main.is_empty() {
            let half = 0.5 * self.spacing;
            let (lo, hi) = main.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &q| {
                (a.min(position[q].x), b.max(position[q].x))
            });
            m.front_x = hi + half;
            m.tail_x = lo - half;
            m.front_travel = m.front_x - self.runout.first().map_or(m.front_x, |i| i.front_x);
            let (mut ms, mut momentum) = (0.0, DVec2::ZERO);
            for &q in main.iter().filter(|&&q| position[q].x >= hi - column) {
                ms += mass[q];
                momentum += mass[q] * velocity[q];
            }
            m.front_speed = if ms > 0.0 { momentum.length() / ms } else { 0.0 };
        }
        m
    }

    pub(crate) fn record<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &mut self,
        solver: &Solver<M, S, N>,
    ) {
        let t = solver.time();
        let l = solver.energy();
        let relative = self.check.observe(t, &l);
        let alarm = self.scene.alarm;
        if self.alarm_time.is_none() && relative.abs() > alarm.threshold {
            self.alarm_time = Some(t);
            self.progress.warn(&format!(
                "energy alarm at t = {t:.4} s: |energy residual| is {:.1} % of the energy scale \
                 (threshold {:.1} %)",
                100.0 * relative.abs(),
                100.0 * alarm.threshold
            ));
            if alarm.stop {
                self.stop = Some(Stop::EnergyAlarm);
            }
        }
        self.watch_rest(t, l.kinetic);
        self.energy.push(EnergyRow {
            time: t,
            step: solver.step_count(),
            dt: solver.last_report().dt,
            ledger: l,
        });
        let m = self.metrics(solver);
        self.runout.push(m);
        if let Some(w) = &mut self.edges {
            let (scene, p) = (self.scene, solver.particles());
            let grains: Vec<Grain> = flowing(scene, p)
                .map(|q| {
                    let x = p.position[q];
                    let ground = scene.grid.ground(x.x, x.z).0;
                    Grain { position: x.to_array(), ground, mass: p.mass[q] }
                })
                .collect();
            w.observe(t, &grains, 0.5 * self.spacing);
        }
        if self.walls.is_none() {
            let (b, walls) = (&self.scene.config.boundaries, self.scene.config.walls.len());
            let sides = [b.ground, b.left_wall, b.right_wall, b.back_wall, b.front_wall];
            let sides = sides.map(|s| s.is_some());
            let boundaries =
                crate::loads::boundaries(&mpm_solver3d::SIDE_NAMES, &sides, walls, false);
            if !boundaries.is_empty() {
                self.walls = Some(WallSeries::new(boundaries, 3));
            }
        }
        if let Some(w) = &mut self.walls {
            w.push(t, &load_samples(solver.boundary_loads()));
        }
    }

    fn write_frame<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &mut self,
        solver: &Solver<M, S, N>,
    ) -> Result<(), RunError> {
        let o = &self.scene.output;
        let Some(dir) = self.dir.filter(|_| o.vtk) else { return Ok(()) };
        let clock = Instant::now();
        let name = format!("frames/particles_{:06}.vtp", self.frames.len());
        let path = dir.join(&name);
        if self.frames.is_empty() {
            std::fs::create_dir_all(dir.join("frames"))
                .map_err(|source| OutputError::Io { path: dir.join("frames"), source })?;
        }
        let frame = vtk::frame_3d(
            solver.particles(),
            solver.materials(),
            &o.fields,
            o.vtk_format,
            solver.time(),
        )
        .map_err(|source| RunError::from(OutputError::Io { path: path.clone(), source }))?;
        atomic::write_parts(&path, &frame.parts())?;
        self.frames.push((solver.time(), name));
        atomic::write(&dir.join("particles.pvd"), vtk::pvd(&self.frames).as_bytes())?;
        self.output_time += clock.elapsed().as_secs_f64();
        Ok(())
    }

    fn flush(&mut self) -> Result<(), RunError> {
        let Some(dir) = self.dir else { return Ok(()) };
        let clock = Instant::now();
        let [e, r, w] = &mut self.flushed;
        csv::flush(&dir.join("energy.csv"), csv::ENERGY_HEADER, &self.energy, e, csv::energy)?;
        csv::flush(&dir.join("runout.csv"), csv::RUNOUT_HEADER, &self.runout, r, csv::runout)?;
        if let Some(s) = &self.walls {
            csv::flush(&dir.join("walls.csv"), &s.header(), &s.rows, w, loads::lines)?;
        }
        self.output_time += clock.elapsed().as_secs_f64();
        Ok(())
    }

    fn alarm_message(&self) -> Option<String> {
        let t = self.alarm_time?;
        Some(format!(
            "energy alarm: at t = {t:.4} s the energy residual exceeded {:.1} % of the run's \
             energy scale (`[solver] energy_alarm`); the worst was {:+.1} % at t = {:.4} s",
            100.0 * self.scene.alarm.threshold,
            100.0 * self.check.worst,
            self.check.worst_time
        ))
    }

    pub(crate) fn finish<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &mut self,
        solver: &Solver<M, S, N>,
        status: RunStatus,
        error: Option<String>,
        threads: usize,
    ) -> Result<RunSummary, RunError> {
        let t = solver.time();
        // the checkpoint of an interrupted run holds the history as an uninterrupted run has it
        // at this step (before the closing row and frame below)
        if status == RunStatus::Interrupted {
            self.write_checkpoint(solver)?;
        }
        if self.energy.last().is_none_or(|row| row.time < t) {
            self.record(solver);
        }
        if self.frames.last().is_none_or(|f| f.0 < t) {
            self.write_frame(solver)?;
        }
        let (status, error) = match status {
            RunStatus::Completed | RunStatus::AtRest if self.alarm_time.is_some() => {
                (RunStatus::EnergyAlarm, self.alarm_message())
            }
            _ => (status, error),
        };
        self.flush()?;
        let scene = self.scene;
        let steps = solver.step_count();
        let n = solver.particles().len();
        let p = solver.particles();
        let d = scene.runout_direction;
        let crown =
            DVec2::new(self.crown.dot(d), self.crown.y) + DVec2::new(0.0, 0.5 * self.spacing);
        let kinetic: Vec<(f64, f64)> =
            self.energy.iter().map(|e| (e.time, e.ledger.kinetic)).collect();
        let mut check = self.check;
        let wall = self.earlier.0 + self.wall_time;
        let particle_steps = self.earlier.1 + self.session_particle_steps;
        let gone = solver.outflowed();
        let edges = self.edges.as_ref().map_or_else(Vec::new, |w| {
            w.reached(flowing(scene, p).map(|q| p.mass[q]).sum::<f64>() + gone.mass)
        });
        let mut warnings: Vec<String> = scene.warnings.iter().map(ToString::to_string).collect();
        warnings.extend(edges.iter().map(EdgeContact::warning));
        let o = scene.config.outflow;
        let outflow = OutflowReport::new(
            &[
                ("left_wall", o.x_min),
                ("right_wall", o.x_max),
                ("back_wall", o.z_min),
                ("front_wall", o.z_max),
            ],
            (gone.particles, gone.mass, gone.momentum.to_array().to_vec(), gone.energy),
            gone.first_time,
            p.mass.iter().sum::<f64>(),
        );
        let mut summary = RunSummary {
            code_version: env!("CARGO_PKG_VERSION").to_string(),
            scene_origin: scene.origin().to_string(),
            scene_hash: format!("{:016x}", fnv1a(scene.text().as_bytes())),
            status,
            error,
            particles: n,
            scheme: scene.config.scheme.name().to_string(),
            shape_function: scene.shape_function.name().to_string(),
            steps,
            simulated_time: t,
            end_time: scene.end_time,
            dt: DtStats {
                min: if self.dt.min.is_finite() { self.dt.min } else { 0.0 },
                mean: if steps > 0 { t / steps as f64 } else { 0.0 },
                ..self.dt
            },
            wall_time_s: wall,
            particle_steps_per_s: if wall > 0.0 { particle_steps / wall } else { 0.0 },
            output_time_s: self.output_time,
            threads,
            energy: solver.energy(),
            energy_check: EnergyReport {
                relative_residual: check.observe(t, &solver.energy()),
                worst_relative_residual: check.worst,
                worst_time: check.worst_time,
                alarm_threshold: scene.alarm.threshold,
                alarm_time: self.alarm_time,
            },
            runout: RunoutReport {
                last: self.runout.last().copied().unwrap_or_default(),
                indicators: summary::indicators(&self.runout, &kinetic, crown, &self.ground),
            },
            observed: None,
            state_hash: state_hash(&solver.checkpoint()),
            initial_state: None,
            warnings,
            dimension: 3,
            hazard_maps: None,
            walls: self
                .walls
                .as_ref()
                .map(|w| w.summary(&load_samples(solver.boundary_loads())))
                .unwrap_or_default(),
            outflow,
            edges,
        };
        let deposit = self.plan.as_ref().map(|e| {
            let flow: Vec<mpm_solver3d::Vector> =
                flowing(scene, p).map(|q| p.position[q]).collect();
            let normal = e.deposit(self.spacing, &flow, |x, z| scene.grid.ground(x, z));
            let vertical = e.deposit(self.spacing, &flow, |x, z| (scene.grid.ground(x, z).0, 1.0));
            (normal, vertical)
        });
        if let (Some(e), Some((depth, vertical))) = (&self.plan, &deposit) {
            summary.hazard_maps = Some(e.indicators(depth, vertical));
        }
        if let Some((file, raster)) = &scene.output.observed {
            // the deposit's vertical depth per plan cell, as an observed DEM difference gives it
            let g = &scene.grid;
            let [nx, _, nz] = g.cells();
            let e = PlanEnvelope::new(g.plan_origin(), g.plan_cell(), [nx, nz]);
            let flow: Vec<Vector> = flowing(scene, p).map(|q| p.position[q]).collect();
            let depth = e.deposit(self.spacing, &flow, |x, z| (g.ground(x, z).0, 1.0));
            summary.observed = e.compare(file, raster, &depth, scene.runout_direction);
        }
        if let Some(dir) = self.dir {
            let json = serde_json::to_string_pretty(&summary)
                .map_err(|e| RunError::Setup(format!("cannot encode summary.json: {e}")))?;
            atomic::write(&dir.join("summary.json"), json.as_bytes())?;
            if let (Some(e), Some((depth, _))) = (&self.plan, &deposit) {
                maps::write(dir, e, depth, &scene.output.crs)?;
                let centre = |k: usize| e.cell * (k as f64 + 0.5);
                let ground: Vec<f64> = (0..e.rows * e.cols)
                    .map(|k| {
                        let (c, r) = (k % e.cols, k / e.cols);
                        scene.grid.ground(e.x0 + centre(c), e.z0 + centre(r)).0
                    })
                    .collect();
                let mut release = vec![false; e.rows * e.cols];
                for q in flowing(scene, p) {
                    let x = p.initial_position[q];
                    let (c, r) = ((x.x - e.x0) / e.cell, (x.z - e.z0) / e.cell);
                    if c >= 0.0 && r >= 0.0 && (c as usize) < e.cols && (r as usize) < e.rows {
                        release[r as usize * e.cols + c as usize] = true;
                    }
                }
                let title = format!(
                    "{}: largest flow height, t = {t:.1} s",
                    scene.title().unwrap_or("hazard map")
                );
                let edges: Vec<String> = summary.edges.iter().map(|c| c.face.clone()).collect();
                let context = maps::Context {
                    title: &title,
                    ground: &ground,
                    release: &release,
                    edges: &edges,
                };
                maps::figures(dir, e, depth, &context)?;
            }
            if scene.output.plots {
                // the flowing particles, north (−z) up as in maps/
                let plan = |v: &[mpm_solver3d::Vector]| {
                    flowing(scene, p).map(|q| (v[q].x, -v[q].z)).collect()
                };
                let deposit = report::PlanDeposit {
                    positions: plan(&p.position),
                    initial: plan(&p.initial_position),
                    time: t,
                };
                report::space_plots(&dir.join("plots"), &self.energy, &self.runout, &deposit)?;
            }
        }
        Ok(summary)
    }
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
