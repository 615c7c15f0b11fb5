//! A run driven from outside, step by step: for bindings, coupling and custom analysis.
//!
//! [`Simulation`] owns a worker thread on which the scene's solver lives with its concrete model
//! and shape-function types (chosen once by `mpm_scene::dispatch`, as for [`run_scene`]); each
//! call sends the worker one command and waits for its answer. While it waits, the caller's
//! `poll` runs every [`POLL`] and may ask the work to stop after its current step (a Python
//! front end checks for Ctrl-C there), so the state is always that of a whole step.
//!
//! The records are those of a run without an output directory: the same initial state, energy
//! ledger, runout series, envelopes and rest watch, and advanced by steps the same bits as
//! [`run_scene`] (see [`Simulation::summary`] for what its summary holds).
//!
//! [`run_scene`]: crate::run_scene

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::thread::JoinHandle;
use std::time::Duration;

use mpm_grid::ShapeFunctions;
use mpm_output::checkpoint::{self, CheckpointFile, History};
use mpm_output::{OutputError, atomic};
use mpm_scene::dispatch::{self, Job, SceneModel};
use mpm_scene::materials::ModelJob;
use mpm_scene::{InitialStateSummary, RunStatus, RunSummary, Scene};
use mpm_solver::{EnergyLedger, Solver, Vector};

mod serve;
mod space;

use serve::Served;

use crate::driver::plane::{Plane, initial_state};
use crate::error::RunError;
use crate::options::RunOptions;

/// How often a waiting call runs its `poll`.
pub const POLL: Duration = Duration::from_millis(20);

/// How far [`Simulation::advance`] goes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Limit {
    /// this many more steps.
    Steps(u64),
    /// until this simulated time (s); the last step is shortened to land on it, so a run
    /// advanced to intermediate times takes other steps than one run in one go (whose output
    /// times never shorten a step); [`Limit::Steps`] keeps them.
    Time(f64),
}

/// Where an advance ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Advance {
    /// `None` when the limit was reached; otherwise why the run stopped before it
    /// ([`RunStatus::AtRest`], [`RunStatus::EnergyAlarm`], [`RunStatus::StepLimit`], or
    /// [`RunStatus::Interrupted`] when `poll` asked).
    pub stopped: Option<RunStatus>,
    /// simulated time (s).
    pub time: f64,
    /// steps taken since the start.
    pub steps: u64,
    /// particles in the run (fewer than at the start once some left through outflow sides).
    pub particles: usize,
}

/// The particles' fields, copied: in plane strain (the defaults `D` = 2, `C` = 4) 2 components a
/// vector and stresses as xx, yy, zz, xy; in 3D ([`SpaceFields`]) 3 components and xx, yy, zz,
/// xy, yz, zx (Pa, tension positive).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ParticleFields<const D: usize = 2, const C: usize = 4> {
    /// positions (m).
    pub position: Vec<[f64; D]>,
    /// velocities (m/s).
    pub velocity: Vec<[f64; D]>,
    /// Cauchy stresses: xx, yy, zz (out of plane in 2D), xy[, yz, zx] (Pa).
    pub stress: Vec<[f64; C]>,
    /// masses (kg; per m of thickness in 2D).
    pub mass: Vec<f64>,
    /// volumes (m³; m² per m of thickness in 2D).
    pub volume: Vec<f64>,
    /// positions at the start (m).
    pub initial_position: Vec<[f64; D]>,
    /// each particle's body, as numbered in the scene's `[[bodies]]`.
    pub body: Vec<u16>,
    /// each particle's material, in the scene's order of `[materials.*]`.
    pub material: Vec<u16>,
    /// equivalent plastic strain ε̄ᵖ (its model's measure; 0 for an elastic material).
    pub plastic_strain: Vec<f64>,
}

/// A 3D run's particle fields.
pub type SpaceFields = ParticleFields<3, 6>;

pub(crate) enum Command {
    Advance(Limit),
    Fields,
    Energy,
    Summary,
    Checkpoint(PathBuf),
    SetVelocities(Vec<f64>),
    SetBodyForce(Option<Vec<f64>>),
    SetMaterial { path: String, value: String },
}

pub(crate) enum Reply {
    Ready { time: f64, steps: u64, particles: usize },
    Advanced(Box<Result<Advance, RunError>>),
    Fields(Box<ParticleFields>),
    SpaceFields(Box<SpaceFields>),
    Energy(EnergyLedger),
    Summary(Box<RunSummary>),
    Written(Result<(), RunError>),
    Set(Result<(), RunError>),
    Failed(RunError),
}

