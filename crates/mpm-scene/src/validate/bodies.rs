//! `[[bodies]]`: each body's shape, checked, filled with particles (n × n per cell), inside the
//! grid and overlapping no other body.

use mpm_grid::LocateError;
use mpm_solver::Vector;
use mpm_solver::generate::{self, Shape};

use super::{Ctx, finite_pos, num, pair};
use crate::error::SceneError;
use crate::file::{
    BodySpec, InitialStateMethod, SceneFile, ShapeFunctionKind, ShapeKind, Transfer, VtkField,
};
use crate::ground::segment_at;
use crate::limits::{MAX_BODIES, MAX_PARTICLES, MAX_PARTICLES_PER_CELL, MAX_VERTICES};
use crate::scene::{GridBuilt, MaterialsBuilt, Seed};

/// Each earlier body's shape, bounding box and range of seeds.
type Placed = Vec<(Shape, [Vector; 2], std::ops::Range<usize>)>;

/// Refuses a scene without bodies or with more than [`MAX_BODIES`].
pub(super) fn count(ctx: &Ctx<'_>, f: &SceneFile) -> Result<(), SceneError> {
    if f.bodies.is_empty() {
        return Err(ctx.err(
            "bodies",
            None,
            "no body is defined",
            "at least one [[bodies]] table",
            "add a [[bodies]] table with material, shape and its dimensions",
        ));
    }
    if f.bodies.len() > MAX_BODIES {
        return Err(ctx.err(
            "bodies",
            Some(f.bodies.len().to_string()),
            "too many bodies",
            format!("at most {MAX_BODIES} bodies"),
            "merge bodies of the same material (a polygon can hold any outline)",
        ));
    }
    Ok(())
}

/// The particle seeds of every body, in file order, with `used` the materials' names in index
/// order: (seeds, the smallest particle spacing, the largest particles per cell).
pub(super) fn seeds(
    ctx: &Ctx<'_>,
    f: &SceneFile,
    grid: &GridBuilt,
    cell_x: f64,
    shape_function: ShapeFunctionKind,
    materials: &MaterialsBuilt,
    used: &[&str],
) -> Result<(Vec<Seed>, f64, usize), SceneError> {
    fits_in_memory(ctx, f, grid, cell_x, shape_function, materials.state_bytes())?;
    let mut seeds: Vec<Seed> = Vec::new();
    // each earlier body's shape, bounding box and range of `seeds`.
    let mut shapes: Placed = Vec::new();
    let mut spacing_min = f64::INFINITY;
    let mut gimp_ppc = 1usize;
    for (b, body) in f.bodies.iter().enumerate() {
        let base = format!("bodies[{b}]");
        let p = |field: &str| format!("{base}.{field}");
        let ppc = body.particles_per_cell.unwrap_or(2);
        if !(1..=MAX_PARTICLES_PER_CELL).contains(&ppc) {
            return Err(ctx.err(
                &p("particles_per_cell"),
                Some(ppc.to_string()),
                "particles per cell out of range",
                format!("1 ≤ particles_per_cell ≤ {MAX_PARTICLES_PER_CELL} (n × n per cell)"),
                "use 2 (the paper's 2 × 2 per cell)",
            ));
        }
        gimp_ppc = gimp_ppc.max(ppc as usize);
        let spacing = cell_x / ppc as f64;
        spacing_min = spacing_min.min(spacing);
        let velocity = body.velocity.unwrap_or([0.0, 0.0]);
        if !(velocity[0].is_finite()
            && velocity[1].is_finite()
            && velocity[0].hypot(velocity[1]) < 1e5)
        {
            return Err(ctx.err(
                &p("velocity"),
                Some(pair(velocity)),
                "initial velocity out of range",
                "finite components, speed < 1e5 m/s",
                "give the initial velocity in m/s, e.g. [10.0, 0.0]",
            ));
        }
        let shape = body_shape(ctx, &base, body, grid)?;
        let area = shape_area(&shape);
        if !(area.is_finite() && area / (spacing * spacing) <= MAX_PARTICLES as f64) {
            return Err(ctx.err(
                &base,
                None,
                format!(
                    "this body would generate about {:.3e} particles",
                    area / (spacing * spacing)
                ),
                format!("at most {MAX_PARTICLES} particles in a scene"),
                "use a coarser grid, fewer particles per cell or a smaller body",
            ));
        }
        let mut fill = generate::fill(&shape, spacing);
        if let (Shape::BetweenProfiles { .. }, GridBuilt::Terrain(t)) = (&shape, grid) {
            // Between two columns the ground is a chord of the rupture surface cut into it
            // (`grid.rupture_surface`); the sliver between that chord and a curved surface holds
            // points just below the ground: they are left out. A mass deeper below the ground
            // is misplaced and reported as such below.
            let sliver = 0.5 * t.row_height();
            fill.retain(|s| {
                t.ground_height(s.position.x)
                    .is_none_or(|g| s.position.y > g || s.position.y < g - sliver)
            });
        }
        if fill.is_empty() {
            return Err(no_particle(ctx, &base, spacing));
        }
        if seeds.len() + fill.len() > MAX_PARTICLES {
            return Err(too_many(ctx, &base));
        }
        let m_index = used.iter().position(|n| *n == body.material).unwrap_or(0);
        let density =
            f.materials.get(&body.material).and_then(|m| m.number("density")).unwrap_or(1.0);
        for s in &fill {
            let located = match grid {
                GridBuilt::Terrain(t) => t.locate(s.position).map(|_| ()),
                GridBuilt::Regular(r) => r.locate(s.position).map(|_| ()),
            };
            if let Err(e) = located {
                return Err(outside_error(ctx, &base, body, e, grid));
            }
        }
        overlap(ctx, &base, &fill, &shape, &shapes, &seeds)?;
        let bounds = shape_box(&shape);
        let first = seeds.len();
        seeds.extend(fill.iter().map(|s| Seed {
            position: s.position,
            velocity: Vector::new(velocity[0], velocity[1]),
            volume: s.area,
            density,
            material: m_index as u16,
            body: b as u16,
        }));
        shapes.push((shape, bounds, first..seeds.len()));
    }
    Ok((seeds, spacing_min, gimp_ppc))
}

