//! The 3D worker of [`crate::Simulation`]: the 3D solver built with the scene's types, serving
//! the commands the 2D worker serves, recording through the 3D run's driver
//! ([`crate::space`]) as a run without an output folder does.

use mpm_grid3d::ShapeFunctions;
use mpm_output::checkpoint::{CheckpointFile, History};
use mpm_scene::SpaceScene;
use mpm_scene::dispatch::SceneModel;
use mpm_scene::space::{SpaceJob, space_particles};
use mpm_scene::summary::RunStatus;
use mpm_solver3d::{Observer, RunEnd, Solver, Vector};

use super::{Advance, Command, Limit, Reply, SpaceFields, Worker, argument, write_checkpoint};
use crate::common::setup_error;
use crate::error::RunError;
use crate::options::RunOptions;
use crate::space::{SpaceDriver, Stop, describe};

/// The 3D side of [`crate::Simulation`]: builds the 3D solver with the scene's types and serves
/// the commands the 2D worker serves (`simulation.rs`), recording as a run without an output
/// folder does; the driver is rebuilt from its history for each command, so that a changed
/// scene (`set_material`) takes effect from the next one.
pub(crate) struct SpaceWorker(pub(crate) Worker);

impl SpaceJob for SpaceWorker {
    type Output = ();

