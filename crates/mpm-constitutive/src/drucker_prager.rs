//! Drucker-Prager plasticity with non-associated flow and Prager mixed hardening, the paper's
//! eqs 23–25, integrated by a closed-form return mapping (cone or apex) with its consistent
//! tangent.
//!
//! # Glossary
//! - `σ` stress, `s = dev σ`, `I1 = tr σ` (Pa); `K`, `G` bulk and shear moduli (Pa), `C` the
//!   elastic stiffness (eq 10).
//! - `β` deviatoric back stress (Pa); `ξ = s − β` the relative deviator; `q = √J2(ξ) = ‖ξ‖/√2`;
//!   `n̂ = ξ/‖ξ‖` its unit direction (so `∂q/∂σ = n̂/√2`).
//! - `k` cone size (Pa), `k0` its initial value; `α`, `αg` friction and dilatancy coefficients.
//! - `H` plastic modulus (Pa), `M ∈ [0, 1]` mixing parameter (1 isotropic, 0 kinematic).
//! - `Δλ` plastic multiplier, `ε̄ᵖ` equivalent plastic (shear) strain.
//! - Shorthands: `D = 9Kααg + G + H`, `B = G + (1 − M)H`.
//!
//! Tension positive (so compression makes `I1 < 0` and raises the strength `k − α I1`), SI units,
//! tensor shear strain components (see [`crate::tensor`]).
//!
//! # Model (eqs 23–25)
//! ```text
//! f = α I1 + q − k(ε̄ᵖ)                         yield function            (23)
//! g = αg I1 + q                                 plastic potential         (24)
//! Δεᵖ = Δλ ∂g/∂σ = Δλ (αg I + n̂/√2)             non-associated flow rule  (25)
//! ```
//! `ε̄ᵖ` is the accumulated equivalent plastic shear strain `Σ √(2 Δeᵖ : Δeᵖ)` (`eᵖ = dev εᵖ`);
//! on the cone this increment equals `Δλ`, so `H = dk/dε̄ᵖ` is the plastic modulus in `√J2` units
//! and `q Δλ = ξ : Δεᵖ` (the multiplier is work-conjugate to `√J2`).
//! Prager mixed hardening: `k ← k + M H Δλ` and `β ← β + √2 (1 − M) H Δλ n̂`, i.e. `β` moves
//! along the return direction by `(1 − M) H Δλ` in `√J2` units.
//!
//! The paper's plane-strain parameters follow from Mohr-Coulomb `(c, φ, ψ)` by [`ConeMatch`].
//!
//! # Cone return (closed form)
//! With the elastic trial `σᵗʳ = σ + C : Δε`, `ξᵗʳ = dev σᵗʳ − β`, `qᵗʳ = √J2(ξᵗʳ)`,
//! `fᵗʳ = α I1ᵗʳ + qᵗʳ − k > 0`, the return `σ = σᵗʳ − Δλ C : ∂g/∂σ` gives
//! ```text
//! I1 = I1ᵗʳ − 9K αg Δλ,   ξ = ξᵗʳ − √2 (G + (1 − M)H) Δλ n̂   (n̂ unchanged: radial return)
//! f  = α I1ᵗʳ − 9Kααg Δλ + qᵗʳ − (G + (1 − M)H) Δλ − k − MH Δλ = fᵗʳ − D Δλ
//! ```
//! hence `Δλ = fᵗʳ / (9Kααg + G + H)`. The returned state is assembled from its invariants with
//! `q := k_{n+1} − α I1_{n+1}`, so `f = 0` holds to rounding of the *returned* magnitudes, not of
//! the (possibly much larger) trial ones.
//!
//! # Apex return
//! The cone return is valid while the returned `q = qᵗʳ − B Δλ` is non-negative. Otherwise it
//! overshoots the tip and the stress goes to the apex of the hardened cone: deviator `= β`, on
//! the yield surface. At the apex the deviatoric plastic strain is whatever removes `ξᵗʳ`; the
//! multiplier is defined, as on the cone, by the equivalent plastic shear strain it produces:
//! ```text
//! s_{n+1} = β_{n+1} = β + (1 − M)H Δλ √2 n̂,   s_{n+1} = sᵗʳ − 2G Δeᵖ,   √2 ‖Δeᵖ‖ = Δλ
//!   ⇒ ξᵗʳ = √2 (G + (1 − M)H) Δλ n̂   ⇒   Δλ = qᵗʳ / B
//! k_{n+1} = k + MH Δλ,   I1_{n+1} = k_{n+1} / α,   Δεᵖ = C⁻¹ : (σᵗʳ − σ_{n+1})
//! ```
//! The textbook apex instead takes `Δλ` from the volumetric flow rule,
//! `Δλ = (α I1ᵗʳ − k)/(9Kααg + MH)`, which is unbounded as `ψ → 0` with `MH = 0`: exactly the
//! cohesionless, non-dilatant sand of the paper whose particles separate all the time. Here no
//! division by `αg` occurs: the apex costs one square root and is finite for `ψ = 0`, `c = 0` and
//! pure tension (`σ → β`, which is zero stress for a virgin cohesionless point). Both definitions
//! give the same stress whenever `MH = 0` and agree with the cone return on the cone/apex
//! boundary (there `qᵗʳ/B = fᵗʳ/D`), so the update is continuous. The volumetric plastic strain
//! at the apex, `(I1ᵗʳ − I1_{n+1})/(3K)`, is at least the flow rule's `3αg Δλ` (the cone
//! overshoots exactly when `α I1ᵗʳ − k > (9Kααg + MH) qᵗʳ/B`); the excess is opening of the
//! granular skeleton, which neither hardens nor counts in `ε̄ᵖ`.
//! The plastic work is `σ_{n+1} : Δεᵖ = I1_{n+1} (I1ᵗʳ − I1_{n+1})/(9K) + β_{n+1} : ξᵗʳ/(2B)`.
//!
//! # Well-posedness
//! The constructor requires `D > 0` (unique cone multiplier) and `B > 0` (unique apex multiplier,
//! and the overshoot test is meaningful); softening `H < 0` is allowed within these bounds. With
//! `φ = 0` there is no apex; a cone softened to `k < 0` is then empty and the update returns
//! [`ConstitutiveError::EmptyElasticDomain`].

