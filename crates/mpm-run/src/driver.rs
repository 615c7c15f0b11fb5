//! The run's observer: after each step it records the time series, frames, envelopes and
//! checkpoints a scene asks for, watches for rest, alarms, limits and interrupts, and at the end
//! writes the final files and the summary.

use std::borrow::Cow;
use std::ops::ControlFlow;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use mpm_grid::ShapeFunctions;
use mpm_scene::dispatch::SceneModel;
use mpm_scene::edges::{EdgeContact, EdgeWatch, Grain};
use mpm_scene::envelope::{self, Envelope};
use mpm_scene::observed;
use mpm_scene::summary::{
    self, DtStats, EnergyReport, OutflowReport, RunStatus, RunSummary, RunoutMetrics, RunoutReport,
};
use mpm_scene::{InitialState, InitialStateSummary, Resolved, Scene, ground_height};
use mpm_solver::{
    EnergyCheck, Observer, Particles, RunEnd, Solver, SolverError, StepReport, Vector,
};

use mpm_output::checkpoint::{self, CheckpointFile, History};
use mpm_output::csv::{self, EnergyRow, ProbeRow};
use mpm_output::loads::{self, LoadSample, WallSeries};
use mpm_output::report::{self, Deposit};
use mpm_output::{OutputError, atomic, vtk};

use crate::error::RunError;
use crate::options::RunOptions;
use crate::progress::ProgressSink;

mod ends;

/// the solver's boundary loads as the output's samples.
fn load_samples(loads: &[mpm_solver::BoundaryLoad]) -> Vec<LoadSample> {
    let v = |v: Vector| [v.x, v.y, 0.0];
    loads
        .iter()
        .map(|l| LoadSample {
            impulse: v(l.impulse),
            normal: l.normal,
            tangential: v(l.tangential),
        })
        .collect()
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

pub(crate) struct Driver<'a> {
    /// what the initial-state stage did (a new run with `[initial_state]`).
    pub(crate) initial: Option<InitialStateSummary>,
    pub(crate) scene: &'a Scene,
    pub(crate) dir: Option<&'a Path>,
    pub(crate) history: History,
    flushed: Flushed,
    pub(crate) progress: ProgressSink,
    pub(crate) interrupt: Option<Arc<AtomicBool>>,
    pub(crate) stop_after: Option<f64>,
    pub(crate) io_error: Option<RunError>,
    /// why the driver stopped the run, when not on request.
    stop: Option<Stop>,
    /// the kinetic energy's course for `stop_at_rest`, kept as the rows come.
    rest: RestWatch,
    /// particle-steps of this session not yet in the history: the particles of each step
    /// (fewer once some left through outflow sides).
    pub(crate) session_particle_steps: f64,
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
pub(crate) fn initial_state<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
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

/// The particles the runout measures, envelopes and deposit see: all of them, or in a scene of
/// flowing and structural materials (sand beside elastic bedrock or an obstacle,
/// `MaterialsBuilt::flow_mask`) the flow's alone, copied at output times.
struct Flow<'a> {
    position: Cow<'a, [Vector]>,
    velocity: Cow<'a, [Vector]>,
    mass: Cow<'a, [f64]>,
    volume: Cow<'a, [f64]>,
    initial_position: Cow<'a, [Vector]>,
}

impl<'a> Flow<'a> {
    /// the flow with the positions it would have had without wrapping through periodic sides:
    /// what the runout measures of an endless slope follow (R3-15: the centre of mass of a mass
    /// thrown across the seam moved backwards).
    fn unwrapped<St>(r: &Resolved, p: &'a Particles<St>) -> Self {
        if p.unwrap.is_empty() {
            return Self::of(r, p);
        }
        let unwrapped: Vec<Vector> = (0..p.len()).map(|q| p.unwrapped_position(q)).collect();
        Self::with_positions(r, p, Cow::Owned(unwrapped))
    }

    fn of<St>(r: &Resolved, p: &'a Particles<St>) -> Self {
        Self::with_positions(r, p, Cow::Borrowed(&p.position))
    }

    /// the flowing particles' fields, with `position` (one per particle) for their positions.
    fn with_positions<St>(r: &Resolved, p: &'a Particles<St>, position: Cow<'a, [Vector]>) -> Self {
        let Some(mask) = r.materials.flow_mask() else {
            return Self {
                position,
                velocity: Cow::Borrowed(&p.velocity),
                mass: Cow::Borrowed(&p.mass),
                volume: Cow::Borrowed(&p.volume),
                initial_position: Cow::Borrowed(&p.initial_position),
            };
        };
        let keep = |q: &usize| mask.get(usize::from(p.material[*q])).copied().unwrap_or(true);
        fn pick<T: Copy>(v: &[T], idx: &[usize]) -> Cow<'static, [T]> {
            Cow::Owned(idx.iter().map(|&q| v[q]).collect())
        }
        let idx: Vec<usize> = (0..p.len()).filter(keep).collect();
        Self {
            position: pick(&position, &idx),
            velocity: pick(&p.velocity, &idx),
            mass: pick(&p.mass, &idx),
            volume: pick(&p.volume, &idx),
            initial_position: pick(&p.initial_position, &idx),
        }
    }
}

