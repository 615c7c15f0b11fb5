//! Mohr–Coulomb plasticity with non-associated flow, integrated by the exact return in
//! principal stresses to a face, an edge or the apex of the pyramid (Clausen, Damkilde &
//! Andersen 2006, 2007), with its consistent tangent and optional hardening or softening of
//! `c`, `φ` and `ψ` with plastic strain.
//!
//! Drucker-Prager (eqs 23–25 of the paper) is a cone that must be fitted to the pyramid, and no
//! single fit is right on every stress path (`ConeMatch`): at φ = 30° the cone through the
//! compression corners is, in plane strain, a material of φ ≈ 44° (ψ = 0) to 49° (associated). Mohr–Coulomb needs no such
//! choice: its surface is what a friction angle measured in a shear test means, on every path.
//!
//! # Glossary
//! - `σ1 ≥ σ2 ≥ σ3` principal stresses, **tension positive** (`σ3` is the most compressive).
//! - `c` cohesion (Pa), `φ` friction angle, `ψ` dilatancy angle (`ψ = φ`: associated flow).
//! - `k = (1 + sin φ)/(1 − sin φ)`, `m = (1 + sin ψ)/(1 − sin ψ)`, `c̄ = 2c cos φ/(1 − sin φ)`.
//! - `D` the elastic stiffness in principal space, `D_ij = λ + 2G δ_ij`.
//! - `ε̄ᵖ` equivalent plastic shear strain `Σ √(2 Δeᵖ : Δeᵖ)` (`eᵖ = dev εᵖ`), the same measure as
//!   Drucker-Prager's (a simple shear's plastic `γ`), so that the two models' softening laws
//!   read alike.
//!
//! # Model
//! ```text
//! f = (σ1 − σ3) + (σ1 + σ3) sin φ − 2c cos φ  ∝  k σ1 − σ3 − c̄          yield function
//! g = m σ1 − σ3                                                         plastic potential
//! ```
//! on the sector `σ1 ≥ σ2 ≥ σ3`; the other five faces follow by symmetry. Tension cut-off at
//! the apex `σ1 = σ2 = σ3 = c cot φ`: a point pulled apart goes there (zero stress for a
//! cohesionless sand, whose grains then separate), whatever `ψ`.
//!
//! # Return (exact, closed form)
//! With the elastic trial `σᴮ` (principal, sorted) and `a = ∂f/∂σ`, `b = ∂g/∂σ`:
//! - **face**: `σ = σᴮ − Δλ D b`, `Δλ = f(σᴮ)/(aᵀ D b)`; valid while the result stays sorted;
//! - **edge** (triaxial compression `σ1 = σ2`, or extension `σ2 = σ3`): two multipliers for the
//!   face and its neighbour, `σ = σᴮ − Δλ1 D b1 − Δλ2 D b2` with both yield functions zero, a
//!   2 × 2 solve; valid when both multipliers are non-negative and the edge point is not
//!   beyond the apex;
//! - **apex**: `σ = c cot φ (1, 1, 1)`.
//!
//! For linear yield planes these regions partition the stress space (Clausen et al. 2007):
//! exactly one return is admissible (a property test checks it). The stress is rebuilt as
//! `σᵗʳ − Σ (σᴮ_a − σ_a) n_a ⊗ n_a` in the trial's principal directions `n_a` (isotropic
//! elasticity keeps them). The plastic strain `Δεᵖ = D⁻¹ (σᴮ − σ)` is coaxial; its deviatoric
//! norm gives `Δε̄ᵖ` and `σ : Δεᵖ` the dissipation. At the apex, as for the Drucker-Prager apex,
//! the volumetric part beyond the flow rule is the opening of the granular skeleton.
//!
//! # Hardening and softening
//! `c`, `φ` and `ψ` may change with `ε̄ᵖ`: constant up to `peak_plastic_strain`, linear to their
//! residual values at `residual_plastic_strain`, constant after (the peak-to-critical-state
//! softening of dense sand, or hardening when the residual values are higher). They are taken
//! at the start of each increment (explicit in `ε̄ᵖ`, as CB-Geo mpm does): the return stays
//! exact and closed form, and the increment's own plastic strain acts from the next one on;
//! with the small increments of an explicit MPM step the lag is one step of `ε̄ᵖ`.
//!
//! # Plane strain
//! With `yz = zx = 0`, `σ_zz` is a principal stress and the decomposition is closed form
//! ([`crate::principal`]); the returned stress keeps `yz = zx = 0` to the bit, so the default
//! [`ConstitutiveModel::update_plane`] (through the full tensor, [`crate::PlaneTensor`]) is exact.
// (3 × 3 index arithmetic reads as the formulas it implements)
#![allow(clippy::needless_range_loop)]