use std::marker::PhantomData;

use glam::DMat3;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::elastic::LinearElastic;
use crate::error::ConstitutiveError;
use crate::model::{Branch, ConstitutiveModel, TangentModel, UpdateReport, check_finite};
use crate::tensor::{
    PlaneTensor, SymTensor, Symmetric, Tangent, deviatoric_projector, dyad, tangent_axpby,
};

/// How the cone is fitted to the Mohr-Coulomb pyramid of `(c, φ)` (and `ψ` for `αg`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ConeMatch {
    /// same collapse load in plane strain (the paper's choice):
    /// `α = tanφ/√(9 + 12 tan²φ)`, `k0 = 3c/√(9 + 12 tan²φ)`.
    #[default]
    PlaneStrain,
    /// through the triaxial-extension corners of the pyramid (the smaller of the two triaxial
    /// cones): `α = 2 sinφ/(√3 (3 + sinφ))`, `k0 = 6c cosφ/(√3 (3 + sinφ))`.
    Inner,
    /// through the triaxial-compression corners (circumscribes the pyramid):
    /// `α = 2 sinφ/(√3 (3 − sinφ))`, `k0 = 6c cosφ/(√3 (3 − sinφ))`.
    Outer,
}

impl ConeMatch {
    /// `(α, k0)` of the cone matched to cohesion `c` (Pa) and friction angle `φ` (degrees).
    /// Used with `(0, ψ)` it gives `(αg, 0)`.
    pub fn coefficients(self, friction_angle_deg: f64, cohesion: f64) -> (f64, f64) {
        let phi = friction_angle_deg.to_radians();
        match self {
            Self::PlaneStrain => {
                let t = phi.tan();
                let root = (9.0 + 12.0 * t * t).sqrt();
                (t / root, 3.0 * cohesion / root)
            }
            Self::Inner | Self::Outer => {
                let (sin, cos) = phi.sin_cos();
                let den = 3.0f64.sqrt() * if self == Self::Inner { 3.0 + sin } else { 3.0 - sin };
                (2.0 * sin / den, 6.0 * cohesion * cos / den)
            }
        }
    }
}

/// Material parameters of [`DruckerPrager`] (SI units, angles in degrees). As a serde table (a
/// scene's `[materials.NAME]` with `kind = "drucker_prager"`) it refuses unknown fields, and
/// `dilatancy_angle_deg` (0), `hardening_modulus` (0), `mixing` (1, isotropic) and `cone_match`
/// (`"plane_strain"`, the paper's; or `"inner"`, `"outer"`) may be left out.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DruckerPragerParams {
    /// Young's modulus `E > 0` (Pa).
    pub young: f64,
    /// Poisson's ratio `−1 < ν < 0.5`.
    pub poisson: f64,
    /// Mohr-Coulomb cohesion `c ≥ 0` (Pa).
    pub cohesion: f64,
    /// friction angle `0 ≤ φ < 90` (degrees).
    pub friction_angle_deg: f64,
    /// dilatancy angle `0 ≤ ψ ≤ φ` (degrees); `ψ = φ` is associated flow.
    #[serde(default)]
    pub dilatancy_angle_deg: f64,
    /// plastic modulus `H = dk/dε̄ᵖ` (Pa); negative values (softening) only while well posed.
    #[serde(default)]
    pub hardening_modulus: f64,
    /// M ∈ \[0,1\]: 1 isotropic, 0 kinematic
    #[serde(default = "isotropic")]
    pub mixing: f64,
    /// how `(α, k0, αg)` are matched to `(c, φ, ψ)`.
    #[serde(default)]
    pub cone_match: ConeMatch,
}

