//! `[grid]` of a 3D scene: a regular grid of cubic cells or the terrain-following grid over a
//! DEM, with a release cut into it.

use super::*;

/// `[grid]`: regular (cubic cells, a positive count along each axis) or terrain (over a DEM);
/// each kind's fields only.
/// The grid, the ground before a release was cut into it (if one was), and the DEM's CRS.
pub(super) type Grids = (SpaceGrid, Option<TerrainGrid>, mpm_dem::Crs);

pub(super) fn grid(ctx: &Ctx<'_>, f: &SpaceFile) -> Result<Grids, SceneError> {
    let g = &f.grid;
    let regular_fields = [
        ("grid.origin", g.origin.is_some()),
        ("grid.cell", g.cell.is_some()),
        ("grid.cells", g.cells.is_some()),
    ];
    let terrain_fields = [
        ("grid.dem", g.dem.is_some()),
        ("grid.from", g.from.is_some()),
        ("grid.to", g.to.is_some()),
        ("grid.plan_cell", g.plan_cell.is_some()),
        ("grid.layer_height", g.layer_height.is_some()),
        ("grid.layers", g.layers.is_some()),
        ("grid.rupture", g.rupture.is_some()),
        ("grid.release_polygon", g.release_polygon.is_some()),
        ("grid.release_depth", g.release_depth.is_some()),
    ];
    match g.kind {
        GridKind::Terrain => {
            if let Some((path, _)) = regular_fields.iter().find(|(_, here)| *here) {
                return Err(ctx.foreign(
                    path,
                    "a terrain grid takes its plan from `from`, `to` \
                     and `plan_cell`, its layers from `layer_height` and `layers`",
                ));
            }
            terrain_grid(ctx, f).map(|(t, surface, crs)| (SpaceGrid::Terrain(t), surface, crs))
        }
        GridKind::Regular => {
            if let Some((path, _)) = terrain_fields.iter().find(|(_, here)| *here) {
                return Err(ctx.foreign(path, "it belongs to `kind = \"terrain\"`"));
            }
            regular_grid(ctx, f).map(|g| (SpaceGrid::Regular(g), None, mpm_dem::Crs::default()))
        }
    }
}

/// a regular grid's `origin`, `cell` and `cells`.
pub(super) fn regular_grid(ctx: &Ctx<'_>, f: &SpaceFile) -> Result<RegularGrid, SceneError> {
    let g = &f.grid;
    let origin =
        g.origin.ok_or_else(|| ctx.missing("grid.origin", "a regular grid", "[0.0, 0.0, 0.0]"))?;
    let cell =
        g.cell.ok_or_else(|| ctx.missing("grid.cell", "a regular grid", "[0.1, 0.1, 0.1]"))?;
    let cells =
        g.cells.ok_or_else(|| ctx.missing("grid.cells", "a regular grid", "[40, 20, 40]"))?;
    if !origin.iter().all(|x| x.is_finite()) {
        return Err(ctx.err(
            "grid.origin",
            Some(triple(origin)),
            "the origin is not finite",
            "finite coordinates (m)",
            "give the lowest node, e.g. `origin = [0.0, 0.0, 0.0]`",
        ));
    }
    let [dx, dy, dz] = cell;
    if !(finite_pos(dx) && dx == dy && dx == dz) {
        return Err(ctx.err(
            "grid.cell",
            Some(triple(cell)),
            "3D cells are cubes of positive finite side",
            "[h, h, h] with h > 0 (m)",
            "give the same size along each axis, e.g. `cell = [0.1, 0.1, 0.1]`",
        ));
    }
    for (a, &n) in cells.iter().enumerate() {
        if !(1..=MAX_CELLS_PER_AXIS as i64).contains(&n) {
            return Err(ctx.err(
                "grid.cells",
                Some(format!("{cells:?}")),
                format!("{} cells along {}", n, ["x", "y", "z"][a]),
                format!("1 ≤ cells ≤ {MAX_CELLS_PER_AXIS} along each axis"),
                "give the number of cells along x, y and z, e.g. `cells = [40, 20, 40]`",
            ));
        }
    }
    let far = (0..3)
        .map(|a| origin[a].abs().max((origin[a] + cells[a] as f64 * dx).abs()))
        .fold(0.0, f64::max);
    precise(ctx, "grid.origin", far, dx)?;
    let cells = cells.map(|n| n as usize);
    RegularGrid::new(Vector::from_array(origin), Vector::from_array(cell), cells).map_err(|e| {
        ctx.err(
            "grid",
            None,
            e.to_string(),
            "a grid whose far corner is finite",
            "check origin, cell and cells",
        )
    })
}