/// Refuses a body whose particles lie strictly inside an earlier body, or the reverse. Only
/// bodies whose bounding boxes meet can overlap: O(bodies²) box tests, and particle tests only
/// for the pairs that are close.
fn overlap(
    ctx: &Ctx<'_>,
    base: &str,
    fill: &[generate::Seed],
    shape: &Shape,
    shapes: &Placed,
    seeds: &[Seed],
) -> Result<(), SceneError> {
    let bounds = shape_box(shape);
    for (other, (shape_o, bounds_o, range)) in shapes.iter().enumerate() {
        let apart = (0..2).any(|k| bounds[1][k] < bounds_o[0][k] || bounds_o[1][k] < bounds[0][k]);
        if apart {
            continue;
        }
        let hit =
            fill.iter().find(|s| contains(shape_o, s.position)).map(|s| s.position).or_else(|| {
                seeds[range.clone()]
                    .iter()
                    .find(|s| contains(shape, s.position))
                    .map(|s| s.position)
            });
        if let Some(at) = hit {
            return Err(ctx.err(
                base,
                None,
                format!(
                    "this body overlaps bodies[{other}] (a particle at ({}, {}) lies in both)",
                    num(at.x),
                    num(at.y)
                ),
                "bodies that do not overlap (they may touch)",
                "move or shrink one of the two bodies",
            ));
        }
    }
    Ok(())
}