/// [`DruckerPragerParams::mixing`]'s default: isotropic hardening.
fn isotropic() -> f64 {
    1.0
}

impl DruckerPragerParams {
    /// the paper's dry sand (§7, table 2): `E = 2e6 Pa`, `ν = 0.3`, `c = 10 Pa`, `φ = 40°`,
    /// `ψ = 0`, `H = 0`, `M = 0.8`, plane-strain match.
    pub const ABE2005_DRY_SAND: Self = Self {
        young: 2.0e6,
        poisson: 0.3,
        cohesion: 10.0,
        friction_angle_deg: 40.0,
        dilatancy_angle_deg: 0.0,
        hardening_modulus: 0.0,
        mixing: 0.8,
        cone_match: ConeMatch::PlaneStrain,
    };
}

/// Internal variables of a [`DruckerPrager`] material point with mixed hardening.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DpState {
    /// deviatoric back stress β
    pub back_stress: SymTensor,
    /// current cone size k (Pa)
    pub k: f64,
    /// equivalent plastic strain ε̄ᵖ
    pub eps_p_bar: f64,
}

/// Internal variables of a perfectly plastic [`DruckerPrager`] point (`H = 0`, as the paper's
/// dry sand): its cone size stays `k0` and its back stress zero, so only `ε̄ᵖ` is stored, 8 bytes
/// instead of [`DpState`]'s 64.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DpPerfectState {
    /// equivalent plastic strain ε̄ᵖ
    pub eps_p_bar: f64,
}

/// What a [`DruckerPrager`] point stores: [`DpState`] (mixed hardening, the default) or
/// [`DpPerfectState`] (`H = 0`). The return mapping is written once against this trait; a point
/// that does not harden reads `k = k0` and `β = 0` and stores neither, with the same results.
pub trait DpVariables:
    Copy + Default + std::fmt::Debug + Send + Sync + PartialEq + Serialize + DeserializeOwned + 'static
{
    /// whether `k` and `β` are stored (false: they stay `k0` and 0).
    const HARDENS: bool;
    /// the variables with back stress `β`, cone size `k` and `ε̄ᵖ` (`β` and `k` are dropped when
    /// [`HARDENS`](Self::HARDENS) is false: they are then 0 and `k0`).
    fn new(back_stress: SymTensor, k: f64, eps_p_bar: f64) -> Self;
    /// deviatoric back stress `β`.
    fn back_stress(&self) -> SymTensor;
    /// cone size `k` (Pa) of a material whose initial cone size is `k0`.
    fn k(&self, k0: f64) -> f64;
    /// equivalent plastic strain `ε̄ᵖ`.
    fn eps_p_bar(&self) -> f64;
}

impl DpVariables for DpState {
    const HARDENS: bool = true;
    #[inline(always)]
    fn new(back_stress: SymTensor, k: f64, eps_p_bar: f64) -> Self {
        Self { back_stress, k, eps_p_bar }
    }
    #[inline(always)]
    fn back_stress(&self) -> SymTensor {
        self.back_stress
    }
    #[inline(always)]
    fn k(&self, _k0: f64) -> f64 {
        self.k
    }
    #[inline(always)]
    fn eps_p_bar(&self) -> f64 {
        self.eps_p_bar
    }
}

impl DpVariables for DpPerfectState {
    const HARDENS: bool = false;
    #[inline(always)]
    fn new(_back_stress: SymTensor, _k: f64, eps_p_bar: f64) -> Self {
        Self { eps_p_bar }
    }
    #[inline(always)]
    fn back_stress(&self) -> SymTensor {
        SymTensor::ZERO
    }
    #[inline(always)]
    fn k(&self, k0: f64) -> f64 {
        k0
    }
    #[inline(always)]
    fn eps_p_bar(&self) -> f64 {
        self.eps_p_bar
    }
}