use serde::{Deserialize, Serialize};

use crate::elastic::LinearElastic;
use crate::error::ConstitutiveError;
use crate::model::{Branch, ConstitutiveModel, TangentModel, UpdateReport, check_finite};
use crate::principal::Principal;
use crate::tensor::{SymTensor, Symmetric, Tangent};

/// Material parameters of [`MohrCoulomb`] (SI units, angles in degrees).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MohrCoulombParams {
    /// Young's modulus `E > 0` (Pa).
    pub young: f64,
    /// Poisson's ratio `−1 < ν < 0.5`.
    pub poisson: f64,
    /// cohesion `c ≥ 0` (Pa), at the peak.
    pub cohesion: f64,
    /// friction angle `0 ≤ φ < 90` (degrees), at the peak.
    pub friction_angle_deg: f64,
    /// dilatancy angle `0 ≤ ψ ≤ φ` (degrees), at the peak; `ψ = φ` is associated flow.
    pub dilatancy_angle_deg: f64,
    /// how `c`, `φ` and `ψ` change with plastic strain; `None`: perfectly plastic.
    pub softening: Option<MohrCoulombSoftening>,
}

/// Hardening or softening of a [`MohrCoulomb`] material: the peak values hold up to
/// `peak_plastic_strain`, change linearly to the residual ones at `residual_plastic_strain`,
/// and stay there.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MohrCoulombSoftening {
    /// residual cohesion `c_r ≥ 0` (Pa).
    pub residual_cohesion: f64,
    /// residual friction angle `0 ≤ φ_r < 90` (degrees).
    pub residual_friction_angle_deg: f64,
    /// residual dilatancy angle `0 ≤ ψ_r ≤ φ_r` (degrees).
    pub residual_dilatancy_angle_deg: f64,
    /// `ε̄ᵖ` up to which the peak values hold (≥ 0).
    pub peak_plastic_strain: f64,
    /// `ε̄ᵖ` at which the residual values are reached (> `peak_plastic_strain`).
    pub residual_plastic_strain: f64,
}

impl MohrCoulombParams {
    /// a cohesionless sand, non-dilatant, perfectly plastic: `E = 2 MPa`, `ν = 0.3`, `c = 0`,
    /// `φ` as given.
    pub fn sand(friction_angle_deg: f64) -> Self {
        Self {
            young: 2.0e6,
            poisson: 0.3,
            cohesion: 0.0,
            friction_angle_deg,
            dilatancy_angle_deg: 0.0,
            softening: None,
        }
    }
}

/// Internal variables of a [`MohrCoulomb`] point: the equivalent plastic strain only (8 B).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct McState {
    /// equivalent plastic shear strain `ε̄ᵖ`.
    pub eps_p_bar: f64,
}

/// The branches of the Mohr–Coulomb return, in the order of its
/// [`ConstitutiveModel::BRANCHES`].
pub struct McBranch;