/// A body's shape, refusing the fields its `shape` does not take.
fn body_shape(
    ctx: &Ctx<'_>,
    base: &str,
    body: &BodySpec,
    grid: &GridBuilt,
) -> Result<Shape, SceneError> {
    let p = |field: &str| format!("{base}.{field}");
    let kind = body.shape;
    let allowed: &[&str] = match kind {
        ShapeKind::Rectangle => &["min", "max"],
        ShapeKind::Polygon => &["vertices"],
        ShapeKind::OnSlope => &["base_start", "base_x", "angle_deg", "length", "thickness"],
        ShapeKind::BetweenProfiles => &["top", "bottom"],
    };
    for (field, present) in [
        ("min", body.min.is_some()),
        ("max", body.max.is_some()),
        ("vertices", body.vertices.is_some()),
        ("base_start", body.base_start.is_some()),
        ("base_x", body.base_x.is_some()),
        ("angle_deg", body.angle_deg.is_some()),
        ("length", body.length.is_some()),
        ("thickness", body.thickness.is_some()),
        ("top", body.top.is_some()),
        ("bottom", body.bottom.is_some()),
    ] {
        if present && !allowed.contains(&field) {
            return Err(ctx.foreign(
                &p(field),
                &format!("a shape = \"{}\" body takes {}", shape_name(kind), allowed.join(", ")),
            ));
        }
    }
    match kind {
        ShapeKind::Rectangle => rectangle(ctx, base, body),
        ShapeKind::Polygon => polygon(ctx, base, body),
        ShapeKind::OnSlope => on_slope(ctx, base, body, grid),
        ShapeKind::BetweenProfiles => between_profiles(ctx, base, body, grid),
    }
}

/// `shape = "between_profiles"`: the mass between a `top` and a `bottom` polyline (inline, a
/// CSV or a DEM section), each with x strictly increasing; particles only where top > bottom.
fn between_profiles(
    ctx: &Ctx<'_>,
    base: &str,
    body: &BodySpec,
    grid: &GridBuilt,
) -> Result<Shape, SceneError> {
    let spacing = grid.column_width();
    let mut lines = [Vec::new(), Vec::new()];
    for (k, (name, spec)) in [("top", &body.top), ("bottom", &body.bottom)].into_iter().enumerate()
    {
        let path = format!("{base}.{name}");
        let spec = spec
            .as_ref()
            .ok_or_else(|| ctx.missing(&path, "between_profiles", "[[0.0, 2.0], [10.0, 1.0]]"))?;
        let points = super::polyline::points(ctx, &path, spec, spacing)?;
        super::polyline::check_increasing(ctx, &path, &points)?;
        if points.len() > MAX_VERTICES {
            return Err(ctx.err(
                &path,
                Some(format!("{} point(s)", points.len())),
                format!("a profile may have at most {MAX_VERTICES} points"),
                "2 or more [x, y] points with x increasing",
                "give the surface as [[x0, y0], [x1, y1], ...]",
            ));
        }
        lines[k] = super::polyline::vectors(&points);
    }
    let [top, bottom] = lines;
    let shape = Shape::BetweenProfiles { top, bottom };
    if enclosed_area(&shape) <= 0.0 {
        return Err(ctx.err(
            &format!("{base}.top"),
            None,
            "the top profile is nowhere above the bottom one over their common x range",
            "a top surface above the bottom surface somewhere",
            "check that `top` is the upper surface and that the two overlap in x",
        ));
    }
    Ok(shape)
}

/// ∫ max(0, top − bottom) dx over the common x range of two polylines (x increasing): exact for
/// the piecewise-linear difference, sign changes included.
fn area_between(top: &[Vector], bottom: &[Vector]) -> f64 {
    use mpm_solver::generate::polyline_height;
    let (Some(t0), Some(b0), Some(t1), Some(b1)) =
        (top.first(), bottom.first(), top.last(), bottom.last())
    else {
        return 0.0;
    };
    let (x0, x1) = (t0.x.max(b0.x), t1.x.min(b1.x));
    if x1 <= x0 || x1.is_nan() || x0.is_nan() {
        return 0.0;
    }
    let mut xs: Vec<f64> =
        top.iter().chain(bottom).map(|p| p.x).filter(|&x| x > x0 && x < x1).collect();
    xs.extend([x0, x1]);
    xs.sort_by(f64::total_cmp);
    let d =
        |x: f64| polyline_height(top, x).unwrap_or(0.0) - polyline_height(bottom, x).unwrap_or(0.0);
    let mut area = 0.0;
    for w in xs.windows(2) {
        let (xa, xb) = (w[0], w[1]);
        let (da, db) = (d(xa), d(xb));
        area += if da >= 0.0 && db >= 0.0 {
            0.5 * (da + db) * (xb - xa)
        } else if da > 0.0 || db > 0.0 {
            // one sign change: the positive triangle
            let pos = da.max(db);
            0.5 * pos * pos / (da - db).abs() * (xb - xa)
        } else {
            0.0
        };
    }
    area
}