/// Drucker-Prager with non-associated flow and Prager mixed hardening (eqs 23–25), see the module
/// docs for the return mapping. `V` is what a point stores: [`DpState`] ([`DruckerPrager::new`])
/// or, for a material that does not harden, [`DpPerfectState`]
/// ([`DruckerPrager::perfectly_plastic`], [`DruckerPrager::without_hardening`]).
#[derive(Clone, Debug)]
pub struct DruckerPrager<V: DpVariables = DpState> {
    params: DruckerPragerParams,
    elastic: LinearElastic,
    alpha: f64,
    alpha_g: f64,
    k0: f64,
    /// `2G`.
    two_g: f64,
    /// `λ` (Lamé).
    lame: f64,
    /// `9K αg`: drop of `I1` per unit `Δλ`.
    nine_k_alpha_g: f64,
    /// `M H`: growth of `k` per unit `Δλ`.
    iso_h: f64,
    /// `(1 − M) H`: travel of `β` per unit `Δλ` in `√J2` units.
    kin_h: f64,
    /// `1 / (9Kααg + G + H)`.
    inv_d: f64,
    /// `1 / (G + (1 − M)H)`.
    inv_b: f64,
    /// `1 / α` (0 when `α = 0`: no apex).
    inv_alpha: f64,
    /// `1 / (9K)`.
    inv_9k: f64,
    variables: PhantomData<fn() -> V>,
}

const SQRT_2: f64 = std::f64::consts::SQRT_2;
const FRAC_1_SQRT_2: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// quantities of the elastic trial state shared by the update and the tangent.
struct Trial<T> {
    sigma: T,
    i1: f64,
    /// `ξᵗʳ = dev σᵗʳ − dev β`.
    xi: T,
    /// `J2(ξᵗʳ) = qᵗʳ²`.
    j2: f64,
    /// `dev β`.
    beta: T,
}

/// outcome of the return mapping, before it is written back (`q_tr = qᵗʳ`; `i1`, `q`, `k` are
/// the returned values).
enum Return {
    Elastic,
    Cone { dl: f64, i1: f64, q: f64, k: f64, q_tr: f64 },
    Apex { dl: f64, i1: f64, k: f64 },
}

impl DruckerPrager {
    /// validates `p` and precomputes the cone coefficients.
    ///
    /// Admissible: `E > 0`, `−1 < ν < 0.5`, `c ≥ 0`, `0 ≤ φ < 90°`, `0 ≤ ψ ≤ φ`, `M ∈ [0, 1]`,
    /// finite `H` with `9Kααg + G + H > 0` and `G + (1 − M)H > 0`.
    pub fn new(p: DruckerPragerParams) -> Result<Self, ConstitutiveError> {
        Self::build(p)
    }

    /// the same material storing only `ε̄ᵖ` per point ([`DpPerfectState`]) when it does not
    /// harden (`H = 0`); `None` otherwise. Its updates give the same stresses, `ε̄ᵖ` and reports.
    pub fn without_hardening(&self) -> Option<DruckerPrager<DpPerfectState>> {
        // (the same validated parameters give the same coefficients)
        DruckerPrager::perfectly_plastic(self.params).ok()
    }
}

impl DruckerPrager<DpPerfectState> {
    /// [`DruckerPrager::new`] for a material that does not harden: `H = 0` is required (it is
    /// refused otherwise), and each point stores only `ε̄ᵖ`.
    pub fn perfectly_plastic(p: DruckerPragerParams) -> Result<Self, ConstitutiveError> {
        if p.hardening_modulus != 0.0 {
            return Err(ConstitutiveError::InvalidParameter {
                name: "hardening_modulus",
                value: p.hardening_modulus,
                range: "0 for a perfectly plastic material (DruckerPrager::new hardens)",
            });
        }
        Self::build(p)
    }
}