impl McBranch {
    /// the trial state was admissible.
    pub const ELASTIC: Branch = Branch::ELASTIC;
    /// return to the face of the pyramid (`σ1 > σ2 > σ3` after the return).
    pub const FACE: Branch = Branch::new(1);
    /// return to the triaxial-compression edge (`σ1 = σ2 > σ3`).
    pub const COMPRESSION_EDGE: Branch = Branch::new(2);
    /// return to the triaxial-extension edge (`σ1 > σ2 = σ3`).
    pub const EXTENSION_EDGE: Branch = Branch::new(3);
    /// return to the apex (`σ1 = σ2 = σ3 = c cot φ`): the tension cut-off.
    pub const VERTEX: Branch = Branch::new(4);
}

/// The strength at one `ε̄ᵖ`: the coefficients of the sector's yield plane and potential.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Strength {
    /// `k = (1 + sin φ)/(1 − sin φ)`.
    k: f64,
    /// `c̄ = 2c cos φ/(1 − sin φ)` (Pa).
    cbar: f64,
    /// `m = (1 + sin ψ)/(1 − sin ψ)`.
    m: f64,
    /// the apex `c cot φ` (Pa); `None` for φ = 0 (Tresca: no apex).
    apex: Option<f64>,
    /// `c cos φ` (Pa) and `sin φ`: the cone inscribed in the pyramid,
    /// `√J2 √(1 + sin²φ/3) ≤ c cos φ − p sin φ`, an elastic test without the decomposition.
    c_cos: f64,
    sin: f64,
    /// `1 + sin²φ/3`.
    inscribed: f64,
}

impl Strength {
    fn new(c: f64, phi_deg: f64, psi_deg: f64) -> Self {
        let (sin, cos) = phi_deg.to_radians().sin_cos();
        let sin_psi = psi_deg.to_radians().sin();
        let k = (1.0 + sin) / (1.0 - sin);
        let cbar = 2.0 * c * cos / (1.0 - sin);
        let apex = (sin > 0.0).then(|| c * cos / sin);
        Self {
            k,
            cbar,
            m: (1.0 + sin_psi) / (1.0 - sin_psi),
            apex,
            c_cos: c * cos,
            sin,
            inscribed: 1.0 + sin * sin / 3.0,
        }
    }
}

/// Mohr–Coulomb plasticity (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MohrCoulomb {
    params: MohrCoulombParams,
    elastic: LinearElastic,
    /// the strength at the peak (and throughout, without softening).
    peak: Strength,
    /// λ and 2G.
    lame: f64,
    two_g: f64,
}

/// Which return, with the principal stresses it gives and `dσ/dσᴮ` in principal space.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Return {
    branch: Branch,
    stress: [f64; 3],
    jacobian: [[f64; 3]; 3],
}

impl MohrCoulomb {
    /// validates the parameters.
    pub fn new(p: MohrCoulombParams) -> Result<Self, ConstitutiveError> {
        let elastic = LinearElastic::from_young_poisson(p.young, p.poisson)?;
        let invalid =
            |name, value, range| ConstitutiveError::InvalidParameter { name, value, range };
        check_strength(
            p.cohesion,
            p.friction_angle_deg,
            p.dilatancy_angle_deg,
            ["cohesion", "friction_angle_deg", "dilatancy_angle_deg"],
        )?;
        if let Some(s) = p.softening {
            check_strength(
                s.residual_cohesion,
                s.residual_friction_angle_deg,
                s.residual_dilatancy_angle_deg,
                [
                    "residual_cohesion",
                    "residual_friction_angle_deg",
                    "residual_dilatancy_angle_deg",
                ],
            )?;
            if !(s.peak_plastic_strain.is_finite() && s.peak_plastic_strain >= 0.0) {
                return Err(invalid(
                    "peak_plastic_strain",
                    s.peak_plastic_strain,
                    "0 <= peak_plastic_strain < inf",
                ));
            }
            if !(s.residual_plastic_strain.is_finite()
                && s.residual_plastic_strain > s.peak_plastic_strain)
            {
                return Err(invalid(
                    "residual_plastic_strain",
                    s.residual_plastic_strain,
                    "peak_plastic_strain < residual_plastic_strain < inf",
                ));
            }
        }
        let peak = Strength::new(p.cohesion, p.friction_angle_deg, p.dilatancy_angle_deg);
        if !peak.cbar.is_finite() {
            return Err(invalid(
                "cohesion",
                p.cohesion,
                "0 <= cohesion with a finite strength (Pa)",
            ));
        }
        Ok(Self {
            params: p,
            elastic,
            peak,
            lame: elastic.lame_lambda(),
            two_g: 2.0 * elastic.shear_modulus(),
        })
    }

