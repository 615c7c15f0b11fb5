//! `kind = "drucker_prager"`: the paper's elastoplastic sand, Drucker-Prager with non-associated
//! flow and mixed hardening (eqs 23–25). A scene whose Drucker-Prager materials do not harden
//! runs with particles that store only ε̄ᵖ (8 B instead of 64 B each).

use mpm_constitutive::{
    ConeMatch, ConstitutiveError, DpPerfectState, DruckerPrager, DruckerPragerParams,
};
use serde::{Deserialize, Serialize};

use super::{ModelJob, SceneMaterial};

/// How the Drucker-Prager cone is matched to Mohr-Coulomb.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ConeMatchSpec {
    /// same plane-strain collapse load (the paper's choice).
    PlaneStrain,
    /// through the triaxial-extension corners.
    Inner,
    /// through the triaxial-compression corners.
    Outer,
}

/// The parameters of a Drucker-Prager `[materials.NAME]` table (besides `kind` and `density`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DruckerPragerSpec {
    /// Young's modulus E (Pa).
    pub young: f64,
    /// Poisson's ratio ν.
    pub poisson: f64,
    /// cohesion c (Pa).
    pub cohesion: f64,
    /// friction angle φ (degrees).
    pub friction_angle_deg: f64,
    /// dilatancy angle ψ (degrees), default 0.
    #[serde(default)]
    pub dilatancy_angle_deg: f64,
    /// plastic modulus H (Pa), default 0.
    #[serde(default)]
    pub hardening_modulus: f64,
    /// mixing parameter M (1 isotropic, 0 kinematic), default 1.
    #[serde(default = "isotropic")]
    pub mixing: f64,
    /// cone match, default `"plane_strain"`.
    #[serde(default = "plane_strain")]
    pub cone_match: ConeMatchSpec,
}

fn isotropic() -> f64 {
    1.0
}

fn plane_strain() -> ConeMatchSpec {
    ConeMatchSpec::PlaneStrain
}

impl SceneMaterial for DruckerPrager {
    const KIND: &'static str = "drucker_prager";
    const TITLE: &'static str = "Drucker-Prager";
    const OBJECTIVE_STRESS: bool = true;
    const PIC_FRACTION: f64 = crate::GRANULAR_PIC_FRACTION;
    const SEPARATION_DENSITY: f64 = crate::GRANULAR_SEPARATION_DENSITY;
    const FLOWS: bool = true;
    type Spec = DruckerPragerSpec;

    fn build(s: DruckerPragerSpec, _density: f64) -> Result<Self, ConstitutiveError> {
        DruckerPrager::new(DruckerPragerParams {
            young: s.young,
            poisson: s.poisson,
            cohesion: s.cohesion,
            friction_angle_deg: s.friction_angle_deg,
            dilatancy_angle_deg: s.dilatancy_angle_deg,
            hardening_modulus: s.hardening_modulus,
            mixing: s.mixing,
            cone_match: match s.cone_match {
                ConeMatchSpec::PlaneStrain => ConeMatch::PlaneStrain,
                ConeMatchSpec::Inner => ConeMatch::Inner,
                ConeMatchSpec::Outer => ConeMatch::Outer,
            },
        })
    }

    fn fix(field: &str) -> &'static str {
        match field {
            "cohesion" => "use a cohesion ≥ 0 in Pa (10 Pa in the paper's sand)",
            "friction_angle_deg" => "use a friction angle below 90°, e.g. 40 for dry sand",
            "dilatancy_angle_deg" => "use 0 ≤ ψ ≤ φ (0 in the paper)",
            "mixing" => "use M between 0 (kinematic) and 1 (isotropic); 0.8 in the paper",
            "hardening_modulus" => "use H ≥ 0 (0 in the paper) or a milder softening",
            _ => super::elastic_fix(field),
        }
    }

    /// A scene pays for the hardening variables (64 B per particle) only if some material
    /// hardens; otherwise its particles store only ε̄ᵖ.
    fn run<J: ModelJob>(materials: Vec<Self>, job: J) -> J::Output {
        let perfect: Option<Vec<DruckerPrager<DpPerfectState>>> =
            materials.iter().map(DruckerPrager::without_hardening).collect();
        match perfect {
            Some(perfect) => job.run(perfect),
            None => job.run(materials),
        }
    }
}
