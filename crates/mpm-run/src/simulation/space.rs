//! The 3D worker of [`crate::Simulation`]: the 3D solver built with the scene's types, serving
//! the commands the 2D worker serves, recording through the 3D run's driver
//! ([`crate::space`]) as a run without an output folder does.

use mpm_grid3d::ShapeFunctions;
use mpm_output::checkpoint::{CheckpointFile, History};
use mpm_scene::SpaceScene;
use mpm_scene::dispatch::SceneModel;
use mpm_scene::space::{SpaceJob, space_particles};
use mpm_scene::summary::RunStatus;
use mpm_solver3d::{Solver, Vector};

use super::{Command, Limit, Reply, SpaceFields, Worker, argument, outcome, write_checkpoint};
use crate::common::setup_error;
use crate::driver::space::Space;
use crate::driver::{Driver, describe};
use crate::error::RunError;
use crate::options::RunOptions;

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
        let mut history = History { dt_min: f64::INFINITY, ..History::default() };
        {
            let wing = Space::new(&current, &history, &solver);
            let mut d = Driver::begin(wing, None, std::mem::take(&mut history), &opts);
            if let Err(e) = d.record_start(&solver) {
                let _ = outbox.send(Reply::Failed(e));
                return;
            }
            history = d.history;
        }
        let ready = Reply::Ready {
            time: solver.time(),
            steps: solver.step_count(),
            particles: solver.particles().len(),
        };
        if outbox.send(ready).is_err() {
            return;
        }
        let threads = rayon::current_num_threads();
        let mut failed = false;
        while let Ok(command) = inbox.recv() {
            let reply = match command {
                Command::Advance(_) if failed => {
                    Reply::Failed(RunError::Setup("the simulation failed earlier".into()))
                }
                Command::Advance(limit) => {
                    let wing = Space::new(&current, &history, &solver);
                    let mut d = Driver::begin(wing, None, std::mem::take(&mut history), &opts);
                    let result = match limit {
                        Limit::Time(t) => d.run(&mut solver, t),
                        Limit::Steps(n) => d.run_steps(&mut solver, n),
                    };
                    failed = result.is_err();
                    let reply = outcome(&solver, &d, result, threads, &describe::<Solver<M, S, N>>);
                    history = d.history;
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
                    let wing = Space::new(&current, &history, &solver);
                    let d = Driver::begin(wing, None, std::mem::take(&mut history), &opts);
                    let s = d.summary(&solver, status, None, threads);
                    history = d.history;
                    Reply::Summary(Box::new(s))
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