/// both coordinates finite.
fn finite2(v: [f64; 2]) -> bool {
    v[0].is_finite() && v[1].is_finite()
}

/// Refuses a corner with a non-finite coordinate at `path`.
fn finite_corner(ctx: &Ctx<'_>, path: &str, v: [f64; 2]) -> Result<(), SceneError> {
    if finite2(v) {
        return Ok(());
    }
    Err(ctx.err(
        path,
        Some(pair(v)),
        "corner is not finite",
        "finite coordinates (m)",
        "give the corner in metres",
    ))
}

/// `shape = "rectangle"`: `min` and `max` corners.
fn rectangle(ctx: &Ctx<'_>, base: &str, body: &BodySpec) -> Result<Shape, SceneError> {
    let p = |field: &str| format!("{base}.{field}");
    let min = body.min.ok_or_else(|| ctx.missing(&p("min"), "rectangle", "[0.0, 0.0]"))?;
    let max = body.max.ok_or_else(|| ctx.missing(&p("max"), "rectangle", "[1.0, 1.0]"))?;
    for (f, v) in [("min", min), ("max", max)] {
        finite_corner(ctx, &p(f), v)?;
    }
    if !(max[0] > min[0] && max[1] > min[1]) {
        return Err(ctx.err(
            &p("max"),
            Some(pair(max)),
            format!("the upper-right corner is not above and right of min = {}", pair(min)),
            "max[0] > min[0] and max[1] > min[1]",
            "swap the corners or correct them",
        ));
    }
    Ok(Shape::Rectangle { min: Vector::new(min[0], min[1]), max: Vector::new(max[0], max[1]) })
}

/// `shape = "polygon"`: a simple polygon (a closing vertex that repeats the first is dropped).
fn polygon(ctx: &Ctx<'_>, base: &str, body: &BodySpec) -> Result<Shape, SceneError> {
    let p = |field: &str| format!("{base}.{field}");
    let v = body.vertices.clone().ok_or_else(|| {
        ctx.missing(&p("vertices"), "polygon", "[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]")
    })?;
    if v.len() < 3 || v.len() > MAX_VERTICES {
        return Err(ctx.err(
            &p("vertices"),
            Some(format!("{} vertices", v.len())),
            format!("a polygon needs at least three vertices and at most {MAX_VERTICES}"),
            format!("3 to {MAX_VERTICES} vertices, in order"),
            "list the polygon's corners in order",
        ));
    }
    if let Some(k) = v.iter().position(|x| !finite2(*x)) {
        return Err(ctx.err(
            &format!("{}[{k}]", p("vertices")),
            Some(pair(v[k])),
            "vertex is not finite",
            "finite coordinates (m)",
            "give the vertex in metres",
        ));
    }
    let mut vertices: Vec<Vector> = v.iter().map(|x| Vector::new(x[0], x[1])).collect();
    // A closing vertex that repeats the first one is a common way to write an outline.
    if vertices.len() > 3 && vertices.first() == vertices.last() {
        vertices.pop();
    }
    if let Some((a, b)) = self_intersection(&vertices) {
        return Err(ctx.err(
            &format!("{}[{a}]", p("vertices")),
            Some(pair(v[a])),
            format!(
                "the polygon is not simple: its edge from vertex {a} crosses the edge from \
                 vertex {b} (a bow-tie has no inside)"
            ),
            "a simple polygon: edges meet only at their shared corners",
            "list the corners in order around the outline (clockwise or counter-\
             clockwise), or split the shape into two bodies",
        ));
    }
    Ok(Shape::Polygon { vertices })
}

