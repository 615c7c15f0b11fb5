//! The μ(I) rheology of dense granular flow (Jop, Forterre & Pouliquen 2006, "A constitutive law
//! for dense granular flows", Nature 441), integrated as an elasto-viscoplastic model in the
//! manner of Dunatunga & Kamrin (2015, J. Fluid Mech. 779): pressure- and rate-dependent friction,
//! an elastic response below the static friction, and a material that separates in tension.
//!
//! # Glossary
//! - `σ` stress (tension positive), `p = −tr σ/3` pressure, `s = dev σ`,
//!   `τ̄ = √(½ s : s) = √J2` equivalent shear stress (Pa).
//! - `Dᵖ` plastic strain rate, `γ̇ᵖ = √(2 Dᵖ : Dᵖ)` equivalent plastic shear rate (1/s); in
//!   simple shear `u(z)` it is `du/dz`, and `τ̄ = |τ_xz|`.
//! - `d` grain diameter (m), `ρ_s` grain density (kg/m³; the bulk density is `φ ρ_s` for a solid
//!   fraction `φ`), `I = γ̇ᵖ d / √(p/ρ_s)` the inertial number.
//! - `μ(I) = μ_s + (μ_2 − μ_s) / (I_0/I + 1)`: friction from its static value `μ_s` (I → 0) to its
//!   limit `μ_2` (I → ∞); `I_0` the inertial number half-way.
//! - `K`, `G` the elastic bulk and shear moduli ([`LinearElastic`]).
//!
//! # Model
//! Elastic trial `σᵗʳ = σ + C : Δε` (eq 10 of Abe et al. 2005). Then, with `pᵗʳ`, `τ̄ᵗʳ` its
//! pressure and equivalent shear stress:
//! - `pᵗʳ ≤ 0` (**separated**): the grains lose contact, `σ = 0`. A cohesionless granular
//!   material carries no tension. The volumetric strain past the point of zero pressure,
//!   `e_o = −pᵗʳ/K`, is kept as the *opening* (the loose material's volume in excess of the
//!   volume at which it lost contact, the role of Dunatunga & Kamrin's critical density): while
//!   `e_o > 0` the material is a stress-free granular gas that stretches and compacts freely,
//!   and it carries stress again only once compaction has closed the opening (the part of the
//!   increment after closure loads the skeleton). Without it, a cloud of separated grains at a
//!   tenth of its density would stiffen at the first compression as if it were dense.
//! - `τ̄ᵗʳ ≤ μ_s pᵗʳ` (**elastic**): `σ = σᵗʳ`.
//! - otherwise (**flowing**): the deviator shrinks radially at constant pressure (no dilatancy,
//!   as in Jop et al.), `Dᵖ = γ̇ᵖ s/(2τ̄)`, so `τ̄ = τ̄ᵗʳ − G Δt γ̇ᵖ`, and the shear stress is the
//!   rheology's, `τ̄ = μ(I(γ̇ᵖ)) p`. With `R = τ̄ᵗʳ − μ_s p > 0`, `A = G Δt`,
//!   `b = I_0 √(p/ρ_s)/d` (so `I_0/I = b/γ̇ᵖ`) and `Δμ = μ_2 − μ_s`, this is the quadratic
//!   ```text
//!   A γ̇² − B γ̇ − R b = 0,   B = R − A b − p Δμ,
//!   ```
//!   whose one positive root is `γ̇ᵖ = (B + √(B² + 4ARb)) / (2A)` (written as
//!   `2Rb / (√(B² + 4ARb) − B)` when `B < 0`, free of cancellation). The return is closed form,
//!   unconditionally stable in `Δt`, and tends to the rate-independent return onto `τ̄ = μ_s p`
//!   as `Δμ → 0`.
//!
//! In steady simple shear the elastic strain is constant, so `γ̇ᵖ` is the shear rate and
//! `τ/p = μ(I)` exactly: Jop et al.'s law. On an inclined plane (`τ/p = tan θ` at every depth)
//! this gives Bagnold's profile.
//!
//! The plastic work of a flowing step is `σ : Dᵖ Δt = τ̄ γ̇ᵖ Δt ≥ 0`.

use glam::DMat3;
use serde::{Deserialize, Serialize};

