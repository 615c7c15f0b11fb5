//! Rasters of known analytic surfaces through both formats, and malformed rasters refused with
//! their file and line or cell.

use std::path::PathBuf;

use mpm_dem::{DemError, Raster};

/// a path in the temporary directory, unique to this test process.
fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("mpm-dem-{}-{name}", std::process::id()))
}

/// `f` sampled at the centres of `cols × rows` cells of `cell` m, north-west corner (`west`,
/// `north`).
fn sampled(
    f: impl Fn(f64, f64) -> f64,
    [cols, rows]: [usize; 2],
    cell: f64,
    [west, north]: [f64; 2],
) -> Raster {
    let mut z = Vec::with_capacity(cols * rows);
    for r in 0..rows {
        for c in 0..cols {
            z.push(f(west + (c as f64 + 0.5) * cell, north - (r as f64 + 0.5) * cell));
        }
    }
    Raster::new("analytic", [cols, rows], cell, [west, north], z, None).unwrap()
}

/// Heights of order 1 000 m written in full precision and interpolated with weights of order
/// 1: the round trip and the interpolation lose a few ulps (1e-13 m), far inside the issue's
/// 1e-9.
const HEIGHT_ABS: f64 = 1e-9;

fn both_formats(raster: &Raster, name: &str) -> [Raster; 2] {
    let (asc, tif) = (temp(&format!("{name}.asc")), temp(&format!("{name}.tif")));
    mpm_dem::ascii::write(raster, &asc).unwrap();
    mpm_dem::geotiff::write(raster, &tif).unwrap();
    let out = [Raster::read(&asc).unwrap(), Raster::read(&tif).unwrap()];
    let _ = (std::fs::remove_file(asc), std::fs::remove_file(tif));
    out
}

#[test]
fn a_plane_reads_back_exactly_along_any_line_in_both_formats() {
    let plane = |x: f64, y: f64| 812.0 - 0.35 * (x - 500_000.0) + 0.12 * (y - 4_100_000.0);
    let dem = sampled(plane, [40, 30], 5.0, [500_000.0, 4_100_150.0]);
    for r in both_formats(&dem, "plane") {
        let s = r.section([500_012.0, 4_100_140.0], [500_190.0, 4_100_011.0], 5.0).unwrap();
        assert_eq!(s.len(), 45); // 219.8 m at 5 m: 44 intervals and the end
        for p in &s {
            assert!((p.z - plane(p.x, p.y)).abs() <= HEIGHT_ABS, "{}: {p:?}", r.file());
        }
    }
}

#[test]
fn a_paraboloid_is_exact_at_the_cell_centres_and_both_formats_give_the_same_section() {
    let bowl = |x: f64, y: f64| 100.0 + 0.01 * ((x - 50.0).powi(2) + (y - 40.0).powi(2));
    let dem = sampled(bowl, [20, 16], 5.0, [0.0, 80.0]);
    let [asc, tif] = both_formats(&dem, "bowl");
    // along the row of centres y = 42.5, from the first centre, one station per cell
    let a = asc.section([2.5, 42.5], [97.5, 42.5], 5.0).unwrap();
    let t = tif.section([2.5, 42.5], [97.5, 42.5], 5.0).unwrap();
    assert_eq!(a.len(), 20);
    assert_eq!(a, t, "the two formats hold the same bits");
    for p in &a {
        assert!((p.z - bowl(p.x, p.y)).abs() <= HEIGHT_ABS, "{p:?}");
    }
    // between centres bilinear interpolation is the chord: above the convex surface
    let mid = asc.height(5.0, 42.5).unwrap();
    assert!(
        mid > bowl(5.0, 42.5) && (mid - 0.5 * (bowl(2.5, 42.5) + bowl(7.5, 42.5))).abs() < 1e-9
    );
}

#[test]
fn a_section_through_a_hole_names_the_cell_in_both_formats() {
    let mut z = vec![10.0; 6 * 4];
    z[2 * 6 + 3] = -9999.0; // row 2, column 3
    let dem = Raster::new("holes", [6, 4], 1.0, [0.0, 4.0], z, Some(-9999.0)).unwrap();
    for r in both_formats(&dem, "holes") {
        let e = r.section([0.5, 1.5], [5.5, 1.5], 1.0).unwrap_err();
        assert!(matches!(e, DemError::Nodata { row: 2, col: 3, .. }), "{e}");
        assert!(e.to_string().contains(r.file()), "{e}");
        assert!(r.section([0.5, 3.5], [5.5, 3.5], 1.0).is_ok());
        let e = r.section([0.5, 3.5], [8.5, 3.5], 1.0).unwrap_err();
        assert!(matches!(e, DemError::Outside { .. }), "{e}");
    }
}