/// A scene's run, advanced by the caller (see the module's documentation).
pub struct Simulation {
    commands: Option<Sender<Command>>,
    replies: Receiver<Reply>,
    worker: Option<JoinHandle<()>>,
    interrupt: Arc<AtomicBool>,
    time: f64,
    steps: u64,
    particles: usize,
    dimension: u8,
}

impl std::fmt::Debug for Simulation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Simulation")
            .field("time", &self.time)
            .field("steps", &self.steps)
            .field("particles", &self.particles)
            .field("dimension", &self.dimension)
            .finish_non_exhaustive()
    }
}

impl Simulation {
    /// generates the scene's particles and finds its initial state (`[initial_state]`) on
    /// `threads` threads at most (default one per core; a small scene uses fewer, with the same
    /// results). `poll` runs while the initial state is found; returning true stops it.
    pub fn new(
        scene: &Scene,
        threads: Option<usize>,
        poll: &mut dyn FnMut() -> bool,
    ) -> Result<Simulation, RunError> {
        let scene = scene.clone();
        Self::start(2, scene.resolved().seeds.len(), threads, poll, move |job, outbox| {
            if let Err(e) = dispatch::dispatch(&scene, job) {
                let _ = outbox.send(Reply::Failed(e.into()));
            }
        })
    }

    /// [`Simulation::new`] for a 3D scene: the same commands, with 3-component vectors
    /// ([`Simulation::space_fields`]; `set_velocities` and `set_body_force` take x, y, z per
    /// particle).
    pub fn new_space(
        scene: &mpm_scene::SpaceScene,
        threads: Option<usize>,
        poll: &mut dyn FnMut() -> bool,
    ) -> Result<Simulation, RunError> {
        let scene = scene.clone();
        Self::start(3, scene.seeds.len(), threads, poll, move |job, outbox| {
            if let Err(e) = mpm_scene::dispatch_space(&scene, space::SpaceWorker(job)) {
                let _ = outbox.send(Reply::Failed(e.into()));
            }
        })
    }

    /// starts the worker thread with a pool for `particles` particles, running `serve`.
    fn start(
        dimension: u8,
        particles: usize,
        threads: Option<usize>,
        poll: &mut dyn FnMut() -> bool,
        serve: impl FnOnce(Worker, Sender<Reply>) + Send + 'static,
    ) -> Result<Simulation, RunError> {
        let (commands, inbox) = mpsc::channel();
        let (outbox, replies) = mpsc::channel();
        let interrupt = Arc::new(AtomicBool::new(false));
        let available = crate::options::available_threads(threads)?;
        let count = mpm_solver::useful_threads(particles, available);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(count)
            .build()
            .map_err(|e| RunError::Setup(format!("cannot start threads: {e}")))?;
        let job = Worker { inbox, outbox: outbox.clone(), interrupt: interrupt.clone() };
        let worker = std::thread::Builder::new()
            .name("mpm-simulation".into())
            .spawn(move || pool.install(|| serve(job, outbox)))
            .map_err(|e| RunError::Setup(format!("cannot start the simulation's thread: {e}")))?;
        let mut sim = Simulation {
            commands: Some(commands),
            replies,
            worker: Some(worker),
            interrupt,
            time: 0.0,
            steps: 0,
            particles: 0,
            dimension,
        };
        match sim.wait(poll)? {
            Reply::Ready { time, steps, particles } => {
                (sim.time, sim.steps, sim.particles) = (time, steps, particles);
                Ok(sim)
            }
            Reply::Failed(e) => Err(e),
            _ => Err(RunError::Setup("the simulation's thread answered out of turn".into())),
        }
    }

    /// simulated time (s).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// steps taken since the start.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// number of particles.
    pub fn particle_count(&self) -> usize {
        self.particles
    }

    /// 2 (plane strain) or 3.
    pub fn dimension(&self) -> u8 {
        self.dimension
    }

