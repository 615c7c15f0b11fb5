//! ESRI ASCII grids (`.asc`, "Arc/Info ASCII Grid"): a header of `key value` lines, then the
//! heights row by row from the north, separated by any whitespace.
//!
//! ```text
//! ncols         4          columns
//! nrows         3          rows
//! xllcorner     500000.0   western edge (or xllcenter: the south-west cell's centre)
//! yllcorner     4100000.0  southern edge (or yllcenter)
//! cellsize      5.0        square cells (GDAL's dx/dy are read too, and must be equal)
//! NODATA_value  -9999      optional: holes
//! 812.5 811.9 …
//! ```
//!
//! Keys are case-insensitive and each may appear once. The declared size is checked against the
//! file's length (every height takes at least two bytes) before the heights are stored.

use std::path::Path;

use crate::error::DemError;
use crate::limits::Budget;
use crate::raster::{MAX_CELLS, Raster};

/// Reads the ESRI ASCII grid at `path`, within `budget` bytes of memory if given.
pub fn read(path: &Path, budget: Budget) -> Result<Raster, DemError> {
    use std::io::Read;
    let file = path.display().to_string();
    let size = crate::limits::regular_file(path)?;
    // the text is read whole: refused before reading when it alone does not fit
    if let Some((room, _)) = budget
        && size > room
    {
        return Err(crate::limits::too_big(&file, None, size, budget));
    }
    // at most the length the file had when it was looked at (a file still growing is cut)
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(size).read_to_end(&mut bytes))
        .map_err(|source| DemError::Io { file: file.clone(), source })?;
    let text = std::str::from_utf8(&bytes).map_err(|e| {
        let at = e.valid_up_to();
        DemError::Data {
            file: file.clone(),
            line: 1 + bytes[..at].iter().filter(|&&b| b == b'\n').count(),
            problem: "not text: an ESRI ASCII grid is plain text (is this a binary raster?)".into(),
        }
    })?;
    let raster = parse(text, &file, bytes.len() as u64, budget)?;
    let wkt = geographic(path, &raster)?;
    Ok(raster.with_crs(crate::Crs { geokeys: None, wkt }))
}

/// An ESRI ASCII grid carries no CRS: its map units are taken as metres. It is refused as
/// being in degrees when its `.prj` beside it says so (a `GEOGCS` without a `PROJCS`), or when
/// its cells are under a millimetre across an extent that fits in longitude and latitude (no
/// DEM in metres has such cells; 1 arc-second is 2.8e-4 degrees).
/// Returns the `.prj`'s text (its CRS, carried to what is written on the raster's frame).
fn geographic(path: &Path, r: &Raster) -> Result<Option<String>, DemError> {
    let file = path.display().to_string();
    let prj = path.with_extension("prj");
    let wkt = std::fs::metadata(&prj)
        .is_ok_and(|m| m.file_type().is_file() && m.len() < 1 << 20)
        .then(|| std::fs::read_to_string(&prj).ok())
        .flatten();
    if let Some(wkt) = &wkt {
        let wkt = wkt.to_ascii_uppercase();
        let geographic = wkt.contains("GEOGCS") || wkt.contains("GEOGCRS");
        if geographic && !wkt.contains("PROJCS") && !wkt.contains("PROJCRS") {
            return Err(DemError::Geographic {
                file,
                evidence: "its .prj declares a geographic coordinate system (GEOGCS)".into(),
            });
        }
    }
    let [west, south, east, north] = r.extent();
    let cell = r.cell();
    let lon_lat = west >= -180.0 && east <= 360.0 && south >= -90.0 && north <= 90.0;
    // and heights that rise far more than the grid is wide: metres over degrees (a laboratory
    // scan in metres with sub-millimetre cells has a relief below its width)
    let (low, high) = r
        .heights()
        .iter()
        .filter(|&&z| z.is_finite() && Some(z) != r.nodata())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &z| (a.min(z), b.max(z)));
    let relief = high - low;
    let width = (east - west).max(north - south);
    if cell < 1e-3 && lon_lat && relief > 100.0 * width {
        return Err(DemError::Geographic {
            file,
            evidence: format!(
                "its cells of {cell} across an extent within longitude and latitude \
                 ({west}…{east}, {south}…{north})"
            ),
        });
    }
    Ok(wkt)
}

