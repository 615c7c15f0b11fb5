//! `kind = "drucker_prager"`: the paper's elastoplastic sand, Drucker-Prager with non-associated
//! flow and mixed hardening (eqs 23–25). A scene whose Drucker-Prager materials do not harden
//! runs with particles that store only ε̄ᵖ (8 B instead of 64 B each). Its table is
//! [`DruckerPragerParams`] (besides `kind` and `density`).

use mpm_constitutive::{ConstitutiveError, DpPerfectState, DruckerPrager, DruckerPragerParams};

use super::{ModelJob, SceneMaterial};

impl SceneMaterial for DruckerPrager {
    const KIND: &'static str = "drucker_prager";
    const TITLE: &'static str = "Drucker-Prager";
    const OBJECTIVE_STRESS: bool = true;
    const PIC_FRACTION: f64 = crate::GRANULAR_PIC_FRACTION;
    const SEPARATION_DENSITY: f64 = crate::GRANULAR_SEPARATION_DENSITY;
    const FLOWS: bool = true;
    type Spec = DruckerPragerParams;

    fn build(params: DruckerPragerParams, _density: f64) -> Result<Self, ConstitutiveError> {
        DruckerPrager::new(params)
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
