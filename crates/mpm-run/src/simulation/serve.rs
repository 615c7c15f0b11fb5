//! The worker's command loop, one for both dimensions: a built solver (after its initial state)
//! answers the caller's commands one at a time, recording through the run driver as a run
//! without an output folder does. The driver is rebuilt from the history for each command, so
//! that a changed scene (`set_material`) takes effect from the next one.

use std::sync::mpsc::{Receiver, Sender};

use mpm_output::checkpoint::History;
use mpm_scene::{InitialStateSummary, RunStatus};

use super::{Advance, Command, Limit, Reply, write_checkpoint};
use crate::driver::{Driver, Stepper, Wing, describe};
use crate::error::RunError;
use crate::options::RunOptions;

/// What a worker needs of a solver build beyond the driver's view: its scene and wing, its
/// particles' fields and the setters between steps.
pub(crate) trait Served: Stepper + Sized {
    /// the scene of the build's dimension.
    type Scene: Clone;
    /// the driver's wing of that dimension over a scene borrowed for `'a`.
    type Wing<'a>: Wing<Vector = Self::Vector>
    where
        Self::Scene: 'a;

    /// the wing of a driver over `scene` continuing `h` (with the initial state found, in 2D).
    fn wing<'a>(
        &self,
        scene: &'a Self::Scene,
        h: &History,
        initial: &Option<InitialStateSummary>,
    ) -> Self::Wing<'a>;
    /// the scene's end time (s).
    fn end_time(scene: &Self::Scene) -> f64;
    /// the particles' fields, as the reply of the dimension.
    fn fields(&self) -> Reply;
    /// sets the particles' velocities (their components in a row, one particle after another;
    /// the count was checked on the caller's side).
    fn set_velocities_flat(&mut self, v: &[f64]) -> Result<(), RunError>;
    /// sets a body force per particle (as `set_velocities_flat`), or clears it.
    fn set_body_force_flat(&mut self, b: Option<&[f64]>) -> Result<(), RunError>;
    /// changes `path` = `value` in `scene`, validated, and gives its materials to the solver.
    fn set_material(
        &mut self,
        scene: &mut Self::Scene,
        path: &str,
        value: &str,
    ) -> Result<(), RunError>;
}

/// records the start of `sv`'s run of `scene` (found `initial`), says it is ready on `outbox`
/// and answers the commands of `inbox` until the caller closes it.
pub(crate) fn serve<Sv: Served>(
    sv: &mut Sv,
    scene: &Sv::Scene,
    initial: Option<InitialStateSummary>,
    inbox: Receiver<Command>,
    outbox: Sender<Reply>,
    opts: &RunOptions,
) {
    // the scene as changed by `set_material` (its text goes into checkpoints)
    let mut current = scene.clone();
    let mut history = History { dt_min: f64::INFINITY, ..History::default() };
    {
        let wing = sv.wing(&current, &history, &initial);
        let mut d = Driver::begin(wing, None, std::mem::take(&mut history), opts);
        if let Err(e) = d.record_start(sv) {
            let _ = outbox.send(Reply::Failed(e));
            return;
        }
        history = d.history;
    }
    let ready =
        Reply::Ready { time: sv.time(), steps: sv.step_count(), particles: sv.particles().len() };
    if outbox.send(ready).is_err() {
        return;
    }
    let threads = rayon::current_num_threads();
    let describe = describe::<Sv>;
    let mut failed = false;
    while let Ok(command) = inbox.recv() {
        let reply = match command {
            Command::Advance(_) if failed => {
                Reply::Failed(RunError::Setup("the simulation failed earlier".into()))
            }
            Command::Advance(limit) => {
                let wing = sv.wing(&current, &history, &initial);
                let mut d = Driver::begin(wing, None, std::mem::take(&mut history), opts);
                let result = match limit {
                    Limit::Time(t) => d.run(sv, t),
                    Limit::Steps(n) => d.run_steps(sv, n),
                };
                failed = result.is_err();
                let reply = outcome(sv, &mut d, result, threads, &describe);
                history = d.history;
                Reply::Advanced(Box::new(reply))
            }
            Command::Fields => sv.fields(),
            Command::Energy => Reply::Energy(sv.energy()),
            Command::Summary => {
                let status = if mpm_solver::reached(sv.time(), Sv::end_time(&current)) {
                    RunStatus::Completed
                } else {
                    RunStatus::Interrupted
                };
                let wing = sv.wing(&current, &history, &initial);
                let mut d = Driver::begin(wing, None, std::mem::take(&mut history), opts);
                let s = d.summary_now(sv, status, None, threads);
                history = d.history;
                Reply::Summary(Box::new(s))
            }
            Command::Checkpoint(dir) => {
                let wing = sv.wing(&current, &history, &initial);
                let d = Driver::begin(wing, None, std::mem::take(&mut history), opts);
                let file = d.checkpoint(sv);
                history = d.history;
                Reply::Written(write_checkpoint(&dir, file))
            }
            _ if failed => Reply::Set(Err(RunError::Setup("the simulation failed earlier".into()))),
            Command::SetVelocities(v) => Reply::Set(sv.set_velocities_flat(&v)),
            Command::SetBodyForce(b) => Reply::Set(sv.set_body_force_flat(b.as_deref())),
            Command::SetMaterial { path, value } => {
                Reply::Set(sv.set_material(&mut current, &path, &value))
            }
        };
        if outbox.send(reply).is_err() {
            return;
        }
    }
}

/// the caller's view of an advance (a solver error's message through `describe`).
fn outcome<W: Wing, Sv: Stepper<Vector = W::Vector>>(
    sv: &Sv,
    driver: &mut Driver<'_, W>,
    result: Result<mpm_solver::RunEnd, Sv::Error>,
    threads: usize,
    describe: &dyn Fn(&Sv::Error) -> String,
) -> Result<Advance, RunError> {
    let (status, error) = driver.status(&result, sv, describe);
    match result {
        Err(e) => Err(RunError::Solver {
            message: describe(&e),
            summary: Box::new(driver.summary_now(sv, status, error, threads)),
        }),
        Ok(end) => Ok(Advance {
            stopped: (end == mpm_solver::RunEnd::Stopped).then_some(status),
            time: sv.time(),
            steps: sv.step_count(),
            particles: sv.particles().len(),
        }),
    }
}
