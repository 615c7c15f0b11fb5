//! `[grid]`: the terrain-following grid (eqs 19–20) or a regular one, and the shape functions
//! it can take.

use mpm_grid::{Extent, GridError, KinkPolicy, RegularGrid, TerrainGrid, TerrainGridSpec};
use mpm_solver::Vector;

use super::{Ctx, num, pair};
use crate::error::SceneError;
use crate::file::{GridKind, GridSpec, KinkPolicySpec, ShapeFunctionKind, SolverSpec};
use crate::presets::PresetSettings;
use crate::scene::GridBuilt;

/// Builds the grid: (grid, ground polyline, column width).
pub(super) fn build(
    ctx: &Ctx<'_>,
    g: &GridSpec,
) -> Result<(GridBuilt, Vec<Vector>, f64), SceneError> {
    Ok(match g.kind {
        GridKind::Terrain => {
            for (name, present) in [
                ("origin", g.origin.is_some()),
                ("cell", g.cell.is_some()),
                ("cells", g.cells.is_some()),
            ] {
                if present {
                    return Err(ctx.foreign(
                        &format!("grid.{name}"),
                        "a terrain grid is given by cell_width, row_height, rows and profile",
                    ));
                }
            }
            let cell_width = g
                .cell_width
                .ok_or_else(|| ctx.missing("grid.cell_width", "terrain grid", "0.1"))?;
            let row_height = g
                .row_height
                .ok_or_else(|| ctx.missing("grid.row_height", "terrain grid", "0.1"))?;
            let rows = g.rows.ok_or_else(|| ctx.missing("grid.rows", "terrain grid", "15"))?;
            let spec = g.profile.as_ref().ok_or_else(|| {
                ctx.missing("grid.profile", "terrain grid", "[[0.0, 1.0], [5.0, 0.0]]")
            })?;
            if !(cell_width.is_finite() && cell_width > 0.0) {
                return Err(ctx.range(
                    "grid.cell_width",
                    cell_width,
                    "> 0 (m), finite",
                    "give the column width in metres",
                ));
            }
            let profile = super::polyline::points(ctx, "grid.profile", spec, cell_width)?;
            let too_many = || {
                ctx.err(
                    "grid.cell_width",
                    Some(super::num(cell_width)),
                    "more than 10⁷ columns over the profile",
                    "a column width that gives at most 10⁷ columns",
                    "give the column width in metres",
                )
            };
            // A profile from a file, or with a rupture surface cut in, is resampled on the
            // column boundaries (its kinks there); one written inline is taken as written.
            let profile = match (&g.rupture_surface, spec.points()) {
                (None, Some(_)) => profile,
                (None, None) => {
                    super::polyline::check_increasing(ctx, "grid.profile", &profile)?;
                    super::polyline::on_columns(&profile, cell_width).ok_or_else(too_many)?
                }
                (Some(r), _) => {
                    let path = "grid.rupture_surface";
                    let rupture = super::polyline::points(ctx, path, r, cell_width)?;
                    super::polyline::check_increasing(ctx, path, &rupture)?;
                    super::polyline::check_increasing(ctx, "grid.profile", &profile)?;
                    super::polyline::cut(&profile, &rupture, cell_width).ok_or_else(too_many)?
                }
            };
            // (the grid's own bound on cells along an axis: one rule for rows and cells)
            if !(1..=mpm_grid::MAX_CELLS_PER_AXIS as i64).contains(&rows) {
                return Err(ctx.err(
                    "grid.rows",
                    Some(rows.to_string()),
                    "number of rows out of range",
                    format!("1 ≤ rows ≤ {}", mpm_grid::MAX_CELLS_PER_AXIS),
                    "give enough rows to hold the material above the ground at its highest",
                ));
            }
            let spec = TerrainGridSpec {
                profile: profile.iter().map(|p| Vector::new(p[0], p[1])).collect(),
                cell_width,
                row_height,
                rows: rows as usize,
                kink_policy: match g.kink_policy {
                    Some(KinkPolicySpec::Reject) => KinkPolicy::Reject,
                    _ => KinkPolicy::Snap,
                },
            };
            let grid = TerrainGrid::new(spec).map_err(|e| grid_error(ctx, e, &profile))?;
            let ground = grid.profile().to_vec();
            (GridBuilt::Terrain(grid), ground, cell_width)
        }
        GridKind::Regular => {
            for (name, present) in [
                ("cell_width", g.cell_width.is_some()),
                ("row_height", g.row_height.is_some()),
                ("rows", g.rows.is_some()),
                ("profile", g.profile.is_some()),
                ("rupture_surface", g.rupture_surface.is_some()),
                ("kink_policy", g.kink_policy.is_some()),
            ] {
                if present {
                    return Err(ctx.foreign(
                        &format!("grid.{name}"),
                        "a regular grid is given by origin, cell and cells",
                    ));
                }
            }
            let origin = g.origin.unwrap_or([0.0, 0.0]);
            let cell =
                g.cell.ok_or_else(|| ctx.missing("grid.cell", "regular grid", "[0.1, 0.1]"))?;
            let cells =
                g.cells.ok_or_else(|| ctx.missing("grid.cells", "regular grid", "[50, 20]"))?;
            for (k, n) in cells.iter().enumerate() {
                if !(1..=100_000_000).contains(n) {
                    return Err(ctx.err(
                        &format!("grid.cells[{k}]"),
                        Some(n.to_string()),
                        "number of cells out of range",
                        "1 ≤ cells ≤ 1e8 along each axis",
                        "give a positive number of cells",
                    ));
                }
            }
            let grid = RegularGrid::new(
                Vector::new(origin[0], origin[1]),
                Vector::new(cell[0], cell[1]),
                [cells[0] as usize, cells[1] as usize],
            )
            .map_err(|e| grid_error(ctx, e, &[]))?;
            let lo = grid.origin();
            let hi = grid.upper_corner();
            (GridBuilt::Regular(grid), vec![lo, Vector::new(hi.x, lo.y)], cell[0])
        }
    })
}