    /// the validated parameters.
    pub fn params(&self) -> &MohrCoulombParams {
        &self.params
    }

    /// the elastic part.
    pub fn elasticity(&self) -> &LinearElastic {
        &self.elastic
    }

    /// `(c, φ, ψ)` (Pa, degrees) at the equivalent plastic strain `eps_p_bar`.
    pub fn strength_at(&self, eps_p_bar: f64) -> (f64, f64, f64) {
        let p = &self.params;
        let peak = (p.cohesion, p.friction_angle_deg, p.dilatancy_angle_deg);
        let Some(s) = p.softening else { return peak };
        let t = ((eps_p_bar - s.peak_plastic_strain)
            / (s.residual_plastic_strain - s.peak_plastic_strain))
            .clamp(0.0, 1.0);
        let lerp = |a: f64, b: f64| a + t * (b - a);
        (
            lerp(peak.0, s.residual_cohesion),
            lerp(peak.1, s.residual_friction_angle_deg),
            // (ψ ≤ φ at both ends, so along the line too)
            lerp(peak.2, s.residual_dilatancy_angle_deg),
        )
    }

    #[inline]
    fn strength(&self, state: &McState) -> Strength {
        if self.params.softening.is_none() {
            return self.peak;
        }
        let (c, phi, psi) = self.strength_at(state.eps_p_bar);
        Strength::new(c, phi, psi)
    }

    /// the yield function in stress units, `f = (σ1 − σ3) + (σ1 + σ3) sin φ − 2c cos φ` (Pa),
    /// at the strength of `state`; `f ≤ 0` is admissible.
    pub fn yield_function(&self, sigma: &SymTensor, state: &McState) -> f64 {
        let (c, phi, _) = self.strength_at(state.eps_p_bar);
        let (sin, cos) = phi.to_radians().sin_cos();
        let [s1, _, s3] = Principal::of(sigma).values;
        (s1 - s3) + (s1 + s3) * sin - 2.0 * c * cos
    }

    /// `D v` with `D_ij = λ + 2G δ_ij` (the elastic stiffness in principal space).
    #[inline]
    fn d(&self, v: [f64; 3]) -> [f64; 3] {
        let l = self.lame * (v[0] + v[1] + v[2]);
        [l + self.two_g * v[0], l + self.two_g * v[1], l + self.two_g * v[2]]
    }

