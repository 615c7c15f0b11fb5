//! Isotropic linear elasticity, the paper's eq 10 (`Δσ = T : Δε` with `T` isotropic) and eq 11
//! (`σ_{n+1} = σ_n + Δσ`).
//!
//! # Glossary
//! - `E` Young's modulus, `ν` Poisson's ratio, `K = E / (3(1 − 2ν))` bulk modulus,
//!   `G = E / (2(1 + ν))` shear modulus, `λ = K − 2G/3` Lamé's first parameter,
//!   `λ + 2G = K + 4G/3` the P-wave (constrained) modulus; all in Pa.
//! - `ρ` mass density (kg/m³); `c_p = √((λ + 2G)/ρ)`, `c_s = √(G/ρ)` wave speeds (m/s).
//! - `C` the elastic stiffness: `C : ε = λ tr(ε) I + 2G ε`;
//!   `C⁻¹ : σ = tr(σ)/(9K) I + dev(σ)/(2G)`.
//!
//! Tension positive, SI units, tensor shear strain components (see [`crate::tensor`]).

use glam::DMat3;
use serde::{Deserialize, Serialize};

use crate::error::ConstitutiveError;
use crate::model::{ConstitutiveModel, TangentModel, UpdateReport, check_finite};
use crate::tensor::{
    PlaneTensor, SymTensor, Symmetric, Tangent, deviatoric_projector, dyad, tangent_axpby,
};

/// Isotropic linear elasticity, stored as bulk modulus `K` and shear modulus `G` (Pa).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LinearElastic {
    bulk: f64,
    shear: f64,
}

impl LinearElastic {
    /// from Young's modulus `E > 0` (Pa) and Poisson's ratio `−1 < ν < 0.5`.
    pub fn from_young_poisson(young: f64, poisson: f64) -> Result<Self, ConstitutiveError> {
        if !(young.is_finite() && young > 0.0) {
            return Err(ConstitutiveError::InvalidParameter {
                name: "young",
                value: young,
                range: "0 < young < inf (Pa)",
            });
        }
        if !(poisson > -1.0 && poisson < 0.5) {
            return Err(ConstitutiveError::InvalidParameter {
                name: "poisson",
                value: poisson,
                range: "-1 < poisson < 0.5",
            });
        }
        let bulk = young / (3.0 * (1.0 - 2.0 * poisson));
        let shear = young / (2.0 * (1.0 + poisson));
        Self::from_bulk_shear(bulk, shear)
    }

    /// from bulk modulus `K > 0` and shear modulus `G > 0` (Pa).
    pub fn from_bulk_shear(bulk: f64, shear: f64) -> Result<Self, ConstitutiveError> {
        if !(bulk.is_finite() && bulk > 0.0) {
            return Err(ConstitutiveError::InvalidParameter {
                name: "bulk",
                value: bulk,
                range: "0 < bulk < inf (Pa)",
            });
        }
        if !(shear.is_finite() && shear > 0.0) {
            return Err(ConstitutiveError::InvalidParameter {
                name: "shear",
                value: shear,
                range: "0 < shear < inf (Pa)",
            });
        }
        Ok(Self { bulk, shear })
    }

    /// bulk modulus `K` (Pa).
    #[inline]
    pub fn bulk_modulus(&self) -> f64 {
        self.bulk
    }

    /// shear modulus `G` (Pa).
    #[inline]
    pub fn shear_modulus(&self) -> f64 {
        self.shear
    }

    /// Lamé's first parameter `λ = K − 2G/3` (Pa).
    #[inline]
    pub fn lame_lambda(&self) -> f64 {
        self.bulk - 2.0 * self.shear / 3.0
    }

    /// Young's modulus `E = 9KG / (3K + G)` (Pa).
    pub fn young_modulus(&self) -> f64 {
        9.0 * self.bulk * self.shear / (3.0 * self.bulk + self.shear)
    }

    /// Poisson's ratio `ν = (3K − 2G) / (2(3K + G))`.
    pub fn poisson_ratio(&self) -> f64 {
        (3.0 * self.bulk - 2.0 * self.shear) / (2.0 * (3.0 * self.bulk + self.shear))
    }

    /// P-wave (constrained) modulus `λ + 2G = K + 4G/3` (Pa).
    #[inline]
    pub fn p_wave_modulus(&self) -> f64 {
        self.bulk + 4.0 * self.shear / 3.0
    }

    /// dilatational wave speed `√((λ + 2G)/ρ)` (m/s), the `c` of the paper's eq 13.
    ///
    /// `density` (kg/m³) must be positive and finite; otherwise the result is NaN or infinite
    /// (the solver validates densities where they are read).
    pub fn dilatational_wave_speed(&self, density: f64) -> f64 {
        (self.p_wave_modulus() / density).sqrt()
    }