/// takes the solver's current state into the envelopes.
fn observe<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
    e: &mut Envelope,
    r: &Resolved,
    solver: &Solver<M, S, N>,
) {
    let f = Flow::of(r, solver.particles());
    e.observe(solver.time(), r.spacing, [&f.position, &f.velocity], [&f.mass, &f.volume]);
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
    walls: usize,
    probes: usize,
    runout: usize,
}

/// A slot time counts as reached when the clock is within this fraction of the interval of it
/// (round-off of summed steps, never a physical time difference).
pub(crate) const SLOT_SLACK: f64 = 1e-9;

/// index of the last slot k·interval reached at time t.
pub(crate) fn slot(t: f64, interval: f64) -> u64 {
    (t / interval + SLOT_SLACK).floor().max(0.0) as u64
}

/// the next output time after `t` with `[output] exact_times` (the earliest of the next series
/// row, frame and checkpoint marks; infinity without it): where a step must end so that each
/// record falls on its mark.
pub(crate) fn next_mark(t: f64, exact: bool, intervals: &[Option<f64>]) -> f64 {
    if !exact {
        return f64::INFINITY;
    }
    intervals.iter().flatten().map(|&i| (slot(t, i) + 1) as f64 * i).fold(f64::INFINITY, f64::min)
}

/// whether a step ending at `t` was shortened to land on a mark of `intervals` (with
/// `exact_times`): such a step does not count as the run's smallest Δt.
pub(crate) fn on_mark(t: f64, exact: bool, intervals: &[Option<f64>]) -> bool {
    exact
        && intervals.iter().flatten().any(|&i| {
            let k = t / i;
            (k - k.round()).abs() <= SLOT_SLACK
        })
}

