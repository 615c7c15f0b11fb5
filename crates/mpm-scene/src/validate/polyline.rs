//! Polylines a scene gives inline or by file: the section of a DEM along a line (`mpm-dem`) or
//! a CSV of points. Paths are relative to the scene file's directory.

use std::path::PathBuf;

use mpm_dem::{DemError, Raster};

use super::{Ctx, pair};
use crate::error::SceneError;
use crate::file::{PolylineFile, PolylineSpec};

/// Most points a CSV polyline may have (the scene's own outlines are bounded likewise).
const MAX_CSV_POINTS: usize = 1_000_000;
/// Largest CSV polyline file read (bytes).
const MAX_CSV_BYTES: u64 = 64 << 20;

/// The points of the polyline at `path` (a field path such as `grid.profile`): inline as
/// written, or read from its file. `spacing` is the DEM station spacing when the scene gives
/// none (the grid's column width).
pub(super) fn points(
    ctx: &Ctx<'_>,
    path: &str,
    spec: &PolylineSpec,
    spacing: f64,
) -> Result<Vec<[f64; 2]>, SceneError> {
    match spec {
        PolylineSpec::Points(p) => Ok(p.clone()),
        PolylineSpec::File(f) => from_file(ctx, path, f, spacing),
    }
}

/// Refuses a polyline at `path` with fewer than two points, a non-finite point or x not
/// strictly increasing.
pub(super) fn check_increasing(
    ctx: &Ctx<'_>,
    path: &str,
    points: &[[f64; 2]],
) -> Result<(), SceneError> {
    if points.len() < 2 {
        return Err(ctx.err(
            path,
            Some(format!("{} point(s)", points.len())),
            "a profile needs at least two points",
            "2 or more [x, y] points with x increasing",
            "give the surface as [[x0, y0], [x1, y1], ...]",
        ));
    }
    for (i, w) in points.windows(2).enumerate() {
        let finite = w.iter().flatten().all(|v| v.is_finite());
        if !(finite && w[1][0] > w[0][0]) {
            return Err(ctx.err(
                &format!("{path}[{}]", i + 1),
                Some(pair(w[1])),
                format!("x must increase along the profile (after {})", pair(w[0])),
                "finite points with x strictly increasing",
                "list the surface's points from left to right",
            ));
        }
    }
    Ok(())
}

/// a scene's `[x, y]` points as vectors.
pub(super) fn vectors(points: &[[f64; 2]]) -> Vec<mpm_solver::Vector> {
    points.iter().map(|p| mpm_solver::Vector::new(p[0], p[1])).collect()
}

/// Most columns a resampled ground may have.
const MAX_COLUMNS: f64 = 10_000_000.0;

/// The polyline `profile` (x increasing) resampled at the column boundaries `x0 + k·cell` from
/// its start, and at its end when that lies more than half a column past the last boundary (a
/// terrain grid snaps an end nearer than that onto the boundary, where it would coincide with
/// it). Every kink then sits on a column boundary. `None` for more than 10⁷ columns.
pub(super) fn on_columns(profile: &[[f64; 2]], cell: f64) -> Option<Vec<[f64; 2]>> {
    use mpm_solver::generate::polyline_height;
    let line = vectors(profile);
    let (x0, x_end) = (profile.first()?[0], profile.last()?[0]);
    let n = ((x_end - x0) / cell + 1e-9).floor();
    if !(n.is_finite() && (0.0..=MAX_COLUMNS).contains(&n)) {
        return None;
    }
    let mut xs: Vec<f64> = (0..=n as usize).map(|k| (x0 + k as f64 * cell).min(x_end)).collect();
    if x_end - xs[xs.len() - 1] > 0.5 * cell {
        xs.push(x_end);
    }
    xs.into_iter().map(|x| Some([x, polyline_height(&line, x)?])).collect()
}

/// The ground `profile`, resampled on the columns ([`on_columns`]), with the `rupture`
/// surface cut into it: at each point the lower of the two where the rupture surface is
/// defined.
pub(super) fn cut(profile: &[[f64; 2]], rupture: &[[f64; 2]], cell: f64) -> Option<Vec<[f64; 2]>> {
    use mpm_solver::generate::polyline_height;
    let surface = vectors(rupture);
    let mut ground = on_columns(profile, cell)?;
    for p in &mut ground {
        if let Some(r) = polyline_height(&surface, p[0]) {
            p[1] = p[1].min(r);
        }
    }
    Some(ground)
}