    /// advances by `limit`, calling `poll` every [`POLL`] while the steps run; when `poll`
    /// returns true the run stops after its current step (`stopped` is then
    /// [`RunStatus::Interrupted`]). A solver failure is [`RunError::Solver`] with the summary at
    /// the failing step; the simulation cannot go on after it.
    pub fn advance(
        &mut self,
        limit: Limit,
        poll: &mut dyn FnMut() -> bool,
    ) -> Result<Advance, RunError> {
        match limit {
            Limit::Time(t) if !t.is_finite() => {
                return Err(RunError::Arguments(format!(
                    "advance to t = {t} s: not a finite time"
                )));
            }
            // (a time already passed would return at once, as if it had been reached)
            Limit::Time(t) if t < self.time => {
                return Err(RunError::Arguments(format!(
                    "advance to t = {t} s: the simulation is already at t = {} s; give a time \
                     at or after it",
                    self.time
                )));
            }
            _ => {}
        }
        self.send(Command::Advance(limit))?;
        match self.wait(poll)? {
            Reply::Advanced(r) => match *r {
                Ok(a) => {
                    (self.time, self.steps, self.particles) = (a.time, a.steps, a.particles);
                    Ok(a)
                }
                Err(e) => {
                    // the state is the failing step's (its fields and summary show it)
                    if let RunError::Solver { summary, .. } = &e {
                        (self.time, self.steps, self.particles) =
                            (summary.simulated_time, summary.steps, summary.particles);
                    }
                    Err(e)
                }
            },
            other => Err(unexpected(other)),
        }
    }

    /// a copy of the particles' fields (a 2D run's; a 3D run's are [`Self::space_fields`]).
    pub fn fields(&mut self) -> Result<ParticleFields, RunError> {
        if self.dimension != 2 {
            return Err(RunError::Arguments("a 3D run: its fields are space_fields()".into()));
        }
        self.send(Command::Fields)?;
        match self.wait(&mut || false)? {
            Reply::Fields(f) => Ok(*f),
            other => Err(unexpected(other)),
        }
    }

    /// a copy of a 3D run's particle fields.
    pub fn space_fields(&mut self) -> Result<SpaceFields, RunError> {
        if self.dimension != 3 {
            return Err(RunError::Arguments("a 2D run: its fields are fields()".into()));
        }
        self.send(Command::Fields)?;
        match self.wait(&mut || false)? {
            Reply::SpaceFields(f) => Ok(*f),
            other => Err(unexpected(other)),
        }
    }

    /// the energy ledger now (J per m of thickness).
    pub fn energy(&mut self) -> Result<EnergyLedger, RunError> {
        self.send(Command::Energy)?;
        match self.wait(&mut || false)? {
            Reply::Energy(e) => Ok(e),
            other => Err(unexpected(other)),
        }
    }

    /// the summary of the run so far, as [`run_scene`](crate::run_scene) would close it now: the
    /// state's figures (steps, time, Δt, energy ledger and check, state hash) and the runout
    /// measures and indicators with a closing row of the state now (the run's own series keep
    /// their rows as they were), status `Completed` once the scene's end time is reached and
    /// `Interrupted` before, `EnergyAlarm` once the energy alarm has tripped (a stop at rest is
    /// the `stopped` of the advance that met it).
    pub fn summary(&mut self) -> Result<RunSummary, RunError> {
        self.send(Command::Summary)?;
        match self.wait(&mut || false)? {
            Reply::Summary(s) => Ok(*s),
            other => Err(unexpected(other)),
        }
    }

    /// writes `dir/checkpoint.bin` and `dir/scene.toml` (creating `dir`): `mpm resume DIR`
    /// continues the run from here, bit-identically, writing its output into `dir`.
    pub fn checkpoint(&mut self, dir: &Path) -> Result<(), RunError> {
        self.send(Command::Checkpoint(dir.to_path_buf()))?;
        match self.wait(&mut || false)? {
            Reply::Written(r) => r,
            other => Err(unexpected(other)),
        }
    }

    /// sets every particle's velocity (m/s) before the next step: `velocities` holds x, y (and
    /// z in 3D) of each particle in turn, in the order of the fields; the kinetic energy it
    /// changes is booked as external work in the ledger. A wrong count or a non-finite
    /// velocity is refused ([`RunError::Arguments`]) and nothing changes.
    pub fn set_velocities(&mut self, velocities: Vec<f64>) -> Result<(), RunError> {
        self.check_count("velocities", velocities.len())?;
        self.set(Command::SetVelocities(velocities))
    }

    /// prescribes a body force per unit mass on each particle (m/s², its components in turn as
    /// [`Self::set_velocities`]'s), added to gravity from the next step until set again (`None`
    /// removes it); its work is booked as external work. It is not part of a checkpoint: a
    /// resumed run has gravity alone. A wrong count or a non-finite force is refused and the
    /// force set before stays.
    pub fn set_body_force(&mut self, force: Option<Vec<f64>>) -> Result<(), RunError> {
        if let Some(f) = &force {
            self.check_count("body_force", f.len())?;
        }
        self.set(Command::SetBodyForce(force))
    }

