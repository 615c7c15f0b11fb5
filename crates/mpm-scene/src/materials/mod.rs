//! The material registry: every constitutive model a scene can name with `kind = "..."` in
//! `[materials.NAME]`, listed once, in the [`registry!`] call below.
//!
//! # Adding a model
//! 1. Write the model in `mpm-constitutive` (a [`ConstitutiveModel`]: Δt reaches `update`, the
//!    time step asks `p_wave_modulus`, return branches are named by `BRANCHES`).
//! 2. Add a file here implementing [`SceneMaterial`] for it: the `KIND` name, the `TITLE` of
//!    messages, whether `OBJECTIVE_STRESS` defaults on, its parameter table (a
//!    `#[serde(deny_unknown_fields)]` struct) and how the table builds the model.
//! 3. Add one line to the registry: `Variant(Model)` under `models`, and the run types it
//!    stores in checkpoints under `states` (append only: a variant's position is part of the
//!    checkpoint format).
//! 4. Document its table in `docs/scene-format.md`.
//!
//! Nothing else changes: validation, the Δt, the run driver, checkpoints and output are
//! generic over the model.

mod drucker_prager;
mod elastic;
mod mu_i;

pub use drucker_prager::{ConeMatchSpec, DruckerPragerSpec};
pub use elastic::ElasticSpec;

use mpm_constitutive::{
    ConstitutiveError, ConstitutiveModel, DpPerfectState, DruckerPrager, LinearElastic, MuI,
    TangentModel,
};
use mpm_solver::Checkpoint;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

/// A constitutive model as a scene's run uses it: stored in checkpoints as one variant of
/// [`SavedState`], with its consistent tangent for the implicit initial state
/// (`[initial_state] method = "implicit"`).
pub trait SceneModel: TangentModel + Clone + std::fmt::Debug + 'static {
    /// wraps a solver checkpoint for storage.
    fn wrap(c: Checkpoint<Self::State>) -> SavedState;
    /// unwraps a stored checkpoint of this model (`None` for another model).
    fn unwrap(s: SavedState) -> Option<Checkpoint<Self::State>>;
}

/// A constitutive model a scene can name: `kind = KIND` in `[materials.NAME]`.
pub trait SceneMaterial: SceneModel {
    /// the `kind` that names the model in scene files.
    const KIND: &'static str;
    /// the model's name in messages.
    const TITLE: &'static str;
    /// whether `[solver] objective_stress` defaults to on for this model (models meant for
    /// large deformation: the Jaumann rate keeps stress objective under rotation).
    const OBJECTIVE_STRESS: bool;
    /// the default `[solver] pic_fraction` of its scenes: non-zero for granular models, whose
    /// deposits must come to rest (`mpm_solver::SolverConfig::pic_fraction`).
    const PIC_FRACTION: f64;
    /// the default `[solver] separation_density` of its scenes: non-zero for a granular model
    /// that does not track separation itself (Drucker-Prager; μ(I) has its own opening)
    /// (`mpm_solver::SolverConfig::separation_density`).
    const SEPARATION_DENSITY: f64;
    /// the table's parameters besides `kind` and `density`.
    type Spec: DeserializeOwned;
    /// builds the model from its parameters and the material's density (kg/m³); a refused
    /// value is a [`ConstitutiveError::InvalidParameter`] naming the table's field.
    fn build(spec: Self::Spec, density: f64) -> Result<Self, ConstitutiveError>;
    /// how to correct a refused field.
    fn fix(field: &str) -> &'static str {
        elastic_fix(field)
    }
    /// runs `job` with these materials, as the run type whose particles store the least
    /// state (the default: the model itself).
    fn run<J: ModelJob>(materials: Vec<Self>, job: J) -> J::Output {
        job.run(materials)
    }
}

/// Work generic over the model a scene's materials are.
pub trait ModelJob {
    /// what the job returns.
    type Output;
    /// runs with the concrete model.
    fn run<M: SceneModel>(self, materials: Vec<M>) -> Self::Output;
}

/// fixes for the elastic parameters every model has.
fn elastic_fix(field: &str) -> &'static str {
    match field {
        "young" => "give Young's modulus in Pa, e.g. 2e6 for loose sand",
        "poisson" => "use a Poisson's ratio below 0.5, e.g. 0.3",
        _ => "see docs/scene-format.md",
    }
}

