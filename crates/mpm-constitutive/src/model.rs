//! The interface every constitutive model offers to a solver: one strain increment at a time.
//!
//! # Glossary
//! - `σ`: Cauchy stress (Pa), `Δε`: small-strain increment of one step (tensor shear components),
//!   both [`SymTensor`], tension positive.
//! - `Δλ`: plastic multiplier of the increment (eq 25: `Δεᵖ = Δλ ∂g/∂σ`), `ε̄ᵖ`: equivalent
//!   plastic strain, `σ : Δεᵖ`: plastic work of the increment (J/m³).
//!
//! The update is the paper's eq 11 (`σ_{n+1} = σ_n + Δσ`) with `Δσ` from eq 10 for elasticity or
//! from the return mapping of eqs 23–25 for Drucker-Prager.

use glam::DMat3;

use crate::error::ConstitutiveError;
use crate::tensor::{PlaneTensor, SymTensor, Tangent};

/// The most branches a model may name in [`ConstitutiveModel::BRANCHES`] (so that a solver can
/// count them in a fixed array, without allocating per step).
pub const MAX_BRANCHES: usize = 12;

/// Which branch an update took: an index into the model's [`ConstitutiveModel::BRANCHES`], whose
/// entry 0 is the elastic branch. A solver counts branches by this index and prints them by the
/// model's names, so it needs no model's vocabulary.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Branch(u8);

impl Branch {
    /// the elastic branch (no plastic flow), index 0 of every model.
    pub const ELASTIC: Self = Self(0);

    /// branch `index` of a model; below [`MAX_BRANCHES`] (checked where a constant is built).
    pub const fn new(index: u8) -> Self {
        assert!((index as usize) < MAX_BRANCHES, "a model names at most MAX_BRANCHES branches");
        Self(index)
    }

    /// the index into [`ConstitutiveModel::BRANCHES`], below [`MAX_BRANCHES`].
    #[inline(always)]
    pub const fn index(self) -> usize {
        self.0 as usize
    }
}

/// What one update did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UpdateReport {
    /// the branch taken.
    pub branch: Branch,
    /// the plastic multiplier `Δλ ≥ 0` (the increment of `ε̄ᵖ`; 0 when elastic).
    pub delta_lambda: f64,
    /// plastic dissipation `σ : Δεᵖ` of the increment per unit volume (J/m³), evaluated with the
    /// updated stress (backward Euler). With kinematic hardening this plastic work includes the
    /// part `β : Δεᵖ` stored in the back stress.
    pub dissipation: f64,
}

impl UpdateReport {
    /// the report of an elastic step.
    pub const ELASTIC: Self = Self { branch: Branch::ELASTIC, delta_lambda: 0.0, dissipation: 0.0 };
}

/// A small-strain model integrated one strain increment (over a time step `Δt`) at a time.
///
/// Rate-independent models ignore `Δt`; rate-dependent ones (viscoplasticity, μ(I) rheology)
/// take the strain rate as `Δε/Δt`. What a solver needs besides the update is asked of the model,
/// never assumed: its current wave speed (through [`p_wave_modulus`](Self::p_wave_modulus)) for
/// the time step, its stored elastic energy for the energy ledger, and the names of its branches.
pub trait ConstitutiveModel: Send + Sync {
    /// Internal variables per material point; `()` for elasticity.
    type State: Copy
        + Clone
        + Default
        + std::fmt::Debug
        + Send
        + Sync
        + PartialEq
        + serde::Serialize
        + serde::de::DeserializeOwned;

    /// true when [`update`](Self::update) can ever take a plastic branch (lets the solver skip
    /// work for elastic scenes).
    const IS_PLASTIC: bool;

