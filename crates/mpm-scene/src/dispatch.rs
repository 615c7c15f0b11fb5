//! The one place where a scene's run-time choices become types: constitutive model (any model
//! of the registry in `materials`, as the run type that stores the least state per particle)
//! × grid with shape functions (bilinear on the terrain grid, bilinear | uGIMP | quadratic
//! B-spline on the regular grid). [`dispatch`] matches once per scene and calls a generic
//! [`Job`]; everything below runs monomorphised, with no per-particle dynamic dispatch.

use mpm_constitutive::PlaneTensor;
use mpm_grid::{Bilinear, RegularShape, ShapeFunctions, ShapeJob, with_regular_shape};
use mpm_solver::{NewParticle, Particles};

use crate::error::SceneError;
use crate::file::ShapeFunctionKind;
pub use crate::materials::{AnyModel, AnyState, ModelJob, SavedState, SceneModel};
use crate::scene::{GridBuilt, Scene, Seed};

/// Work generic over the model and the shape functions.
pub trait Job {
    /// what the job returns.
    type Output;
    /// runs with concrete types.
    fn run<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
        self,
        scene: &Scene,
        shape: S,
        materials: Vec<M>,
    ) -> Self::Output;
}

/// Builds the scene's shape functions and materials and runs `job` with them.
pub fn dispatch<J: Job>(scene: &Scene, job: J) -> Result<J::Output, SceneError> {
    let r = &scene.r;
    fn with_shape<J: Job, M: SceneModel>(
        scene: &Scene,
        job: J,
        materials: Vec<M>,
    ) -> Result<J::Output, SceneError> {
        /// the scene's job as a job over the shape functions alone.
        struct WithModel<'a, J, M> {
            job: J,
            scene: &'a Scene,
            materials: Vec<M>,
        }
        impl<J: Job, M: SceneModel> ShapeJob for WithModel<'_, J, M> {
            type Output = J::Output;
            fn run<S: ShapeFunctions<N>, const N: usize>(self, shape: S) -> J::Output {
                self.job.run(self.scene, shape, self.materials)
            }
        }
        let r = &scene.r;
        match &r.grid {
            GridBuilt::Terrain(t) => Ok(job.run(scene, Bilinear(t.clone()), materials)),
            GridBuilt::Regular(g) => {
                let kind = match r.shape_function {
                    ShapeFunctionKind::Bilinear => RegularShape::Bilinear,
                    ShapeFunctionKind::Gimp => RegularShape::Gimp,
                    ShapeFunctionKind::Bspline => RegularShape::BSpline,
                };
                let job = WithModel { job, scene, materials };
                with_regular_shape(kind, *g, r.gimp_ppc, job).map_err(|e| SceneError {
                    origin: scene.origin.clone(),
                    line: None,
                    column: None,
                    path: "solver.shape_function".into(),
                    value: Some(format!("\"{}\"", r.shape_function.name())),
                    problem: e.to_string(),
                    admissible: "particles_per_cell ≥ 1".into(),
                    fix: "check particles_per_cell".into(),
                })
            }
        }
    }
    /// the scene's job as a job over the model alone.
    struct WithScene<'a, J> {
        job: J,
        scene: &'a Scene,
    }
    impl<J: Job> ModelJob for WithScene<'_, J> {
        type Output = Result<J::Output, SceneError>;
        fn run<M: SceneModel>(self, materials: Vec<M>) -> Self::Output {
            with_shape(self.scene, self.job, materials)
        }
    }
    r.materials.run(WithScene { job, scene })
}

/// The scene's particles with each material's initial state.
pub fn particles<M: SceneModel>(seeds: &[Seed], materials: &[M]) -> Particles<M::State> {
    let mut p = Particles::with_capacity(seeds.len());
    for s in seeds {
        let state =
            materials.get(usize::from(s.material)).map(|m| m.initial_state()).unwrap_or_default();
        p.push(NewParticle {
            position: s.position,
            velocity: s.velocity,
            volume: s.volume,
            density: s.density,
            stress: PlaneTensor::ZERO,
            state,
            material: s.material,
            body: s.body,
        });
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenes::embedded_scene;
    use crate::validate::load_scene_str;

    /// the bytes of constitutive state a scene's particles carry.
    struct StateBytes;

    impl Job for StateBytes {
        type Output = usize;
        fn run<M: SceneModel, S: ShapeFunctions<N>, const N: usize>(
            self,
            _scene: &Scene,
            _shape: S,
            _materials: Vec<M>,
        ) -> usize {
            std::mem::size_of::<M::State>()
        }
    }

    /// The paper's sand does not harden, so its particles store only ε̄ᵖ; a hardening material
    /// in the same scene brings k and β back.
    #[test]
    fn a_scene_stores_hardening_variables_only_when_a_material_hardens() {
        let flume = load_scene_str(embedded_scene("flume").unwrap(), "flume").unwrap();
        assert_eq!(dispatch(&flume, StateBytes).unwrap(), 8);
        let hardening = flume
            .modified(|f| f.materials.get_mut("sand").unwrap().set("hardening_modulus", 1.0e4))
            .unwrap();
        assert_eq!(dispatch(&hardening, StateBytes).unwrap(), 64);
        let elastic = load_scene_str(embedded_scene("free_fall").unwrap(), "free_fall").unwrap();
        assert_eq!(dispatch(&elastic, StateBytes).unwrap(), 0);
    }
}
