//! Typed errors of the constitutive crate: each names the offending quantity, its value and what
//! would have been admissible.

use thiserror::Error;

/// Everything that can go wrong when building or integrating a constitutive model.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum ConstitutiveError {
    /// a material or loading parameter lies outside its admissible range.
    #[error("parameter `{name}` = {} is outside its admissible range {range}", short(*value))]
    InvalidParameter {
        /// parameter name as spelled in the API (e.g. `"poisson"`).
        name: &'static str,
        /// the rejected value.
        value: f64,
        /// the admissible range, e.g. `"-1 < poisson < 0.5"`.
        range: &'static str,
    },
    /// a parameter that the others given make necessary is absent.
    #[error("parameter `{name}` is missing: {reason}")]
    MissingParameter {
        /// parameter name as spelled in the API.
        name: &'static str,
        /// why it is needed.
        reason: &'static str,
    },
    /// softening so strong that the return mapping has no unique solution.
    #[error(
        "hardening_modulus H = {hardening_modulus} Pa makes the return mapping ill posed \
         ({condition}); admissible: H > {lower_bound} Pa"
    )]
    IllPosedSoftening {
        /// the rejected plastic modulus `H` (Pa).
        hardening_modulus: f64,
        /// the smallest (excluded) admissible `H` for the other parameters (Pa).
        lower_bound: f64,
        /// which well-posedness condition fails.
        condition: &'static str,
    },
    /// a component of the strain increment is NaN or infinite.
    #[error("strain increment component `{component}` = {value} is not finite")]
    NonFiniteStrainIncrement {
        /// component name (`"xx"`, `"xy"`, ...).
        component: &'static str,
        /// the offending value.
        value: f64,
    },
    /// a component of the stress passed to the model is NaN or infinite.
    #[error("stress component `{component}` = {value} Pa is not finite")]
    NonFiniteStress {
        /// component name (`"xx"`, `"xy"`, ...).
        component: &'static str,
        /// the offending value.
        value: f64,
    },
    /// an internal variable passed to the model is NaN or infinite.
    #[error("internal variable `{name}` = {value} is not finite")]
    NonFiniteState {
        /// variable name (`"k"`, `"eps_p_bar"`, `"back_stress.xy"`, ...).
        name: &'static str,
        /// the offending value.
        value: f64,
    },
    /// a plane-strain update met (or would create) an out-of-plane shear, which the four
    /// components of plane strain cannot carry.
    #[error(
        "plane strain: `{name}` = {value} is an out-of-plane shear, which plane strain keeps at 0 \
         (use the full update for a 3D state)"
    )]
    OutOfPlane {
        /// the quantity (`"stress.yz"`, `"back_stress.zx"`, ...).
        name: &'static str,
        /// its value.
        value: f64,
    },
    /// the internal variables handed to a model are another model's (a composite of several
    /// models, such as a scene's materials of several kinds, met a point whose state does not
    /// belong to its material).
    #[error(
        "the material point's internal variables are those of {found}, but its material is {expected}"
    )]
    ForeignState {
        /// the material's model.
        expected: &'static str,
        /// the model the state belongs to.
        found: &'static str,
    },
    /// a friction-free cone (α = 0) softened to a negative size: no stress satisfies `f ≤ 0`.
    #[error(
        "the yield surface is empty: cone size k = {k} Pa < 0 with friction coefficient alpha = 0 \
         (admissible: k >= 0 when the friction angle is 0)"
    )]
    EmptyElasticDomain {
        /// the (softened) cone size `k` (Pa).
        k: f64,
    },
    /// the mixed-control Newton iteration of an element test did not reach its tolerance.
    #[error(
        "element test step {step}: Newton iteration stopped after {iterations} iterations with \
         relative residual {relative_residual:e} (required <= {tolerance:e})"
    )]
    NewtonDidNotConverge {
        /// load step (1-based) that failed.
        step: usize,
        /// iterations performed.
        iterations: usize,
        /// last residual of the controlled stresses divided by the stress scale.
        relative_residual: f64,
        /// required relative residual.
        tolerance: f64,
    },
    /// the controlled block of the tangent is singular (e.g. stress control on a perfectly
    /// plastic plateau).
    #[error("element test step {step}: the stress-controlled block of the tangent is singular")]
    SingularTangent {
        /// load step (1-based) that failed.
        step: usize,
    },
}

/// a number for a message: as written for ordinary magnitudes, in scientific notation beyond
/// (1e308 printed in full is 309 digits).
fn short(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || !x.is_finite() || (1e-4..1e9).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A refused value reads as written, or in scientific notation when extreme (hostile
    /// report R9: 1e308 was printed as 309 digits).
    #[test]
    fn refused_values_read_short() {
        let e = |value| {
            ConstitutiveError::InvalidParameter { name: "i0", value, range: "0 < i0 <= 10" }
                .to_string()
        };
        assert!(e(1e308).contains("`i0` = 1e308 is outside"), "{}", e(1e308));
        assert!(e(1e-320).contains("= 1e-320 is"), "{}", e(1e-320));
        assert!(e(0.279).contains("= 0.279 is"), "{}", e(0.279));
        assert!(e(-5.0).contains("= -5 is"), "{}", e(-5.0));
    }
}