/// the little-endian TIFF at `path` with the value of IFD entry `tag` (a LONG or SHORT held in
/// the entry) replaced by `value`.
fn patch_tag(path: &PathBuf, tag: u16, value: u32) {
    let mut b = std::fs::read(path).unwrap();
    assert_eq!(&b[..4], b"II*\0", "the encoder writes little-endian classic TIFF");
    let ifd = u32::from_le_bytes(b[4..8].try_into().unwrap()) as usize;
    let n = u16::from_le_bytes(b[ifd..ifd + 2].try_into().unwrap()) as usize;
    for k in 0..n {
        let e = ifd + 2 + 12 * k;
        if u16::from_le_bytes(b[e..e + 2].try_into().unwrap()) == tag {
            match u16::from_le_bytes(b[e + 2..e + 4].try_into().unwrap()) {
                3 => b[e + 8..e + 10].copy_from_slice(&(value as u16).to_le_bytes()),
                _ => b[e + 8..e + 12].copy_from_slice(&value.to_le_bytes()),
            }
            std::fs::write(path, b).unwrap();
            return;
        }
    }
    panic!("tag {tag} not in the IFD");
}

#[test]
fn malformed_geotiffs_are_refused_with_their_file_never_a_panic() {
    let dem = sampled(|x, y| x + y, [8, 8], 2.0, [0.0, 16.0]);
    let path = temp("bad.tif");
    let file = path.display().to_string();

    // a huge declared size in a small file: refused before the heights are allocated
    mpm_dem::geotiff::write(&dem, &path).unwrap();
    patch_tag(&path, 256, 60_000); // ImageWidth
    patch_tag(&path, 257, 60_000); // ImageLength
    // (the tiff crate finds the strips inconsistent with the size before our file-size check
    // does; either refusal comes before any allocation of 60 000² heights)
    let e = Raster::read(&path).unwrap_err();
    assert!(
        matches!(e, DemError::Size { cols: 60_000, rows: 60_000, .. } | DemError::GeoTiff { .. }),
        "{e}"
    );
    assert!(e.to_string().starts_with(&file), "{e}");

    // truncated: half the file
    mpm_dem::geotiff::write(&dem, &path).unwrap();
    let b = std::fs::read(&path).unwrap();
    std::fs::write(&path, &b[..b.len() / 2]).unwrap();
    let e = Raster::read(&path).unwrap_err();
    assert!(e.to_string().starts_with(&file), "{e}");

    // not a TIFF at all
    std::fs::write(&path, b"ncols 3\n").unwrap();
    let e = Raster::read(&path).unwrap_err();
    assert!(matches!(e, DemError::GeoTiff { .. }) && e.to_string().contains("not a readable TIFF"));

    // a plain TIFF without georeferencing
    {
        let out = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
        let mut enc = tiff::encoder::TiffEncoder::new(out).unwrap();
        enc.write_image::<tiff::encoder::colortype::Gray32Float>(2, 2, &[1.0, 2.0, 3.0, 4.0])
            .unwrap();
    }
    let e = Raster::read(&path).unwrap_err();
    assert!(e.to_string().contains("not a GeoTIFF"), "{e}");

    // cells that are not square (a raster in degrees)
    mpm_dem::geotiff::write(&dem, &path).unwrap();
    {
        let mut b = std::fs::read(&path).unwrap();
        // ModelPixelScaleTag holds [2.0, 2.0, 0.0] as doubles: make sy = 3
        let two = 2.0f64.to_le_bytes();
        let at = b.windows(16).position(|w| w[..8] == two && w[8..] == two).unwrap();
        b[at + 8..at + 16].copy_from_slice(&3.0f64.to_le_bytes());
        std::fs::write(&path, b).unwrap();
    }
    let e = Raster::read(&path).unwrap_err();
    assert!(matches!(e, DemError::NonSquareCells { .. }), "{e}");
    let _ = std::fs::remove_file(&path);

    // an unknown extension
    let e = Raster::read(std::path::Path::new("slope.xyz")).unwrap_err();
    assert!(matches!(e, DemError::UnknownFormat { .. }), "{e}");
}