/// `file` relative to the scene's directory.
pub(super) fn file_path(ctx: &Ctx<'_>, file: &str) -> PathBuf {
    let p = PathBuf::from(file);
    let found = match ctx.dir {
        Some(dir) if p.is_relative() => dir.join(p),
        _ => p,
    };
    ctx.inputs.borrow_mut().push((file.to_string(), found.clone()));
    found
}

fn from_file(
    ctx: &Ctx<'_>,
    path: &str,
    f: &PolylineFile,
    default_spacing: f64,
) -> Result<Vec<[f64; 2]>, SceneError> {
    let field = |name: &str| format!("{path}.{name}");
    match (&f.dem, &f.csv) {
        (Some(_), Some(_)) => Err(ctx.err(
            &field("csv"),
            None,
            "a polyline comes from one file: a DEM section or a CSV, not both",
            "`dem` with `from` and `to`, or `csv`",
            "remove `dem` or `csv`",
        )),
        (None, None) => Err(ctx.err(
            path,
            None,
            "a polyline table names its file",
            "`{ dem = \"slope.asc\", from = [x, y], to = [x, y] }` or `{ csv = \"points.csv\" }`",
            "add `dem = ...` or `csv = ...`, or give the points inline as [[x, y], ...]",
        )),
        (Some(dem), None) => {
            let from =
                f.from.ok_or_else(|| ctx.missing(&field("from"), "a DEM section", "[x, y]"))?;
            let to = f.to.ok_or_else(|| ctx.missing(&field("to"), "a DEM section", "[x, y]"))?;
            let spacing = f.spacing.unwrap_or(default_spacing);
            if !(spacing.is_finite() && spacing > 0.0) {
                return Err(ctx.range(
                    &field("spacing"),
                    spacing,
                    "> 0 (m)",
                    "give the station spacing in metres, or leave it out (the column width)",
                ));
            }
            let raster =
                Raster::read_within(&file_path(ctx, dem), crate::limits::available_memory())
                    .map_err(|e| dem_error(ctx, &field("dem"), e))?;
            let s =
                raster.section(from, to, spacing).map_err(|e| dem_error(ctx, &field("dem"), e))?;
            Ok(s.iter().map(|p| [p.station, p.z]).collect())
        }
        (None, Some(csv)) => {
            for (name, present) in [
                ("from", f.from.is_some()),
                ("to", f.to.is_some()),
                ("spacing", f.spacing.is_some()),
            ] {
                if present {
                    return Err(ctx.foreign(&field(name), "a CSV polyline holds its points"));
                }
            }
            read_csv(ctx, &field("csv"), &file_path(ctx, csv))
        }
    }
}

/// A raster error at `field`, with the fix its kind calls for.
pub(super) fn dem_error(ctx: &Ctx<'_>, field: &str, e: DemError) -> SceneError {
    let fix = match &e {
        DemError::Io { .. } => "check the path (relative to the scene file's directory)",
        DemError::UnknownFormat { .. } => "give an ESRI ASCII grid (.asc) or a GeoTIFF (.tif)",
        DemError::Nodata { .. } => "move the line off the hole, or fill the raster's holes",
        DemError::Outside { .. } => {
            "keep `from` and `to` inside the raster (`mpm section` shows it)"
        }
        DemError::NonSquareCells { .. } => "reproject the DEM to square metric cells (e.g. UTM)",
        DemError::Line { .. } => "give two different map points and a positive spacing",
        _ => "check the raster (GDAL's `gdalinfo` describes it)",
    };
    ctx.err(field, None, e.to_string(), "", fix)
}

/// Reads a CSV polyline: columns `station` and `z` if the header names them (what `mpm section`
/// writes), else the first two columns as x and y. An optional header line; `#` comments.
fn read_csv(
    ctx: &Ctx<'_>,
    field: &str,
    file: &std::path::Path,
) -> Result<Vec<[f64; 2]>, SceneError> {
    let columns = |cells: &[&str]| {
        let at = |n: &str| cells.iter().position(|c| c.eq_ignore_ascii_case(n));
        Ok(at("station").zip(at("z")).unwrap_or((0, 1)))
    };
    Ok(read_pairs(ctx, field, file, &columns)?.0)
}

/// picks two columns from a header's cells, or says how to fix the header.
pub(super) type PickColumns<'a> = dyn Fn(&[&str]) -> Result<(usize, usize), String> + 'a;