/// `shape = "on_slope"`: a parallelogram whose base lies along the ground (or `angle_deg`).
fn on_slope(
    ctx: &Ctx<'_>,
    base: &str,
    body: &BodySpec,
    grid: &GridBuilt,
) -> Result<Shape, SceneError> {
    let p = |field: &str| format!("{base}.{field}");
    let length = body.length.ok_or_else(|| ctx.missing(&p("length"), "on_slope", "1.2"))?;
    let thickness =
        body.thickness.ok_or_else(|| ctx.missing(&p("thickness"), "on_slope", "0.7"))?;
    for (f, v) in [("length", length), ("thickness", thickness)] {
        if !finite_pos(v) {
            return Err(ctx.range(&p(f), v, "0 < value < ∞ (m)", "give the body's size in metres"));
        }
    }
    let ground_of = |x: f64| -> Option<(f64, f64)> {
        match grid {
            GridBuilt::Terrain(t) => {
                let y = t.ground_height(x)?;
                let (a, b) = segment_at(t.profile(), x);
                Some((y, (b.y - a.y).atan2(b.x - a.x)))
            }
            GridBuilt::Regular(r) => {
                let (lo, hi) = (r.origin(), r.upper_corner());
                (lo.x..=hi.x).contains(&x).then_some((lo.y, 0.0))
            }
        }
    };
    let (start, ground_angle) = match (body.base_start, body.base_x) {
        (Some(_), Some(_)) => {
            return Err(ctx.err(
                &p("base_x"),
                body.base_x.map(num),
                "both `base_start` and `base_x` are given",
                "one of them",
                "keep `base_x` to put the body on the ground, or `base_start` for an \
                 explicit corner",
            ));
        }
        (Some(bs), None) => {
            finite_corner(ctx, &p("base_start"), bs)?;
            (Vector::new(bs[0], bs[1]), ground_of(bs[0]).map(|g| g.1))
        }
        (None, Some(x)) => {
            let Some((y, angle)) = ground_of(x).filter(|_| x.is_finite()) else {
                return Err(ctx.err(
                    &p("base_x"),
                    Some(num(x)),
                    "this x is not over the grid's ground",
                    "an x within the grid's horizontal extent (m)",
                    "give an x between the grid's left and right ends",
                ));
            };
            (Vector::new(x, y), Some(angle))
        }
        (None, None) => {
            return Err(ctx.missing(&p("base_x"), "on_slope: base_x or base_start", "0.1"));
        }
    };
    let angle_rad = match body.angle_deg {
        Some(a) => {
            if !(a.is_finite() && a > -90.0 && a < 90.0) {
                return Err(ctx.range(
                    &p("angle_deg"),
                    a,
                    "-90 < angle_deg < 90 (degrees from +x; negative descends to the \
                     right)",
                    "remove it to follow the ground's slope",
                ));
            }
            a.to_radians()
        }
        None => ground_angle.unwrap_or(0.0),
    };
    Ok(Shape::OnSlope { base_start: start, angle_rad, length, thickness })
}

fn shape_name(k: ShapeKind) -> &'static str {
    match k {
        ShapeKind::Rectangle => "rectangle",
        ShapeKind::Polygon => "polygon",
        ShapeKind::OnSlope => "on_slope",
        ShapeKind::BetweenProfiles => "between_profiles",
    }
}

/// the bytes a particle's state takes in a copy of the particles (a checkpoint, or the final state
/// hash, holds two: the copy and its encoding; R3-02 measured them in 3D).
pub fn checkpoint_copy(state: usize, apic: bool) -> usize {
    use mpm_solver::{Matrix, Stress, Vector};
    3 * size_of::<Vector>()
        + 2 * size_of::<f64>()
        + size_of::<Stress>()
        + state
        + 2 * size_of::<u16>()
        + if apic { size_of::<Matrix>() } else { 0 }
}