impl<V: DpVariables> DruckerPrager<V> {
    fn build(p: DruckerPragerParams) -> Result<Self, ConstitutiveError> {
        let elastic = LinearElastic::from_young_poisson(p.young, p.poisson)?;
        let invalid =
            |name, value, range| ConstitutiveError::InvalidParameter { name, value, range };
        if !(p.cohesion.is_finite() && p.cohesion >= 0.0) {
            return Err(invalid("cohesion", p.cohesion, "0 <= cohesion < inf (Pa)"));
        }
        if !(p.friction_angle_deg >= 0.0 && p.friction_angle_deg < 90.0) {
            return Err(invalid("friction_angle_deg", p.friction_angle_deg, "0 <= phi < 90 (deg)"));
        }
        if !(p.dilatancy_angle_deg >= 0.0 && p.dilatancy_angle_deg <= p.friction_angle_deg) {
            return Err(invalid(
                "dilatancy_angle_deg",
                p.dilatancy_angle_deg,
                "0 <= psi <= friction_angle_deg (deg)",
            ));
        }
        if !(p.mixing >= 0.0 && p.mixing <= 1.0) {
            return Err(invalid("mixing", p.mixing, "0 <= mixing <= 1"));
        }
        if !p.hardening_modulus.is_finite() {
            return Err(invalid(
                "hardening_modulus",
                p.hardening_modulus,
                "finite, with 9K alpha alpha_g + G + H > 0 and G + (1 - M) H > 0 (Pa)",
            ));
        }
        let (alpha, k0) = p.cone_match.coefficients(p.friction_angle_deg, p.cohesion);
        if !k0.is_finite() {
            // (a cohesion near f64::MAX overflows the cone size)
            return Err(invalid(
                "cohesion",
                p.cohesion,
                "0 <= cohesion with a finite cone size k0 (Pa)",
            ));
        }
        let (alpha_g, _) = p.cone_match.coefficients(p.dilatancy_angle_deg, 0.0);
        let (bulk, shear) = (elastic.bulk_modulus(), elastic.shear_modulus());
        let h = p.hardening_modulus;
        let nine_k_aag = 9.0 * bulk * alpha * alpha_g;
        let d = nine_k_aag + shear + h;
        // every input is finite here, so `d` and `b` are not NaN.
        if d <= 0.0 {
            return Err(ConstitutiveError::IllPosedSoftening {
                hardening_modulus: h,
                lower_bound: -(nine_k_aag + shear),
                condition: "cone return needs 9K alpha alpha_g + G + H > 0",
            });
        }
        let kin_h = (1.0 - p.mixing) * h;
        let b = shear + kin_h;
        if b <= 0.0 {
            return Err(ConstitutiveError::IllPosedSoftening {
                hardening_modulus: h,
                lower_bound: -shear / (1.0 - p.mixing),
                condition: "apex return needs G + (1 - M) H > 0",
            });
        }
        Ok(Self {
            params: p,
            elastic,
            alpha,
            alpha_g,
            k0,
            two_g: 2.0 * shear,
            lame: elastic.lame_lambda(),
            nine_k_alpha_g: 9.0 * bulk * alpha_g,
            iso_h: p.mixing * h,
            kin_h,
            inv_d: 1.0 / d,
            inv_b: 1.0 / b,
            inv_alpha: if alpha > 0.0 { 1.0 / alpha } else { 0.0 },
            inv_9k: 1.0 / (9.0 * bulk),
            variables: PhantomData,
        })
    }

    /// the validated parameters.
    pub fn params(&self) -> &DruckerPragerParams {
        &self.params
    }

    /// the elastic part (eq 10).
    pub fn elasticity(&self) -> &LinearElastic {
        &self.elastic
    }

    /// friction coefficient `α` of eq 23.
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// dilatancy coefficient `αg` of eq 24.
    pub fn alpha_g(&self) -> f64 {
        self.alpha_g
    }

    /// initial cone size `k0` (Pa).
    pub fn k0(&self) -> f64 {
        self.k0
    }

    /// `9Kααg + G + H` (Pa), the denominator of the cone return.
    pub fn cone_denominator(&self) -> f64 {
        1.0 / self.inv_d
    }

    /// eq 23: `f = α I1 + √J2(σ − β) − k` (Pa); `f ≤ 0` is admissible.
    pub fn yield_function(&self, sigma: &SymTensor, state: &V) -> f64 {
        self.alpha * sigma.trace() + (*sigma - state.back_stress()).j2().sqrt() - state.k(self.k0)
    }

    /// the plastic potential's gradient `∂g/∂σ = αg I + n̂/√2` at `(sigma, state)`; at the apex
    /// (`ξ = 0`) the deviatoric part is taken as zero.
    pub fn flow_direction(&self, sigma: &SymTensor, state: &V) -> SymTensor {
        let xi = (*sigma - state.back_stress()).deviator();
        let norm = xi.norm();
        let dev = if norm > 0.0 { xi * (FRAC_1_SQRT_2 / norm) } else { SymTensor::ZERO };
        SymTensor::IDENTITY * self.alpha_g + dev
    }

