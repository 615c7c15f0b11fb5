//! The raster: a north-up grid of square cells with one height at each cell's centre, its
//! bilinear interpolation, and sections along a line.

use crate::error::DemError;

/// The most cells a raster may declare (2²⁸ = 268 M cells, 2 GiB of heights): a guard against a
/// corrupt header, far above a slope's DEM (a 10 km × 10 km area at 1 m is 100 M cells).
pub const MAX_CELLS: u64 = 1 << 28;

/// The largest height a raster may hold, in size (m): 100 km, far beyond any terrain in metres
/// (or feet), and far below the fill values that mark holes in rasters that do not declare them
/// (the float32 maximum 3.4e38, ±1e300). Such a value read as a height would stretch the grid
/// and its time step beyond any use, far from the file that caused it.
pub const MAX_HEIGHT: f64 = 1.0e5;

/// The most stations a section may have: a guard against a spacing typed in the wrong unit.
pub const MAX_STATIONS: usize = 10_000_000;

/// A north-up elevation raster with square cells. Heights are at the cells' centres; row 0 is
/// the northern row (the first in an ASCII grid or a GeoTIFF), column 0 the western one.
#[derive(Clone, Debug, PartialEq)]
pub struct Raster {
    crs: Crs,
    file: String,
    cols: usize,
    rows: usize,
    cell: f64,
    west: f64,
    north: f64,
    z: Vec<f64>,
    nodata: Option<f64>,
}

/// One point of a section: its distance along the line from its start, its map position and
/// the interpolated ground height (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Station {
    /// distance from the line's start (m).
    pub station: f64,
    /// map x (east, m).
    pub x: f64,
    /// map y (north, m).
    pub y: f64,
    /// ground height (m).
    pub z: f64,
}

/// A raster's coordinate reference system, as its file stated it, kept to be written again with
/// what is drawn on its frame. Not interpreted (no projection library): carried.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Crs {
    /// a GeoTIFF's GeoKeys: the `GeoKeyDirectoryTag` shorts (its header and entries), the
    /// `GeoDoubleParamsTag` values and the `GeoAsciiParamsTag` text they point into.
    pub geokeys: Option<(Vec<u16>, Vec<f64>, String)>,
    /// the WKT of the `.prj` beside an ESRI ASCII grid.
    pub wkt: Option<String>,
}

impl Crs {
    /// true when the file stated none.
    pub fn is_empty(&self) -> bool {
        self.geokeys.is_none() && self.wkt.is_none()
    }
}

impl Raster {
    /// A raster of `cols × rows` square cells of size `cell`, with its north-west corner at
    /// (`west`, `north`) and heights `z` row by row from the north. `file` names it in errors.
    /// Values equal to `nodata`, and non-finite values, are holes.
    pub fn new(
        file: &str,
        [cols, rows]: [usize; 2],
        cell: f64,
        [west, north]: [f64; 2],
        z: Vec<f64>,
        nodata: Option<f64>,
    ) -> Result<Self, DemError> {
        let size = |problem: String| DemError::Size {
            file: file.into(),
            cols: cols as u64,
            rows: rows as u64,
            problem,
        };
        if cols == 0 || rows == 0 {
            return Err(size("a raster needs at least one cell".into()));
        }
        if (cols as u64).saturating_mul(rows as u64) > MAX_CELLS {
            return Err(size(format!("more than the {MAX_CELLS} cells a raster may have")));
        }
        if z.len() != cols * rows {
            return Err(size(format!("but {} heights are given", z.len())));
        }
        if !(cell.is_finite() && cell > 0.0) {
            return Err(DemError::Line {
                file: file.into(),
                problem: format!("cell size {cell} is not a positive length"),
            });
        }
        if !(west.is_finite() && north.is_finite()) {
            return Err(DemError::Line {
                file: file.into(),
                problem: format!("corner ({west}, {north}) is not a finite map point"),
            });
        }
        Ok(Self {
            crs: Crs::default(),
            file: file.into(),
            cols,
            rows,
            cell,
            west,
            north,
            z,
            nodata,
        })
    }