/// The shape functions: the scene's, else the preset's, else bilinear; only bilinear on a
/// terrain grid.
pub(super) fn shape_function(
    ctx: &Ctx<'_>,
    s: &SolverSpec,
    preset: Option<PresetSettings>,
    grid: &GridBuilt,
) -> Result<ShapeFunctionKind, SceneError> {
    Ok(match (s.shape_function, grid) {
        (
            Some(k @ (ShapeFunctionKind::Gimp | ShapeFunctionKind::Bspline)),
            GridBuilt::Terrain(_),
        ) => {
            return Err(ctx.err(
                "solver.shape_function",
                Some(format!("\"{}\"", k.name())),
                "this shape function needs a regular grid",
                "\"bilinear\" on a terrain grid; \"bilinear\", \"gimp\" or \"bspline\" on a \
                 regular grid",
                "use `shape_function = \"bilinear\"` or a `kind = \"regular\"` grid",
            ));
        }
        (Some(k), _) => k,
        (None, GridBuilt::Terrain(_)) => ShapeFunctionKind::Bilinear,
        (None, GridBuilt::Regular(_)) => {
            preset.map_or(ShapeFunctionKind::Bilinear, |p| p.shape_function)
        }
    })
}

/// A grid construction error, located at the field it comes from.
pub(super) fn grid_error(ctx: &Ctx<'_>, e: GridError, profile: &[[f64; 2]]) -> SceneError {
    let point = |i: usize| profile.get(i).map(|p| pair(*p));
    match e {
        GridError::TooFewProfilePoints { count } => ctx.err(
            "grid.profile",
            Some(format!("{count} point(s)")),
            "the ground profile needs at least two points",
            "2 or more [x, y] points with x increasing",
            "give the ground as [[x0, y0], [x1, y1], ...]",
        ),
        GridError::NonFiniteProfilePoint { index, .. } => ctx.err(
            &format!("grid.profile[{index}]"),
            point(index),
            "profile point is not finite",
            "finite coordinates (m)",
            "give the point in metres",
        ),
        GridError::NonIncreasingProfile { index, x, previous_x } => ctx.err(
            &format!("grid.profile[{index}]"),
            point(index),
            format!("profile x decreases (or repeats): x = {} after {}", num(x), num(previous_x)),
            "x strictly increasing from one profile point to the next",
            "order the points from left to right; an overhang cannot be represented",
        ),
        GridError::KinkOffColumnBoundary { index, x, nearest_boundary_x } => ctx.err(
            &format!("grid.profile[{index}]"),
            point(index),
            format!("profile point x = {} is not on a column boundary", num(x)),
            "with kink_policy = \"reject\": x = x0 + k·cell_width",
            format!("move it to x = {} or use kink_policy = \"snap\"", num(nearest_boundary_x)),
        ),
        GridError::SnappedPointsCoincide { index, boundary_x, .. } => ctx.err(
            &format!("grid.profile[{index}]"),
            point(index),
            format!(
                "this point and the previous one snap to the same column boundary x = {}",
                num(boundary_x)
            ),
            "profile points at least one cell_width apart",
            "drop the point or use a smaller cell_width",
        ),
        GridError::NonPositiveSize { what, value } => {
            let path = match what {
                Extent::CellWidth => "grid.cell_width",
                Extent::RowHeight => "grid.row_height",
                Extent::CellSize(0) => "grid.cell[0]",
                Extent::CellSize(1) => "grid.cell[1]",
                _ => "grid",
            };
            ctx.range(path, value, "0 < size < ∞ (m)", "give the cell size in metres, e.g. 0.1")
        }
        GridError::NonFinitePoint { what, x, y } => ctx.err(
            "grid.origin",
            Some(pair([x, y])),
            format!("{what} is not finite"),
            "finite coordinates (m)",
            "give the origin and cell sizes in metres",
        ),
        GridError::CellCountOutOfRange { what, count, max } => {
            let path = match what {
                Extent::Rows => "grid.rows",
                Extent::Cells(0) => "grid.cells[0]",
                Extent::Cells(1) => "grid.cells[1]",
                _ => "grid.profile",
            };
            ctx.err(
                path,
                Some(num(count)),
                format!("{what} out of range"),
                format!("1 ≤ {what} ≤ {max}"),
                "use a larger cell size or a shorter grid",
            )
        }
        GridError::DegenerateSegment { index, slope, .. } => ctx.err(
            &format!("grid.profile[{}]", index + 1),
            point(index + 1),
            format!("the ground segment ending here is too steep (slope {})", num(slope)),
            "finite slopes (a vertical step cannot be represented)",
            "spread the step over one or more columns",
        ),
        GridError::DegenerateCell { .. } => ctx.err(
            "grid.row_height",
            None,
            e.to_string(),
            "positive cell heights",
            "check row_height and the profile",
        ),
        GridError::InvalidParticleHalfSize { .. } => ctx.err(
            "solver.shape_function",
            None,
            e.to_string(),
            "particles per cell ≥ 1",
            "check particles_per_cell",
        ),
        // (a terrain lattice of heights is the 3D grid's: `validate/space.rs`)
        GridError::HeightCount { .. } | GridError::NonFiniteHeight { .. } => ctx.err(
            "grid.dem",
            None,
            e.to_string(),
            "a finite height at every lattice node",
            "check the DEM",
        ),
    }
}