/// The header's values, as they are read.
#[derive(Default)]
struct Header {
    cols: Option<u64>,
    rows: Option<u64>,
    /// (value, is it a cell centre rather than an edge)
    x: Option<(f64, bool)>,
    y: Option<(f64, bool)>,
    cell: Option<f64>,
    dx: Option<f64>,
    dy: Option<f64>,
    nodata: Option<f64>,
}

/// reads the header lines (up to the first height) of an ESRI ASCII grid: its keys and the
/// bytes they took.
fn read_header<'a, I: Iterator<Item = (usize, &'a str)>>(
    lines: &mut std::iter::Peekable<I>,
    file: &str,
) -> Result<(Header, u64), DemError> {
    let header_err =
        |line: usize, problem: String| DemError::Header { file: file.into(), line, problem };
    let mut h = Header::default();
    let mut header_bytes = 0u64;
    while let Some(&(n, line)) = lines.peek() {
        let mut tokens = line.split_whitespace();
        let Some(key) = tokens.next() else {
            header_bytes += line.len() as u64 + 1;
            lines.next();
            continue;
        };
        if key.starts_with(|c: char| c.is_ascii_digit() || matches!(c, '-' | '+' | '.'))
            || key.eq_ignore_ascii_case("nan")
        {
            break; // the first height
        }
        let value = tokens.next().ok_or_else(|| header_err(n, format!("`{key}` has no value")))?;
        if let Some(extra) = tokens.next() {
            return Err(header_err(n, format!("`{key} {value}` is followed by `{extra}`")));
        }
        let number = || -> Result<f64, DemError> {
            value
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| header_err(n, format!("`{key}` = `{value}` is not a number")))
        };
        let count = || -> Result<u64, DemError> {
            value.parse::<u64>().ok().filter(|&v| v > 0).ok_or_else(|| {
                header_err(n, format!("`{key}` = `{value}` is not a positive whole number"))
            })
        };
        let key_lc = key.to_ascii_lowercase();
        let twice = || header_err(n, format!("`{key}` is given twice"));
        macro_rules! set {
            ($slot:expr, $v:expr) => {{
                if $slot.is_some() {
                    return Err(twice());
                }
                $slot = Some($v);
            }};
        }
        match key_lc.as_str() {
            "ncols" => set!(h.cols, count()?),
            "nrows" => set!(h.rows, count()?),
            "xllcorner" => set!(h.x, (number()?, false)),
            "xllcenter" => set!(h.x, (number()?, true)),
            "yllcorner" => set!(h.y, (number()?, false)),
            "yllcenter" => set!(h.y, (number()?, true)),
            "cellsize" => set!(h.cell, number()?),
            "dx" => set!(h.dx, number()?),
            "dy" => set!(h.dy, number()?),
            "nodata_value" => set!(
                h.nodata,
                value.parse::<f64>().map_err(|_| {
                    header_err(n, format!("`{key}` = `{value}` is not a number"))
                })?
            ),
            _ => {
                return Err(header_err(
                    n,
                    format!(
                        "unknown header key `{key}` (an ESRI ASCII grid has ncols, nrows, \
                         xllcorner/xllcenter, yllcorner/yllcenter, cellsize and NODATA_value)"
                    ),
                ));
            }
        }
        header_bytes += line.len() as u64 + 1;
        lines.next();
    }
    Ok((h, header_bytes))
}