use crate::elastic::LinearElastic;
use crate::error::ConstitutiveError;
use crate::model::{Branch, ConstitutiveModel, TangentModel, UpdateReport, check_finite};
use crate::tensor::{SymTensor, Tangent};

/// Parameters of [`MuI`] (SI units). As a serde table (a scene's `[materials.NAME]` with
/// `kind = "mu_i"`) it refuses unknown fields.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MuIParams {
    /// Young's modulus `E` of the granular skeleton (Pa), > 0.
    pub young: f64,
    /// Poisson's ratio `ν`, in (−1, 0.5).
    pub poisson: f64,
    /// static friction `μ_s = μ(0)`, ≥ 0 (Jop et al.'s glass beads: tan 20.9° = 0.38).
    pub mu_s: f64,
    /// limiting friction `μ_2 = μ(∞)`, ≥ `μ_s` (glass beads: tan 32.76° = 0.64).
    pub mu_2: f64,
    /// the inertial number `I_0` at which `μ` is half-way from `μ_s` to `μ_2`, > 0 (0.279).
    pub i0: f64,
    /// grain diameter `d` (m), > 0.
    pub grain_diameter: f64,
    /// grain (solid) density `ρ_s` (kg/m³), > 0: the bulk density divided by the solid
    /// fraction.
    pub grain_density: f64,
}

impl MuIParams {
    /// Jop, Forterre & Pouliquen's (2006) glass beads: μ_s = tan 20.9°, μ_2 = tan 32.76°,
    /// I_0 = 0.279, d = 0.53 mm, ρ_s = 2450 kg/m³, on an elastic skeleton (`young`, `poisson`)
    /// that the rheology does not specify.
    pub fn glass_beads(young: f64, poisson: f64) -> Self {
        Self {
            young,
            poisson,
            mu_s: 20.9f64.to_radians().tan(),
            mu_2: 32.76f64.to_radians().tan(),
            i0: 0.279,
            grain_diameter: 0.53e-3,
            grain_density: 2450.0,
        }
    }
}

/// The branches of the μ(I) update, in the order of its [`ConstitutiveModel::BRANCHES`]
/// (`["elastic", "flowing", "separated"]`).
pub struct MuIBranch;

impl MuIBranch {
    /// below the static friction: elastic.
    pub const ELASTIC: Branch = Branch::ELASTIC;
    /// shear stress at `μ(I) p`: viscoplastic flow.
    pub const FLOWING: Branch = Branch::new(1);
    /// no pressure: the grains separate, the stress vanishes.
    pub const SEPARATED: Branch = Branch::new(2);
}

/// Internal variables of [`MuI`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MuIState {
    /// the accumulated equivalent plastic shear strain `Σ γ̇ᵖ Δt` (dimensionless).
    pub gamma_p: f64,
    /// the opening `e_o ≥ 0`: volumetric strain of separated material in excess of the volume
    /// at which it lost contact (module docs); 0 while the grains touch.
    pub opening: f64,
}

/// The elasto-viscoplastic μ(I) rheology (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MuI {
    params: MuIParams,
    elastic: LinearElastic,
}

impl MuI {
    /// a μ(I) material from validated parameters.
    pub fn new(params: MuIParams) -> Result<Self, ConstitutiveError> {
        const MAX_I0: f64 = 10.0;
        const GRAIN_DIAMETER_RANGE: (f64, f64) = (1e-6, 10.0);
        let elastic = LinearElastic::from_young_poisson(params.young, params.poisson)?;
        let checks = [
            ("mu_s", params.mu_s, params.mu_s.is_finite() && params.mu_s >= 0.0, "0 <= mu_s"),
            (
                "mu_2",
                params.mu_2,
                params.mu_2.is_finite() && params.mu_2 >= params.mu_s,
                "mu_s <= mu_2 (finite)",
            ),
            // Measured I_0 lie between 0.005 and 1 (GDR MiDi 2004); beyond 10 the flow rule's
            // rate I_0 √(p/ρ_s)/d overflows at a step for ordinary pressures (1e308 gave NaN).
            (
                "i0",
                params.i0,
                params.i0 > 0.0 && params.i0 <= MAX_I0,
                "0 < i0 <= 10 (measured values 0.005–1)",
            ),
            // From silt (a micrometre) to boulders (ten metres); a subnormal diameter (1e-320)
            // made 1/d infinite.
            (
                "grain_diameter",
                params.grain_diameter,
                (GRAIN_DIAMETER_RANGE.0..=GRAIN_DIAMETER_RANGE.1).contains(&params.grain_diameter),
                "1e-6 <= grain_diameter <= 10 (m)",
            ),
            (
                "grain_density",
                params.grain_density,
                params.grain_density.is_finite() && params.grain_density > 0.0,
                "grain_density > 0 (kg/m³)",
            ),
        ];
        for (name, value, ok, range) in checks {
            if !ok {
                return Err(ConstitutiveError::InvalidParameter { name, value, range });
            }
        }
        Ok(Self { params, elastic })
    }

