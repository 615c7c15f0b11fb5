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
//!    stores in checkpoints under `states` (both lists append only: a variant's position is
//!    part of the checkpoint format, `models` through the state of a mixed scene, `AnyState`).
//! 4. Document its table in `docs/scene-format.md`.
//!
//! Nothing else changes: validation, the Δt, the run driver, checkpoints and output are
//! generic over the model.

mod drucker_prager;
mod elastic;
mod mohr_coulomb;
mod mu_i;

pub use elastic::ElasticSpec;
pub use mohr_coulomb::MohrCoulombSpec;

use glam::DMat3;
use mpm_constitutive::{
    Branch, ConstitutiveError, ConstitutiveModel, DpPerfectState, DruckerPrager, LinearElastic,
    MAX_BRANCHES, MohrCoulomb, MuI, PlaneTensor, SymTensor, Tangent, TangentModel, UpdateReport,
};
use mpm_solver::Checkpoint;
use mpm_solver3d::Checkpoint as SpaceCheckpoint;
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
    /// wraps a checkpoint of the 3D solver (`mpm-solver3d`) for storage.
    fn wrap_space(c: SpaceCheckpoint<Self::State>) -> SavedState;
    /// unwraps a stored 3D checkpoint of this model (`None` for another model or a 2D one).
    fn unwrap_space(s: SavedState) -> Option<SpaceCheckpoint<Self::State>>;
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
    /// whether the model's bodies are the flow (granular: their runout, envelope and deposit
    /// are measured) or, beside a flowing model in a mixed scene, a structure it meets
    /// (elastic bedrock, an obstacle), left out of those measures.
    const FLOWS: bool;
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

/// The branches of several models as one list: the shared elastic branch (index 0), then each
/// model's other branches in registry order.
struct BranchUnion<const K: usize> {
    /// the names, the first `len` used.
    names: [&'static str; MAX_BRANCHES],
    /// how many names there are.
    len: usize,
    /// where model k's branch 1 lands, minus 1.
    offsets: [u8; K],
}

impl<const K: usize> BranchUnion<K> {
    /// the union of the models' branch lists (a build error if it exceeds [`MAX_BRANCHES`]).
    const fn new(lists: [&'static [&'static str]; K]) -> Self {
        let mut names = [""; MAX_BRANCHES];
        names[0] = "elastic";
        let (mut len, mut offsets, mut k) = (1, [0u8; K], 0);
        while k < K {
            offsets[k] = (len - 1) as u8;
            let mut i = 1;
            while i < lists[k].len() {
                assert!(len < MAX_BRANCHES, "the registered models name too many branches");
                names[len] = lists[k][i];
                len += 1;
                i += 1;
            }
            k += 1;
        }
        Self { names, len, offsets }
    }

    /// the first `L` names (`L` = `len`).
    const fn names<const L: usize>(&self) -> [&'static str; L] {
        assert!(L == self.len, "the branch list's length");
        let mut out = [""; L];
        let mut i = 0;
        while i < L {
            out[i] = self.names[i];
            i += 1;
        }
        out
    }

    /// model `k`'s report with its branch renumbered into the union.
    #[inline(always)]
    fn report(&self, k: usize, mut r: UpdateReport) -> UpdateReport {
        let i = r.branch.index();
        if i > 0 {
            r.branch = Branch::new(self.offsets[k] + i as u8);
        }
        r
    }
}