    /// the raster, refused at its first cell whose height is beyond [`MAX_HEIGHT`] in size: an
    /// undeclared fill value, refused where it is rather than later as a grid or a time step.
    /// The file readers apply it to heights and depths; a raster made in memory (a map of
    /// pressures in Pa) holds whatever it is given.
    pub fn plausible_heights(self) -> Result<Self, DemError> {
        let z = &self.z;
        let hole = |v: f64| !v.is_finite() || Some(v) == self.nodata;
        match z.iter().position(|&v| !hole(v) && v.abs() > MAX_HEIGHT) {
            None => Ok(self),
            Some(k) => Err(DemError::Implausible {
                file: self.file.clone(),
                row: k / self.cols,
                col: k % self.cols,
                z: z[k],
                max: MAX_HEIGHT,
            }),
        }
    }

    /// the coordinate reference system it came with (none for a raster made in memory).
    pub fn crs(&self) -> &Crs {
        &self.crs
    }

    /// the raster with `crs` as its coordinate reference system: what [`crate::geotiff::write`]
    /// and [`crate::ascii::write`] write with it (a map drawn on a DEM's frame takes the DEM's).
    pub fn with_crs(mut self, crs: Crs) -> Self {
        self.crs = crs;
        self
    }

    /// the file the raster came from.
    pub fn file(&self) -> &str {
        &self.file
    }

    /// (columns, rows).
    pub fn size(&self) -> [usize; 2] {
        [self.cols, self.rows]
    }

    /// the cells' side (m).
    pub fn cell(&self) -> f64 {
        self.cell
    }

    /// (western, southern, eastern, northern) edges of the raster (m).
    pub fn extent(&self) -> [f64; 4] {
        let c = self.cell;
        [self.west, self.north - self.rows as f64 * c, self.west + self.cols as f64 * c, self.north]
    }

    /// heights row by row from the north (holes included as stored).
    pub fn heights(&self) -> &[f64] {
        &self.z
    }

    /// the nodata value, if the raster declares one.
    pub fn nodata(&self) -> Option<f64> {
        self.nodata
    }

    /// the height stored for cell (row from the north, column from the west), `None` for a
    /// hole.
    pub fn at(&self, row: usize, col: usize) -> Option<f64> {
        if row >= self.rows || col >= self.cols {
            return None;
        }
        let v = self.z[row * self.cols + col];
        (v.is_finite() && Some(v) != self.nodata).then_some(v)
    }

    /// The ground height at map point (x, y): bilinear between the four nearest cell centres,
    /// so planes and z = a + bx + cy + dxy are reproduced exactly. Within half a cell of the
    /// raster's edge the height is the edge centres' (constant across that half cell). A point
    /// outside the raster, or one that needs a hole, is refused.
    pub fn height(&self, x: f64, y: f64) -> Result<f64, DemError> {
        let [x_min, y_min, x_max, y_max] = self.extent();
        let slack = 1e-9 * self.cell;
        if !(x >= x_min - slack && x <= x_max + slack && y >= y_min - slack && y <= y_max + slack) {
            return Err(DemError::Outside {
                file: self.file.clone(),
                x,
                y,
                x_min,
                x_max,
                y_min,
                y_max,
            });
        }
        // continuous (column, row) of the point among the cell centres
        let u = ((x - self.west) / self.cell - 0.5).clamp(0.0, (self.cols - 1) as f64);
        let v = ((self.north - y) / self.cell - 0.5).clamp(0.0, (self.rows - 1) as f64);
        let (c0, fu) = split(u, self.cols);
        let (r0, fv) = split(v, self.rows);
        let mut h = 0.0;
        for (dr, wr) in [(0, 1.0 - fv), (1, fv)] {
            for (dc, wc) in [(0, 1.0 - fu), (1, fu)] {
                let w = wr * wc;
                if w == 0.0 {
                    continue;
                }
                let (row, col) = (r0 + dr, c0 + dc);
                let z = self.at(row, col).ok_or_else(|| DemError::Nodata {
                    file: self.file.clone(),
                    row,
                    col,
                    x,
                    y,
                })?;
                h += w * z;
            }
        }
        Ok(h)
    }