    /// shear wave speed `√(G/ρ)` (m/s); same `density` caveat as
    /// [`dilatational_wave_speed`](Self::dilatational_wave_speed).
    pub fn shear_wave_speed(&self, density: f64) -> f64 {
        (self.shear / density).sqrt()
    }

    /// eq 10: `Δσ = λ tr(Δε) I + 2G Δε`.
    #[inline]
    pub fn stress_increment(&self, d_eps: &SymTensor) -> SymTensor {
        self.increment(d_eps)
    }

    /// [`stress_increment`](Self::stress_increment) on full or plane-strain tensors.
    #[inline(always)]
    fn increment<T: Symmetric>(&self, d_eps: &T) -> T {
        d_eps.elastic_increment(self.lame_lambda() * d_eps.trace(), 2.0 * self.shear)
    }

    /// eqs 10–11, `σ ← start + Δσ`, on full or plane-strain tensors: writes `sigma` only when
    /// the inputs and the result are finite, else names the first culprit.
    #[inline(always)]
    fn update_in<T: Symmetric>(
        &self,
        sigma: &mut T,
        start: T,
        d_eps: &T,
    ) -> Result<UpdateReport, ConstitutiveError> {
        let next = start + self.increment(d_eps);
        if start.finite_probe() + d_eps.finite_probe() + next.finite_probe() != 0.0 {
            check_finite(&start.to_sym(), &d_eps.to_sym())?;
            // finite inputs whose sum overflows: refuse rather than store an infinite stress.
            let (component, value) = next.to_sym().first_non_finite().unwrap_or(("xx", f64::NAN));
            return Err(ConstitutiveError::NonFiniteStress { component, value });
        }
        *sigma = next;
        Ok(UpdateReport::ELASTIC)
    }

    /// `C⁻¹ : σ = tr(σ)/(9K) I + dev(σ)/(2G)`, the elastic strain carrying `σ`.
    pub fn strain_from_stress(&self, sigma: &SymTensor) -> SymTensor {
        SymTensor::IDENTITY * (sigma.trace() / (9.0 * self.bulk))
            + sigma.deviator() * (0.5 / self.shear)
    }

    /// `½ σ : C⁻¹ : σ = I1²/(18K) + J2/(2G)` (J/m³), the stored elastic energy density.
    pub fn strain_energy_density(&self, sigma: &SymTensor) -> f64 {
        let i1 = sigma.trace();
        i1 * i1 / (18.0 * self.bulk) + sigma.j2() / (2.0 * self.shear)
    }

    /// the stiffness `C` as a [`Tangent`] (`T[3][3] = 2G`: tensor shear convention).
    pub fn stiffness_matrix(&self) -> Tangent {
        let i = SymTensor::IDENTITY;
        // C = K I ⊗ I + 2G P_dev.
        tangent_axpby(self.bulk, &dyad(&i, &i), 2.0 * self.shear, &deviatoric_projector())
    }
}

impl ConstitutiveModel for LinearElastic {
    type State = ();
    const IS_PLASTIC: bool = false;
    const BRANCHES: &'static [&'static str] = &["elastic"];

    fn initial_state(&self) -> Self::State {}

    fn p_wave_modulus(&self, _state: &Self::State) -> f64 {
        LinearElastic::p_wave_modulus(self)
    }

    fn stored_energy_density(&self, sigma: &SymTensor, _state: &Self::State) -> f64 {
        self.strain_energy_density(sigma)
    }

    #[inline]
    fn update(
        &self,
        sigma: &mut SymTensor,
        _state: &mut Self::State,
        d_eps: &SymTensor,
        _dt: f64,
    ) -> Result<UpdateReport, ConstitutiveError> {
        self.update_in(sigma, *sigma, d_eps)
    }

    /// the rotation and [`update`](ConstitutiveModel::update) on the four plane-strain
    /// components, same bits.
    #[inline(always)]
    fn update_plane(
        &self,
        sigma: &mut PlaneTensor,
        _state: &mut Self::State,
        d_eps: &PlaneTensor,
        _dt: f64,
        rotation: Option<(f64, f64)>,
    ) -> Result<UpdateReport, ConstitutiveError> {
        let start = match rotation {
            Some((c, s)) => sigma.rotated_z(c, s),
            None => *sigma,
        };
        self.update_in(sigma, start, d_eps)
    }

    fn rotate_state(&self, _state: &mut Self::State, _r: &DMat3) {}

    #[inline(always)]
    fn rotate_state_z(&self, _state: &mut Self::State, _c: f64, _s: f64) {}

    fn equivalent_plastic_strain(&self, _state: &Self::State) -> f64 {
        0.0
    }
}