    /// the names of the branches an update can take, indexed by [`Branch::index`]: entry 0 is
    /// `"elastic"`; at most [`MAX_BRANCHES`]. Lowercase, used as CSV values.
    const BRANCHES: &'static [&'static str];

    /// true when [`p_wave_modulus`](Self::p_wave_modulus) depends on the state; `false` lets a
    /// solver ask once per material (at the initial state) instead of once per particle.
    const WAVE_SPEED_VARIES: bool = false;

    /// the internal variables of a virgin material point.
    fn initial_state(&self) -> Self::State;

    /// the internal variables that a material point of `previous` carries into this material
    /// when a run changes the material's parameters between steps (a strength reduction): by
    /// default `state` as it is. A model whose state holds the size of its yield surface moves
    /// it with the parameters, so that they take effect (hardening Drucker-Prager shifts its cone
    /// size `k` by the change of `k0`).
    fn carried_state(&self, previous: &Self, state: &Self::State) -> Self::State
    where
        Self: Sized,
    {
        let _ = previous;
        *state
    }

    /// the constrained (P-wave) modulus `M = ρ c²` of the material at `state` (Pa): the
    /// stiffness of the fastest wave, `c = √(M/ρ)`, that the time step (eq 13) must resolve.
    fn p_wave_modulus(&self, state: &Self::State) -> f64;

    /// the elastic energy stored per unit volume at stress `sigma` and `state` (J/m³), for the
    /// energy ledger.
    fn stored_energy_density(&self, sigma: &SymTensor, state: &Self::State) -> f64;

    /// Integrates the strain increment `d_eps` (tensor strain, tension positive) applied over the
    /// time `dt > 0` (s): updates `sigma` and `state` in place.
    ///
    /// Returns `Err` (leaving `sigma` and `state` untouched) if `d_eps`, `sigma` or the state is
    /// not finite.
    fn update(
        &self,
        sigma: &mut SymTensor,
        state: &mut Self::State,
        d_eps: &SymTensor,
        dt: f64,
    ) -> Result<UpdateReport, ConstitutiveError>;

    /// [`update`](Self::update) in plane strain, after turning `sigma` and the state by
    /// `rotation = Some((cos θ, sin θ))`, the rotation about z of an objective stress rate
    /// ([`PlaneTensor::rotated_z`], [`rotate_state_z`](Self::rotate_state_z)).
    ///
    /// `sigma` and `d_eps` have no out-of-plane shear, and neither have the state's
    /// tensor-valued variables (what this update writes keeps it so). An isotropic model creates
    /// none from in-plane increments, so the result is that of the rotation and `update`; a
    /// model overrides this to skip the two zero components (Drucker-Prager: same results, two
    /// thirds of the work). Returns `Err`, leaving `sigma` and `state` untouched, as `update`
    /// does, and [`ConstitutiveError::OutOfPlane`] where the update would create an out-of-plane
    /// stress (a state with out-of-plane parts): never a result with a shear silently dropped.
    #[inline(always)]
    fn update_plane(
        &self,
        sigma: &mut PlaneTensor,
        state: &mut Self::State,
        d_eps: &PlaneTensor,
        dt: f64,
        rotation: Option<(f64, f64)>,
    ) -> Result<UpdateReport, ConstitutiveError> {
        let (mut full, mut st) = (sigma.to_sym(), *state);
        if let Some((c, s)) = rotation {
            full = full.rotated_z(c, s);
            self.rotate_state_z(&mut st, c, s);
        }
        let report = self.update(&mut full, &mut st, &d_eps.to_sym(), dt)?;
        for (name, value) in [("stress.yz", full.yz), ("stress.zx", full.zx)] {
            if value != 0.0 {
                return Err(ConstitutiveError::OutOfPlane { name, value });
            }
        }
        *sigma = PlaneTensor::from_sym(&full);
        *state = st;
        Ok(report)
    }

    /// Rotates tensor-valued internal variables (e.g. the back stress) by `r` (`β ← R β Rᵀ`), for
    /// objective stress rates. Elastic: no-op.
    fn rotate_state(&self, state: &mut Self::State, r: &DMat3);

    /// [`rotate_state`](Self::rotate_state) by the rotation about z with `c = cos θ`,
    /// `s = sin θ` (the only one plane strain produces).
    #[inline(always)]
    fn rotate_state_z(&self, state: &mut Self::State, c: f64, s: f64) {
        let r = DMat3::from_cols(
            glam::DVec3::new(c, s, 0.0),
            glam::DVec3::new(-s, c, 0.0),
            glam::DVec3::Z,
        );
        self.rotate_state(state, &r);
    }

    /// Equivalent plastic strain `ε̄ᵖ` for output (0 for elasticity).
    fn equivalent_plastic_strain(&self, state: &Self::State) -> f64;
}

/// A model that also provides its algorithmic (consistent) tangent, as needed by implicit solvers
/// and by the mixed-control element tests of [`crate::element_test`].
pub trait TangentModel: ConstitutiveModel {
    /// `dσ_{n+1}/dΔε` of [`ConstitutiveModel::update`] at the start state (`sigma`, `state`),
    /// increment `d_eps` and time step `dt`, as a [`Tangent`] (storage order
    /// `[xx, yy, zz, xy, yz, zx]`, acting on tensor strain components).
    fn consistent_tangent(
        &self,
        sigma: &SymTensor,
        state: &Self::State,
        d_eps: &SymTensor,
        dt: f64,
    ) -> Result<Tangent, ConstitutiveError>;
}

/// `Err` naming the first non-finite component of the increment or the stress.
#[inline]
pub(crate) fn check_finite(sigma: &SymTensor, d_eps: &SymTensor) -> Result<(), ConstitutiveError> {
    if sigma.is_finite() && d_eps.is_finite() {
        return Ok(());
    }
    if let Some((component, value)) = d_eps.first_non_finite() {
        return Err(ConstitutiveError::NonFiniteStrainIncrement { component, value });
    }
    if let Some((component, value)) = sigma.first_non_finite() {
        return Err(ConstitutiveError::NonFiniteStress { component, value });
    }
    Ok(())
}