    /// algorithmic (consistent) tangent `dσ_{n+1}/dΔε` of [`update`](ConstitutiveModel::update)
    /// for the start state (`sigma`, `state`) and increment `d_eps`.
    ///
    /// The matrix is in the [`SymTensor`] storage order `[xx, yy, zz, xy, yz, zx]` and acts on
    /// **tensor** strain components: `dσ[i] = Σ_j T[i][j] dε[j]` with `dε[3] = dε_xy = dγ_xy/2`
    /// (so the elastic entry is `T[3][3] = 2G`). Multiply the shear columns by ½ for a matrix
    /// acting on engineering shear strains.
    ///
    /// Cone: `C − (C:∂g/∂σ) ⊗ (C:∂f/∂σ)/D − (2G² Δλ/qᵗʳ)(P_dev − n̂ ⊗ n̂)`.
    /// Apex: `(√2 G MH/(3αB)) I ⊗ n̂ + (2G (1 − M)H/B) P_dev`.
    pub fn consistent_tangent(
        &self,
        sigma: &SymTensor,
        state: &V,
        d_eps: &SymTensor,
    ) -> Result<Tangent, ConstitutiveError> {
        let back_stress = state.back_stress();
        self.check_inputs(sigma, &back_stress, state, d_eps)?;
        let trial = self.trial(sigma, &back_stress, d_eps);
        let g = self.elastic.shear_modulus();
        let bulk = self.elastic.bulk_modulus();
        let q_tr = trial.j2.sqrt();
        let n_hat = if q_tr > 0.0 { trial.xi * (FRAC_1_SQRT_2 / q_tr) } else { SymTensor::ZERO };
        let p_dev = deviatoric_projector();
        match self.return_map(&trial, state.k(self.k0))? {
            Return::Elastic => Ok(self.elastic.stiffness_matrix()),
            Return::Cone { dl, .. } => {
                let c_dg = SymTensor::IDENTITY * (3.0 * bulk * self.alpha_g) + n_hat * (SQRT_2 * g);
                let c_df = SymTensor::IDENTITY * (3.0 * bulk * self.alpha) + n_hat * (SQRT_2 * g);
                let t = tangent_axpby(
                    1.0,
                    &self.elastic.stiffness_matrix(),
                    -self.inv_d,
                    &dyad(&c_dg, &c_df),
                );
                let radial = tangent_axpby(1.0, &p_dev, -1.0, &dyad(&n_hat, &n_hat));
                Ok(tangent_axpby(1.0, &t, -2.0 * g * g * dl / q_tr, &radial))
            }
            Return::Apex { .. } => {
                let vol = SQRT_2 * g * self.iso_h * self.inv_b / (3.0 * self.alpha);
                let t = dyad(&SymTensor::IDENTITY, &n_hat);
                Ok(tangent_axpby(vol, &t, self.two_g * self.kin_h * self.inv_b, &p_dev))
            }
        }
    }

    #[inline(always)]
    // x − x is the point: 0 for finite x, NaN otherwise.
    #[allow(clippy::eq_op)]
    fn check_inputs<T: Symmetric>(
        &self,
        sigma: &T,
        back_stress: &T,
        state: &V,
        d_eps: &T,
    ) -> Result<(), ConstitutiveError> {
        // One test for the common all-finite case (see `SymTensor::finite_probe`); a point that
        // does not harden has no back stress or k of its own to test.
        let (k, eps) = (state.k(self.k0), state.eps_p_bar());
        let variables = if V::HARDENS {
            back_stress.finite_probe() + ((k - k) + (eps - eps))
        } else {
            eps - eps
        };
        let probe = sigma.finite_probe() + d_eps.finite_probe() + variables;
        if probe == 0.0 {
            Ok(())
        } else {
            Self::non_finite_input(
                &sigma.to_sym(),
                &back_stress.to_sym(),
                state,
                self.k0,
                &d_eps.to_sym(),
            )
        }
    }

    /// the error for a back stress with out-of-plane parts `(yz, zx)`, not both 0.
    #[cold]
    #[inline(never)]
    fn out_of_plane(yz: f64, zx: f64) -> ConstitutiveError {
        let (name, value) = if yz != 0.0 { ("back_stress.yz", yz) } else { ("back_stress.zx", zx) };
        if value.is_finite() {
            ConstitutiveError::OutOfPlane { name, value }
        } else {
            ConstitutiveError::NonFiniteState { name, value }
        }
    }

    /// names the first non-finite input (the slow path of [`check_inputs`](Self::check_inputs)).
    #[cold]
    #[inline(never)]
    fn non_finite_input(
        sigma: &SymTensor,
        back_stress: &SymTensor,
        state: &V,
        k0: f64,
        d_eps: &SymTensor,
    ) -> Result<(), ConstitutiveError> {
        check_finite(sigma, d_eps)?;
        let (k, eps_p_bar) = (state.k(k0), state.eps_p_bar());
        let (name, value) = if !k.is_finite() {
            ("k", k)
        } else if !eps_p_bar.is_finite() {
            ("eps_p_bar", eps_p_bar)
        } else {
            let (c, v) = back_stress.first_non_finite().unwrap_or(("xx", f64::NAN));
            let name = match c {
                "xx" => "back_stress.xx",
                "yy" => "back_stress.yy",
                "zz" => "back_stress.zz",
                "xy" => "back_stress.xy",
                "yz" => "back_stress.yz",
                _ => "back_stress.zx",
            };
            (name, v)
        };
        Err(ConstitutiveError::NonFiniteState { name, value })
    }

    #[inline]
    fn trial<T: Symmetric>(&self, sigma: &T, back_stress: &T, d_eps: &T) -> Trial<T> {
        // eq 10: σᵗʳ = σ + λ tr(Δε) I + 2G Δε.
        let lt = self.lame * d_eps.trace();
        let st = sigma.elastic_trial(lt, self.two_g, d_eps);
        let beta = back_stress.deviator();
        let i1 = st.trace();
        let xi = st.deviator() - beta;
        let j2 = 0.5 * xi.ddot(&xi);
        Trial { sigma: st, i1, xi, j2, beta }
    }

