//! The hazard maps of a 3D run (`[output] hazard_maps = true`): one raster per quantity of
//! [`mpm_scene::plan::PlanEnvelope`], each written as an ESRI ASCII grid (`maps/NAME.asc`) and a
//! GeoTIFF (`maps/NAME.tif`), in the plan frame that module states (map x = x, map y = −z), with
//! the DEM's coordinate reference system on a terrain grid (none on a regular grid); and the
//! outlines (`maps/outlines.geojson`) and the figure (`maps/hazard_map.png`) drawn from them.

use std::path::Path;

use mpm_dem::Raster;
use mpm_scene::plan::{PlanCell, PlanEnvelope};

use crate::OutputError;

/// What a cell holds where no material ever came, in the arrival map (the others hold 0).
pub const NODATA: f64 = -9999.0;

/// The maps, by file name (without extension), with what each holds.
pub const MAPS: [(&str, &str); 7] = [
    ("max_height", "largest flow height above the floor (m)"),
    ("max_mean_speed", "largest depth-averaged speed |Σmv|/Σm (m/s)"),
    ("max_speed", "largest particle speed (m/s)"),
    ("max_pressure", "largest impact pressure ρ̄ū² (Pa)"),
    ("max_momentum", "largest momentum h·ū (m²/s)"),
    ("arrival_time", "first arrival (s); −9999 where never reached"),
    ("deposit_depth", "final deposit depth (m)"),
];

/// writes every map of `plan` and the final `deposit` depths into `dir/maps/`, with the
/// coordinate reference system `crs` (the DEM's: its GeoKeys into the GeoTIFFs, its `.prj`
/// beside the ESRI ASCII grids).
pub fn write(
    dir: &Path,
    plan: &PlanEnvelope,
    deposit: &[f64],
    crs: &mpm_dem::Crs,
) -> Result<(), OutputError> {
    let maps = dir.join("maps");
    std::fs::create_dir_all(&maps)
        .map_err(|source| OutputError::Io { path: maps.clone(), source })?;
    let field = |f: fn(&PlanCell) -> f64| -> Vec<f64> { plan.cells.iter().map(f).collect() };
    for (name, _) in MAPS {
        let values = match name {
            "max_height" => field(|c| c.max_height),
            "max_mean_speed" => field(|c| c.max_mean_speed),
            "max_speed" => field(|c| c.max_speed),
            "max_pressure" => field(|c| c.max_pressure),
            "max_momentum" => field(|c| c.max_momentum),
            "arrival_time" => field(|c| c.arrival.unwrap_or(NODATA)),
            _ => deposit.to_vec(),
        };
        let nodata = (name == "arrival_time").then_some(NODATA);
        // rows from the north (−z): the plan's rows in z order
        let raster = Raster::new(
            name,
            [plan.cols, plan.rows],
            plan.cell,
            [plan.x0, -plan.z0],
            values,
            nodata,
        )
        .map_err(|e| fail(&maps.join(name), e))?;
        // the GeoTIFF carries the GeoKeys; the grid's `.prj` is written here, atomically, and
        // not by the grid's writer (which would put it beside the temporary name)
        let tif = raster.clone().with_crs(mpm_dem::Crs { wkt: None, ..crs.clone() });
        if let Some(wkt) = &crs.wkt {
            crate::atomic::write(&maps.join(format!("{name}.prj")), wkt.as_bytes())?;
        }
        for (ext, raster, write) in [
            (
                "asc",
                &raster,
                mpm_dem::ascii::write as fn(&Raster, &Path) -> Result<(), mpm_dem::DemError>,
            ),
            ("tif", &tif, mpm_dem::geotiff::write),
        ] {
            // under a temporary name, then renamed: a crash leaves no truncated map
            let path = maps.join(format!("{name}.{ext}"));
            let tmp = crate::atomic::temp_path(&path);
            write(raster, &tmp).map_err(|e| {
                let _ = std::fs::remove_file(&tmp);
                fail(&path, e)
            })?;
            crate::atomic::commit(&tmp, &path)?;
        }
    }
    Ok(())
}

/// What the figure and the outlines need beside the maps: the terrain's height at each plan
/// cell's centre, the cells the release started in, and a title.
pub struct Context<'a> {
    /// the figure's title.
    pub title: &'a str,
    /// the terrain height at each plan cell's centre (m), in the plan's order.
    pub ground: &'a [f64],
    /// the cells where the released material started.
    pub release: &'a [bool],
    /// the grid's undeclared sides the material reached (their `[boundaries]` keys).
    pub edges: &'a [String],
}

