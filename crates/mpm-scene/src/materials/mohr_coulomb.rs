//! `kind = "mohr_coulomb"`: Mohr–Coulomb sand or soil, non-associated, with the exact return in
//! principal stresses and optional softening of `c`, `φ`, `ψ` with plastic strain
//! ([`mpm_constitutive::MohrCoulomb`]). Its surface is what a measured friction angle means on
//! every stress path: no cone to choose, in 2D or 3D alike.

use mpm_constitutive::{ConstitutiveError, MohrCoulomb, MohrCoulombParams, MohrCoulombSoftening};
use serde::{Deserialize, Serialize};

use super::SceneMaterial;

/// The parameters of a Mohr–Coulomb `[materials.NAME]` table (besides `kind` and `density`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MohrCoulombSpec {
    /// Young's modulus E (Pa).
    pub young: f64,
    /// Poisson's ratio ν.
    pub poisson: f64,
    /// cohesion c (Pa), at the peak.
    pub cohesion: f64,
    /// friction angle φ (degrees), at the peak.
    pub friction_angle_deg: f64,
    /// dilatancy angle ψ (degrees), default 0.
    #[serde(default)]
    pub dilatancy_angle_deg: f64,
    /// residual cohesion (Pa); with the other residual fields, turns softening on.
    #[serde(default)]
    pub residual_cohesion: Option<f64>,
    /// residual friction angle (degrees).
    #[serde(default)]
    pub residual_friction_angle_deg: Option<f64>,
    /// residual dilatancy angle (degrees), default 0.
    #[serde(default)]
    pub residual_dilatancy_angle_deg: Option<f64>,
    /// equivalent plastic strain up to which the peak values hold, default 0.
    #[serde(default)]
    pub peak_plastic_strain: Option<f64>,
    /// equivalent plastic strain at which the residual values are reached.
    #[serde(default)]
    pub residual_plastic_strain: Option<f64>,
}

impl SceneMaterial for MohrCoulomb {
    const KIND: &'static str = "mohr_coulomb";
    const TITLE: &'static str = "Mohr-Coulomb";
    const OBJECTIVE_STRESS: bool = true;
    const PIC_FRACTION: f64 = crate::GRANULAR_PIC_FRACTION;
    const SEPARATION_DENSITY: f64 = crate::GRANULAR_SEPARATION_DENSITY;
    const FLOWS: bool = true;
    type Spec = MohrCoulombSpec;

    fn build(s: MohrCoulombSpec, _density: f64) -> Result<Self, ConstitutiveError> {
        let any = s.residual_cohesion.is_some()
            || s.residual_friction_angle_deg.is_some()
            || s.residual_dilatancy_angle_deg.is_some()
            || s.peak_plastic_strain.is_some()
            || s.residual_plastic_strain.is_some();
        let softening = if any {
            // the softening law needs its end point: where and to what it goes.
            let missing = |name| ConstitutiveError::MissingParameter {
                name,
                reason: "softening needs residual_cohesion, residual_friction_angle_deg and \
                         residual_plastic_strain together",
            };
            Some(MohrCoulombSoftening {
                residual_cohesion: s.residual_cohesion.ok_or(missing("residual_cohesion"))?,
                residual_friction_angle_deg: s
                    .residual_friction_angle_deg
                    .ok_or(missing("residual_friction_angle_deg"))?,
                residual_dilatancy_angle_deg: s.residual_dilatancy_angle_deg.unwrap_or(0.0),
                peak_plastic_strain: s.peak_plastic_strain.unwrap_or(0.0),
                residual_plastic_strain: s
                    .residual_plastic_strain
                    .ok_or(missing("residual_plastic_strain"))?,
            })
        } else {
            None
        };
        MohrCoulomb::new(MohrCoulombParams {
            young: s.young,
            poisson: s.poisson,
            cohesion: s.cohesion,
            friction_angle_deg: s.friction_angle_deg,
            dilatancy_angle_deg: s.dilatancy_angle_deg,
            softening,
        })
    }

    fn fix(field: &str) -> &'static str {
        match field {
            "cohesion" => "use a cohesion ≥ 0 in Pa (0 for a dry sand)",
            "friction_angle_deg" => {
                "use the friction angle of a shear test, below 90°, e.g. 30 for a loose dry sand"
            }
            "dilatancy_angle_deg" => "use 0 ≤ ψ ≤ φ (0 for a sand at its critical state)",
            "residual_cohesion" => "give the residual cohesion in Pa (≥ 0)",
            "residual_friction_angle_deg" => {
                "give the residual (critical-state) friction angle, below 90°"
            }
            "residual_dilatancy_angle_deg" => "use 0 ≤ ψ_r ≤ residual_friction_angle_deg",
            "peak_plastic_strain" => "give ε̄ᵖ ≥ 0 up to which the peak values hold",
            "residual_plastic_strain" => {
                "give ε̄ᵖ at which the residual values are reached, above peak_plastic_strain"
            }
            _ => super::elastic_fix(field),
        }
    }
}
