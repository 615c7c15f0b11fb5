//! `[[bodies]]` of a 3D scene: boxes, cylinders and prisms filled with particles, and the
//! release of a terrain scene.

use super::*;

/// the body's shape, its fields checked against its `shape`.
pub(super) fn body_shape(
    ctx: &Ctx<'_>,
    base: &str,
    b: &SpaceBodySpec,
) -> Result<Shape, SceneError> {
    let p = |field: &str| format!("{base}.{field}");
    let why = |shape: &str| format!("it belongs to another shape than `{shape}`");
    let foreign = |present: &[(&str, bool)], shape: &str| -> Result<(), SceneError> {
        match present.iter().find(|(_, here)| *here) {
            Some((field, _)) => Err(ctx.foreign(&p(field), &why(shape))),
            None => Ok(()),
        }
    };
    let positive = |field: &str, v: Option<f64>, example: &str| -> Result<f64, SceneError> {
        let v = v.ok_or_else(|| ctx.missing(&p(field), "this shape needs it", example))?;
        if !finite_pos(v) {
            return Err(ctx.range(&p(field), v, "> 0 (m)", "give a positive length in metres"));
        }
        Ok(v)
    };
    let finite = |field: &str, v: [f64; 3]| -> Result<Vector, SceneError> {
        if v.iter().all(|x| x.is_finite()) {
            Ok(Vector::from_array(v))
        } else {
            Err(ctx.err(&p(field), Some(triple(v)), "not finite", "finite values", "give numbers"))
        }
    };
    match b.shape {
        SpaceShapeKind::Release => Err(ctx.err(
            &p("shape"),
            Some("\"release\"".into()),
            "a release body has no shape of its own",
            "box, cylinder or prism",
            "give the body a shape",
        )),
        SpaceShapeKind::Box => {
            foreign(
                &[
                    ("base", b.base.is_some()),
                    ("direction", b.direction.is_some()),
                    ("radius", b.radius.is_some()),
                    ("height", b.height.is_some()),
                    ("vertices", b.vertices.is_some()),
                    ("axis", b.axis.is_some()),
                    ("from", b.from.is_some()),
                    ("to", b.to.is_some()),
                ],
                "box",
            )?;
            let min =
                b.min.ok_or_else(|| ctx.missing(&p("min"), "a box has corners", "[0, 0, 0]"))?;
            let max =
                b.max.ok_or_else(|| ctx.missing(&p("max"), "a box has corners", "[1, 1, 1]"))?;
            let (lo, hi) = (finite(&p("min"), min)?, finite(&p("max"), max)?);
            if !hi.cmpgt(lo).all() {
                return Err(ctx.err(
                    &p("max"),
                    Some(triple(max)),
                    format!("not above `min` = {} along every axis", triple(min)),
                    "max > min along x, y and z",
                    "swap the corners or give the box a positive size",
                ));
            }
            Ok(Shape::Box { min: lo, max: hi })
        }
        SpaceShapeKind::Cylinder => {
            foreign(
                &[
                    ("min", b.min.is_some()),
                    ("max", b.max.is_some()),
                    ("vertices", b.vertices.is_some()),
                    ("axis", b.axis.is_some()),
                    ("from", b.from.is_some()),
                    ("to", b.to.is_some()),
                ],
                "cylinder",
            )?;
            let base = b.base.ok_or_else(|| {
                ctx.missing(&p("base"), "a cylinder stands on the centre of its base", "[1, 0, 1]")
            })?;
            let base = finite(&p("base"), base)?;
            let direction = finite(&p("direction"), b.direction.unwrap_or([0.0, 1.0, 0.0]))?;
            // scaled by its largest component first: the length of [0, 1e308, 1e308] overflows
            // and that of [1e-320, 0, 0] underflows, yet both are directions
            let largest = direction.abs().max_element();
            let direction = if largest > 0.0 { direction / largest } else { direction };
            if largest == 0.0 {
                return Err(ctx.err(
                    &p("direction"),
                    b.direction.map(triple),
                    "the axis has no direction",
                    "a non-zero vector",
                    "give the axis's direction, e.g. `direction = [0, 1, 0]` (upright)",
                ));
            }
            let radius = positive("radius", b.radius, "0.5")?;
            let height = positive("height", b.height, "1.0")?;
            Ok(Shape::Cylinder { base, axis: direction.normalize(), radius, height })
        }
        SpaceShapeKind::Prism => {
            foreign(
                &[
                    ("min", b.min.is_some()),
                    ("max", b.max.is_some()),
                    ("base", b.base.is_some()),
                    ("direction", b.direction.is_some()),
                    ("radius", b.radius.is_some()),
                    ("height", b.height.is_some()),
                ],
                "prism",
            )?;
            let vertices = b.vertices.as_ref().ok_or_else(|| {
                ctx.missing(
                    &p("vertices"),
                    "a prism extrudes a polygon",
                    "[[0, 0], [1, 0], [0, 1]]",
                )
            })?;
            let polygon = simple_polygon(
                ctx,
                &p("vertices"),
                vertices,
                "a prism's polygon",
                "list the polygon's corners in order around the outline, or split the prism into \
                 two bodies",
            )?;
            let axis = b.axis.ok_or_else(|| {
                ctx.missing(&p("axis"), "a prism is extruded along an axis", "\"z\"")
            })?;
            let from = b.from.ok_or_else(|| ctx.missing(&p("from"), "where it starts", "0.0"))?;
            let to = b.to.ok_or_else(|| ctx.missing(&p("to"), "where it ends", "1.0"))?;
            if !(from.is_finite() && to.is_finite() && to > from) {
                return Err(ctx.err(
                    &p("to"),
                    Some(num(to)),
                    format!("not beyond `from` = {}", num(from)),
                    "to > from, finite (m)",
                    "give the prism a positive length along its axis",
                ));
            }
            let axis = match axis {
                Axis::X => generate::Axis::X,
                Axis::Y => generate::Axis::Y,
                Axis::Z => generate::Axis::Z,
            };
            Ok(Shape::Prism { vertices: polygon, axis, from, to })
        }
    }
}