#[test]
fn a_truncated_ascii_grid_names_its_last_line() {
    let dem = sampled(|x, y| x - y, [5, 4], 1.0, [0.0, 4.0]);
    let path = temp("cut.asc");
    mpm_dem::ascii::write(&dem, &path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let cut: Vec<&str> = text.lines().take(7).collect(); // 5 header lines + 2 of 4 rows
    std::fs::write(&path, cut.join("\n")).unwrap();
    let e = Raster::read(&path).unwrap_err().to_string();
    let _ = std::fs::remove_file(&path);
    assert!(e.contains("line 7") && e.contains("after 10 of the 20 heights"), "{e}");
}

/// A DEM in degrees is refused, never taken for metres: a GeoTIFF whose GeoKeys declare a
/// geographic model, an ESRI ASCII grid whose `.prj` is a GEOGCS, and one with arc-second cells
/// inside longitude and latitude; the same grid in metres (a `.prj` with a PROJCS) is read.
#[test]
fn a_dem_in_degrees_is_refused_with_how_to_reproject() {
    let dem = sampled(|x, y| x + y, [8, 8], 2.0, [0.0, 16.0]);
    let path = temp("geographic.tif");
    mpm_dem::geotiff::write(&dem, &path).unwrap();
    let mut b = std::fs::read(&path).unwrap();
    // the one key the writer puts, GTRasterTypeGeoKey (1025) = 1, becomes GTModelTypeGeoKey
    // (1024) = 2, geographic
    let key: Vec<u8> = [1025u16, 0, 1, 1].iter().flat_map(|k| k.to_le_bytes()).collect();
    let at = b.windows(8).position(|w| w == key.as_slice()).unwrap();
    let geo: Vec<u8> = [1024u16, 0, 1, 2].iter().flat_map(|k| k.to_le_bytes()).collect();
    b[at..at + 8].copy_from_slice(&geo);
    std::fs::write(&path, b).unwrap();
    let e = Raster::read(&path).unwrap_err();
    assert!(matches!(e, DemError::Geographic { .. }) && e.to_string().contains("gdalwarp"), "{e}");

    let asc = temp("geographic.asc");
    mpm_dem::ascii::write(&dem, &asc).unwrap();
    let prj = asc.with_extension("prj");
    std::fs::write(&prj, "GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\"]]").unwrap();
    assert!(matches!(Raster::read(&asc).unwrap_err(), DemError::Geographic { .. }));
    std::fs::write(&prj, "PROJCS[\"WGS 84 / UTM zone 32N\",GEOGCS[\"WGS 84\"]]").unwrap();
    assert!(Raster::read(&asc).is_ok());
    std::fs::remove_file(&prj).unwrap();

    // 1 arc-second cells near (8.5° E, 46.5° N), no .prj
    let text = "ncols 3\nnrows 2\nxllcorner 8.5\nyllcorner 46.5\ncellsize 0.000277777778\n\
                1 2 3\n4 5 6\n";
    std::fs::write(&asc, text).unwrap();
    let e = Raster::read(&asc).unwrap_err();
    assert!(matches!(e, DemError::Geographic { .. }) && e.to_string().contains("0.000277"), "{e}");
    // a laboratory scan in metres, 0.5 mm cells near the origin, 2 cm of relief: read
    let lab = "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 0.0005\n\
               0.01 0.02 0.03\n0.00 0.01 0.02\n";
    std::fs::write(&asc, lab).unwrap();
    assert!(Raster::read(&asc).is_ok());
    let _ = std::fs::remove_file(&path);
    let _ = std::fs::remove_file(&asc);
}

/// A raster that does not fit in the memory the process may use is refused before its heights
/// are allocated, with the memory it needs and what is available (a 30 M-cell ESRI grid under
/// `ulimit -v` aborted the process: hostile report R4); within the budget it reads as without.
#[test]
fn a_raster_beyond_the_memory_budget_is_refused_before_allocating() {
    let dem = sampled(|x, y| x - y, [40, 30], 1.0, [0.0, 30.0]);
    for name in ["budget.asc", "budget.tif"] {
        let path = temp(name);
        if name.ends_with(".asc") {
            mpm_dem::ascii::write(&dem, &path).unwrap();
        } else {
            mpm_dem::geotiff::write(&dem, &path).unwrap();
        }
        // 1 200 heights need 9 600 bytes as f64, beside the text or the decoded image (the
        // ASCII text alone, ~7 kB, fits)
        let e = Raster::read_within(&path, Some((12_000, "a test's budget"))).unwrap_err();
        let text = e.to_string();
        assert!(matches!(e, DemError::Size { cols: 40, rows: 30, .. }), "{text}");
        assert!(text.contains("MB of memory") && text.contains("a test's budget"), "{text}");
        let within = Raster::read_within(&path, Some((10_000_000, "a test's budget"))).unwrap();
        assert_eq!(within, Raster::read(&path).unwrap());
    }
}