/// The finest detail doubles can hold at coordinates of size `far` must be far below a cell of
/// `cell` (a millionth of it; positions are rounded to that spacing every step): R3-13, a grid at
/// x = 1e15 m with 5 cm cells (doubles there are 0.125 m apart) filled a cylinder with 768
/// particles instead of 1 344 and ran on. Map coordinates in metres (UTM: 5e6 m, 1e-9 m apart)
/// pass with room to spare. A coordinate that is not a number at all is refused too.
pub(super) fn precise(ctx: &Ctx<'_>, path: &str, far: f64, cell: f64) -> Result<(), SceneError> {
    let spacing = far * f64::EPSILON;
    if far.is_finite() && spacing <= 1e-6 * cell {
        return Ok(());
    }
    Err(ctx.err(
        path,
        None,
        if far.is_finite() {
            format!(
                "coordinates reach {} m, where doubles are {} m apart: {} of a {} m cell",
                num(far),
                num(spacing),
                num(spacing / cell),
                num(cell)
            )
        } else {
            "the grid reaches beyond the largest number (its far corner or top is infinite)".into()
        },
        "coordinates whose precision is below a millionth of a cell",
        "move the model near the origin (subtract a reference point from the map coordinates), \
         or check the sizes' units",
    ))
}

/// The terrain-following grid over the DEM `dem`: plan lattice from `from` (south-west) to
/// `to` (north-east) in map coordinates at `plan_cell`, the ground at each lattice node the
/// DEM's bilinear height there, cut down by `rupture` or the release area; model x = map x,
/// z = −map y. With a cut, the DEM's own surface on the same lattice comes too (what a release
/// body fills up to).
pub(super) fn terrain_grid(
    ctx: &Ctx<'_>,
    f: &SpaceFile,
) -> Result<(TerrainGrid, Option<TerrainGrid>, mpm_dem::Crs), SceneError> {
    let g = &f.grid;
    let why = "a terrain grid";
    let dem = g.dem.as_deref().ok_or_else(|| ctx.missing("grid.dem", why, "\"valley.asc\""))?;
    let from = g.from.ok_or_else(|| ctx.missing("grid.from", why, "[x_west, y_south]"))?;
    let to = g.to.ok_or_else(|| ctx.missing("grid.to", why, "[x_east, y_north]"))?;
    let h = g.plan_cell.ok_or_else(|| ctx.missing("grid.plan_cell", why, "5.0"))?;
    let r = g.layer_height.ok_or_else(|| ctx.missing("grid.layer_height", why, "2.0"))?;
    let layers = g.layers.ok_or_else(|| ctx.missing("grid.layers", why, "20"))?;
    for (path, v) in [("grid.plan_cell", h), ("grid.layer_height", r)] {
        if !finite_pos(v) {
            return Err(ctx.range(path, v, "0 < size < ∞ (m)", "give the size in metres"));
        }
    }
    if !(1..=MAX_CELLS_PER_AXIS as i64).contains(&layers) {
        return Err(ctx.range(
            "grid.layers",
            layers as f64,
            &format!("1 ≤ layers ≤ {MAX_CELLS_PER_AXIS}"),
            "give the number of cell layers above the ground, e.g. 20",
        ));
    }
    // the grid's top, layers × layer_height above the ground, must be a number (R3-13: 8
    // layers of 1e308 m put it at infinity)
    let depth = layers as f64 * r;
    precise(ctx, "grid.layer_height", depth, r)?;
    let far = from.iter().chain(&to).map(|x| x.abs()).fold(0.0, f64::max);
    precise(ctx, "grid.from", far, h)?;
    let mut cells = [0usize; 2];
    for a in 0..2 {
        let span = to[a] - from[a];
        let n = span / h;
        let whole = n.round();
        let path = ["grid.to", "grid.to"][a];
        if !(from[a].is_finite() && to[a].is_finite() && span > 0.0) {
            return Err(ctx.err(
                path,
                Some(format!("[{}, {}]", num(to[0]), num(to[1]))),
                "`to` is not north-east of `from`",
                "from = [x_west, y_south], to = [x_east, y_north], finite (m)",
                "give the plan's south-west corner in `from` and its north-east corner in `to`",
            ));
        }
        if !((1.0..=MAX_CELLS_PER_AXIS as f64).contains(&whole)
            && (n - whole).abs() <= 1e-9 * whole)
        {
            return Err(ctx.err(
                path,
                Some(format!("[{}, {}]", num(to[0]), num(to[1]))),
                format!(
                    "the plan spans {} m along map {}: {} plan cells of {} m, not a whole number",
                    num(span),
                    ["x", "y"][a],
                    num(n),
                    num(h)
                ),
                format!("to − from a whole number (1 to {MAX_CELLS_PER_AXIS}) of plan_cell"),
                format!("use to[{a}] = {} or change plan_cell", num(from[a] + whole.max(1.0) * h)),
            ));
        }
        cells[a] = whole as usize;
    }
    let heights_bytes = (cells[0] + 1) as f64 * (cells[1] + 1) as f64 * 8.0;
    let budget = crate::limits::available_memory().map_or(f64::INFINITY, |(b, _)| b as f64 / 4.0);
    if heights_bytes > budget {
        return Err(ctx.err(
            "grid.plan_cell",
            Some(num(h)),
            format!("the plan has {} × {} cells: too many for the memory", cells[0], cells[1]),
            "a plan whose lattice fits in a quarter of the memory",
            "use a larger plan_cell or a smaller plan",
        ));
    }
    release_bound(ctx, f, (h, r), (from, to))?;
    let raster = mpm_dem::Raster::read_within(
        &crate::validate::polyline::file_path(ctx, dem),
        crate::limits::available_memory(),
    )
    .map_err(|e| crate::validate::polyline::dem_error(ctx, "grid.dem", e))?;
    let [nx, nz] = cells;
    let mut heights = Vec::with_capacity((nx + 1) * (nz + 1));
    // lattice node (i, k) at x = x_west + i h, z = −y_north + k h: map y = y_north − k h
    for k in 0..=nz {
        for i in 0..=nx {
            let (x, y) = (from[0] + i as f64 * h, to[1] - k as f64 * h);
            let z = raster
                .height(x, y)
                .map_err(|e| crate::validate::polyline::dem_error(ctx, "grid.dem", e))?;
            heights.push(z);
        }
    }
    let surface = heights.clone();
    let node_map = |i: usize, k: usize| (from[0] + i as f64 * h, to[1] - k as f64 * h);
    if let Some(rupture) = &g.rupture {
        let raster = mpm_dem::Raster::read_within(
            &crate::validate::polyline::file_path(ctx, rupture),
            crate::limits::available_memory(),
        )
        .map_err(|e| crate::validate::polyline::dem_error(ctx, "grid.rupture", e))?;
        // where the rupture raster has a height (inside it, not a hole) the ground is the lower
        for k in 0..=nz {
            for i in 0..=nx {
                let (x, y) = node_map(i, k);
                if let Ok(z) = raster.height(x, y) {
                    let at = &mut heights[k * (nx + 1) + i];
                    *at = at.min(z);
                }
            }
        }
    }
    match (&g.release_polygon, g.release_depth) {
        (None, None) => {}
        (Some(_), None) => {
            return Err(ctx.missing("grid.release_depth", "a release polygon", "2.0"));
        }
        (None, Some(_)) => {
            return Err(ctx.missing("grid.release_polygon", "a release depth", "[[x, y], ...]"));
        }
        (Some(polygon), Some(depth)) => {
            if !finite_pos(depth) {
                return Err(ctx.range(
                    "grid.release_depth",
                    depth,
                    "> 0 (m)",
                    "give the release's depth below the DEM in metres",
                ));
            }
            let vertices = simple_polygon(
                ctx,
                "grid.release_polygon",
                polygon,
                "a release polygon",
                "give the release area's corners [x, y] in map coordinates (m), in order around \
                 its outline",
            )?;
            let mut inside = 0usize;
            // row by row: the crossings of a row once, then each node in O(log n) (a polygon of
            // many vertices over a fine plan cost vertices × nodes point tests)
            let mut crossings = Vec::new();
            for k in 0..=nz {
                generate::row_crossings(&vertices, node_map(0, k).1, &mut crossings);
                for i in 0..=nx {
                    let (x, _) = node_map(i, k);
                    if generate::inside_row(&crossings, x) {
                        // `depth` below the DEM, wherever a rupture raster cut too
                        let at = k * (nx + 1) + i;
                        heights[at] = heights[at].min(surface[at] - depth);
                        inside += 1;
                    }
                }
            }
            if inside == 0 {
                return Err(ctx.err(
                    "grid.release_polygon",
                    None,
                    "no lattice node of the plan lies inside the release polygon",
                    "a polygon over the plan, larger than a plan cell",
                    "check its map coordinates against `from` and `to`",
                ));
            }
        }
    }
    let cut = heights != surface;
    let build = |heights: Vec<f64>| {
        TerrainGrid::new(TerrainGridSpec {
            origin: [from[0], -to[1]],
            spacing: [h, h],
            cells,
            heights,
            layer_height: r,
            layers: layers as usize,
        })
        .map_err(|e| {
            ctx.err(
                "grid",
                None,
                e.to_string(),
                "a terrain grid whose cells are not degenerate",
                "check the DEM, plan_cell and layer_height",
            )
        })
    };
    let surface = if cut { Some(build(surface)?) } else { None };
    Ok((build(heights)?, surface, raster.crs().clone()))
}