/// Two columns of a CSV file as pairs, at most [`MAX_CSV_POINTS`]; lines starting with `#` and
/// blank lines are skipped. A first non-comment line that is not two numbers is a header:
/// `columns` picks the two columns from its cells (or explains why it cannot); without a header
/// the first two columns are read. Returns the pairs and whether there was a header.
pub(super) fn read_pairs(
    ctx: &Ctx<'_>,
    field: &str,
    file: &std::path::Path,
    columns: &PickColumns<'_>,
) -> Result<(Vec<[f64; 2]>, bool), SceneError> {
    use std::io::Read;
    let name = file.display().to_string();
    let fail = |problem: String, fix: &str| ctx.err(field, None, problem, "", fix);
    if std::fs::metadata(file).is_ok_and(|m| !m.file_type().is_file()) {
        // a FIFO would block the open for ever
        return Err(fail(
            format!("{name}: not a regular file (a directory, a FIFO or a device)"),
            "give the path of the CSV file",
        ));
    }
    let mut text = String::new();
    std::fs::File::open(file)
        .and_then(|f| f.take(MAX_CSV_BYTES + 1).read_to_string(&mut text))
        .map_err(|e| {
            fail(
                format!("{name}: cannot read: {e}"),
                "check the path (relative to the scene file's directory)",
            )
        })?;
    if text.len() as u64 > MAX_CSV_BYTES {
        return Err(fail(
            format!("{name}: larger than {} MiB", MAX_CSV_BYTES >> 20),
            "give fewer points",
        ));
    }
    let mut picked = (0usize, 1usize);
    let mut header = false;
    let mut out = Vec::new();
    // One delimiter per file, from its first line: `;` or a tab where a spreadsheet or GIS
    // writes decimal commas (`150;157,86`), else `,`. Every line has the first line's count of
    // fields, so a decimal comma in a comma-separated file is an error at its line, never a
    // silently different number.
    let mut delimiter = None;
    let mut fields = 0;
    for (k, line) in text.lines().enumerate() {
        // (only spaces and a CR off the line: a tab may be the delimiter of an empty edge field)
        let line = line.trim_matches(|c| c == ' ' || c == '\r');
        if line.trim().is_empty() || line.trim_start().starts_with('#') {
            continue;
        }
        let d = *delimiter.get_or_insert_with(|| {
            if line.contains(';') {
                ';'
            } else if line.contains('\t') {
                '\t'
            } else {
                ','
            }
        });
        let cells: Vec<String> = line
            .split(d)
            .map(|c| {
                let c = c.trim();
                // a decimal comma (only where `,` is not the delimiter): 157,86 is 157.86
                if d != ',' && c.matches(',').count() == 1 && !c.contains('.') {
                    c.replace(',', ".")
                } else {
                    c.to_string()
                }
            })
            .collect();
        if fields == 0 {
            fields = cells.len();
        } else if cells.len() != fields {
            let name_d = match d {
                ';' => "`;`",
                '\t' => "tabs",
                _ => "`,`",
            };
            return Err(fail(
                format!(
                    "{name}, line {}: {} fields where the first line has {fields} (fields \
                     separated by {name_d}, read from the first line)",
                    k + 1,
                    cells.len()
                ),
                "give every line the same columns; with decimal commas (157,86) separate the \
                 fields by `;` or tabs",
            ));
        }
        let number = |i: usize| cells.get(i).is_some_and(|c| c.parse::<f64>().is_ok());
        if out.is_empty() && !header && !(number(0) && number(1)) {
            header = true;
            let names: Vec<&str> = cells.iter().map(String::as_str).collect();
            picked = columns(&names)
                .map_err(|fix| fail(format!("{name}, line {}: header `{line}`", k + 1), &fix))?;
            continue;
        }
        let get = |i: usize| -> Result<f64, SceneError> {
            cells.get(i).and_then(|c| c.parse::<f64>().ok()).filter(|v| v.is_finite()).ok_or_else(
                || {
                    fail(
                        format!("{name}, line {}: column {} is not a finite number", k + 1, i + 1),
                        "every data line holds numbers in the columns the header names (or the first two)",
                    )
                },
            )
        };
        if out.len() == MAX_CSV_POINTS {
            return Err(fail(
                format!("{name}: more than {MAX_CSV_POINTS} points"),
                "give fewer points",
            ));
        }
        out.push([get(picked.0)?, get(picked.1)?]);
    }
    if out.len() < 2 {
        return Err(fail(
            format!("{name}: {} point(s); at least two are needed", out.len()),
            "give the points as lines `x, y`",
        ));
    }
    Ok((out, header))
}