/// Declares the registered models: the built-material enums, the checkpoint state enum and
/// the matches over them, so that the list below is the only place a model is named.
macro_rules! registry {
    (
        models { $( $variant:ident($model:ty) ),* $(,)? }
        states { $( $state:ident / $space:ident ($run:ty) ),* $(,)? }
    ) => {
        /// One material of any registered model, built: what a `[materials.NAME]` table
        /// becomes, and the run type of a scene whose bodies use materials of several models
        /// (sand on elastic bedrock). Each point is updated by its own material's model through
        /// a `match` on this enum (static dispatch, no virtual call); particles are stored in
        /// body order, so a material's points are contiguous and the branch is predicted.
        #[derive(Clone, Debug)]
        pub enum AnyModel {
            $(
                #[doc = concat!("a material of the model `", stringify!($model), "`.")]
                $variant($model),
            )*
        }

        /// The internal variables of a point of an [`AnyModel`] material: its own model's.
        #[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
        pub enum AnyState {
            $(
                #[doc = concat!("the state of a point of `", stringify!($model), "`.")]
                $variant(<$model as ConstitutiveModel>::State),
            )*
        }

        /// The registry position of each model (the index into [`ANY_BRANCHES`]' offsets).
        #[derive(Clone, Copy)]
        #[repr(u8)]
        enum Position {
            $( $variant, )*
        }

        /// The branch names of [`AnyModel`] (every model's, its elastic branch shared) and
        /// where each model's plastic branches start.
        const ANY_BRANCHES: BranchUnion<{ [$( stringify!($variant) ),*].len() }> =
            BranchUnion::new([$( <$model as ConstitutiveModel>::BRANCHES ),*]);

        /// The branch names of [`AnyModel`].
        const ANY_BRANCH_NAMES: [&str; ANY_BRANCHES.len] = ANY_BRANCHES.names();

        impl Default for AnyState {
            /// the state of the first registered model (never used: a point's state comes from
            /// its material's [`ConstitutiveModel::initial_state`]).
            fn default() -> Self {
                [$( AnyState::$variant(Default::default()) ),*][0]
            }
        }

        impl AnyState {
            /// the model the state belongs to, for messages.
            fn title(&self) -> &'static str {
                match self {
                    $( AnyState::$variant(_) => <$model as SceneMaterial>::TITLE, )*
                }
            }
        }

        impl ConstitutiveModel for AnyModel {
            type State = AnyState;
            const IS_PLASTIC: bool = false $( || <$model as ConstitutiveModel>::IS_PLASTIC )*;
            const BRANCHES: &'static [&'static str] = &ANY_BRANCH_NAMES;
            const WAVE_SPEED_VARIES: bool =
                false $( || <$model as ConstitutiveModel>::WAVE_SPEED_VARIES )*;

            fn initial_state(&self) -> AnyState {
                match self {
                    $( AnyModel::$variant(m) => AnyState::$variant(ConstitutiveModel::initial_state(m)), )*
                }
            }

            fn carried_state(&self, previous: &Self, state: &AnyState) -> AnyState {
                match (self, previous, state) {
                    $(
                        (AnyModel::$variant(m), AnyModel::$variant(p), AnyState::$variant(s)) => {
                            AnyState::$variant(ConstitutiveModel::carried_state(m, p, s))
                        }
                    )*
                    _ => *state,
                }
            }

            fn p_wave_modulus(&self, state: &AnyState) -> f64 {
                match (self, state) {
                    $( (AnyModel::$variant(m), AnyState::$variant(s)) => ConstitutiveModel::p_wave_modulus(m, s), )*
                    // a foreign state is refused by the next update; its material's initial
                    // stiffness keeps the time step meaningful until then.
                    #[allow(unreachable_patterns)]
                    _ => self.p_wave_modulus(&self.initial_state()),
                }
            }

            fn stored_energy_density(&self, sigma: &SymTensor, state: &AnyState) -> f64 {
                match (self, state) {
                    $(
                        (AnyModel::$variant(m), AnyState::$variant(s)) => {
                            ConstitutiveModel::stored_energy_density(m, sigma, s)
                        }
                    )*
                    #[allow(unreachable_patterns)]
                    _ => self.stored_energy_density(sigma, &self.initial_state()),
                }
            }

            fn update(
                &self,
                sigma: &mut SymTensor,
                state: &mut AnyState,
                d_eps: &SymTensor,
                dt: f64,
            ) -> Result<UpdateReport, ConstitutiveError> {
                match (self, state) {
                    $(
                        (AnyModel::$variant(m), AnyState::$variant(s)) => ConstitutiveModel::update(m, sigma, s, d_eps, dt)
                            .map(|r| ANY_BRANCHES.report(Position::$variant as usize, r)),
                    )*
                    #[allow(unreachable_patterns)]
                    (m, s) => Err(m.foreign(s)),
                }
            }

            #[inline(always)]
            fn update_plane(
                &self,
                sigma: &mut PlaneTensor,
                state: &mut AnyState,
                d_eps: &PlaneTensor,
                dt: f64,
                rotation: Option<(f64, f64)>,
            ) -> Result<UpdateReport, ConstitutiveError> {
                match (self, state) {
                    $(
                        (AnyModel::$variant(m), AnyState::$variant(s)) => ConstitutiveModel::update_plane(m, sigma, s, d_eps, dt, rotation)
                            .map(|r| ANY_BRANCHES.report(Position::$variant as usize, r)),
                    )*
                    #[allow(unreachable_patterns)]
                    (m, s) => Err(m.foreign(s)),
                }
            }

            fn rotate_state(&self, state: &mut AnyState, r: &DMat3) {
                match (self, state) {
                    $( (AnyModel::$variant(m), AnyState::$variant(s)) => ConstitutiveModel::rotate_state(m, s, r), )*
                    #[allow(unreachable_patterns)]
                    _ => {}
                }
            }

            #[inline(always)]
            fn rotate_state_z(&self, state: &mut AnyState, c: f64, sn: f64) {
                match (self, state) {
                    $(
                        (AnyModel::$variant(m), AnyState::$variant(s)) => {
                            ConstitutiveModel::rotate_state_z(m, s, c, sn)
                        }
                    )*
                    #[allow(unreachable_patterns)]
                    _ => {}
                }
            }

            fn equivalent_plastic_strain(&self, state: &AnyState) -> f64 {
                match (self, state) {
                    $(
                        (AnyModel::$variant(m), AnyState::$variant(s)) => {
                            ConstitutiveModel::equivalent_plastic_strain(m, s)
                        }
                    )*
                    #[allow(unreachable_patterns)]
                    _ => 0.0,
                }
            }
        }

        impl TangentModel for AnyModel {
            fn consistent_tangent(
                &self,
                sigma: &SymTensor,
                state: &AnyState,
                d_eps: &SymTensor,
                dt: f64,
            ) -> Result<Tangent, ConstitutiveError> {
                match (self, state) {
                    $(
                        (AnyModel::$variant(m), AnyState::$variant(s)) => {
                            TangentModel::consistent_tangent(m, sigma, s, d_eps, dt)
                        }
                    )*
                    #[allow(unreachable_patterns)]
                    (m, s) => Err(m.foreign(s)),
                }
            }
        }

        /// The materials a scene's bodies use, built, in index order: of one model, run as
        /// that model, or of several, run as [`AnyModel`].
        #[derive(Clone, Debug)]
        pub enum MaterialsBuilt {
            $(
                #[doc = concat!("materials of the model `", stringify!($model), "`.")]
                $variant(Vec<$model>),
            )*
            /// materials of several models.
            Mixed(Vec<AnyModel>),
        }

        /// The registered `kind` names, in registry order.
        pub const KINDS: &[&str] = &[$( <$model as SceneMaterial>::KIND ),*];

        impl AnyModel {
            /// builds a material of the registered `kind` from its parameter table.
            pub(crate) fn new(
                kind: &str,
                params: toml::Table,
                density: f64,
            ) -> Result<Self, BuildError> {
                $(
                    if kind == <$model as SceneMaterial>::KIND {
                        return parse::<$model>(params, density).map(AnyModel::$variant);
                    }
                )*
                Err(BuildError::UnknownKind)
            }

            /// the model's `kind`.
            pub fn kind(&self) -> &'static str {
                match self {
                    $( AnyModel::$variant(_) => <$model as SceneMaterial>::KIND, )*
                }
            }

            /// the model's name in messages.
            pub fn title(&self) -> &'static str {
                match self {
                    $( AnyModel::$variant(_) => <$model as SceneMaterial>::TITLE, )*
                }
            }
        }

        impl AnyModel {
            /// the error of a point whose state is another model's.
            fn foreign(&self, state: &AnyState) -> ConstitutiveError {
                ConstitutiveError::ForeignState { expected: self.title(), found: state.title() }
            }

            /// the `[solver] separation_density` default of the model's scenes.
            fn separation_density(&self) -> f64 {
                match self {
                    $( AnyModel::$variant(_) => <$model as SceneMaterial>::SEPARATION_DENSITY, )*
                }
            }

            /// whether the material's bodies are the flow ([`SceneMaterial::FLOWS`]).
            pub fn flows(&self) -> bool {
                match self {
                    $( AnyModel::$variant(_) => <$model as SceneMaterial>::FLOWS, )*
                }
            }

            /// the `[solver] pic_fraction` default of the model's scenes.
            fn pic_fraction(&self) -> f64 {
                match self {
                    $( AnyModel::$variant(_) => <$model as SceneMaterial>::PIC_FRACTION, )*
                }
            }

            /// whether `[solver] objective_stress` defaults to on for the model.
            fn objective_stress(&self) -> bool {
                match self {
                    $( AnyModel::$variant(_) => <$model as SceneMaterial>::OBJECTIVE_STRESS, )*
                }
            }
        }

        impl MaterialsBuilt {
            /// the materials, in index order: as their model's own run type when they are all
            /// of one model, else as [`AnyModel`].
            pub(crate) fn collect(all: Vec<AnyModel>) -> Self {
                $(
                    if all.iter().all(|m| matches!(m, AnyModel::$variant(_))) {
                        let one = all.iter().filter_map(|m| match m {
                            AnyModel::$variant(m) => Some(m.clone()),
                            #[allow(unreachable_patterns)]
                            _ => None,
                        });
                        return MaterialsBuilt::$variant(one.collect());
                    }
                )*
                MaterialsBuilt::Mixed(all)
            }

            /// runs `job` with the concrete model (see [`SceneMaterial::run`]).
            pub fn run<J: ModelJob>(&self, job: J) -> J::Output {
                match self {
                    $( MaterialsBuilt::$variant(m) => <$model as SceneMaterial>::run(m.clone(), job), )*
                    MaterialsBuilt::Mixed(m) => job.run(m.clone()),
                }
            }

            /// material `i` (index order) as an [`AnyModel`].
            pub fn get(&self, i: usize) -> Option<AnyModel> {
                match self {
                    $( MaterialsBuilt::$variant(m) => m.get(i).cloned().map(AnyModel::$variant), )*
                    MaterialsBuilt::Mixed(m) => m.get(i).cloned(),
                }
            }

            /// in a scene of flowing and structural materials ([`SceneMaterial::FLOWS`]), which
            /// materials (index order) are the flow that the runout measures; `None` when all
            /// bodies are measured.
            pub fn flow_mask(&self) -> Option<Vec<bool>> {
                let MaterialsBuilt::Mixed(m) = self else { return None };
                let mask: Vec<bool> = m.iter().map(AnyModel::flows).collect();
                (mask.contains(&true) && mask.contains(&false)).then_some(mask)
            }

            /// the `kind` of the materials (`"mixed"` for several).
            pub fn kind(&self) -> &'static str {
                match self {
                    $( MaterialsBuilt::$variant(_) => <$model as SceneMaterial>::KIND, )*
                    MaterialsBuilt::Mixed(_) => "mixed",
                }
            }

            /// the default `[solver] separation_density`: with several models, the largest of
            /// theirs (a granular body's threshold; an elastic body never halves its density).
            pub fn separation_density(&self) -> f64 {
                match self {
                    $( MaterialsBuilt::$variant(_) => <$model as SceneMaterial>::SEPARATION_DENSITY, )*
                    MaterialsBuilt::Mixed(m) => {
                        m.iter().map(AnyModel::separation_density).fold(0.0, f64::max)
                    }
                }
            }

            /// the default `[solver] pic_fraction`: with several models, the largest of theirs
            /// (a granular body's deposit must come to rest).
            pub fn pic_fraction(&self) -> f64 {
                match self {
                    $( MaterialsBuilt::$variant(_) => <$model as SceneMaterial>::PIC_FRACTION, )*
                    MaterialsBuilt::Mixed(m) => {
                        m.iter().map(AnyModel::pic_fraction).fold(0.0, f64::max)
                    }
                }
            }

            /// whether `[solver] objective_stress` defaults to on: with several models, when
            /// any of theirs does.
            pub fn objective_stress(&self) -> bool {
                match self {
                    $( MaterialsBuilt::$variant(_) => <$model as SceneMaterial>::OBJECTIVE_STRESS, )*
                    MaterialsBuilt::Mixed(m) => m.iter().any(AnyModel::objective_stress),
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
            $(
                #[doc = concat!("a 3D run of `", stringify!($run), "`.")]
                $space(SpaceCheckpoint<<$run as ConstitutiveModel>::State>),
            )*
        }

        impl SavedState {
            /// (simulated time, steps, particles the run started with) of the stored state:
            /// the particles it holds and those that left through outflow faces.
            pub fn clock(&self) -> (f64, u64, u64) {
                match self {
                    $( SavedState::$state(c) => (
                        c.time,
                        c.step,
                        (c.particles.len() as u64).saturating_add(c.dissipation.outflow.particles),
                    ), )*
                    $( SavedState::$space(c) => (
                        c.time,
                        c.step,
                        (c.particles.len() as u64).saturating_add(c.dissipation.outflow.particles),
                    ), )*
                }
            }

            /// the dimension of the run the state belongs to (2 or 3).
            pub fn dimension(&self) -> u8 {
                match self {
                    $( SavedState::$state(_) => 2, )*
                    $( SavedState::$space(_) => 3, )*
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
                fn wrap_space(
                    c: SpaceCheckpoint<<$run as ConstitutiveModel>::State>,
                ) -> SavedState {
                    SavedState::$space(c)
                }
                fn unwrap_space(
                    s: SavedState,
                ) -> Option<SpaceCheckpoint<<$run as ConstitutiveModel>::State>> {
                    match s {
                        SavedState::$space(c) => Some(c),
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
        MohrCoulomb(MohrCoulomb),
    }
    // (2D variant / 3D variant: the 3D ones follow all the 2D ones in checkpoint files)
    states {
        Elastic / SpaceElastic (LinearElastic),
        Plastic / SpacePlastic (DruckerPrager),
        PerfectlyPlastic / SpacePerfectlyPlastic (DruckerPrager<DpPerfectState>),
        MuI / SpaceMuI (MuI),
        Mixed / SpaceMixed (AnyModel),
        MohrCoulomb / SpaceMohrCoulomb (MohrCoulomb),
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

#[cfg(test)]
mod tests {
    use super::*;
    use mpm_constitutive::PlaneTensor;

    /// a material of `kind` from its table's text (besides `kind`).
    fn material(kind: &str, table: &str, density: f64) -> AnyModel {
        AnyModel::new(kind, toml::from_str(table).unwrap(), density)
            .unwrap_or_else(|_| panic!("{kind} does not build"))
    }

    fn sand() -> AnyModel {
        let dp = "young = 2e6\npoisson = 0.3\ncohesion = 0.0\nfriction_angle_deg = 30.0";
        material("drucker_prager", dp, 1600.0)
    }

    fn beads() -> AnyModel {
        let mu = "young = 2e6\npoisson = 0.3\nmu_s = 0.38\nmu_2 = 0.64\ni0 = 0.28\n\
                  grain_diameter = 0.5e-3\ngrain_density = 2450.0";
        material("mu_i", mu, 1470.0)
    }

    /// The composite names each model's branches once, the elastic one shared, and a point's
    /// report names the branch its own model took.
    #[test]
    fn a_mixed_run_reports_each_models_own_branches() {
        assert_eq!(
            AnyModel::BRANCHES,
            [
                "elastic",
                "cone",
                "apex",
                "flowing",
                "separated",
                "face",
                "compression_edge",
                "extension_edge",
                "vertex"
            ]
        );
        let (sand, beads) = (sand(), beads());
        let confined = PlaneTensor::new(-1e3, -1e3, -1e3, 0.0);
        // a large shear pushes both past yield
        let shear = PlaneTensor::new(0.0, 0.0, 0.0, 1e-2);
        for (m, expected) in [(&sand, "cone"), (&beads, "flowing")] {
            let (mut sigma, mut state) = (confined, m.initial_state());
            let r = m.update_plane(&mut sigma, &mut state, &shear, 1e-3, None).unwrap();
            assert_eq!(AnyModel::BRANCHES[r.branch.index()], expected, "{}", m.title());
            // the same update of the model alone: the composite adds no arithmetic
            let (mut alone, mut alone_state) = (confined, m.initial_state());
            match (m, &mut alone_state) {
                (AnyModel::DruckerPrager(dp), AnyState::DruckerPrager(s)) => {
                    dp.update_plane(&mut alone, s, &shear, 1e-3, None).unwrap();
                }
                (AnyModel::MuI(mu), AnyState::MuI(s)) => {
                    mu.update_plane(&mut alone, s, &shear, 1e-3, None).unwrap();
                }
                _ => unreachable!(),
            }
            assert_eq!((sigma, state), (alone, alone_state));
        }
    }

    /// A point whose state is another model's is refused with both models named, never
    /// updated by the wrong law.
    #[test]
    fn a_foreign_state_is_an_error_naming_both_models() {
        let (sand, beads) = (sand(), beads());
        let (mut sigma, mut state) = (PlaneTensor::ZERO, beads.initial_state());
        let e =
            sand.update_plane(&mut sigma, &mut state, &PlaneTensor::ZERO, 1e-3, None).unwrap_err();
        assert!(matches!(e, ConstitutiveError::ForeignState { .. }), "{e}");
        let text = e.to_string();
        assert!(text.contains(sand.title()) && text.contains(beads.title()), "{text}");
    }

    /// Materials of one model run as that model; several, as the composite.
    #[test]
    fn materials_of_one_model_keep_their_own_run_type() {
        let one = MaterialsBuilt::collect(vec![sand(), sand()]);
        assert!(matches!(one, MaterialsBuilt::DruckerPrager(ref v) if v.len() == 2));
        let both = MaterialsBuilt::collect(vec![sand(), beads()]);
        assert_eq!(both.kind(), "mixed");
        assert_eq!(both.state_bytes(), std::mem::size_of::<AnyState>());
        // the granular defaults of the sand hold for the mixed scene
        assert_eq!(both.pic_fraction(), one.pic_fraction());
        assert!(both.separation_density() > 0.0 && both.objective_stress());
    }
}