/// refuses a scene whose particles would not fit in the memory this process may use, before any
/// particle exists: the count comes from the bodies' areas (n² particles per cell), the bytes per
/// particle from the solver's own accounting (`mpm_solver::estimated_bytes`), plus the scene's
/// seeds, a checkpoint's two copies of the particles and one particle frame being written.
fn fits_in_memory(
    ctx: &Ctx<'_>,
    f: &SceneFile,
    grid: &GridBuilt,
    cell_x: f64,
    shape_function: ShapeFunctionKind,
    state: usize,
) -> Result<(), SceneError> {
    let mut particles = 0.0;
    for (b, body) in f.bodies.iter().enumerate() {
        let ppc = body.particles_per_cell.unwrap_or(2).clamp(1, MAX_PARTICLES_PER_CELL) as f64;
        // a body whose shape is invalid is reported, located, by the bodies' loop
        if let Ok(shape) = body_shape(ctx, &format!("bodies[{b}]"), body, grid) {
            particles += enclosed_area(&shape) * (ppc / cell_x).powi(2);
        }
    }
    if !(particles.is_finite() && particles <= MAX_PARTICLES as f64) {
        // the bodies' loop names the body and the limit
        return Ok(());
    }
    let n = particles.ceil() as usize;
    let (stencil, nodes) = match (grid, shape_function) {
        (GridBuilt::Terrain(t), _) => (4, (t.columns() + 1) * (t.rows() + 1)),
        (GridBuilt::Regular(g), kind) => {
            let [nx, ny] = g.cells();
            (if kind == ShapeFunctionKind::Bilinear { 4 } else { 9 }, (nx + 3) * (ny + 3))
        }
    };
    let apic = f.solver.transfer == Some(Transfer::Apic);
    let fields = f.output.fields.clone().unwrap_or_else(|| VtkField::ALL.to_vec());
    let frame = f.output.vtk_format.unwrap_or_default().frame_bytes(n, &fields);
    // the implicit initial state's stiffness and factors, on top of the run's own memory
    let implicit =
        f.initial_state.as_ref().is_some_and(|s| s.method == InitialStateMethod::Implicit);
    let solve = if implicit { mpm_solver::geostatic::estimated_bytes(n, stencil) } else { 0 };
    let need =
        mpm_solver::estimated_bytes(n, nodes.min(n.saturating_mul(stencil)), stencil, state, apic)
            + (n * (std::mem::size_of::<Seed>() + 2 * checkpoint_copy(state, apic))) as u64
            + frame
            + solve;
    let Some((available, source)) = crate::limits::available_memory() else { return Ok(()) };
    if need > available {
        return Err(ctx.err(
            "bodies",
            None,
            format!(
                "the scene needs about {:.0} MB for {n} particles ({:.0} B each, with the grid, \
                 a checkpoint and one frame being written{}), but only {:.0} MB are available \
                 ({source})",
                need as f64 / 1e6,
                need as f64 / n.max(1) as f64,
                if implicit {
                    format!(", {:.0} MB of them for the implicit initial state", solve as f64 / 1e6)
                } else {
                    String::new()
                },
                available as f64 / 1e6
            ),
            format!("at most about {:.0} MB", available as f64 / 1e6),
            if implicit {
                "use a coarser grid or fewer particles per cell, `[initial_state] method = \
                 \"gravity_ramp\"` (explicit, no matrix), or a machine with more memory"
            } else {
                "use a coarser grid, fewer particles per cell or smaller bodies, or run it on a \
                 machine with more memory"
            },
        ));
    }
    Ok(())
}