    /// the parameters.
    pub fn params(&self) -> &MuIParams {
        &self.params
    }

    /// the elastic part.
    pub fn elasticity(&self) -> &LinearElastic {
        &self.elastic
    }

    /// `μ(I) = μ_s + (μ_2 − μ_s) I / (I_0 + I)` for `I ≥ 0`.
    pub fn friction(&self, inertial_number: f64) -> f64 {
        let p = &self.params;
        p.mu_s + (p.mu_2 - p.mu_s) * inertial_number / (p.i0 + inertial_number)
    }

    /// the inertial number `I = γ̇ d / √(p/ρ_s)` of shear rate `shear_rate` (1/s) at pressure
    /// `pressure > 0` (Pa).
    pub fn inertial_number(&self, shear_rate: f64, pressure: f64) -> f64 {
        let p = &self.params;
        shear_rate * p.grain_diameter / (pressure / p.grain_density).sqrt()
    }

    /// the inertial number at which `μ(I) = mu`, for `μ_s ≤ mu < μ_2`:
    /// `I = I_0 (mu − μ_s)/(μ_2 − mu)` (e.g. `I_θ` of a steady flow on a slope, `mu = tan θ`).
    pub fn inertial_number_at(&self, mu: f64) -> f64 {
        let p = &self.params;
        p.i0 * (mu - p.mu_s) / (p.mu_2 - mu)
    }

    /// the plastic shear rate `γ̇ᵖ` of a flowing step (module docs) from the trial shear stress
    /// `tau_trial` at pressure `p > 0` over `dt`.
    fn plastic_rate(&self, tau_trial: f64, p: f64, dt: f64) -> f64 {
        let q = &self.params;
        let a = self.elastic.shear_modulus() * dt;
        let r = tau_trial - q.mu_s * p;
        let b = q.i0 * (p / q.grain_density).sqrt() / q.grain_diameter;
        let bb = r - a * b - p * (q.mu_2 - q.mu_s);
        let root = (bb * bb + 4.0 * a * r * b).sqrt();
        if bb >= 0.0 { (bb + root) / (2.0 * a) } else { 2.0 * r * b / (root - bb) }
    }
}