    /// the return of the sorted trial principal stresses `sb` (see the module docs).
    fn return_map(&self, sb: [f64; 3], st: &Strength) -> Result<Return, ConstitutiveError> {
        let Strength { k, cbar, m, apex, .. } = *st;
        let f = k * sb[0] - sb[2] - cbar;
        let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        if !f.is_finite() {
            return Err(ConstitutiveError::NonFiniteStress { component: "trial", value: f });
        }
        if f <= 0.0 {
            return Ok(Return { branch: McBranch::ELASTIC, stress: sb, jacobian: identity });
        }
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        // the sector's face: a1 = (k, 0, −1), b1 = (m, 0, −1).
        let (a1, b1) = ([k, 0.0, -1.0], [m, 0.0, -1.0]);
        let db1 = self.d(b1);
        let den = dot(a1, db1);
        let dl = f / den;
        let face = [sb[0] - dl * db1[0], sb[1] - dl * db1[1], sb[2] - dl * db1[2]];
        if face[0] >= face[1] && face[1] >= face[2] {
            let mut jac = identity;
            for (i, row) in jac.iter_mut().enumerate() {
                for (j, x) in row.iter_mut().enumerate() {
                    *x -= db1[i] * a1[j] / den;
                }
            }
            return Ok(Return { branch: McBranch::FACE, stress: face, jacobian: jac });
        }
        // an edge: the face and its neighbour across σ1 = σ2 (compression) or σ2 = σ3
        // (extension); the one the face return crossed first.
        let compression = face[1] > face[0];
        let edges = if compression { [true, false] } else { [false, true] };
        for compression in edges {
            let (a2, b2) = if compression {
                ([0.0, k, -1.0], [0.0, m, -1.0])
            } else {
                ([k, -1.0, 0.0], [m, -1.0, 0.0])
            };
            let db2 = self.d(b2);
            let f2 = dot(a2, sb) - cbar;
            // [a1·Db1 a1·Db2; a2·Db1 a2·Db2] (Δλ1, Δλ2) = (f1, f2)
            let (m11, m12, m21, m22) = (den, dot(a1, db2), dot(a2, db1), dot(a2, db2));
            let det = m11 * m22 - m12 * m21;
            if det.is_nan() || det == 0.0 {
                continue;
            }
            let dl1 = (m22 * f - m12 * f2) / det;
            let dl2 = (m11 * f2 - m21 * f) / det;
            // (a multiplier that is zero but for rounding: the face return was just invalid)
            let slack = 1e-12 * (dl1.abs() + dl2.abs());
            if dl1 < -slack || dl2 < -slack {
                continue;
            }
            let mut s = [0.0; 3];
            for i in 0..3 {
                s[i] = sb[i] - dl1 * db1[i] - dl2 * db2[i];
            }
            // the two equal values exactly equal, and the edge point on this side of the apex
            let (branch, on_side) = if compression {
                let x = 0.5 * (s[0] + s[1]);
                s[0] = x;
                s[1] = x;
                (McBranch::COMPRESSION_EDGE, x >= s[2])
            } else {
                let x = 0.5 * (s[1] + s[2]);
                s[1] = x;
                s[2] = x;
                (McBranch::EXTENSION_EDGE, s[0] >= x)
            };
            // (without an apex, φ = 0, the edge point is on its side by 2c ≥ 0: rounding
            // must not send it anywhere else)
            if !on_side && apex.is_some() {
                continue;
            }
            // dσ/dσᴮ = I − [Db1 Db2] M⁻¹ [a1 a2]ᵀ
            let inv = [[m22 / det, -m12 / det], [-m21 / det, m11 / det]];
            let mut jac = identity;
            for (i, row) in jac.iter_mut().enumerate() {
                for (j, x) in row.iter_mut().enumerate() {
                    let u = [db1[i], db2[i]];
                    let w = [a1[j], a2[j]];
                    for r in 0..2 {
                        for c in 0..2 {
                            *x -= u[r] * inv[r][c] * w[c];
                        }
                    }
                }
            }
            return Ok(Return { branch, stress: s, jacobian: jac });
        }
        match apex {
            Some(x) => {
                Ok(Return { branch: McBranch::VERTEX, stress: [x; 3], jacobian: [[0.0; 3]; 3] })
            }
            // φ = 0 has no apex; an edge return always exists then (the flow is deviatoric).
            None => Err(ConstitutiveError::EmptyElasticDomain { k: cbar }),
        }
    }

    /// the elastic trial `σ + λ tr(Δε) I + 2G Δε`.
    #[inline]
    fn trial(&self, sigma: &SymTensor, d_eps: &SymTensor) -> SymTensor {
        sigma.elastic_trial(self.lame * d_eps.trace(), self.two_g, d_eps)
    }