/// the first pair (i, j) of non-adjacent edges (edge k runs from vertex k to k + 1, the last one
/// back to vertex 0) that cross or touch, or a repeated vertex: `None` for a simple polygon.
/// O(n²) in the vertices, bounded by [`MAX_VERTICES`].
pub(super) fn self_intersection(v: &[Vector]) -> Option<(usize, usize)> {
    let n = v.len();
    let edge = |k: usize| (v[k], v[(k + 1) % n]);
    let orient = |a: Vector, b: Vector, c: Vector| (b - a).perp_dot(c - a);
    let on_segment = |a: Vector, b: Vector, c: Vector| {
        c.x >= a.x.min(b.x) && c.x <= a.x.max(b.x) && c.y >= a.y.min(b.y) && c.y <= a.y.max(b.y)
    };
    let meet = |(p1, p2): (Vector, Vector), (q1, q2): (Vector, Vector)| {
        let (d1, d2) = (orient(q1, q2, p1), orient(q1, q2, p2));
        let (d3, d4) = (orient(p1, p2, q1), orient(p1, p2, q2));
        if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
            && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
        {
            return true;
        }
        (d1 == 0.0 && on_segment(q1, q2, p1))
            || (d2 == 0.0 && on_segment(q1, q2, p2))
            || (d3 == 0.0 && on_segment(p1, p2, q1))
            || (d4 == 0.0 && on_segment(p1, p2, q2))
    };
    for i in 0..n {
        let (lo_i, hi_i) = (edge(i).0.min(edge(i).1), edge(i).0.max(edge(i).1));
        for j in i + 1..n {
            // adjacent edges share a corner: only a repeated vertex or a fold back counts
            let adjacent = j == i + 1 || (i == 0 && j == n - 1);
            let (a, b) = (edge(j).0.min(edge(j).1), edge(j).0.max(edge(j).1));
            if a.x > hi_i.x || b.x < lo_i.x || a.y > hi_i.y || b.y < lo_i.y {
                continue;
            }
            if adjacent {
                // collinear and overlapping beyond the shared corner: a fold back
                let (shared, p, q) =
                    if j == i + 1 { (v[j], v[i], v[(j + 1) % n]) } else { (v[0], v[1], v[n - 1]) };
                let folded = orient(p, shared, q) == 0.0 && (p - shared).dot(q - shared) > 0.0;
                if folded || v[i] == v[(i + 1) % n] {
                    return Some((i, j));
                }
                continue;
            }
            if meet(edge(i), edge(j)) {
                return Some((i, j));
            }
        }
    }
    None
}

/// the axis-aligned bounding box [min, max] of a shape.
fn shape_box(shape: &Shape) -> [Vector; 2] {
    let corners: Vec<Vector> = match shape {
        Shape::Rectangle { min, max } => vec![*min, *max],
        Shape::Polygon { vertices } => vertices.clone(),
        Shape::BetweenProfiles { top, bottom } => top.iter().chain(bottom).copied().collect(),
        Shape::OnSlope { base_start, angle_rad, length, thickness } => {
            let d = Vector::new(angle_rad.cos(), angle_rad.sin());
            let n = Vector::new(-d.y, d.x);
            vec![
                *base_start,
                *base_start + *length * d,
                *base_start + *length * d + *thickness * n,
                *base_start + *thickness * n,
            ]
        }
    };
    let lo = corners.iter().fold(Vector::splat(f64::INFINITY), |a, &c| a.min(c));
    let hi = corners.iter().fold(Vector::splat(f64::NEG_INFINITY), |a, &c| a.max(c));
    [lo, hi]
}

/// the area the fill's lattice scans (a polygon's bounding box): what bounds generation work.
fn shape_area(shape: &Shape) -> f64 {
    match shape {
        Shape::Rectangle { min, max } => (max.x - min.x) * (max.y - min.y),
        Shape::OnSlope { length, thickness, .. } => length * thickness,
        Shape::Polygon { .. } | Shape::BetweenProfiles { .. } => {
            let [lo, hi] = shape_box(shape);
            (hi.x - lo.x) * (hi.y - lo.y)
        }
    }
}

/// the area a shape encloses (a polygon's by the shoelace formula): what bounds its particles.
fn enclosed_area(shape: &Shape) -> f64 {
    match shape {
        Shape::Polygon { vertices } => {
            let n = vertices.len();
            0.5 * (0..n).map(|k| vertices[k].perp_dot(vertices[(k + 1) % n])).sum::<f64>().abs()
        }
        Shape::BetweenProfiles { top, bottom } => area_between(top, bottom),
        other => shape_area(other),
    }
}