    /// one value per particle and component, or the argument's error.
    fn check_count(&self, name: &str, len: usize) -> Result<(), RunError> {
        let d = usize::from(self.dimension);
        if len == d * self.particles {
            return Ok(());
        }
        Err(RunError::Arguments(format!(
            "{name}: {len} values for {} particles in {d}D; give {d} per particle ({})",
            self.particles,
            d * self.particles
        )))
    }

    /// changes a material's parameter between steps: `path` is `materials.<name>.<field>` and
    /// `value` a TOML value, the scene with it validated as a scene file is (a refused value is
    /// the scene's located [`RunError::Scene`]). The model (`kind`) and the `density` (the
    /// particles' masses) cannot change. The particles keep their stresses; the stored elastic
    /// energy the new stiffness gives them is booked as external work. A checkpoint written
    /// after it holds the changed scene.
    pub fn set_material(&mut self, path: &str, value: &str) -> Result<(), RunError> {
        let parts: Vec<&str> = path.split('.').collect();
        match parts.as_slice() {
            ["materials", name, field] if !name.is_empty() && !field.is_empty() => {
                if matches!(*field, "kind" | "density") {
                    return Err(RunError::Arguments(format!(
                        "{path}: a material's {field} cannot change during a run (the \
                         particles' {} were set at the start); run the scene again with it",
                        if *field == "kind" { "model and state" } else { "masses" }
                    )));
                }
            }
            _ => {
                return Err(RunError::Arguments(format!(
                    "{path}: give a material's parameter as materials.<name>.<field> (e.g. \
                     materials.sand.friction_angle_deg); other fields cannot change during a \
                     run"
                )));
            }
        }
        self.set(Command::SetMaterial { path: path.to_string(), value: value.to_string() })
    }

    fn set(&mut self, c: Command) -> Result<(), RunError> {
        self.send(c)?;
        match self.wait(&mut || false)? {
            Reply::Set(r) => r,
            other => Err(unexpected(other)),
        }
    }

    fn send(&self, c: Command) -> Result<(), RunError> {
        // cleared before the command goes: a stop asked during the previous command must not
        // stop this one
        self.interrupt.store(false, Ordering::Relaxed);
        self.commands
            .as_ref()
            .and_then(|s| s.send(c).ok())
            .ok_or_else(|| RunError::Setup("the simulation has ended after an error".into()))
    }

    /// the worker's next reply, polling while waiting.
    fn wait(&mut self, poll: &mut dyn FnMut() -> bool) -> Result<Reply, RunError> {
        loop {
            match self.replies.recv_timeout(POLL) {
                Ok(Reply::Failed(e)) => {
                    self.commands = None;
                    return Err(e);
                }
                Ok(r) => return Ok(r),
                Err(RecvTimeoutError::Timeout) => {
                    if poll() {
                        self.interrupt.store(true, Ordering::Relaxed);
                    }
                }
                Err(RecvTimeoutError::Disconnected) => {
                    self.commands = None;
                    return Err(RunError::Setup(
                        "the simulation's thread ended (a panic in the solver)".into(),
                    ));
                }
            }
        }
    }
}

impl Drop for Simulation {
    fn drop(&mut self) {
        // closing the channel ends the worker's loop (after the command it may still be on)
        self.interrupt.store(true, Ordering::Relaxed);
        self.commands = None;
        if let Some(w) = self.worker.take() {
            let _ = w.join();
        }
    }
}

fn unexpected(r: Reply) -> RunError {
    match r {
        Reply::Failed(e) => e,
        _ => RunError::Setup("the simulation's thread answered out of turn".into()),
    }
}

/// The worker's side: builds the solver with the scene's types and serves commands.
pub(crate) struct Worker {
    pub(crate) inbox: Receiver<Command>,
    pub(crate) outbox: Sender<Reply>,
    pub(crate) interrupt: Arc<AtomicBool>,
}

impl Job for Worker {
    type Output = ();

    fn run<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        self,
        scene: &Scene,
        shape: S,
        materials: Vec<M>,
    ) {
        let r = scene.resolved();
        let particles = dispatch::particles(&r.seeds, &materials);
        let mut solver = match Solver::new(shape, materials, particles, r.config.clone()) {
            Ok(s) => s,
            Err(e) => {
                let _ = self.outbox.send(Reply::Failed(RunError::Setup(format!(
                    "{}: the solver refused the scene: {e}",
                    scene.origin()
                ))));
                return;
            }
        };
        let opts = RunOptions { interrupt: Some(self.interrupt.clone()), ..Default::default() };
        solver.set_interrupt(opts.interrupt.clone());
        let initial = initial_state(&mut solver, &r.initial_state, &opts.progress);
        solver.set_interrupt(None);
        let initial = match initial {
            Ok(i) => i,
            Err(e) => {
                let _ = self.outbox.send(Reply::Failed(RunError::Setup(format!(
                    "{}: initial state: {e}",
                    scene.origin()
                ))));
                return;
            }
        };
        serve::serve(&mut solver, scene, initial, self.inbox, self.outbox, &opts);
    }
}