/// Parses an ASCII grid held in `text` (`bytes` long on disk), naming it `file` in errors.
pub(crate) fn parse(
    text: &str,
    file: &str,
    bytes: u64,
    budget: Budget,
) -> Result<Raster, DemError> {
    let header_err =
        |line: usize, problem: String| DemError::Header { file: file.into(), line, problem };
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l)).peekable();
    let (h, header_bytes) = read_header(&mut lines, file)?;
    let first_data = lines.peek().map_or(1, |&(n, _)| n);
    let missing = |key: &str| header_err(first_data, format!("the header has no `{key}`"));
    let cols = h.cols.ok_or_else(|| missing("ncols"))?;
    let rows = h.rows.ok_or_else(|| missing("nrows"))?;
    let (x, x_centre) = h.x.ok_or_else(|| missing("xllcorner"))?;
    let (y, y_centre) = h.y.ok_or_else(|| missing("yllcorner"))?;
    let cell = match (h.cell, h.dx, h.dy) {
        (Some(c), None, None) => c,
        (None, Some(dx), Some(dy)) => {
            if (dx - dy).abs() > 1e-9 * dx.abs().max(dy.abs()) {
                return Err(DemError::NonSquareCells { file: file.into(), dx, dy });
            }
            dx
        }
        _ => return Err(missing("cellsize")),
    };
    if cell <= 0.0 {
        return Err(header_err(first_data, format!("cellsize {cell} is not a positive length")));
    }
    let declared =
        cols.checked_mul(rows).filter(|&n| n <= MAX_CELLS).ok_or_else(|| DemError::Size {
            file: file.into(),
            cols,
            rows,
            problem: format!("more than the {MAX_CELLS} cells a raster may have"),
        })?;
    // every height is at least one character and a separator (the last may end the file)
    let room = bytes.saturating_sub(header_bytes) / 2 + 1;
    if declared > room {
        return Err(DemError::Size {
            file: file.into(),
            cols,
            rows,
            problem: format!(
                "but the file's {bytes} bytes hold at most {room} heights: the header or the \
                 file is wrong (truncated?)"
            ),
        });
    }
    // the heights beside the text already read
    let need = declared.saturating_mul(8).saturating_add(text.len() as u64);
    if budget.is_some_and(|(room, _)| need > room) {
        return Err(crate::limits::too_big(file, Some((cols, rows)), need, budget));
    }
    let n = declared as usize;
    let mut z = Vec::with_capacity(n);
    let mut last_line = first_data;
    for (line_no, line) in lines {
        last_line = line_no;
        for token in line.split_whitespace() {
            if z.len() == n {
                return Err(DemError::Data {
                    file: file.into(),
                    line: line_no,
                    problem: format!(
                        "more heights than ncols × nrows = {cols} × {rows} = {n} (`{token}` is \
                         one too many)"
                    ),
                });
            }
            let v: f64 = token.parse().map_err(|_| DemError::Data {
                file: file.into(),
                line: line_no,
                problem: format!(
                    "`{token}` is not a number (height {} of {n}: row {}, column {})",
                    z.len() + 1,
                    z.len() / cols as usize,
                    z.len() % cols as usize
                ),
            })?;
            let hole = h.nodata.is_some_and(|d| v == d || (v.is_nan() && d.is_nan()));
            if !v.is_finite() && !hole {
                return Err(DemError::Data {
                    file: file.into(),
                    line: line_no,
                    problem: format!(
                        "`{token}` is not a finite height (row {}, column {}); declare it as \
                         NODATA_value if it marks a hole",
                        z.len() / cols as usize,
                        z.len() % cols as usize
                    ),
                });
            }
            z.push(v);
        }
    }
    if z.len() < n {
        return Err(DemError::Data {
            file: file.into(),
            line: last_line,
            problem: format!(
                "the file ends after {} of the {n} heights that ncols × nrows declare \
                 (truncated?)",
                z.len()
            ),
        });
    }
    let (cols, rows) = (cols as usize, rows as usize);
    let west = if x_centre { x - 0.5 * cell } else { x };
    let south = if y_centre { y - 0.5 * cell } else { y };
    Raster::new(file, [cols, rows], cell, [west, south + rows as f64 * cell], z, h.nodata)?
        .plausible_heights()
}