/// The particles of every body, and the particles per cell uGIMP's size follows.
pub(super) fn seeds(
    ctx: &Ctx<'_>,
    f: &SpaceFile,
    (grid, surface): (&SpaceGrid, Option<&TerrainGrid>),
    used: &[&str],
) -> Result<(Vec<SpaceSeed>, usize), SceneError> {
    let cell = grid.plan_cell();
    let mut seeds: Vec<SpaceSeed> = Vec::new();
    let mut shapes: Vec<Shape> = Vec::new();
    let mut gimp_ppc = 1;
    // the release body, once one is met
    let mut release: Option<usize> = None;
    for (b, body) in f.bodies.iter().enumerate() {
        let base = format!("bodies[{b}]");
        let ppc = body.particles_per_cell.unwrap_or(2);
        if !(1..=MAX_PARTICLES_PER_CELL).contains(&ppc) {
            return Err(ctx.range(
                &format!("{base}.particles_per_cell"),
                ppc as f64,
                &format!("1 ≤ particles_per_cell ≤ {MAX_PARTICLES_PER_CELL} (along each axis)"),
                "use 2 (the paper's 2 × 2 per cell; 2 × 2 × 2 in 3D)",
            ));
        }
        gimp_ppc = gimp_ppc.max(ppc as usize);
        let spacing = cell / ppc as f64;
        let (fill, shape) = if body.shape == SpaceShapeKind::Release {
            if let Some(k) = release {
                return Err(ctx.err(
                    &format!("{base}.shape"),
                    Some("\"release\"".into()),
                    format!("bodies[{k}] already fills the release volume"),
                    "one release body",
                    "remove one of the two",
                ));
            }
            release = Some(b);
            let fill = release_body(ctx, &base, body, (grid, surface), spacing, seeds.len())?;
            (fill, None)
        } else {
            let shape = body_shape(ctx, &base, body)?;
            let (lo, hi) = shape.bounds();
            let estimate = ((hi - lo) / spacing).element_product();
            if !(estimate.is_finite() && seeds.len() as f64 + estimate <= MAX_PARTICLES as f64) {
                return Err(bodies::too_many(ctx, &base));
            }
            let mut fill = generate::fill(&shape, spacing);
            if let SpaceGrid::Terrain(t) = grid {
                // over a DEM a body is the part of its shape above the ground
                fill.retain(|s| s.position.y > t.ground_height(s.position.x, s.position.z));
                // and none of it may lie in the release volume a release body fills
                if let (Some(k), Some(top)) = (release, surface) {
                    let cut = |p: Vector| {
                        let (g, s) = (t.ground_height(p.x, p.z), top.ground_height(p.x, p.z));
                        s - g > 0.0 && p.y < s
                    };
                    if let Some(q) = fill.iter().find(|q| cut(q.position)) {
                        return Err(ctx.err(
                            &base,
                            None,
                            format!(
                                "it overlaps bodies[{k}], the release volume (a particle at {})",
                                q.position
                            ),
                            "bodies that do not overlap",
                            "move or shrink this body",
                        ));
                    }
                }
            }
            (fill, Some(shape))
        };
        if fill.is_empty() {
            return Err(bodies::no_particle(ctx, &base, spacing));
        }
        if let Some(s) = fill.iter().find(|s| grid.locate(s.position).is_err()) {
            return Err(ctx.err(
                &base,
                None,
                format!("a particle at {} lies outside the grid", s.position),
                "bodies inside the grid",
                "move the body, or enlarge the grid (origin, cells)",
            ));
        }
        if let Some((k, s)) = fill
            .iter()
            .find_map(|s| shapes.iter().position(|o| o.contains(s.position)).map(|k| (k, s)))
        {
            return Err(ctx.err(
                &base,
                None,
                format!("it overlaps bodies[{k}] (a particle at {})", s.position),
                "bodies that do not overlap",
                "move or shrink one of the two",
            ));
        }
        let velocity = body.velocity.unwrap_or([0.0; 3]);
        if !velocity.iter().all(|v| v.is_finite()) {
            return Err(ctx.err(
                &format!("{base}.velocity"),
                Some(triple(velocity)),
                "not finite",
                "finite components (m/s)",
                "give the initial velocity, e.g. `velocity = [0, 0, 0]`",
            ));
        }
        let material = used.iter().position(|n| *n == body.material).unwrap_or(0);
        let density =
            f.materials.get(&body.material).and_then(|m| m.number("density")).unwrap_or(1.0);
        seeds.extend(fill.iter().map(|s| SpaceSeed {
            position: s.position,
            velocity: Vector::from_array(velocity),
            volume: s.volume,
            density,
            material: material as u16,
            body: b as u16,
        }));
        shapes.extend(shape);
    }
    Ok((seeds, gimp_ppc))
}