impl Driver<'_> {
    /// the marks `[output] exact_times` lands on: series rows, frames, checkpoints.
    fn marks(&self) -> [Option<f64>; 3] {
        let o = &self.scene.resolved().output;
        [Some(o.series_interval), Some(o.interval), o.checkpoint_interval]
    }

    pub(crate) fn metrics<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &self,
        solver: &Solver<M, S, N>,
    ) -> RunoutMetrics {
        let r = self.scene.resolved();
        let f = Flow::unwrapped(r, solver.particles());
        // every flowing particle has left through outflow sides: the measures stay where they
        // were last taken
        if f.mass.is_empty()
            && let Some(last) = self.history.runout.last()
        {
            return RunoutMetrics { time: solver.time(), front_speed: 0.0, ..*last };
        }
        let column = r.grid.column_width();
        summary::runout(
            solver.time(),
            [&f.position, &f.velocity],
            &f.mass,
            &r.ground,
            r.spacing,
            column,
            self.history.initial.as_ref(),
        )
    }

    pub(crate) fn record_series<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
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
            if i >= p.len() {
                continue;
            }
            // (unwrapped across a periodic pair: the probe follows its particle, not its image)
            let x = p.unwrapped_position(i);
            let u = x - p.initial_position[i];
            let v = p.velocity[i];
            self.history.probes.push(ProbeRow {
                time: t,
                probe: k,
                particle: i,
                position: [x.x, x.y, 0.0],
                displacement: [u.x, u.y, 0.0],
                velocity: [v.x, v.y, 0.0],
                along: u.dot(direction),
                reference: r.output.reference.map(|rf| rf.displacement(t)),
            });
        }
        let m = self.metrics(solver);
        self.history.runout.push(m);
        if let Some(w) = &mut self.history.edges {
            let f = Flow::of(r, solver.particles());
            let grains: Vec<Grain> = (f.position.iter().zip(f.mass.iter()))
                .map(|(x, &mass)| Grain {
                    position: [x.x, x.y, 0.0],
                    ground: ground_height(&r.ground, x.x),
                    mass,
                })
                .collect();
            w.observe(t, &grains, 0.5 * r.spacing);
        }
        if self.history.walls.is_none() {
            let (b, walls) = (&r.config.boundaries, r.config.walls.len());
            let sides = [b.ground, b.left_wall, b.right_wall].map(|s| s.is_some());
            let side_walls = r.config.side_walls().is_some();
            let boundaries =
                crate::loads::boundaries(&mpm_solver::SIDE_NAMES, &sides, walls, side_walls);
            if !boundaries.is_empty() {
                self.history.walls = Some(WallSeries::new(boundaries, 2));
            }
        }
        if let Some(w) = &mut self.history.walls {
            w.push(t, &load_samples(solver.boundary_loads()));
        }
    }

    pub(crate) fn write_frame<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
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
    pub(crate) fn rewrite_outputs(&mut self) -> Result<(), RunError> {
        let Some(dir) = self.dir else { return Ok(()) };
        self.flushed = Flushed::default();
        self.flush_series()?;
        if self.scene.resolved().output.vtk {
            atomic::write(&dir.join("particles.pvd"), vtk::pvd(&self.history.frames).as_bytes())?;
        }
        Ok(())
    }

    pub(crate) fn flush_series(&mut self) -> Result<(), RunError> {
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
        if let Some(w) = &h.walls {
            csv::flush(&dir.join("walls.csv"), &w.header(), &w.rows, &mut f.walls, loads::lines)?;
        }
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

    pub(crate) fn write_checkpoint<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &self,
        solver: &Solver<M, S, N>,
    ) -> Result<(), RunError> {
        let Some(dir) = self.dir else { return Ok(()) };
        let file = CheckpointFile::new(
            self.scene.origin(),
            self.scene.text(),
            self.scene.files_dir(),
            self.scene.inputs(),
            M::wrap(solver.checkpoint()),
            self.history.clone(),
        );
        Ok(checkpoint::write(&dir.join(checkpoint::FILE_NAME), &file)?)
    }

    pub(crate) fn summary<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &self,
        solver: &Solver<M, S, N>,
        status: RunStatus,
        error: Option<String>,
        threads: usize,
    ) -> RunSummary {
        let r = self.scene.resolved();
        let h = &self.history;
        let steps = solver.step_count();
        let gone = solver.outflowed().mass;
        let edges = h.edges.as_ref().map_or_else(Vec::new, |w| {
            w.reached(Flow::of(r, solver.particles()).mass.iter().sum::<f64>() + gone)
        });
        let mut warnings: Vec<String> = r.warnings.iter().map(ToString::to_string).collect();
        warnings.extend(edges.iter().map(EdgeContact::warning));
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
                    // the source's top: the highest initial particle's top
                    let top = h.crown.map(|[x, y, _]| Vector::new(x, y)).or_else(|| {
                        let f = Flow::of(r, solver.particles());
                        f.initial_position.iter().copied().max_by(|a, b| a.y.total_cmp(&b.y))
                    });
                    let crown = top.map_or(Vector::ZERO, |c| c + Vector::new(0.0, 0.5 * r.spacing));
                    let kinetic: Vec<(f64, f64)> =
                        h.energy.iter().map(|e| (e.time, e.ledger.kinetic)).collect();
                    summary::indicators(&h.runout, &kinetic, crown, &r.ground)
                },
            },
            observed: r.output.observed.as_ref().and_then(|o| {
                let f = Flow::of(r, solver.particles());
                let sim =
                    observed::simulated(&r.ground, r.grid.column_width(), r.spacing, &f.position);
                let last = h.runout.last()?;
                observed::compare(o, &sim, last.front_x, last.tail_x)
            }),
            state_hash: checkpoint::state_hash(&solver.checkpoint()),
            initial_state: self.initial.clone(),
            warnings,
            dimension: 2,
            hazard_maps: None,
            walls: h
                .walls
                .as_ref()
                .map(|w| w.summary(&load_samples(solver.boundary_loads())))
                .unwrap_or_default(),
            outflow: outflow_report(r, solver),
            edges,
        }
    }

    /// `envelope.csv`, `deposit.csv` and `plots/envelope.png`, when the scene asks for them.
    pub(crate) fn envelope_files<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &self,
        solver: &Solver<M, S, N>,
    ) -> Result<(), RunError> {
        let (Some(dir), Some(e)) = (self.dir, &self.history.envelope) else { return Ok(()) };
        let r = self.scene.resolved();
        let deposit = envelope::deposit(e, r.spacing, &Flow::of(r, solver.particles()).position);
        let section = r.section.as_ref();
        let mut s = csv::header(csv::ENVELOPE_HEADER, section);
        csv::envelope(&mut s, e, section);
        atomic::write(&dir.join("envelope.csv"), s.as_bytes())?;
        let mut s = csv::header(csv::DEPOSIT_HEADER, section);
        csv::deposit(&mut s, &deposit, section);
        atomic::write(&dir.join("deposit.csv"), s.as_bytes())?;
        if let Some(line) = section {
            atomic::write(&dir.join("section.geojson"), section_geojson(line).as_bytes())?;
        }
        if r.output.plots {
            // the undeclared ends of the grid the flow reached
            let edges: Vec<f64> = self.history.edges.as_ref().map_or_else(Vec::new, |w| {
                w.faces.iter().filter(|f| f.first_time.is_some()).map(|f| f.at).collect()
            });
            report::envelope(&dir.join("plots"), e, &deposit, &edges)?;
        }
        Ok(())
    }

    pub(crate) fn plots<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        &self,
        solver: &Solver<M, S, N>,
    ) -> Result<(), RunError> {
        let Some(dir) = self.dir else { return Ok(()) };
        if !self.scene.resolved().output.plots {
            return Ok(());
        }
        let f = Flow::of(self.scene.resolved(), solver.particles());
        let deposit =
            Deposit { positions: &f.position, initial: &f.initial_position, time: solver.time() };
        Ok(report::plots(&dir.join("plots"), self.scene, &self.history, &deposit)?)
    }
}

