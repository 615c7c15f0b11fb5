//! `kind = "mu_i"`: the μ(I) rheology of dense granular flow (Jop, Forterre & Pouliquen 2006)
//! as an elasto-viscoplastic model: pressure- and rate-dependent friction, separation in
//! tension ([`mpm_constitutive::MuI`]). Its table is [`MuIParams`] (besides `kind` and
//! `density`, the bulk density φ ρ_s, which `grain_density` must not be below).

use mpm_constitutive::{ConstitutiveError, MuI, MuIParams};

use super::SceneMaterial;

impl SceneMaterial for MuI {
    const KIND: &'static str = "mu_i";
    const TITLE: &'static str = "μ(I)";
    const OBJECTIVE_STRESS: bool = true;
    const PIC_FRACTION: f64 = crate::GRANULAR_PIC_FRACTION;
    /// off: the model tracks its own opening (separated grains carry no stress until
    /// compaction closes it), which a density threshold on top would only blur (measured: the
    /// example column's front then crept by 2 cm over 0.7 s after it had stopped).
    const SEPARATION_DENSITY: f64 = 0.0;
    const FLOWS: bool = true;
    type Spec = MuIParams;

    fn build(s: MuIParams, density: f64) -> Result<Self, ConstitutiveError> {
        // The bulk density is φ ρ_s with a solid fraction φ ≤ 1.
        if s.grain_density.is_finite() && s.grain_density < density {
            return Err(ConstitutiveError::InvalidParameter {
                name: "grain_density",
                value: s.grain_density,
                range: "grain_density ≥ density (the bulk density is the solid fraction times \
                        the grain density)",
            });
        }
        MuI::new(s)
    }

    fn fix(field: &str) -> &'static str {
        match field {
            "mu_s" | "mu_2" => {
                "give friction coefficients 0 ≤ mu_s ≤ mu_2, e.g. 0.38 and 0.64 for glass beads"
            }
            "i0" => "give 0 < I_0 <= 10, e.g. 0.279 for glass beads",
            "grain_diameter" => "give the grain diameter in m (1e-6 to 10), e.g. 0.53e-3",
            "grain_density" => "give the grains' density, e.g. 2450 for glass",
            _ => super::elastic_fix(field),
        }
    }
}