impl<M: SceneModel, S: ShapeFunctions<N>, const N: usize> Served for Solver<M, S, N> {
    type Scene = Scene;
    type Wing<'a> = Plane<'a>;

    fn wing<'a>(
        &self,
        scene: &'a Scene,
        _h: &History,
        initial: &Option<InitialStateSummary>,
    ) -> Plane<'a> {
        Plane::new(scene, initial.clone())
    }

    fn end_time(scene: &Scene) -> f64 {
        scene.resolved().end_time
    }

    fn fields(&self) -> Reply {
        Reply::Fields(Box::new(fields(self.particles(), self.materials())))
    }

    fn set_velocities_flat(&mut self, v: &[f64]) -> Result<(), RunError> {
        let v: Vec<Vector> = v.chunks_exact(2).map(|c| Vector::new(c[0], c[1])).collect();
        self.set_velocities(&v).map_err(|e| argument("velocities", e))
    }

    fn set_body_force_flat(&mut self, b: Option<&[f64]>) -> Result<(), RunError> {
        let Some(b) = b else {
            self.clear_body_force();
            return Ok(());
        };
        let b: Vec<Vector> = b.chunks_exact(2).map(|c| Vector::new(c[0], c[1])).collect();
        (self.set_body_force(|p, _| b.get(p).copied().unwrap_or(Vector::NAN)))
            .map_err(|e| argument("body_force", e))
    }

    fn set_material(
        &mut self,
        current: &mut Scene,
        path: &str,
        value: &str,
    ) -> Result<(), RunError> {
        let next = current.with_value(path, value)?;
        let materials = materials_of::<M>(&next.resolved().materials, path, value)?;
        self.set_materials(materials).map_err(|e| argument(path, e))?;
        *current = next;
        Ok(())
    }
}

/// a scene's materials as the run's model `M`, or the error of a change (`path` = `value`) that
/// would need another model.
pub(crate) fn materials_of<M: SceneModel>(
    built: &mpm_scene::materials::MaterialsBuilt,
    path: &str,
    value: &str,
) -> Result<Vec<M>, RunError> {
    /// the scene's materials, of whatever model they are.
    struct Take;
    impl ModelJob for Take {
        type Output = Box<dyn std::any::Any>;
        fn run<M2: SceneModel>(self, materials: Vec<M2>) -> Self::Output {
            Box::new(materials)
        }
    }
    built.run(Take).downcast::<Vec<M>>().map(|m| *m).map_err(|_| {
        RunError::Arguments(format!(
            "{path} = {value}: the materials would need another model than the run's; run the \
             scene again with it"
        ))
    })
}

/// a solver error of a setter as the argument's error.
pub(crate) fn argument(name: &str, e: impl std::fmt::Display) -> RunError {
    RunError::Arguments(format!("{name}: {e}"))
}

fn fields<M: SceneModel>(p: &mpm_solver::Particles<M::State>, materials: &[M]) -> ParticleFields {
    ParticleFields {
        position: p.position.iter().map(|v| [v.x, v.y]).collect(),
        velocity: p.velocity.iter().map(|v| [v.x, v.y]).collect(),
        stress: p.stress.iter().map(|s| [s.xx, s.yy, s.zz, s.xy]).collect(),
        mass: p.mass.clone(),
        volume: p.volume.clone(),
        initial_position: p.initial_position.iter().map(|v| [v.x, v.y]).collect(),
        body: p.body.clone(),
        material: p.material.clone(),
        plastic_strain: (0..p.len())
            .map(|i| {
                let m = &materials[usize::from(p.material[i])];
                m.equivalent_plastic_strain(&p.state[i])
            })
            .collect(),
    }
}

/// `dir/checkpoint.bin` and `dir/scene.toml` (the checkpoint's scene).
pub(crate) fn write_checkpoint(dir: &Path, file: CheckpointFile) -> Result<(), RunError> {
    std::fs::create_dir_all(dir)
        .map_err(|source| OutputError::Io { path: dir.to_path_buf(), source })?;
    atomic::write(&dir.join("scene.toml"), file.scene_text.as_bytes())?;
    checkpoint::write(&dir.join(checkpoint::FILE_NAME), &file)?;
    Ok(())
}
