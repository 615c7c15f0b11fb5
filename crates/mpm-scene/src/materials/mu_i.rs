//! `kind = "mu_i"`: the μ(I) rheology of dense granular flow (Jop, Forterre & Pouliquen 2006)
//! as an elasto-viscoplastic model: pressure- and rate-dependent friction, separation in
//! tension ([`mpm_constitutive::MuI`]).

use mpm_constitutive::{ConstitutiveError, MuI, MuIParams};
use serde::{Deserialize, Serialize};

use super::SceneMaterial;

/// The parameters of a μ(I) `[materials.NAME]` table (besides `kind` and `density`, which is
/// the bulk density φ ρ_s).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MuISpec {
    /// Young's modulus E of the granular skeleton (Pa).
    pub young: f64,
    /// Poisson's ratio ν.
    pub poisson: f64,
    /// static friction μ_s = μ(0) (a coefficient, not an angle).
    pub mu_s: f64,
    /// limiting friction μ_2 = μ(∞) ≥ μ_s.
    pub mu_2: f64,
    /// inertial number I_0 half-way from μ_s to μ_2.
    pub i0: f64,
    /// grain diameter d (m).
    pub grain_diameter: f64,
    /// grain density ρ_s (kg/m³), at least the bulk `density`.
    pub grain_density: f64,
}

impl SceneMaterial for MuI {
    const KIND: &'static str = "mu_i";
    const TITLE: &'static str = "μ(I)";
    const OBJECTIVE_STRESS: bool = true;
    type Spec = MuISpec;

    fn build(s: MuISpec, density: f64) -> Result<Self, ConstitutiveError> {
        // The bulk density is φ ρ_s with a solid fraction φ ≤ 1.
        if s.grain_density.is_finite() && s.grain_density < density {
            return Err(ConstitutiveError::InvalidParameter {
                name: "grain_density",
                value: s.grain_density,
                range: "grain_density ≥ density (the bulk density is the solid fraction times \
                        the grain density)",
            });
        }
        MuI::new(MuIParams {
            young: s.young,
            poisson: s.poisson,
            mu_s: s.mu_s,
            mu_2: s.mu_2,
            i0: s.i0,
            grain_diameter: s.grain_diameter,
            grain_density: s.grain_density,
        })
    }

    fn fix(field: &str) -> &'static str {
        match field {
            "mu_s" | "mu_2" => {
                "give friction coefficients 0 ≤ mu_s ≤ mu_2, e.g. 0.38 and 0.64 for glass beads"
            }
            "i0" => "give I_0 > 0, e.g. 0.279 for glass beads",
            "grain_diameter" => "give the grain diameter in m, e.g. 0.53e-3",
            "grain_density" => "give the grains' density, e.g. 2450 for glass",
            _ => super::elastic_fix(field),
        }
    }
}