/// R3-17: the particles a release polygon must take at least, known before any height is
/// computed: a quarter of its area over the plan (the polygon clipped to `from`–`to`) over the
/// plan spacing squared, times its depth over the vertical spacing (at least one). A plan_cell in the wrong unit (0.002 for 2 m) was refused only after
/// every lattice height, the cut and the fill had been computed (16 s and 2.3 GB); now at once.
pub(super) fn release_bound(
    ctx: &Ctx<'_>,
    f: &SpaceFile,
    (h, r): (f64, f64),
    (from, to): ([f64; 2], [f64; 2]),
) -> Result<(), SceneError> {
    let g = &f.grid;
    let (Some(polygon), Some(depth)) = (&g.release_polygon, g.release_depth) else {
        return Ok(());
    };
    let Some(release) = f.bodies.iter().find(|b| b.shape == SpaceShapeKind::Release) else {
        return Ok(());
    };
    // a polygon the later checks refuse is left to them (they name what is wrong with it)
    if !(3..=MAX_VERTICES).contains(&polygon.len())
        || !polygon.iter().flatten().all(|v| v.is_finite())
        || !finite_pos(depth)
    {
        return Ok(());
    }
    // only the part over the plan is cut: the polygon clipped to it, then its area (a bow-tie's
    // is smaller: still a lower bound, and it is refused later)
    let mut clipped: Vec<[f64; 2]> = polygon.clone();
    for (axis, bound, keep_above) in
        [(0, from[0], true), (0, to[0], false), (1, from[1], true), (1, to[1], false)]
    {
        let inside = |p: &[f64; 2]| if keep_above { p[axis] >= bound } else { p[axis] <= bound };
        let mut out = Vec::with_capacity(clipped.len() + 4);
        for i in 0..clipped.len() {
            let (a, b) = (clipped[i], clipped[(i + 1) % clipped.len()]);
            if inside(&a) {
                out.push(a);
            }
            if inside(&a) != inside(&b) {
                let t = (bound - a[axis]) / (b[axis] - a[axis]);
                out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
            }
        }
        clipped = out;
        if clipped.len() < 3 {
            return Ok(());
        }
    }
    let n = clipped.len();
    let area = 0.5
        * (0..n)
            .map(|i| {
                let (a, b) = (clipped[i], clipped[(i + 1) % n]);
                a[0] * b[1] - b[0] * a[1]
            })
            .sum::<f64>()
            .abs();
    let ppc = release.particles_per_cell.unwrap_or(2).clamp(1, MAX_PARTICLES_PER_CELL);
    let s = h / ppc as f64;
    // a quarter of the area's columns: a lower bound with room for the lattice's edges
    let least = 0.25 * area / (s * s) * (depth / s.min(r)).max(1.0);
    if least > MAX_PARTICLES as f64 {
        return Err(ctx.err(
            "grid.plan_cell",
            Some(num(h)),
            format!(
                "the release polygon ({area:.3} m² over the plan, {} m deep) would take at least \
                 {least:.2e} particles at this plan cell, more than the {MAX_PARTICLES} a scene \
                 may have",
                num(depth)
            ),
            "a plan cell (m) that gives the release at most that many particles",
            "check plan_cell's unit (metres), or coarsen it",
        ));
    }
    Ok(())
}