    /// the consistent tangent `dσ_{n+1}/dΔε` (the [`Tangent`] convention of
    /// [`crate::tensor`]): in principal space `J D` with `J = dσ/dσᴮ` of the branch taken,
    /// and the spin of the principal frame `(σ_a − σ_b)/(σᴮ_a − σᴮ_b)` on the shear parts
    /// (the derivative of an isotropic tensor function).
    pub fn consistent_tangent(
        &self,
        sigma: &SymTensor,
        state: &McState,
        d_eps: &SymTensor,
    ) -> Result<Tangent, ConstitutiveError> {
        self.check_inputs(sigma, state, d_eps)?;
        let trial = self.trial(sigma, d_eps);
        if !trial.is_finite() {
            return Err(overflow(&trial));
        }
        let pr = Principal::of(&trial);
        let r = self.return_map(pr.values, &self.strength(state))?;
        let elastic = self.elastic.stiffness_matrix();
        if r.branch == McBranch::ELASTIC {
            return Ok(elastic);
        }
        let (sb, s, jac) = (pr.values, r.stress, r.jacobian);
        let scale = sb.iter().fold(0.0f64, |a, x| a.max(x.abs())).max(1.0);
        let mut theta = [[0.0; 3]; 3];
        for a in 0..3 {
            for b in 0..3 {
                if a == b || s[a] == s[b] {
                    continue;
                }
                let gap = sb[a] - sb[b];
                theta[a][b] = if gap.abs() > 1e-10 * scale {
                    (s[a] - s[b]) / gap
                } else {
                    jac[a][a] - jac[a][b]
                };
            }
        }
        let mut t = [[0.0; 6]; 6];
        for j in 0..6 {
            let column: [f64; 6] = std::array::from_fn(|i| elastic[i][j]);
            let x = pr.to_frame(&SymTensor::from_array(column));
            let mut y = [[0.0; 3]; 3];
            for a in 0..3 {
                y[a][a] = (0..3).map(|b| jac[a][b] * x[b][b]).sum();
                for b in 0..3 {
                    if a != b {
                        y[a][b] = theta[a][b] * x[a][b];
                    }
                }
            }
            let out = pr.from_frame(&y).to_array();
            for i in 0..6 {
                t[i][j] = out[i];
            }
        }
        Ok(t)
    }

    /// `Err` naming the first non-finite input.
    fn check_inputs(
        &self,
        sigma: &SymTensor,
        state: &McState,
        d_eps: &SymTensor,
    ) -> Result<(), ConstitutiveError> {
        check_finite(sigma, d_eps)?;
        if !state.eps_p_bar.is_finite() {
            return Err(ConstitutiveError::NonFiniteState {
                name: "eps_p_bar",
                value: state.eps_p_bar,
            });
        }
        Ok(())
    }
}