/// A `shape = "release"` body: the release volume between the terrain grid's ground and the
/// DEM's surface ([`release_fill`]), at `spacing` (vertically at most a layer height); refused
/// without a cut terrain, with another shape's fields, or with more particles than a scene may
/// hold (`already` are taken).
pub(super) fn release_body(
    ctx: &Ctx<'_>,
    base: &str,
    b: &SpaceBodySpec,
    (grid, surface): (&SpaceGrid, Option<&TerrainGrid>),
    spacing: f64,
    already: usize,
) -> Result<Vec<generate::Seed>, SceneError> {
    let p = |field: &str| format!("{base}.{field}");
    let present = [
        ("min", b.min.is_some()),
        ("max", b.max.is_some()),
        ("base", b.base.is_some()),
        ("direction", b.direction.is_some()),
        ("radius", b.radius.is_some()),
        ("height", b.height.is_some()),
        ("vertices", b.vertices.is_some()),
        ("axis", b.axis.is_some()),
        ("from", b.from.is_some()),
        ("to", b.to.is_some()),
    ];
    if let Some((field, _)) = present.iter().find(|(_, here)| *here) {
        return Err(ctx.foreign(&p(field), "a release body is the volume the grid's cut leaves"));
    }
    let (SpaceGrid::Terrain(t), Some(surface)) = (grid, surface) else {
        return Err(ctx.err(
            &p("shape"),
            Some("\"release\"".into()),
            "a release body fills the volume cut into the terrain, and this grid has no cut",
            "`[grid] kind = \"terrain\"` with `rupture` or `release_polygon` and `release_depth`",
            "cut the release into the DEM in `[grid]`, or give the body a shape",
        ));
    };
    // Vertically at most one cell layer apart (R3-03): at the plan's spacing alone, layers
    // finer than it were left empty, and the release sank through them as in free fall.
    let vertical = spacing.min(t.layers().0);
    // about the particles it will make: each cut lattice node stands for (h/s)² columns of
    // depth/sv + 1 particles at most
    let [nx, nz] = t.plan_cells();
    let h = t.spacing()[0];
    let mut estimate = 0.0;
    for k in 0..=nz as i32 {
        for i in 0..=nx as i32 {
            let node = mpm_grid3d::NodeId::new(i, 0, k);
            let depth = surface.node_position(node).y - t.node_position(node).y;
            if depth > 0.0 {
                estimate += (h / spacing).powi(2) * (depth / vertical + 1.0);
            }
        }
    }
    if !(estimate.is_finite() && already as f64 + estimate <= 2.0 * MAX_PARTICLES as f64) {
        return Err(bodies::too_many(ctx, base));
    }
    let fill: Vec<generate::Seed> = super::grid::release_fill(t, surface, spacing, vertical)
        .into_iter()
        .map(|(position, volume)| generate::Seed { position, volume })
        .collect();
    if already + fill.len() > MAX_PARTICLES {
        return Err(bodies::too_many(ctx, base));
    }
    Ok(fill)
}