impl ConstitutiveModel for MuI {
    type State = MuIState;
    const IS_PLASTIC: bool = true;
    const BRANCHES: &'static [&'static str] = &["elastic", "flowing", "separated"];

    fn initial_state(&self) -> MuIState {
        MuIState::default()
    }

    /// the elastic skeleton's (the rheology changes no stiffness).
    fn p_wave_modulus(&self, _state: &MuIState) -> f64 {
        self.elastic.p_wave_modulus()
    }

    fn stored_energy_density(&self, sigma: &SymTensor, _state: &MuIState) -> f64 {
        self.elastic.strain_energy_density(sigma)
    }

    fn update(
        &self,
        sigma: &mut SymTensor,
        state: &mut MuIState,
        d_eps: &SymTensor,
        dt: f64,
    ) -> Result<UpdateReport, ConstitutiveError> {
        check_finite(sigma, d_eps)?;
        if !state.gamma_p.is_finite() {
            return Err(ConstitutiveError::NonFiniteState {
                name: "gamma_p",
                value: state.gamma_p,
            });
        }
        if !(dt.is_finite() && dt > 0.0) {
            return Err(ConstitutiveError::InvalidParameter {
                name: "dt",
                value: dt,
                range: "finite and > 0 (a rate-dependent model needs the step's duration)",
            });
        }
        if !state.opening.is_finite() {
            return Err(ConstitutiveError::NonFiniteState {
                name: "opening",
                value: state.opening,
            });
        }
        // Separated material is stress-free until compaction closes the opening; only the part
        // of the increment after closure (fraction f, over f Δt) loads the skeleton.
        let (mut start, mut d_eps, mut dt) = (*sigma, *d_eps, dt);
        if state.opening > 0.0 {
            let dv = d_eps.trace();
            let open = state.opening + dv;
            if open >= 0.0 {
                *sigma = SymTensor::ZERO;
                state.opening = open;
                return Ok(UpdateReport {
                    branch: MuIBranch::SEPARATED,
                    delta_lambda: 0.0,
                    dissipation: 0.0,
                });
            }
            let f = open / dv; // both negative: f ∈ (0, 1]
            d_eps = d_eps * f;
            dt *= f;
            start = SymTensor::ZERO;
        }
        let trial = start + self.elastic.stress_increment(&d_eps);
        if !trial.is_finite() {
            let (component, value) = trial.first_non_finite().unwrap_or(("xx", f64::NAN));
            return Err(ConstitutiveError::NonFiniteStress { component, value });
        }
        state.opening = 0.0;
        let p = -trial.mean();
        if p <= 0.0 {
            *sigma = SymTensor::ZERO;
            state.opening = -p / self.elastic.bulk_modulus();
            return Ok(UpdateReport {
                branch: MuIBranch::SEPARATED,
                delta_lambda: 0.0,
                dissipation: 0.0,
            });
        }
        let s = trial.deviator();
        let tau_trial = s.j2().sqrt();
        if tau_trial <= self.params.mu_s * p {
            *sigma = trial;
            return Ok(UpdateReport::ELASTIC);
        }
        let rate = self.plastic_rate(tau_trial, p, dt);
        let tau = tau_trial - self.elastic.shear_modulus() * dt * rate;
        *sigma = SymTensor::IDENTITY * -p + s * (tau / tau_trial);
        let d_gamma = rate * dt;
        state.gamma_p += d_gamma;
        Ok(UpdateReport {
            branch: MuIBranch::FLOWING,
            delta_lambda: d_gamma,
            dissipation: tau * d_gamma,
        })
    }

    fn rotate_state(&self, _state: &mut MuIState, _r: &DMat3) {}

    #[inline(always)]
    fn rotate_state_z(&self, _state: &mut MuIState, _c: f64, _s: f64) {}

    fn equivalent_plastic_strain(&self, state: &MuIState) -> f64 {
        state.gamma_p
    }
}