/// `p` strictly inside `shape` (by more than round-off).
fn contains(shape: &Shape, p: Vector) -> bool {
    const EPS: f64 = 1e-9;
    match shape {
        Shape::Rectangle { min, max } => {
            p.x > min.x + EPS && p.x < max.x - EPS && p.y > min.y + EPS && p.y < max.y - EPS
        }
        Shape::OnSlope { base_start, angle_rad, length, thickness } => {
            let t = Vector::new(angle_rad.cos(), angle_rad.sin());
            let n = t.perp();
            let d = p - *base_start;
            let (s, h) = (d.dot(t), d.dot(n));
            s > EPS && s < length - EPS && h > EPS && h < thickness - EPS
        }
        Shape::Polygon { vertices } => mpm_solver::generate::inside_polygon(vertices, p),
        Shape::BetweenProfiles { top, bottom } => {
            mpm_solver::generate::between_profiles(top, bottom, p)
        }
    }
}

fn outside_error(
    ctx: &Ctx<'_>,
    base: &str,
    body: &BodySpec,
    e: LocateError,
    grid: &GridBuilt,
) -> SceneError {
    let extent = match grid {
        GridBuilt::Terrain(t) => {
            let (x0, x1) = t.x_range();
            format!(
                "x from {} to {} m, between the ground and {} m above it",
                num(x0),
                num(x1),
                num(t.rows() as f64 * t.row_height())
            )
        }
        GridBuilt::Regular(r) => {
            let (lo, hi) = (r.origin(), r.upper_corner());
            format!(
                "x from {} to {} m, y from {} to {} m",
                num(lo.x),
                num(hi.x),
                num(lo.y),
                num(hi.y)
            )
        }
    };
    let field = match body.shape {
        ShapeKind::Rectangle => "min",
        ShapeKind::Polygon => "vertices",
        ShapeKind::BetweenProfiles => "bottom",
        ShapeKind::OnSlope => {
            if body.base_x.is_some() {
                "base_x"
            } else {
                "base_start"
            }
        }
    };
    let problem = match e {
        LocateError::BelowGround { x, y, ground_y } => format!(
            "the body lies outside the grid: its particle at ({}, {}) is below the ground \
             (ground height there {})",
            num(x),
            num(y),
            num(ground_y)
        ),
        LocateError::Outside { x, y } | LocateError::NonFinite { x, y } => format!(
            "the body lies outside the grid: its particle at ({}, {}) is left, right or above \
             the grid",
            num(x),
            num(y)
        ),
    };
    ctx.err(
        &format!("{base}.{field}"),
        None,
        problem,
        format!("every particle inside the grid: {extent}"),
        if body.shape == ShapeKind::BetweenProfiles {
            "a release mass sits on the rupture surface: cut it into the ground with `[grid] \
             rupture_surface` (the body's `bottom`), and give the grid enough rows above it"
        } else {
            "move or shrink the body, or enlarge the grid (more rows, a longer profile or more cells)"
        },
    )
}

/// a body too small to hold a particle at `spacing` (m), located at `base` (2D and 3D).
pub(super) fn no_particle(ctx: &Ctx<'_>, base: &str, spacing: f64) -> SceneError {
    ctx.err(
        base,
        None,
        format!(
            "the body is smaller than one particle spacing ({} m) and holds no particle",
            num(spacing)
        ),
        "a body at least one particle spacing across",
        "enlarge the body or raise particles_per_cell",
    )
}

/// a body that would take the scene beyond [`MAX_PARTICLES`], located at `base` (2D and 3D).
pub(super) fn too_many(ctx: &Ctx<'_>, base: &str) -> SceneError {
    ctx.err(
        base,
        None,
        format!("the scene would generate more than {MAX_PARTICLES} particles"),
        format!("at most {MAX_PARTICLES} particles in a scene"),
        "use a coarser grid or fewer particles per cell",
    )
}