/// Writes `raster` as an ESRI ASCII grid (corner convention; heights in full precision, so a
/// raster read back is the same raster).
pub fn write(raster: &Raster, path: &Path) -> Result<(), DemError> {
    use std::fmt::Write;
    let [cols, rows] = raster.size();
    let [west, south, _, _] = raster.extent();
    let mut s = format!(
        "ncols {cols}\nnrows {rows}\nxllcorner {west:?}\nyllcorner {south:?}\ncellsize {:?}\n",
        raster.cell()
    );
    if let Some(d) = raster.nodata() {
        let _ = writeln!(s, "NODATA_value {d:?}");
    }
    for row in raster.heights().chunks(cols) {
        let line: Vec<String> = row.iter().map(|v| format!("{v:?}")).collect();
        s.push_str(&line.join(" "));
        s.push('\n');
    }
    std::fs::write(path, s)
        .map_err(|source| DemError::Io { file: path.display().to_string(), source })?;
    // the CRS as a `.prj` beside it, when the raster carries one as WKT
    if let Some(wkt) = &raster.crs().wkt {
        let prj = path.with_extension("prj");
        std::fs::write(&prj, wkt)
            .map_err(|source| DemError::Io { file: prj.display().to_string(), source })?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = "ncols 3\nNROWS 2\nxllcenter 1\nyllcorner 0\ncellsize 2\n\
                        NODATA_value -9999\n1 2 3\n4 -9999 6\n";

    fn err(text: &str) -> String {
        parse(text, "t.asc", text.len() as u64, None).unwrap_err().to_string()
    }

    #[test]
    fn a_grid_reads_with_its_corner_cell_and_holes() {
        let r = parse(GOOD, "t.asc", GOOD.len() as u64, None).unwrap();
        assert_eq!(r.size(), [3, 2]);
        assert_eq!(r.extent(), [0.0, 0.0, 6.0, 4.0]);
        assert_eq!(r.at(0, 2), Some(3.0));
        assert_eq!(r.at(1, 1), None);
    }

    #[test]
    fn malformed_grids_name_the_file_and_line() {
        let e = err("ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n4 5\n");
        assert!(e.contains("t.asc, line 7") && e.contains("after 5 of the 6"), "{e}");
        let e = err("ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 x\n4 5 6\n");
        assert!(e.contains("line 6") && e.contains("`x` is not a number"), "{e}");
        let e = err("ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n4 5 6 7\n");
        assert!(e.contains("line 7") && e.contains("one too many"), "{e}");
        let e = err("ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n4 inf 6\n");
        assert!(e.contains("line 7") && e.contains("not a finite height"), "{e}");
        let e = err("ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\n1 2 3\n4 5 6\n");
        assert!(e.contains("line 5") && e.contains("no `cellsize`"), "{e}");
        let e = err("ncols 3\nncols 2\n");
        assert!(e.contains("line 2") && e.contains("given twice"), "{e}");
        let e = err("ncols 3\nrows 2\n");
        assert!(e.contains("line 2") && e.contains("unknown header key `rows`"), "{e}");
        let e = err("ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ndx 1\ndy 2\n1 2 3\n4 5 6\n");
        assert!(e.contains("not square"), "{e}");
    }

    /// R3-11: a hole's fill value that the header does not declare (the float32 maximum, −1e300)
    /// is refused at its cell with the fix; declared as NODATA_value it is a hole; a height of
    /// 8 849 m (or its 29 032 ft) is a height.
    #[test]
    fn an_undeclared_fill_value_is_refused_at_its_cell() {
        let head = "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n";
        for fill in ["3.4028234663852886e38", "-1e300"] {
            let e = err(&format!("{head}1 2 3\n4 5 {fill}\n"));
            assert!(
                e.contains("t.asc: cell (row 1, column 2)")
                    && e.contains("beyond ±100000 m")
                    && e.contains("NODATA_value"),
                "{e}"
            );
            let text = format!("{head}NODATA_value {fill}\n1 2 3\n4 5 {fill}\n");
            let r = parse(&text, "t.asc", text.len() as u64, None).unwrap();
            assert_eq!((r.at(1, 2), r.at(1, 1)), (None, Some(5.0)));
        }
        let text = format!("{head}8849 29032 3\n4 5 6\n");
        assert!(parse(&text, "t.asc", text.len() as u64, None).is_ok());
    }

    #[test]
    fn a_huge_declared_size_is_refused_before_anything_of_that_size_is_allocated() {
        let e = err("ncols 100000\nnrows 100000\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n");
        assert!(e.contains("100000 × 100000") && e.contains("a raster may have"), "{e}");
        let e = err("ncols 10000\nnrows 1000\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n");
        assert!(e.contains("hold at most"), "{e}");
        let e = err("ncols 18446744073709551615\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 1\n");
        assert!(e.contains("a raster may have"), "{e}");
    }
}