impl TangentModel for MuI {
    /// by central differences of the update (the return has a closed form but its derivative
    /// is long; the element-test Newton iteration only needs a tangent good to ~1e-6).
    fn consistent_tangent(
        &self,
        sigma: &SymTensor,
        state: &MuIState,
        d_eps: &SymTensor,
        dt: f64,
    ) -> Result<Tangent, ConstitutiveError> {
        check_finite(sigma, d_eps)?;
        // a strain step far above rounding of the stress (relative 1e-16) and far below the
        // curvature of the return (strains of order Δε).
        let scale = d_eps.norm().max(sigma.norm() / self.elastic.p_wave_modulus()).max(1e-12);
        let h = 1e-6 * scale;
        let mut t = [[0.0; 6]; 6];
        for j in 0..6 {
            let mut plus = d_eps.to_array();
            let mut minus = plus;
            plus[j] += h;
            minus[j] -= h;
            let (mut sp, mut sm) = (*sigma, *sigma);
            let (mut stp, mut stm) = (*state, *state);
            self.update(&mut sp, &mut stp, &SymTensor::from_array(plus), dt)?;
            self.update(&mut sm, &mut stm, &SymTensor::from_array(minus), dt)?;
            let (sp, sm) = (sp.to_array(), sm.to_array());
            for i in 0..6 {
                t[i][j] = (sp[i] - sm[i]) / (2.0 * h);
            }
        }
        Ok(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Jop et al.'s glass beads on a soft elastic skeleton.
    fn beads() -> MuI {
        MuI::new(MuIParams::glass_beads(1.0e6, 0.3)).unwrap()
    }

    /// rounding of the quadratic's root and a few products: relative 1e-12.
    const ROOT_REL: f64 = 1e-12;

    #[test]
    fn a_flowing_step_puts_the_shear_stress_on_mu_of_i() {
        let m = beads();
        let p = 500.0;
        let sigma = SymTensor::IDENTITY * -p;
        let dt = 1e-4;
        // G γ above μ_s p = 191 Pa (G = 0.38 MPa): every increment flows.
        for gamma in [1e-3, 1e-2, 1e-1, 1.0] {
            let (mut s, mut st) = (sigma, m.initial_state());
            let d_eps = SymTensor::new(0.0, 0.0, 0.0, 0.5 * gamma, 0.0, 0.0);
            let rep = m.update(&mut s, &mut st, &d_eps, dt).unwrap();
            assert_eq!(rep.branch, MuIBranch::FLOWING);
            // pressure unchanged (no dilatancy), τ = μ(I(γ̇ᵖ)) p with γ̇ᵖ = Δγᵖ/Δt.
            assert!((-s.mean() - p).abs() <= ROOT_REL * p);
            let rate = rep.delta_lambda / dt;
            let mu = m.friction(m.inertial_number(rate, p));
            let tau = s.j2().sqrt();
            assert!(
                (tau - mu * p).abs() <= ROOT_REL * p,
                "γ = {gamma}: τ = {tau}, μp = {}",
                mu * p
            );
            // and the elastic shear strain left is what the stress says: Δγ = Δγᵉ + Δγᵖ.
            let elastic_gamma = tau / m.elasticity().shear_modulus();
            assert!((elastic_gamma + rep.delta_lambda - gamma).abs() <= ROOT_REL * gamma);
            assert!((rep.dissipation - tau * rep.delta_lambda).abs() <= ROOT_REL * tau * gamma);
        }
    }

    #[test]
    fn branches_elastic_below_mu_s_and_separated_in_tension() {
        let m = beads();
        let sigma = SymTensor::IDENTITY * -500.0;
        let (mut s, mut st) = (sigma, m.initial_state());
        // a shear of 0.1 μ_s p: elastic.
        let g = m.elasticity().shear_modulus();
        let small =
            SymTensor::new(0.0, 0.0, 0.0, 0.5 * 0.1 * m.params().mu_s * 500.0 / g, 0.0, 0.0);
        assert_eq!(m.update(&mut s, &mut st, &small, 1e-4).unwrap(), UpdateReport::ELASTIC);
        // stretched beyond zero pressure: stress-free.
        let k = m.elasticity().bulk_modulus();
        let pull = SymTensor::IDENTITY * (2.0 * 500.0 / (3.0 * k));
        let rep = m.update(&mut s, &mut st, &pull, 1e-4).unwrap();
        assert_eq!(rep.branch, MuIBranch::SEPARATED);
        assert_eq!(s, SymTensor::ZERO);
        // the opening is the volumetric strain past zero pressure: tr(pull) − p/K.
        let past = 3.0 * pull.xx - 500.0 / k;
        assert!((st.opening - past).abs() <= 1e-12 * past, "{} vs {past}", st.opening);
    }

    /// Separated grains carry no stress until compaction has closed the opening; then only the
    /// compaction after closure loads the skeleton, so a loose cloud does not stiffen at once.
    #[test]
    fn separated_material_carries_stress_only_after_the_opening_closes() {
        let m = beads();
        let k = m.elasticity().bulk_modulus();
        let (mut s, mut st) = (SymTensor::ZERO, m.initial_state());
        // open by a volumetric strain of 3e-3 in three steps (stress-free all along).
        let pull = SymTensor::IDENTITY * (1e-3 / 3.0);
        for _ in 0..3 {
            assert_eq!(
                m.update(&mut s, &mut st, &pull, 1e-4).unwrap().branch,
                MuIBranch::SEPARATED
            );
            assert_eq!(s, SymTensor::ZERO);
        }
        assert!((st.opening - 3e-3).abs() <= 1e-15);
        // compact by 2e-3: still loose, no stress.
        let push = SymTensor::IDENTITY * (-1e-3 / 3.0);
        for _ in 0..2 {
            assert_eq!(
                m.update(&mut s, &mut st, &push, 1e-4).unwrap().branch,
                MuIBranch::SEPARATED
            );
            assert_eq!(s, SymTensor::ZERO);
        }
        // compact by 1.5e-3: the opening (1e-3) closes, and the last 0.5e-3 loads the skeleton
        // isotropically: p = K · 0.5e-3.
        let last = SymTensor::IDENTITY * (-1.5e-3 / 3.0);
        assert_eq!(m.update(&mut s, &mut st, &last, 1e-4).unwrap(), UpdateReport::ELASTIC);
        assert_eq!(st.opening, 0.0);
        let p = -s.mean();
        assert!((p - k * 0.5e-3).abs() <= 1e-9 * p, "p = {p}, K e = {}", k * 0.5e-3);
        assert!(s.deviator().j2() <= 1e-20 * p * p);
    }

    /// An increment that closes the opening and then shears the re-formed material into flow
    /// is the update from zero stress of the part after closure, over its share of Δt.
    #[test]
    fn a_closing_step_that_shears_flows_over_its_share_of_the_step() {
        let m = beads();
        let opening = 1e-3;
        let st0 = MuIState { opening, ..m.initial_state() };
        // compaction 3e-3 (closure after a third) with a shear that flows at the pressure
        // reached.
        let d = SymTensor::new(-1e-3, -1e-3, -1e-3, 2e-3, 0.0, 0.0);
        let dt = 1e-4;
        let (mut s, mut st) = (SymTensor::ZERO, st0);
        let rep = m.update(&mut s, &mut st, &d, dt).unwrap();
        assert_eq!(rep.branch, MuIBranch::FLOWING);
        let f = 2.0 / 3.0;
        let (mut s_ref, mut st_ref) = (SymTensor::ZERO, m.initial_state());
        let rep_ref = m.update(&mut s_ref, &mut st_ref, &(d * f), dt * f).unwrap();
        assert_eq!(rep, rep_ref);
        assert_eq!((s, st), (s_ref, st_ref));
    }

    #[test]
    fn without_rate_dependence_the_return_is_onto_mu_s() {
        // μ_2 = μ_s: γ̇ᵖ = R/A and τ = μ_s p for any Δt.
        let mu_s = beads().params().mu_s;
        let m = MuI::new(MuIParams { mu_2: mu_s, ..*beads().params() }).unwrap();
        for dt in [1e-6, 1e-3, 1.0] {
            let mut s = SymTensor::IDENTITY * -500.0;
            let d_eps = SymTensor::new(0.0, 0.0, 0.0, 0.05, 0.0, 0.0);
            m.update(&mut s, &mut m.initial_state(), &d_eps, dt).unwrap();
            assert!((s.j2().sqrt() - mu_s * 500.0).abs() <= ROOT_REL * 500.0);
        }
    }

    #[test]
    fn bad_parameters_and_inputs_are_refused_by_name() {
        let p = *beads().params();
        for (bad, name) in [
            (MuIParams { mu_2: 0.1, ..p }, "mu_2"),
            (MuIParams { i0: 0.0, ..p }, "i0"),
            (MuIParams { grain_diameter: f64::NAN, ..p }, "grain_diameter"),
            // inside the old ranges, but NaN at the first step (hostile input R9)
            (MuIParams { i0: 1e308, ..p }, "i0"),
            (MuIParams { grain_diameter: 1e-320, ..p }, "grain_diameter"),
            (MuIParams { grain_density: -1.0, ..p }, "grain_density"),
            (MuIParams { mu_s: -0.1, ..p }, "mu_s"),
        ] {
            assert!(matches!(
                MuI::new(bad),
                Err(ConstitutiveError::InvalidParameter { name: n, .. }) if n == name
            ));
        }
        let m = beads();
        let mut s = SymTensor::IDENTITY * -500.0;
        let e = m.update(&mut s, &mut m.initial_state(), &SymTensor::ZERO, 0.0).unwrap_err();
        assert!(matches!(e, ConstitutiveError::InvalidParameter { name: "dt", .. }));
        assert_eq!(s, SymTensor::IDENTITY * -500.0);
    }
}