/// writes `maps/outlines.geojson` (the release, the affected area (a flow height > 0) and the
/// deposit (a depth > 0) as MultiPolygons in map coordinates, with their areas) and
/// `maps/hazard_map.png` (`mapfig`) for the plan and its final `deposit` depths.
pub fn figures(
    dir: &Path,
    plan: &PlanEnvelope,
    deposit: &[f64],
    context: &Context<'_>,
) -> Result<(), OutputError> {
    let maps = dir.join("maps");
    let height: Vec<f64> = plan.cells.iter().map(|c| c.max_height).collect();
    let affected: Vec<bool> = height.iter().map(|&h| h > 0.0).collect();
    let deposited: Vec<bool> = deposit.iter().map(|&d| d > 0.0).collect();
    let corner = [plan.x0, -plan.z0];
    let area = |m: &[bool]| m.iter().filter(|&&b| b).count() as f64 * plan.cell * plan.cell;
    let outline = |name, mask| crate::outline::Outline {
        name,
        mask,
        properties: vec![("area_m2", area(mask))],
    };
    let text = crate::outline::geojson(
        &[
            outline("release", context.release),
            outline("affected", &affected),
            outline("deposit", &deposited),
        ],
        plan.cols,
        plan.rows,
        plan.cell,
        corner,
    );
    crate::atomic::write(&maps.join("outlines.geojson"), text.as_bytes())?;
    crate::mapfig::write(
        &maps.join("hazard_map.png"),
        &crate::mapfig::MapFigure {
            title: context.title,
            cols: plan.cols,
            rows: plan.rows,
            cell: plan.cell,
            corner,
            ground: context.ground,
            height: &height,
            release: context.release,
            deposit: &deposited,
            edges: context.edges,
        },
    )
}

fn fail(path: &Path, e: mpm_dem::DemError) -> OutputError {
    OutputError::Io { path: path.to_path_buf(), source: std::io::Error::other(e.to_string()) }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The maps read back (ESRI ASCII and GeoTIFF, through `mpm-dem`'s readers) are the plan's
    /// values at the right map places: cell (col, row) of the plan is the raster cell whose
    /// centre is at map (x0 + (col + ½) w, −(z0 + (row + ½) w)).
    #[test]
    fn maps_read_back_hold_the_plan_at_its_map_places() {
        let mut plan = PlanEnvelope::new([10.0, 20.0], 0.5, [4, 3]);
        for (k, c) in plan.cells.iter_mut().enumerate() {
            c.max_height = k as f64;
            c.arrival = (k % 2 == 0).then_some(0.1 * k as f64);
            // a pressure map holds pascals: far beyond the ±1e5 m a height read from a file
            // may have (mpm_dem::MAX_HEIGHT), and written all the same
            c.max_pressure = 8.0e5;
        }
        let deposit: Vec<f64> = (0..12).map(|k| 0.01 * k as f64).collect();
        let dir = std::env::temp_dir().join(format!("mpm-maps-{}", std::process::id()));
        // the DEM's CRS: a projected one (GTModelTypeGeoKey 1024 = 1, ProjectedCSTypeGeoKey
        // 3072 = EPSG 32633, a citation in the ASCII parameters) and a `.prj`
        let keys = vec![1, 1, 0, 3, 1024, 0, 1, 1, 1025, 0, 1, 2, 3072, 0, 1, 32633];
        let crs = mpm_dem::Crs {
            geokeys: Some((keys, Vec::new(), "WGS 84 / UTM zone 33N|".into())),
            wkt: Some("PROJCS[\"WGS_1984_UTM_Zone_33N\"]".into()),
        };
        write(&dir, &plan, &deposit, &crs).unwrap();
        for ext in ["asc", "tif"] {
            let read = |name: &str| {
                let path = dir.join("maps").join(format!("{name}.{ext}"));
                Raster::read(&path).unwrap()
            };
            let (h, a, d) = (read("max_height"), read("arrival_time"), read("deposit_depth"));
            // west, south, east, north: x from 10 m, map y from −z: −20 m down to −21.5 m
            assert_eq!(h.extent(), [10.0, -21.5, 12.0, -20.0], "{ext}");
            for row in 0..3 {
                for col in 0..4 {
                    // raster rows from the north are the plan's rows in z order
                    let k = row * 4 + col;
                    assert_eq!(h.heights()[k], k as f64, "{ext} ({col}, {row})");
                    assert_eq!(d.heights()[k], 0.01 * k as f64);
                    assert_eq!(a.heights()[k], plan.cells[k].arrival.unwrap_or(NODATA));
                }
            }
            assert_eq!(a.nodata(), Some(NODATA), "{ext}");
            // the CRS copied: the GeoKeys with the raster type set to PixelIsArea (1025 = 1,
            // the corner convention the writer uses; the DEM said PixelIsPoint), the `.prj`
            let expected = match ext {
                "tif" => mpm_dem::Crs {
                    geokeys: Some((
                        vec![1, 1, 0, 3, 1024, 0, 1, 1, 1025, 0, 1, 1, 3072, 0, 1, 32633],
                        Vec::new(),
                        "WGS 84 / UTM zone 33N|".into(),
                    )),
                    wkt: None,
                },
                _ => mpm_dem::Crs { geokeys: None, wkt: crs.wkt.clone() },
            };
            assert_eq!(h.crs(), &expected, "{ext}");
        }
        let leftovers: Vec<_> = std::fs::read_dir(dir.join("maps"))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with('.'))
            .collect();
        assert!(leftovers.is_empty(), "{leftovers:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