    fn run<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        self,
        scene: &SpaceScene,
        shape: S,
        materials: Vec<M>,
    ) {
        let Worker { inbox, outbox, interrupt } = self.0;
        let particles = space_particles(&scene.seeds, &materials);
        let mut solver = match Solver::new(shape, materials, particles, scene.config.clone()) {
            Ok(s) => s,
            Err(e) => {
                let _ = outbox.send(Reply::Failed(setup_error(scene.origin(), &e.to_string())));
                return;
            }
        };
        let opts = RunOptions { interrupt: Some(interrupt), ..Default::default() };
        let mut current = scene.clone();
        let mut history = {
            let mut d = SpaceDriver::begin(&current, None, &opts, &solver, None);
            d.record(&solver);
            d.history()
        };
        let ready = Reply::Ready {
            time: solver.time(),
            steps: solver.step_count(),
            particles: solver.particles().len(),
        };
        if outbox.send(ready).is_err() {
            return;
        }
        let threads = rayon::current_num_threads();
        // the summary of the run now, from a driver of the records so far (left as they are)
        let summary = |solver: &Solver<M, S, N>, scene: &SpaceScene, h: &History, status, error| {
            let mut d = SpaceDriver::begin(scene, None, &opts, solver, Some(h.clone()));
            d.finish(solver, status, error, threads)
        };
        let mut failed = false;
        while let Ok(command) = inbox.recv() {
            let reply = match command {
                Command::Advance(_) if failed => {
                    Reply::Failed(RunError::Setup("the simulation failed earlier".into()))
                }
                Command::Advance(limit) => {
                    let mut d =
                        SpaceDriver::begin(&current, None, &opts, &solver, Some(history.clone()));
                    let steps0 = solver.step_count();
                    let result = match limit {
                        Limit::Time(t) => solver.run_until(t, &mut d),
                        Limit::Steps(n) => loop {
                            if solver.step_count() - steps0 >= n || solver.particles().is_empty() {
                                break Ok(RunEnd::EndTime);
                            }
                            // (lands on the next output mark as `run_until` does)
                            let t = solver.time();
                            let landing = Observer::<M, S, N>::landing(&d, t);
                            let cap = if landing > t { landing - t } else { f64::INFINITY };
                            match solver.step_capped(cap) {
                                Err(e) => break Err(e),
                                Ok(report) => {
                                    if d.after_step(&solver, &report).is_break() {
                                        break Ok(RunEnd::Stopped);
                                    }
                                }
                            }
                        },
                    };
                    history = d.history();
                    let reply = match result {
                        Err(e) => {
                            failed = true;
                            let message = describe(&e);
                            let s = summary(
                                &solver,
                                &current,
                                &history,
                                RunStatus::Failed,
                                Some(message.clone()),
                            );
                            match s {
                                Ok(s) => Err(RunError::Solver { message, summary: Box::new(s) }),
                                Err(e) => Err(e),
                            }
                        }
                        Ok(end) => Ok(Advance {
                            stopped: (end == RunEnd::Stopped).then_some(match d.stop {
                                Some(Stop::AtRest) => RunStatus::AtRest,
                                Some(Stop::EnergyAlarm) => RunStatus::EnergyAlarm,
                                Some(Stop::StepLimit) => RunStatus::StepLimit,
                                None => RunStatus::Interrupted,
                            }),
                            time: solver.time(),
                            steps: solver.step_count(),
                            particles: solver.particles().len(),
                        }),
                    };
                    Reply::Advanced(Box::new(reply))
                }
                Command::Fields => {
                    let (p, m) = (solver.particles(), solver.materials());
                    Reply::SpaceFields(Box::new(SpaceFields {
                        position: p.position.iter().map(|v| v.to_array()).collect(),
                        velocity: p.velocity.iter().map(|v| v.to_array()).collect(),
                        stress: p
                            .stress
                            .iter()
                            .map(|s| [s.xx, s.yy, s.zz, s.xy, s.yz, s.zx])
                            .collect(),
                        mass: p.mass.clone(),
                        volume: p.volume.clone(),
                        initial_position: p.initial_position.iter().map(|v| v.to_array()).collect(),
                        body: p.body.clone(),
                        material: p.material.clone(),
                        plastic_strain: (0..p.len())
                            .map(|i| {
                                m[usize::from(p.material[i])].equivalent_plastic_strain(&p.state[i])
                            })
                            .collect(),
                    }))
                }
                Command::Energy => Reply::Energy(solver.energy()),
                Command::Summary => {
                    let status = if mpm_solver3d::reached(solver.time(), current.end_time) {
                        RunStatus::Completed
                    } else {
                        RunStatus::Interrupted
                    };
                    match summary(&solver, &current, &history, status, None) {
                        Ok(s) => Reply::Summary(Box::new(s)),
                        Err(e) => Reply::Failed(e),
                    }
                }
                Command::Checkpoint(dir) => Reply::Written(write_checkpoint(
                    &dir,
                    CheckpointFile::new(
                        current.origin(),
                        current.text(),
                        current.files_dir(),
                        current.inputs(),
                        M::wrap_space(solver.checkpoint()),
                        history.clone(),
                    ),
                )),
                _ if failed => {
                    Reply::Set(Err(RunError::Setup("the simulation failed earlier".into())))
                }
                Command::SetVelocities(v) => {
                    let v: Vec<Vector> =
                        v.chunks_exact(3).map(|c| Vector::new(c[0], c[1], c[2])).collect();
                    Reply::Set(solver.set_velocities(&v).map_err(|e| argument("velocities", e)))
                }
                Command::SetBodyForce(None) => {
                    solver.clear_body_force();
                    Reply::Set(Ok(()))
                }
                Command::SetBodyForce(Some(b)) => {
                    let b: Vec<Vector> =
                        b.chunks_exact(3).map(|c| Vector::new(c[0], c[1], c[2])).collect();
                    Reply::Set(
                        (solver.set_body_force(|p, _| b.get(p).copied().unwrap_or(Vector::NAN)))
                            .map_err(|e| argument("body_force", e)),
                    )
                }
                Command::SetMaterial { path, value } => {
                    Reply::Set(set_space_material(&mut solver, &mut current, &path, &value))
                }
            };
            if outbox.send(reply).is_err() {
                return;
            }
        }
    }
}

/// the 3D scene with `path` = `value`, validated, and its materials given to the solver (the
/// same model: a changed `kind` is refused).
fn set_space_material<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
    solver: &mut Solver<M, S, N>,
    current: &mut SpaceScene,
    path: &str,
    value: &str,
) -> Result<(), RunError> {
    let next = current.with_value(path, value)?;
    let materials = super::materials_of::<M>(&next.materials, path, value)?;
    solver.set_materials(materials).map_err(|e| argument(path, e))?;
    *current = next;
    Ok(())
}