impl TangentModel for LinearElastic {
    fn consistent_tangent(
        &self,
        sigma: &SymTensor,
        _state: &Self::State,
        d_eps: &SymTensor,
        _dt: f64,
    ) -> Result<Tangent, ConstitutiveError> {
        check_finite(sigma, d_eps)?;
        Ok(self.stiffness_matrix())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tensor::tangent_apply;

    /// moduli of order 1e6 recovered through two or three divisions: a few ulps relative.
    const REL_ROUNDING: f64 = 1e-14;

    fn sand() -> LinearElastic {
        LinearElastic::from_young_poisson(2.0e6, 0.3).unwrap()
    }

    #[test]
    fn moduli_match_textbook_relations() {
        let m = sand();
        // K = E/(3(1−2ν)) = 2e6/1.2, G = E/(2(1+ν)) = 2e6/2.6.
        let (k, g) = (2.0e6 / 1.2, 2.0e6 / 2.6);
        let close = |a: f64, b: f64| (a - b).abs() <= REL_ROUNDING * b.abs();
        assert!(close(m.bulk_modulus(), k));
        assert!(close(m.shear_modulus(), g));
        assert!(close(m.young_modulus(), 2.0e6));
        assert!(close(m.poisson_ratio(), 0.3));
        // λ = Eν/((1+ν)(1−2ν)).
        assert!(close(m.lame_lambda(), 2.0e6 * 0.3 / (1.3 * 0.4)));
        assert!(close(m.p_wave_modulus(), m.lame_lambda() + 2.0 * g));
        // E = 2e6, ν = 0.3, ρ = 1600: λ + 2G = E(1−ν)/((1+ν)(1−2ν)) = 2.6923077e6 Pa,
        // c_p = √(2.6923077e6/1600) = 41.0206327 m/s (hand value quoted to 9 digits).
        let c_p_hand = 41.020_632_7;
        assert!((m.dilatational_wave_speed(1600.0) - c_p_hand).abs() <= 1e-7);
        assert!(close(m.shear_wave_speed(1600.0), (g / 1600.0).sqrt()));
        let m2 = LinearElastic::from_bulk_shear(k, g).unwrap();
        assert!(close(m2.young_modulus(), 2.0e6));
    }

    #[test]
    fn increment_compliance_and_energy_are_consistent() {
        let m = sand();
        let e = SymTensor::new(1e-4, -2e-4, 3e-5, 5e-5, -1e-5, 2e-5);
        let s = m.stress_increment(&e);
        // the 6×6 stiffness acts like eq 10.
        assert!((tangent_apply(&m.stiffness_matrix(), &e) - s).norm() <= REL_ROUNDING * s.norm());
        // C⁻¹ : C : ε = ε.
        assert!((m.strain_from_stress(&s) - e).norm() <= REL_ROUNDING * e.norm());
        // ½ σ : ε with σ = C : ε.
        let w = 0.5 * s.ddot(&e);
        assert!((m.strain_energy_density(&s) - w).abs() <= REL_ROUNDING * w);
        // tensor shear convention: σ_xy = 2G ε_xy.
        assert!((s.xy - 2.0 * m.shear_modulus() * e.xy).abs() <= REL_ROUNDING * s.xy.abs());
    }

    #[test]
    fn bad_parameters_are_named() {
        assert!(matches!(
            LinearElastic::from_young_poisson(-1.0, 0.3),
            Err(ConstitutiveError::InvalidParameter { name: "young", .. })
        ));
        assert!(matches!(
            LinearElastic::from_young_poisson(1.0, 0.5),
            Err(ConstitutiveError::InvalidParameter { name: "poisson", value, .. }) if value == 0.5
        ));
        assert!(matches!(
            LinearElastic::from_young_poisson(1.0, f64::NAN),
            Err(ConstitutiveError::InvalidParameter { name: "poisson", .. })
        ));
        assert!(matches!(
            LinearElastic::from_bulk_shear(1.0, 0.0),
            Err(ConstitutiveError::InvalidParameter { name: "shear", .. })
        ));
        let msg = LinearElastic::from_young_poisson(1.0, -1.0).unwrap_err().to_string();
        assert!(msg.contains("poisson") && msg.contains("-1") && msg.contains("0.5"), "{msg}");
    }

    #[test]
    fn elastic_update_adds_increment_and_rejects_non_finite() {
        let m = sand();
        let mut s = SymTensor::new(-10.0, -20.0, -5.0, 1.0, 0.0, 0.0);
        let e = SymTensor::plane(1e-5, -2e-5, 3e-6);
        let expect = s + m.stress_increment(&e);
        let r = m.update(&mut s, &mut (), &e, 1.0).unwrap();
        assert_eq!(r, UpdateReport::ELASTIC);
        assert_eq!(s, expect);
        let before = s;
        let bad = SymTensor::plane(f64::NAN, 0.0, 0.0);
        assert!(matches!(
            m.update(&mut s, &mut (), &bad, 1.0),
            Err(ConstitutiveError::NonFiniteStrainIncrement { component: "xx", value }) if value.is_nan()
        ));
        assert_eq!(s, before);
        let huge = SymTensor::plane(f64::MAX, 0.0, 0.0);
        assert!(m.update(&mut s, &mut (), &huge, 1.0).is_err());
        assert_eq!(s, before);
    }
}
