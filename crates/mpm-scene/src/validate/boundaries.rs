//! `[boundaries]`: the Coulomb node boundaries (eqs 14–18) of the ground and the walls.

use mpm_contact::{Boundary, ContactError, Friction, Wall};
use mpm_solver::{Boundaries, Outflow, Periodic, SideWalls, Vector};

use super::Ctx;
use crate::error::SceneError;
use crate::file::{BoundarySpec, SceneFile, WallSpec};
use crate::scene::{GridBuilt, Seed};

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

/// The friction law of each declared side of the grid, and the sides declared `"outflow"`.
pub(super) fn build(
    ctx: &Ctx<'_>,
    f: &SceneFile,
    grid: &GridBuilt,
) -> Result<(Boundaries, Outflow), SceneError> {
    let mut boundaries = Boundaries::default();
    let mut outflow = Outflow::default();
    let (x0, x1) = grid.x_range();
    for (name, spec, slot, face) in [
        ("ground", f.boundaries.ground, &mut boundaries.ground, None),
        ("left_wall", f.boundaries.left_wall, &mut boundaries.left_wall, Some(&mut outflow.x_min)),
        (
            "right_wall",
            f.boundaries.right_wall,
            &mut boundaries.right_wall,
            Some(&mut outflow.x_max),
        ),
    ] {
        let Some(spec) = spec else { continue };
        match (spec, face) {
            (BoundarySpec::Outflow, Some(face)) => {
                *face = Some(if name == "left_wall" { x0 } else { x1 });
            }
            _ => *slot = Some(friction(ctx, &format!("boundaries.{name}"), spec)?),
        }
    }
    Ok((boundaries, outflow))
}

/// `"outflow"` where only a friction law goes: the ground, a wall anywhere.
fn not_a_law(ctx: &Ctx<'_>, path: &str) -> SceneError {
    ctx.err(
        path,
        Some("\"outflow\"".into()),
        "`outflow` is a kind of side face of the grid (material leaves the run through it), \
         not a friction law",
        "a friction law: \"rough\", \"fixed\", \"frictionless\", { friction = μ } or \
         { friction_angle_deg = φ }",
        "give a friction law here; `outflow` goes on `left_wall` or `right_wall` (and \
         `back_wall`, `front_wall` in 3D)",
    )
}

/// `[[boundaries.walls]]`: each wall as the solver takes it; refused beside periodic sides, and
/// when a body's particle starts inside a wall's solid.
pub(super) fn walls(
    ctx: &Ctx<'_>,
    f: &SceneFile,
    grid: &GridBuilt,
    seeds: &[Seed],
) -> Result<Vec<Wall>, SceneError> {
    let specs = &f.boundaries.walls;
    if f.boundaries.periodic && !specs.is_empty() {
        return Err(ctx.err(
            "boundaries.walls",
            None,
            "walls beside periodic sides are not supported yet",
            "either `periodic = true` or `[[boundaries.walls]]`",
            "remove the walls or the periodic sides",
        ));
    }
    let walls: Vec<Wall> = specs
        .iter()
        .enumerate()
        .map(|(k, w)| wall(ctx, &format!("boundaries.walls[{k}]"), w, longest_cell_side(f, grid)))
        .collect::<Result<_, _>>()?;
    for (k, w) in walls.iter().enumerate() {
        if let Some(s) = seeds.iter().find(|s| w.contains(s.position)) {
            return Err(ctx.err(
                &format!("bodies[{}]", s.body),
                None,
                format!(
                    "this body starts inside boundaries.walls[{k}] (a particle at ({}, {}) lies \
                     behind its face)",
                    s.position.x, s.position.y
                ),
                "bodies in front of every wall (on the left walking from `from` to `to`)",
                "move the body, or swap the wall's `from` and `to` if it faces the wrong way",
            ));
        }
    }
    Ok(walls)
}

/// A wall's solid must hold grid nodes (the paper's rule holds the nodes inside it) and be
/// thicker than the reach of a stencil (surface contact holds every node of a touching
/// particle's stencil, up to 1.5 cells beyond its centre): at least 2 cells, measured by the
/// grid's longest cell side.
const MIN_WALL_CELLS: f64 = 2.0;

/// the grid's longest cell side as declared (m): the terrain grid's column width or row height.
fn longest_cell_side(f: &SceneFile, grid: &GridBuilt) -> f64 {
    match grid {
        GridBuilt::Regular(g) => g.cell_size().max_element(),
        GridBuilt::Terrain(_) => {
            f.grid.cell_width.unwrap_or(0.0).max(f.grid.row_height.unwrap_or(0.0))
        }
    }
}

