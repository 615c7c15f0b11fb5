//! The 3D worker of [`crate::Simulation`]: the 3D solver built with the scene's types, serving
//! the caller's commands through the loop both dimensions share (`serve.rs`), recording through
//! the run driver with its 3D wing ([`crate::driver`]) as a run without an output folder does.

use mpm_grid3d::ShapeFunctions;
use mpm_output::checkpoint::History;
use mpm_scene::InitialStateSummary;
use mpm_scene::SpaceScene;
use mpm_scene::dispatch::SceneModel;
use mpm_scene::space::{SpaceJob, space_particles};
use mpm_solver3d::{Solver, Vector};

use super::serve::{Served, serve};
use super::{Reply, SpaceFields, Worker, argument};
use crate::common::setup_error;
use crate::driver::space::Space;
use crate::error::RunError;
use crate::options::RunOptions;

/// The 3D side of [`crate::Simulation`]: builds the 3D solver with the scene's types and serves
/// the caller's commands through the shared loop (`serve.rs`).
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
        serve(&mut solver, scene, None, inbox, outbox, &opts);
    }
}

impl<M: SceneModel, S: ShapeFunctions<N>, const N: usize> Served for Solver<M, S, N> {
    type Scene = SpaceScene;
    type Wing<'a> = Space<'a>;

    fn wing<'a>(
        &self,
        scene: &'a SpaceScene,
        h: &History,
        _initial: &Option<InitialStateSummary>,
    ) -> Space<'a> {
        Space::new(scene, h, self)
    }

    fn end_time(scene: &SpaceScene) -> f64 {
        scene.end_time
    }

    fn fields(&self) -> Reply {
        let (p, m) = (self.particles(), self.materials());
        Reply::SpaceFields(Box::new(SpaceFields {
            position: p.position.iter().map(|v| v.to_array()).collect(),
            velocity: p.velocity.iter().map(|v| v.to_array()).collect(),
            stress: p.stress.iter().map(|s| [s.xx, s.yy, s.zz, s.xy, s.yz, s.zx]).collect(),
            mass: p.mass.clone(),
            volume: p.volume.clone(),
            initial_position: p.initial_position.iter().map(|v| v.to_array()).collect(),
            body: p.body.clone(),
            material: p.material.clone(),
            plastic_strain: (0..p.len())
                .map(|i| m[usize::from(p.material[i])].equivalent_plastic_strain(&p.state[i]))
                .collect(),
        }))
    }

    fn set_velocities_flat(&mut self, v: &[f64]) -> Result<(), RunError> {
        let v: Vec<Vector> = v.chunks_exact(3).map(|c| Vector::new(c[0], c[1], c[2])).collect();
        self.set_velocities(&v).map_err(|e| argument("velocities", e))
    }

    fn set_body_force_flat(&mut self, b: Option<&[f64]>) -> Result<(), RunError> {
        let Some(b) = b else {
            self.clear_body_force();
            return Ok(());
        };
        let b: Vec<Vector> = b.chunks_exact(3).map(|c| Vector::new(c[0], c[1], c[2])).collect();
        (self.set_body_force(|p, _| b.get(p).copied().unwrap_or(Vector::NAN)))
            .map_err(|e| argument("body_force", e))
    }

    fn set_material(
        &mut self,
        current: &mut SpaceScene,
        path: &str,
        value: &str,
    ) -> Result<(), RunError> {
        let next = current.with_value(path, value)?;
        let materials = super::materials_of::<M>(&next.materials, path, value)?;
        self.set_materials(materials).map_err(|e| argument(path, e))?;
        *current = next;
        Ok(())
    }
}
