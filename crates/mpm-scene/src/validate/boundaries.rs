//! `[boundaries]`: the Coulomb node boundaries (eqs 14–18) of the ground and the walls.

use mpm_contact::{Boundary, ContactError, Friction};
use mpm_solver::{Boundaries, Periodic, Vector};

use super::Ctx;
use crate::error::SceneError;
use crate::file::{BoundarySpec, SceneFile};
use crate::scene::GridBuilt;

/// `periodic = true`: the regular grid's sides as a periodic pair; refused on a terrain grid
/// (its columns follow the ground, so its sides do not match) and beside a side wall.
pub(super) fn periodic(
    ctx: &Ctx<'_>,
    f: &SceneFile,
    grid: &GridBuilt,
) -> Result<Option<Periodic>, SceneError> {
    if !f.boundaries.periodic {
        return Ok(None);
    }
    let path = "boundaries.periodic";
    let GridBuilt::Regular(g) = grid else {
        return Err(ctx.err(
            path,
            Some("true".into()),
            "periodic sides need a regular grid",
            "a `kind = \"regular\"` grid",
            "use a regular grid and turn gravity for an inclined strip ([solver] gravity)",
        ));
    };
    if f.boundaries.left_wall.is_some() || f.boundaries.right_wall.is_some() {
        return Err(ctx.err(
            path,
            Some("true".into()),
            "the periodic sides cannot also be walls",
            "periodic = true without left_wall and right_wall",
            "remove left_wall and right_wall, or periodic",
        ));
    }
    let columns = g.cells()[0];
    if columns < 4 {
        return Err(ctx.range(
            "grid.cells",
            columns as f64,
            "at least 4 columns between periodic sides",
            "give the grid 4 or more columns",
        ));
    }
    Ok(Some(Periodic {
        x_min: g.origin().x,
        columns: columns as u32,
        length: columns as f64 * g.cell_size().x,
    }))
}

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