/// The release body's particles: in columns on a plan lattice of spacing `s`, from the grid's
/// ground up to the DEM's `surface`, as many as the depth holds at `sv` (at least one), evenly:
/// a column's volume s² (surface − ground) exactly, sampled at its plan centre. Columns less
/// than 0.001 s deep are left out.
pub(super) fn release_fill(
    t: &TerrainGrid,
    surface: &TerrainGrid,
    s: f64,
    sv: f64,
) -> Vec<(Vector, f64)> {
    let [x0, z0] = t.plan_origin();
    let [nx, nz] = t.plan_cells();
    let h = t.spacing()[0];
    let (cols, rows) = ((nx as f64 * h / s).round() as usize, (nz as f64 * h / s).round() as usize);
    let mut out = Vec::new();
    for c in 0..rows {
        for a in 0..cols {
            let (x, z) = (x0 + (a as f64 + 0.5) * s, z0 + (c as f64 + 0.5) * s);
            let (g, top) = (t.ground_height(x, z), surface.ground_height(x, z));
            let depth = top - g;
            if depth < 1e-3 * s {
                continue;
            }
            let n = (depth / sv).round().max(1.0);
            let dy = depth / n;
            for k in 0..n as usize {
                out.push((Vector::new(x, g + (k as f64 + 0.5) * dy, z), s * s * dy));
            }
        }
    }
    out
}
