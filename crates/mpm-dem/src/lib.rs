//! Digital elevation models (DEMs) for slope runout scenes: read a raster of ground heights,
//! interpolate it, and cut the vertical section along a line that a 2D plane-strain analysis
//! runs on.
//!
//! - [`Raster`] is a north-up grid of square cells holding one height per cell (at the cell's
//!   centre), with an optional nodata value. [`Raster::read`] reads an ESRI ASCII grid (`.asc`,
//!   [`ascii`]) or a GeoTIFF elevation raster (`.tif`/`.tiff`, [`geotiff`], pure Rust through
//!   the `tiff` crate: no GDAL).
//! - [`Raster::height`] interpolates bilinearly between cell centres; [`Raster::section`]
//!   samples the heights along a straight line between two map points at a station spacing
//!   (the terrain grid's column width), giving [`Station`]s `(station, x, y, z)`.
//!
//! Every refusal is a [`DemError`] that names the file and, for the data, the line (ASCII) or
//! the cell (row, column); a raster's declared size is checked against what its file can hold
//! (uncompressed: the file's length; compressed: at most 1024× it, and at most 2²⁸ cells)
//! before anything of that size is allocated.
//!
//! Units: map coordinates and heights in metres (a raster in degrees of longitude and latitude
//! has no square cells on the ground; it is refused unless its cells are declared square).
//!
//! ```
//! use mpm_dem::Raster;
//!
//! // a 3 × 2 raster of the plane z = 100 + 0.5 x, 10 m cells, south-west corner at (0, 0)
//! let text = "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 10\n\
//!             102.5 107.5 112.5\n102.5 107.5 112.5\n";
//! let dem = Raster::parse_ascii(text, "plane.asc").unwrap();
//! let s = dem.section([5.0, 5.0], [25.0, 5.0], 10.0).unwrap();
//! assert_eq!(s.len(), 3);
//! assert!((s[1].z - 107.5).abs() < 1e-12 && s[1].station == 10.0);
//! ```

pub mod ascii;
mod error;
pub mod geotiff;
mod limits;
mod raster;
mod read;

pub use error::DemError;
pub use limits::Budget;
pub use raster::{Crs, MAX_CELLS, MAX_HEIGHT, Raster, Station};
