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

use crate::elastic::LinearElastic;
use crate::error::ConstitutiveError;
use crate::tensor::{PlaneTensor, SymTensor, Tangent};

/// Which branch the return mapping took.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Surface {
    /// the elastic trial state was admissible (`f_trial ≤ 0`): no plastic flow.
    Elastic,
    /// closed-form return to the smooth part of the cone.
    Cone,
    /// return to the apex of the cone (the cone return would have overshot the tip).
    Apex,
}

impl Surface {
    /// lowercase name used in CSV output.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Elastic => "elastic",
            Self::Cone => "cone",
            Self::Apex => "apex",
        }
    }
}

/// What one update did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UpdateReport {
    /// the branch taken.
    pub surface: Surface,
    /// the plastic multiplier `Δλ ≥ 0` (the increment of `ε̄ᵖ`; 0 when elastic).
    pub delta_lambda: f64,
    /// plastic dissipation `σ : Δεᵖ` of the increment per unit volume (J/m³), evaluated with the
    /// updated stress (backward Euler). With kinematic hardening this plastic work includes the
    /// part `β : Δεᵖ` stored in the back stress.
    pub dissipation: f64,
}

impl UpdateReport {
    /// the report of an elastic step.
    pub const ELASTIC: Self =
        Self { surface: Surface::Elastic, delta_lambda: 0.0, dissipation: 0.0 };
}

/// A rate-independent small-strain model integrated one strain increment at a time.
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

    /// the internal variables of a virgin material point.
    fn initial_state(&self) -> Self::State;

    /// the elastic part of the model (for wave speeds, time steps and elastic energy).
    fn elasticity(&self) -> &LinearElastic;

    /// Integrates the strain increment `d_eps` (tensor strain, tension positive): updates `sigma`
    /// and `state` in place.
    ///
    /// Returns `Err` (leaving `sigma` and `state` untouched) if `d_eps`, `sigma` or the state is
    /// not finite.
    fn update(
        &self,
        sigma: &mut SymTensor,
        state: &mut Self::State,
        d_eps: &SymTensor,
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
        rotation: Option<(f64, f64)>,
    ) -> Result<UpdateReport, ConstitutiveError> {
        let (mut full, mut st) = (sigma.to_sym(), *state);
        if let Some((c, s)) = rotation {
            full = full.rotated_z(c, s);
            self.rotate_state_z(&mut st, c, s);
        }
        let report = self.update(&mut full, &mut st, &d_eps.to_sym())?;
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
    /// `dσ_{n+1}/dΔε` of [`ConstitutiveModel::update`] at the start state (`sigma`, `state`) and
    /// increment `d_eps`, as a [`Tangent`] (storage order `[xx, yy, zz, xy, yz, zx]`, acting on
    /// tensor strain components).
    fn consistent_tangent(
        &self,
        sigma: &SymTensor,
        state: &Self::State,
        d_eps: &SymTensor,
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
