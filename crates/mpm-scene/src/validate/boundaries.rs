//! `[boundaries]`: the Coulomb node boundaries (eqs 14–18) of the ground and the walls.

use mpm_contact::{Boundary, ContactError, Friction};
use mpm_solver::{Boundaries, Vector};

use super::Ctx;
use crate::error::SceneError;
use crate::file::{BoundarySpec, SceneFile};

/// The friction law of each declared boundary.
pub(super) fn build(ctx: &Ctx<'_>, f: &SceneFile) -> Result<Boundaries, SceneError> {
    let mut boundaries = Boundaries::default();
    for (name, spec, slot) in [
        ("ground", f.boundaries.ground, &mut boundaries.ground),
        ("left_wall", f.boundaries.left_wall, &mut boundaries.left_wall),
        ("right_wall", f.boundaries.right_wall, &mut boundaries.right_wall),
    ] {
        let Some(spec) = spec else { continue };
        let path = format!("boundaries.{name}");
        let friction = match spec {
            BoundarySpec::Friction(mu) => Boundary::new(Vector::Y, Friction::Coulomb { mu })
                .map_err(|e| contact_error(ctx, &format!("{path}.friction"), e))?
                .friction(),
            BoundarySpec::FrictionAngleDeg(a) => Boundary::with_friction_angle_deg(Vector::Y, a)
                .map_err(|e| contact_error(ctx, &format!("{path}.friction_angle_deg"), e))?
                .friction(),
            BoundarySpec::Rough => Friction::Rough,
            BoundarySpec::Fixed => Friction::Fixed,
            BoundarySpec::Frictionless => Friction::Coulomb { mu: 0.0 },
        };
        *slot = Some(friction);
    }
    Ok(boundaries)
}

fn contact_error(ctx: &Ctx<'_>, path: &str, e: ContactError) -> SceneError {
    match e {
        ContactError::InvalidFrictionCoefficient { mu, .. } => ctx.range(
            path,
            mu,
            "0 ≤ friction < ∞ (Coulomb coefficient μ)",
            "give μ ≥ 0, or use \"rough\" for no slip",
        ),
        ContactError::InvalidFrictionAngle { angle_deg, .. } => ctx.range(
            path,
            angle_deg,
            "0 ≤ friction_angle_deg < 90 (degrees)",
            "give the basal friction angle in degrees (27 in the paper's flume), or \"rough\"",
        ),
        other => ctx.err(path, None, other.to_string(), String::new(), "see docs/scene-format.md"),
    }
}