/// Why a `[materials.NAME]` table does not build.
#[derive(Debug)]
pub(crate) enum BuildError {
    /// the `kind` is not registered.
    UnknownKind,
    /// the parameter table does not fit the model's (field path inside the table, serde
    /// message).
    Table(String, String),
    /// the model refused a value (with the model's fix for a field).
    Model(ConstitutiveError, fn(&str) -> &'static str),
}

/// Reads the parameter table as `M::Spec` and builds `M`.
fn parse<M: SceneMaterial>(params: toml::Table, density: f64) -> Result<M, BuildError> {
    let spec: M::Spec = serde_path_to_error::deserialize(toml::Value::Table(params))
        .map_err(|e| BuildError::Table(e.path().to_string(), e.inner().message().to_string()))?;
    M::build(spec, density).map_err(|e| BuildError::Model(e, M::fix))
}

/// Declares the registered models: the built-material enums, the checkpoint state enum and
/// the matches over them, so that the list below is the only place a model is named.
macro_rules! registry {
    (
        models { $( $variant:ident($model:ty) ),* $(,)? }
        states { $( $state:ident($run:ty) ),* $(,)? }
    ) => {
        /// One material, built.
        #[derive(Clone, Debug)]
        pub(crate) enum Built {
            $( $variant($model), )*
        }

        /// The materials a scene's bodies use, built, all of one model, in index order.
        #[derive(Clone, Debug)]
        pub enum MaterialsBuilt {
            $(
                #[doc = concat!("materials of the model `", stringify!($model), "`.")]
                $variant(Vec<$model>),
            )*
        }

        /// The registered `kind` names, in registry order.
        pub const KINDS: &[&str] = &[$( <$model as SceneMaterial>::KIND ),*];

        impl Built {
            /// builds a material of the registered `kind` from its parameter table.
            pub(crate) fn new(
                kind: &str,
                params: toml::Table,
                density: f64,
            ) -> Result<Self, BuildError> {
                $(
                    if kind == <$model as SceneMaterial>::KIND {
                        return parse::<$model>(params, density).map(Built::$variant);
                    }
                )*
                Err(BuildError::UnknownKind)
            }

            /// the model's `kind`.
            pub(crate) fn kind(&self) -> &'static str {
                match self {
                    $( Built::$variant(_) => <$model as SceneMaterial>::KIND, )*
                }
            }

            /// the model's name in messages.
            pub(crate) fn title(&self) -> &'static str {
                match self {
                    $( Built::$variant(_) => <$model as SceneMaterial>::TITLE, )*
                }
            }
        }

        impl MaterialsBuilt {
            /// the materials of one model; `Err(i)` names the first material of another model.
            pub(crate) fn collect(first: Built, rest: Vec<Built>) -> Result<Self, usize> {
                match first {
                    $(
                        Built::$variant(m) => {
                            let mut all = vec![m];
                            for (i, b) in rest.into_iter().enumerate() {
                                match b {
                                    Built::$variant(m) => all.push(m),
                                    #[allow(unreachable_patterns)]
                                    _ => return Err(i + 1),
                                }
                            }
                            Ok(MaterialsBuilt::$variant(all))
                        }
                    )*
                }
            }

            /// runs `job` with the concrete model (see [`SceneMaterial::run`]).
            pub fn run<J: ModelJob>(&self, job: J) -> J::Output {
                match self {
                    $( MaterialsBuilt::$variant(m) => <$model as SceneMaterial>::run(m.clone(), job), )*
                }
            }

            /// the `kind` of the materials.
            pub fn kind(&self) -> &'static str {
                match self {
                    $( MaterialsBuilt::$variant(_) => <$model as SceneMaterial>::KIND, )*
                }
            }

            /// the default `[solver] separation_density`.
            pub fn separation_density(&self) -> f64 {
                match self {
                    $( MaterialsBuilt::$variant(_) => <$model as SceneMaterial>::SEPARATION_DENSITY, )*
                }
            }

            /// the default `[solver] pic_fraction`.
            pub fn pic_fraction(&self) -> f64 {
                match self {
                    $( MaterialsBuilt::$variant(_) => <$model as SceneMaterial>::PIC_FRACTION, )*
                }
            }

            /// whether `[solver] objective_stress` defaults to on.
            pub fn objective_stress(&self) -> bool {
                match self {
                    $( MaterialsBuilt::$variant(_) => <$model as SceneMaterial>::OBJECTIVE_STRESS, )*
                }
            }
        }

        /// A solver state of any registered model, as stored in checkpoint files. Variants
        /// are only ever appended: bincode stores a variant's position.
        #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
        pub enum SavedState {
            $(
                #[doc = concat!("a run of `", stringify!($run), "`.")]
                $state(Checkpoint<<$run as ConstitutiveModel>::State>),
            )*
        }

        impl SavedState {
            /// (simulated time, steps, particles) of the stored state.
            pub fn clock(&self) -> (f64, u64, usize) {
                match self {
                    $( SavedState::$state(c) => (c.time, c.step, c.particles.len()), )*
                }
            }
        }

        $(
            impl SceneModel for $run {
                fn wrap(c: Checkpoint<<$run as ConstitutiveModel>::State>) -> SavedState {
                    SavedState::$state(c)
                }
                fn unwrap(
                    s: SavedState,
                ) -> Option<Checkpoint<<$run as ConstitutiveModel>::State>> {
                    match s {
                        SavedState::$state(c) => Some(c),
                        #[allow(unreachable_patterns)]
                        _ => None,
                    }
                }
            }
        )*
    };
}

registry! {
    models {
        Elastic(LinearElastic),
        DruckerPrager(DruckerPrager),
        MuI(MuI),
    }
    states {
        Elastic(LinearElastic),
        Plastic(DruckerPrager),
        PerfectlyPlastic(DruckerPrager<DpPerfectState>),
        MuI(MuI),
    }
}

impl MaterialsBuilt {
    /// each material's P-wave modulus M = λ + 2G (Pa) in its initial state, in index order:
    /// c = √(M/ρ) is its wave speed (eq 13).
    pub fn p_wave_moduli(&self) -> Vec<f64> {
        struct Moduli;
        impl ModelJob for Moduli {
            type Output = Vec<f64>;
            fn run<M: SceneModel>(self, materials: Vec<M>) -> Vec<f64> {
                materials.iter().map(|m| m.p_wave_modulus(&m.initial_state())).collect()
            }
        }
        self.run(Moduli)
    }

    /// bytes of constitutive state per particle a run of these materials stores.
    pub fn state_bytes(&self) -> usize {
        struct Bytes;
        impl ModelJob for Bytes {
            type Output = usize;
            fn run<M: SceneModel>(self, _materials: Vec<M>) -> usize {
                std::mem::size_of::<M::State>()
            }
        }
        self.run(Bytes)
    }
}