    #[inline]
    fn return_map<T>(&self, t: &Trial<T>, k_n: f64) -> Result<Return, ConstitutiveError> {
        // f = qᵗʳ − r with r = k − α I1ᵗʳ the strength at the trial pressure; f ≤ 0 is
        // r ≥ 0 and J2 ≤ r², which spares the square root on the (most frequent) elastic path.
        let r = k_n - self.alpha * t.i1;
        if r >= 0.0 && t.j2 <= r * r {
            return Ok(Return::Elastic);
        }
        let q_tr = t.j2.sqrt();
        let f = q_tr - r;
        if f <= 0.0 {
            // J2 > r² by rounding only.
            return Ok(Return::Elastic);
        }
        // cone: Δλ = fᵗʳ / (9Kααg + G + H); q from the consistency condition.
        let dl = f * self.inv_d;
        let k = k_n + self.iso_h * dl;
        let i1 = t.i1 - self.nine_k_alpha_g * dl;
        let q = k - self.alpha * i1;
        if q_tr > 0.0 && q >= 0.0 {
            return Ok(Return::Cone { dl, i1, q, k, q_tr });
        }
        // apex: Δλ = qᵗʳ / (G + (1 − M)H), I1 = k_{n+1}/α.
        let dl = q_tr * self.inv_b;
        let k = k_n + self.iso_h * dl;
        if self.alpha > 0.0 {
            Ok(Return::Apex { dl, i1: k * self.inv_alpha, k })
        } else {
            Err(ConstitutiveError::EmptyElasticDomain { k })
        }
    }
}

/// The branches of the Drucker-Prager return mapping, in the order of its
/// [`ConstitutiveModel::BRANCHES`] (`["elastic", "cone", "apex"]`).
pub struct DpBranch;

impl DpBranch {
    /// the elastic trial state was admissible (`f_trial ≤ 0`): no plastic flow.
    pub const ELASTIC: Branch = Branch::ELASTIC;
    /// closed-form return to the smooth part of the cone.
    pub const CONE: Branch = Branch::new(1);
    /// return to the apex of the cone (the cone return would have overshot the tip).
    pub const APEX: Branch = Branch::new(2);
}

impl<V: DpVariables> ConstitutiveModel for DruckerPrager<V> {
    type State = V;
    const IS_PLASTIC: bool = true;
    const BRANCHES: &'static [&'static str] = &["elastic", "cone", "apex"];

    fn initial_state(&self) -> V {
        V::new(SymTensor::ZERO, self.k0, 0.0)
    }

    /// the cone size moved by the change of `k0` (the hardening so far kept), the back stress
    /// and `ε̄ᵖ` as they are.
    fn carried_state(&self, previous: &Self, state: &V) -> V {
        let k = state.k(previous.k0) + (self.k0 - previous.k0);
        V::new(state.back_stress(), k, state.eps_p_bar())
    }

    /// the elastic part's (hardening changes no stiffness).
    fn p_wave_modulus(&self, _state: &V) -> f64 {
        self.elastic.p_wave_modulus()
    }

    /// the elastic part's `½ σ : C⁻¹ : σ` (eq 10); the energy stored in the back stress counts
    /// as plastic work (see [`UpdateReport::dissipation`]).
    fn stored_energy_density(&self, sigma: &SymTensor, _state: &V) -> f64 {
        self.elastic.strain_energy_density(sigma)
    }

    /// rate-independent: `dt` plays no part.
    #[inline(always)]
    fn update(
        &self,
        sigma: &mut SymTensor,
        state: &mut V,
        d_eps: &SymTensor,
        _dt: f64,
    ) -> Result<UpdateReport, ConstitutiveError> {
        let back_stress = state.back_stress();
        self.update_in(sigma, *sigma, back_stress, state, d_eps)
    }

    // Inlined into the solver's particle loop (called out of line, the stress went through
    // memory and its wide loads stalled on the narrow stores: flume 13 % of the run), and the
    // turned stress and back stress stay in registers (stored and read back, the same stall:
    // 10 %).
    #[inline(always)]
    fn update_plane(
        &self,
        sigma: &mut PlaneTensor,
        state: &mut V,
        d_eps: &PlaneTensor,
        _dt: f64,
        rotation: Option<(f64, f64)>,
    ) -> Result<UpdateReport, ConstitutiveError> {
        let full = state.back_stress();
        if V::HARDENS && (full.yz != 0.0 || full.zx != 0.0) {
            // (NaN included) a back stress plane strain cannot carry: refused, not dropped.
            return Err(Self::out_of_plane(full.yz, full.zx));
        }
        let back_stress = PlaneTensor::from_sym(&full);
        match rotation {
            Some((c, s)) => {
                let start = sigma.rotated_z(c, s);
                // (a zero back stress turns into itself)
                let back = if V::HARDENS { back_stress.rotated_z(c, s) } else { back_stress };
                self.update_in(sigma, start, back, state, d_eps)
            }
            None => self.update_in(sigma, *sigma, back_stress, state, d_eps),
        }
    }

    #[inline(always)]
    fn rotate_state_z(&self, state: &mut V, c: f64, s: f64) {
        if V::HARDENS {
            let back_stress = state.back_stress().rotated_z(c, s);
            *state = V::new(back_stress, state.k(self.k0), state.eps_p_bar());
        }
    }

    #[inline(always)]
    fn rotate_state(&self, state: &mut V, r: &DMat3) {
        if V::HARDENS {
            let back_stress = state.back_stress().rotated(r);
            *state = V::new(back_stress, state.k(self.k0), state.eps_p_bar());
        }
    }

    fn equivalent_plastic_strain(&self, state: &V) -> f64 {
        state.eps_p_bar()
    }
}

