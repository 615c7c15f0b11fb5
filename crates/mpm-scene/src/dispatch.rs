//! The one place where a scene's run-time choices become types: constitutive model
//! (elastic | Drucker-Prager, with particles storing the mixed-hardening variables only when some
//! material hardens) × grid with shape functions (bilinear on the terrain grid, bilinear | uGIMP |
//! quadratic B-spline on the regular grid). [`dispatch`] matches once per scene and calls a
//! generic [`Job`]; everything below runs monomorphised, with no per-particle dynamic dispatch.

use mpm_constitutive::{
    ConstitutiveModel, DpPerfectState, DpState, DruckerPrager, LinearElastic, PlaneTensor,
};
use mpm_grid::{Bilinear, RegularShape, ShapeFunctions, ShapeJob, with_regular_shape};
use mpm_solver::{Checkpoint, NewParticle, Particles};
use serde::{Deserialize, Serialize};

use crate::error::SceneError;
use crate::file::ShapeFunctionKind;
use crate::scene::{GridBuilt, MaterialsBuilt, Scene, Seed};

/// A solver state of either model, as stored in checkpoint files.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum SavedState {
    /// elastic scenes.
    Elastic(Checkpoint<()>),
    /// Drucker-Prager scenes with a hardening material.
    Plastic(Checkpoint<DpState>),
    /// Drucker-Prager scenes whose materials do not harden (`H = 0`).
    PerfectlyPlastic(Checkpoint<DpPerfectState>),
}

impl SavedState {
    /// (simulated time, steps, particles) of the stored state.
    pub fn clock(&self) -> (f64, u64, usize) {
        match self {
            SavedState::Elastic(c) => (c.time, c.step, c.particles.len()),
            SavedState::Plastic(c) => (c.time, c.step, c.particles.len()),
            SavedState::PerfectlyPlastic(c) => (c.time, c.step, c.particles.len()),
        }
    }
}

/// A constitutive model a scene can use.
pub trait SceneModel: ConstitutiveModel + Clone + 'static {
    /// wraps a solver checkpoint for storage.
    fn wrap(c: Checkpoint<Self::State>) -> SavedState;
    /// unwraps a stored checkpoint of this model (`None` for the other model).
    fn unwrap(s: SavedState) -> Option<Checkpoint<Self::State>>;
}

impl SceneModel for LinearElastic {
    fn wrap(c: Checkpoint<()>) -> SavedState {
        SavedState::Elastic(c)
    }
    fn unwrap(s: SavedState) -> Option<Checkpoint<()>> {
        match s {
            SavedState::Elastic(c) => Some(c),
            _ => None,
        }
    }
}

impl SceneModel for DruckerPrager {
    fn wrap(c: Checkpoint<DpState>) -> SavedState {
        SavedState::Plastic(c)
    }
    fn unwrap(s: SavedState) -> Option<Checkpoint<DpState>> {
        match s {
            SavedState::Plastic(c) => Some(c),
            _ => None,
        }
    }
}

impl SceneModel for DruckerPrager<DpPerfectState> {
    fn wrap(c: Checkpoint<DpPerfectState>) -> SavedState {
        SavedState::PerfectlyPlastic(c)
    }
    fn unwrap(s: SavedState) -> Option<Checkpoint<DpPerfectState>> {
        match s {
            SavedState::PerfectlyPlastic(c) => Some(c),
            _ => None,
        }
    }
}

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
    match &r.materials {
        MaterialsBuilt::Elastic(m) => with_shape(scene, job, m.clone()),
        // A scene pays for the hardening variables (64 B per particle) only if it hardens.
        MaterialsBuilt::Plastic(m) => match r.materials.without_hardening() {
            Some(perfect) => with_shape(scene, job, perfect),
            None => with_shape(scene, job, m.clone()),
        },
    }
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
            .modified(|f| f.materials.get_mut("sand").unwrap().hardening_modulus = Some(1.0e4))
            .unwrap();
        assert_eq!(dispatch(&hardening, StateBytes).unwrap(), 64);
        let elastic = load_scene_str(embedded_scene("free_fall").unwrap(), "free_fall").unwrap();
        assert_eq!(dispatch(&elastic, StateBytes).unwrap(), 0);
    }
}
