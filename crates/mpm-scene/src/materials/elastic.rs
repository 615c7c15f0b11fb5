//! `kind = "elastic"`: isotropic linear elasticity (eq 10), for rigid-ish blocks, the elastic
//! verification cases and walls of soil that must not yield.

use mpm_constitutive::{ConstitutiveError, LinearElastic};
use serde::{Deserialize, Serialize};

use super::SceneMaterial;

/// The parameters of an elastic `[materials.NAME]` table (besides `kind` and `density`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ElasticSpec {
    /// Young's modulus E (Pa).
    pub young: f64,
    /// Poisson's ratio ν.
    pub poisson: f64,
}

impl SceneMaterial for LinearElastic {
    const KIND: &'static str = "elastic";
    const TITLE: &'static str = "elastic";
    const OBJECTIVE_STRESS: bool = false;
    const PIC_FRACTION: f64 = 0.0;
    const SEPARATION_DENSITY: f64 = 0.0;
    const FLOWS: bool = false;
    type Spec = ElasticSpec;

    fn build(spec: ElasticSpec, _density: f64) -> Result<Self, ConstitutiveError> {
        LinearElastic::from_young_poisson(spec.young, spec.poisson)
    }
}