impl<V: DpVariables> DruckerPrager<V> {
    /// [`ConstitutiveModel::update`] on full or plane-strain tensors (see [`Symmetric`]) from
    /// the stress `start` and back stress `back_stress` (the state's, possibly turned by an
    /// objective rate): writes `sigma` and `state` (its back stress in the components of `T`)
    /// only on success.
    #[inline(always)]
    fn update_in<T: Symmetric>(
        &self,
        sigma: &mut T,
        start: T,
        back_stress: T,
        state: &mut V,
        d_eps: &T,
    ) -> Result<UpdateReport, ConstitutiveError> {
        self.check_inputs(&start, &back_stress, state, d_eps)?;
        let t = self.trial(&start, &back_stress, d_eps);
        let (k_n, eps_n) = (state.k(self.k0), state.eps_p_bar());
        let (new_sigma, new_state, report) = match self.return_map(&t, k_n)? {
            Return::Elastic => {
                let st = V::new(back_stress.to_sym(), k_n, eps_n);
                (t.sigma, st, UpdateReport::ELASTIC)
            }
            Return::Cone { dl, i1, q, k, q_tr } => {
                // with ‖ξᵗʳ‖ = √2 qᵗʳ, √2 n̂ = ξᵗʳ/qᵗʳ: one division for the whole return.
                let inv_q = 1.0 / q_tr;
                let beta = t.beta + t.xi * (self.kin_h * dl * inv_q);
                let s = T::IDENTITY * (i1 / 3.0) + beta + t.xi * (q * inv_q);
                // σ : Δεᵖ = Δλ (αg I1 + s : n̂/√2), s : n̂/√2 = q + β : ξᵗʳ/(2qᵗʳ).
                let work = dl * (self.alpha_g * i1 + q + 0.5 * inv_q * beta.ddot(&t.xi));
                let st = V::new(beta.to_sym(), k, eps_n + dl);
                let rep =
                    UpdateReport { branch: DpBranch::CONE, delta_lambda: dl, dissipation: work };
                (s, st, rep)
            }
            Return::Apex { dl, i1, k } => {
                // β_{n+1} = β + (1 − M)H Δλ √2 n̂ = β + ((1 − M)H/B) ξᵗʳ.
                let beta = t.beta + t.xi * (self.kin_h * self.inv_b);
                let s = T::IDENTITY * (i1 / 3.0) + beta;
                // σ : C⁻¹ : (σᵗʳ − σ) with σᵗʳ − σ = (I1ᵗʳ − I1)/3 I + (G/B) ξᵗʳ.
                let work = i1 * (t.i1 - i1) * self.inv_9k + 0.5 * self.inv_b * beta.ddot(&t.xi);
                let st = V::new(beta.to_sym(), k, eps_n + dl);
                let rep =
                    UpdateReport { branch: DpBranch::APEX, delta_lambda: dl, dissipation: work };
                (s, st, rep)
            }
        };
        if new_sigma.finite_probe() != 0.0 {
            // finite inputs so large that the trial overflowed: refuse, leave inputs untouched.
            let (component, value) =
                new_sigma.to_sym().first_non_finite().unwrap_or(("xx", f64::NAN));
            return Err(ConstitutiveError::NonFiniteStress { component, value });
        }
        *sigma = new_sigma;
        *state = new_state;
        Ok(report)
    }
}

impl<V: DpVariables> TangentModel for DruckerPrager<V> {
    fn consistent_tangent(
        &self,
        sigma: &SymTensor,
        state: &V,
        d_eps: &SymTensor,
        _dt: f64,
    ) -> Result<Tangent, ConstitutiveError> {
        // the inherent method (inherent methods take precedence over trait methods).
        DruckerPrager::<V>::consistent_tangent(self, sigma, state, d_eps)
    }
}