/// checks `(c, φ, ψ)` named by `names`.
fn check_strength(
    c: f64,
    phi: f64,
    psi: f64,
    names: [&'static str; 3],
) -> Result<(), ConstitutiveError> {
    let invalid = |name, value, range| ConstitutiveError::InvalidParameter { name, value, range };
    if !(c.is_finite() && c >= 0.0) {
        return Err(invalid(names[0], c, "0 <= cohesion < inf (Pa)"));
    }
    if !(0.0..90.0).contains(&phi) {
        return Err(invalid(names[1], phi, "0 <= phi < 90 (deg)"));
    }
    if !(psi >= 0.0 && psi <= phi) {
        return Err(invalid(names[2], psi, "0 <= psi <= friction angle (deg)"));
    }
    if c == 0.0 && phi == 0.0 {
        // no strength at all: every deviatoric stress would return to zero, a fluid
        return Err(invalid(
            names[0],
            c,
            "cohesion > 0 when the friction angle is 0 (no strength at all otherwise)",
        ));
    }
    Ok(())
}

impl ConstitutiveModel for MohrCoulomb {
    type State = McState;
    const IS_PLASTIC: bool = true;
    const BRANCHES: &'static [&'static str] =
        &["elastic", "face", "compression_edge", "extension_edge", "vertex"];

    fn initial_state(&self) -> McState {
        McState::default()
    }

    fn p_wave_modulus(&self, _state: &McState) -> f64 {
        self.elastic.p_wave_modulus()
    }

    fn stored_energy_density(&self, sigma: &SymTensor, _state: &McState) -> f64 {
        self.elastic.strain_energy_density(sigma)
    }

    /// rate-independent: `dt` plays no part.
    fn update(
        &self,
        sigma: &mut SymTensor,
        state: &mut McState,
        d_eps: &SymTensor,
        _dt: f64,
    ) -> Result<UpdateReport, ConstitutiveError> {
        self.check_inputs(sigma, state, d_eps)?;
        let trial = self.trial(sigma, d_eps);
        // finite inputs so large that the trial overflowed: refused before the return (whose
        // apex does not depend on the trial, and would hide it)
        if !trial.is_finite() {
            return Err(overflow(&trial));
        }
        let strength = self.strength(state);
        // inside the cone inscribed in the pyramid (touching its faces where the Lode angle
        // maximises cos θ − sin θ sin φ/√3, at √(1 + sin²φ/3)): elastic, no decomposition
        // needed (most points of a deposit at rest, and the whole elastic range)
        let r = strength.c_cos - trial.mean() * strength.sin;
        if r >= 0.0 && trial.j2() * strength.inscribed <= r * r {
            *sigma = trial;
            return Ok(UpdateReport::ELASTIC);
        }
        let pr = Principal::of(&trial);
        let r = self.return_map(pr.values, &strength)?;
        if r.branch == McBranch::ELASTIC {
            *sigma = trial;
            return Ok(UpdateReport::ELASTIC);
        }
        let sb = pr.values;
        let ds = [sb[0] - r.stress[0], sb[1] - r.stress[1], sb[2] - r.stress[2]];
        let new = if r.branch == McBranch::VERTEX {
            SymTensor::IDENTITY * r.stress[0]
        } else {
            trial - pr.compose(ds)
        };
        if !new.is_finite() {
            return Err(overflow(&new));
        }
        // Δεᵖ = D⁻¹ Δσ: deviatoric part dev(Δσ)/2G, volumetric tr(Δσ)/3K.
        let g = self.elastic.shear_modulus();
        let mean = (ds[0] + ds[1] + ds[2]) / 3.0;
        let dev = [ds[0] - mean, ds[1] - mean, ds[2] - mean];
        let dev_norm = (dev[0] * dev[0] + dev[1] * dev[1] + dev[2] * dev[2]).sqrt();
        let d_eps_bar = std::f64::consts::SQRT_2 * dev_norm / (2.0 * g);
        let vol = 3.0 * mean / (3.0 * self.elastic.bulk_modulus());
        let s = r.stress;
        let s_mean = (s[0] + s[1] + s[2]) / 3.0;
        let work = (0..3).map(|i| (s[i] - s_mean) * dev[i]).sum::<f64>() / (2.0 * g) + s_mean * vol;
        if !(d_eps_bar.is_finite() && work.is_finite()) {
            return Err(overflow(&trial));
        }
        *sigma = new;
        state.eps_p_bar += d_eps_bar;
        Ok(UpdateReport { branch: r.branch, delta_lambda: d_eps_bar, dissipation: work })
    }

    fn rotate_state(&self, _state: &mut McState, _r: &glam::DMat3) {}

    #[inline(always)]
    fn rotate_state_z(&self, _state: &mut McState, _c: f64, _s: f64) {}

    fn equivalent_plastic_strain(&self, state: &McState) -> f64 {
        state.eps_p_bar
    }
}

impl TangentModel for MohrCoulomb {
    fn consistent_tangent(
        &self,
        sigma: &SymTensor,
        state: &McState,
        d_eps: &SymTensor,
        _dt: f64,
    ) -> Result<Tangent, ConstitutiveError> {
        MohrCoulomb::consistent_tangent(self, sigma, state, d_eps)
    }
}

/// the error of a stress that overflowed from finite inputs.
#[cold]
fn overflow(t: &SymTensor) -> ConstitutiveError {
    let (component, value) = t.first_non_finite().unwrap_or(("xx", f64::NAN));
    ConstitutiveError::NonFiniteStress { component, value }
}