impl<M: SceneModel, S: ShapeFunctions<N>, const N: usize> Observer<M, S, N> for Driver<'_> {
    fn after_step(&mut self, solver: &Solver<M, S, N>, report: &StepReport) -> ControlFlow<()> {
        let r = self.scene.resolved();
        let landed = on_mark(report.time, r.output.exact_times, &self.marks());
        let h = &mut self.history;
        // The step that lands on the end time (or on an output mark) is shortened; it does not
        // count as the smallest.
        if (!landed && !mpm_solver::reached(report.time, r.end_time)) || h.dt_max == 0.0 {
            h.dt_min = h.dt_min.min(report.dt);
        }
        h.dt_max = h.dt_max.max(report.dt);
        if h.dt_first == 0.0 {
            h.dt_first = report.dt;
        }
        self.session_particle_steps += solver.particles().len() as f64;
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
        if report.step >= r.max_steps && !mpm_solver::reached(t, r.end_time) {
            self.stop.get_or_insert(Stop::StepLimit);
        }
        let interrupted = self.interrupt.as_ref().is_some_and(|f| f.load(Ordering::Relaxed));
        if interrupted {
            self.progress
                .warn("interrupted: writing a checkpoint after this step (a second Ctrl-C aborts)");
        }
        if self.stop.is_some() || interrupted || self.stop_after.is_some_and(|s| t >= s) {
            return ControlFlow::Break(());
        }
        ControlFlow::Continue(())
    }

    fn landing(&self, time: f64) -> f64 {
        next_mark(time, self.scene.resolved().output.exact_times, &self.marks())
    }
}

/// the watch over the grid's sides that the scene left undeclared (no wall law, not outflow,
/// not periodic); `None` when every side is declared.
fn edge_watch(r: &Resolved) -> Option<EdgeWatch> {
    let c = &r.config;
    let (x0, x1) = r.grid.x_range();
    let open = c.periodic.is_none();
    let mut faces = Vec::new();
    if open && c.boundaries.left_wall.is_none() && c.outflow.x_min.is_none() {
        faces.push(("left_wall", 0, x0, -1.0));
    }
    if open && c.boundaries.right_wall.is_none() && c.outflow.x_max.is_none() {
        faces.push(("right_wall", 0, x1, 1.0));
    }
    EdgeWatch::new(faces, r.grid.column_width())
}

/// `summary.json` `outflow` of a scene with outflow faces.
fn outflow_report<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
    r: &Resolved,
    solver: &Solver<M, S, N>,
) -> Option<OutflowReport> {
    let (o, g) = (r.config.outflow, solver.outflowed());
    OutflowReport::new(
        &[("left_wall", o.x_min), ("right_wall", o.x_max)],
        (g.particles, g.mass, g.momentum.to_array().to_vec(), g.energy),
        g.first_time,
        solver.particles().total_mass(),
    )
}

/// The section a DEM scene runs along as a GeoJSON feature collection: the line from `from` to
/// `to` in the DEM's map coordinates (no CRS member: a GIS must be given the DEM's), with the
/// DEM's name and the line's length.
pub(crate) fn section_geojson(line: &mpm_scene::SectionLine) -> String {
    let length = (line.to[0] - line.from[0]).hypot(line.to[1] - line.from[1]);
    let doc = serde_json::json!({
        "type": "FeatureCollection",
        "features": [{
            "type": "Feature",
            "properties": { "name": "section", "dem": line.dem, "length_m": length },
            "geometry": { "type": "LineString", "coordinates": [line.from, line.to] },
        }],
    });
    format!("{doc:#}\n")
}