fn wall(ctx: &Ctx<'_>, path: &str, w: &WallSpec, cell: f64) -> Result<Wall, SceneError> {
    let law = friction(ctx, &format!("{path}.law"), w.law)?;
    let thickness = w.thickness.unwrap_or(f64::INFINITY);
    let [from, to] = [w.from, w.to].map(|p| Vector::new(p[0], p[1]));
    let wall = Wall::segment(from, to, law, thickness).map_err(|e| match e {
        ContactError::InvalidThickness { thickness, .. } => ctx.range(
            &format!("{path}.thickness"),
            thickness,
            "thickness > 0 (m)",
            "give the depth of the wall's solid, or leave it out for a solid all the way behind",
        ),
        ContactError::DegenerateSegment { .. } => ctx.err(
            &format!("{path}.to"),
            Some(format!("[{}, {}]", w.to[0], w.to[1])),
            "the wall's two ends coincide",
            "two distinct, finite points",
            "give the wall's other end",
        ),
        // (`segment` checks `from` first)
        ContactError::NonFinitePoint { .. } => ctx.err(
            &format!("{path}.{}", if w.from.iter().all(|v| v.is_finite()) { "to" } else { "from" }),
            None,
            "a wall end is not finite",
            "finite coordinates (m)",
            "give finite numbers",
        ),
        other => contact_error(ctx, path, other),
    })?;
    if thickness < MIN_WALL_CELLS * cell {
        return Err(ctx.range(
            &format!("{path}.thickness"),
            thickness,
            &format!("thickness ≥ {} m (2 cells: the reach of a stencil)", MIN_WALL_CELLS * cell),
            "give the wall's true thickness, or refine the grid if the wall is thinner",
        ));
    }
    Ok(wall)
}

/// a friction law, validated with the contact layer's own rules.
fn friction(ctx: &Ctx<'_>, path: &str, spec: BoundarySpec) -> Result<Friction, SceneError> {
    Ok(match spec {
        BoundarySpec::Friction(mu) => Boundary::new(Vector::Y, Friction::Coulomb { mu })
            .map_err(|e| contact_error(ctx, &format!("{path}.friction"), e))?
            .friction(),
        BoundarySpec::FrictionAngleDeg(a) => Boundary::with_friction_angle_deg(Vector::Y, a)
            .map_err(|e| contact_error(ctx, &format!("{path}.friction_angle_deg"), e))?
            .friction(),
        BoundarySpec::Rough => Friction::Rough,
        BoundarySpec::Fixed => Friction::Fixed,
        BoundarySpec::Frictionless => Friction::Coulomb { mu: 0.0 },
        BoundarySpec::Outflow => return Err(not_a_law(ctx, path)),
    })
}

/// `[boundaries] side_walls`: a positive width and exactly one of `friction`,
/// `friction_angle_deg` (checked by the contact layer's rules, as the ground's law).
pub(super) fn side_walls(ctx: &Ctx<'_>, f: &SceneFile) -> Result<Option<SideWalls>, SceneError> {
    let Some(s) = f.boundaries.side_walls else { return Ok(None) };
    let path = "boundaries.side_walls";
    if !(s.width > 0.0 && s.width.is_finite()) {
        return Err(ctx.range(
            &format!("{path}.width"),
            s.width,
            "0 < width < ∞ (m)",
            "give the channel's width between its side walls in m, e.g. 0.2",
        ));
    }
    let law = match (s.friction, s.friction_angle_deg) {
        (Some(mu), None) => BoundarySpec::Friction(mu),
        (None, Some(a)) => BoundarySpec::FrictionAngleDeg(a),
        (both, _) => {
            return Err(ctx.err(
                path,
                None,
                if both.is_some() {
                    "both `friction` and `friction_angle_deg` are given"
                } else {
                    "no friction is given"
                },
                "exactly one of `friction` (μ_w) or `friction_angle_deg` (δ)",
                "write e.g. `side_walls = { width = 0.2, friction_angle_deg = 20.0 }`",
            ));
        }
    };
    let Friction::Coulomb { mu } = friction(ctx, path, law)? else {
        unreachable!("a Coulomb law's friction is Coulomb")
    };
    Ok(Some(SideWalls { width: s.width, friction: mu }))
}

/// a friction law for the 3D build of the contact layer (the same law, validated by the 2D
/// one's rules).
pub(super) fn friction_3d(
    ctx: &Ctx<'_>,
    path: &str,
    spec: BoundarySpec,
) -> Result<mpm_contact3d::Friction, SceneError> {
    Ok(match friction(ctx, path, spec)? {
        Friction::Coulomb { mu } => mpm_contact3d::Friction::Coulomb { mu },
        Friction::Rough => mpm_contact3d::Friction::Rough,
        Friction::Fixed => mpm_contact3d::Friction::Fixed,
    })
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