    /// The section along the straight line from map point `from` to `to`: stations at
    /// 0, `spacing`, 2 `spacing`, … and at the line's end (the last interval may be shorter),
    /// each with its bilinear height.
    pub fn section(
        &self,
        from: [f64; 2],
        to: [f64; 2],
        spacing: f64,
    ) -> Result<Vec<Station>, DemError> {
        let line = |problem: String| DemError::Line { file: self.file.clone(), problem };
        if !from.iter().chain(&to).all(|v| v.is_finite()) {
            return Err(line(format!("the line {from:?} → {to:?} is not finite")));
        }
        if !(spacing.is_finite() && spacing > 0.0) {
            return Err(line(format!("station spacing {spacing} is not a positive length")));
        }
        let (dx, dy) = (to[0] - from[0], to[1] - from[1]);
        let length = dx.hypot(dy);
        if length == 0.0 {
            return Err(line(format!("the line starts and ends at {from:?}")));
        }
        let intervals = (length / spacing * (1.0 - 1e-12)).ceil();
        if intervals >= MAX_STATIONS as f64 {
            return Err(line(format!(
                "{length} m at {spacing} m spacing is more than {MAX_STATIONS} stations \
                 (is the spacing in metres?)"
            )));
        }
        let n = intervals as usize;
        let mut out = Vec::with_capacity(n + 1);
        for k in 0..=n {
            let s = if k == n { length } else { k as f64 * spacing };
            let t = s / length;
            let (x, y) = (from[0] + t * dx, from[1] + t * dy);
            out.push(Station { station: s, x, y, z: self.height(x, y)? });
        }
        Ok(out)
    }
}

/// the lower centre index and the fraction towards the next along an axis of `n` centres.
fn split(u: f64, n: usize) -> (usize, f64) {
    if n == 1 {
        return (0, 0.0);
    }
    let i = (u.floor() as usize).min(n - 2);
    (i, u - i as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// z = 3 + 0.2 x − 0.1 y + 0.01 x y on 4 × 3 cells of 2 m, north-west corner (10, 20).
    fn saddle() -> Raster {
        let f = |x: f64, y: f64| 3.0 + 0.2 * x - 0.1 * y + 0.01 * x * y;
        let (cols, rows, cell, west, north) = (4, 3, 2.0, 10.0, 20.0);
        let mut z = Vec::new();
        for r in 0..rows {
            for c in 0..cols {
                z.push(f(west + (c as f64 + 0.5) * cell, north - (r as f64 + 0.5) * cell));
            }
        }
        Raster::new("saddle", [cols, rows], cell, [west, north], z, None).unwrap()
    }

    #[test]
    fn bilinear_heights_reproduce_a_bilinear_surface_between_centres() {
        let r = saddle();
        let f = |x: f64, y: f64| 3.0 + 0.2 * x - 0.1 * y + 0.01 * x * y;
        for (x, y) in [(11.0, 19.0), (12.3, 16.7), (16.9, 15.1), (14.0, 17.0)] {
            // rounding of a few products of O(10) numbers
            assert!((r.height(x, y).unwrap() - f(x, y)).abs() < 1e-12, "({x}, {y})");
        }
    }

    #[test]
    fn the_outer_half_cell_takes_the_edge_centres_height_and_beyond_is_refused() {
        let r = saddle();
        assert_eq!(r.height(10.0, 19.0).unwrap(), r.height(11.0, 19.0).unwrap());
        assert!(matches!(r.height(9.9, 19.0), Err(DemError::Outside { .. })));
        assert!(matches!(r.height(12.0, 13.9), Err(DemError::Outside { .. })));
    }

    #[test]
    fn a_hole_is_refused_only_where_it_is_needed() {
        let mut r = saddle();
        r.z[4 + 2] = -9999.0; // row 1 (of 4 columns), column 2: centre (15, 17)
        r.nodata = Some(-9999.0);
        assert!(r.height(11.0, 19.0).is_ok());
        let e = r.height(15.5, 17.5).unwrap_err();
        assert!(matches!(e, DemError::Nodata { row: 1, col: 2, .. }), "{e}");
    }

    #[test]
    fn a_section_has_stations_at_the_spacing_and_at_its_end() {
        let r = saddle();
        let s = r.section([10.5, 19.0], [17.5, 19.0], 2.0).unwrap();
        let stations: Vec<f64> = s.iter().map(|p| p.station).collect();
        assert_eq!(stations, vec![0.0, 2.0, 4.0, 6.0, 7.0]);
        assert!(matches!(r.section([11.0, 19.0], [11.0, 19.0], 1.0), Err(DemError::Line { .. })));
        assert!(matches!(r.section([11.0, 19.0], [12.0, 19.0], 0.0), Err(DemError::Line { .. })));
        assert!(matches!(r.section([11.0, 19.0], [12.0, 19.0], 1e-9), Err(DemError::Line { .. })));
    }
}
