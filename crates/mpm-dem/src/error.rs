//! What can go wrong with a raster: each variant names the file and where in it.

/// A raster that cannot be read or used. `file` is the path as given.
#[derive(Debug, thiserror::Error)]
pub enum DemError {
    /// The file cannot be opened or read.
    #[error("{file}: cannot read the raster: {source}")]
    Io {
        /// the raster's path.
        file: String,
        /// the operating system's error.
        source: std::io::Error,
    },
    /// The file's name does not say which format it is.
    #[error(
        "{file}: unknown raster format (expected an ESRI ASCII grid `.asc` or a GeoTIFF `.tif`/`.tiff`)"
    )]
    UnknownFormat {
        /// the raster's path.
        file: String,
    },
    /// A header line of an ASCII grid is missing, repeated or malformed.
    #[error("{file}, line {line}: {problem}")]
    Header {
        /// the raster's path.
        file: String,
        /// 1-based line.
        line: usize,
        /// what is wrong and what was expected.
        problem: String,
    },
    /// A height value is not a number, or the values stop before the declared size.
    #[error("{file}, line {line}: {problem}")]
    Data {
        /// the raster's path.
        file: String,
        /// 1-based line.
        line: usize,
        /// what is wrong.
        problem: String,
    },
    /// The declared size cannot be right: larger than the file can hold or than [`MAX_CELLS`].
    ///
    /// [`MAX_CELLS`]: crate::MAX_CELLS
    #[error("{file}: declares {cols} × {rows} cells, {problem}")]
    Size {
        /// the raster's path.
        file: String,
        /// declared columns.
        cols: u64,
        /// declared rows.
        rows: u64,
        /// why that size is refused.
        problem: String,
    },
    /// The cells are not square on the ground (`dx ≠ dy`), e.g. a raster in degrees.
    #[error(
        "{file}: cells of {dx} × {dy} are not square; reproject the raster to a metric projection with square cells (e.g. UTM)"
    )]
    NonSquareCells {
        /// the raster's path.
        file: String,
        /// cell size along x (east).
        dx: f64,
        /// cell size along y (north).
        dy: f64,
    },
    /// A raster in geographic coordinates (longitude and latitude in degrees): the solver
    /// takes map coordinates and heights in metres.
    #[error(
        "{file}: {evidence}: its map coordinates are degrees of longitude and latitude, but heights, stations and cells are taken in metres; reproject it to a projected CRS in metres (e.g. its UTM zone: `gdalwarp -t_srs EPSG:326NN {file} out.tif`)"
    )]
    Geographic {
        /// the raster's path.
        file: String,
        /// what shows it (the GeoTIFF's model type, the `.prj` file, the extent).
        evidence: String,
    },
    /// A GeoTIFF that cannot be decoded, or whose georeferencing is missing or unsupported.
    #[error("{file}: {problem}")]
    GeoTiff {
        /// the raster's path.
        file: String,
        /// what is wrong.
        problem: String,
    },
    /// A height beyond [`MAX_HEIGHT`] in size: no terrain, deposit or rupture is that high or that
    /// deep; it is the fill value of a hole that the file did not declare as its nodata.
    ///
    /// [`MAX_HEIGHT`]: crate::MAX_HEIGHT
    #[error(
        "{file}: cell (row {row}, column {col}) holds {z:e} m, beyond ±{max} m of any terrain: the fill value of a hole? Declare it as the raster's nodata (`NODATA_value {z:e}` in an ASCII grid's header, GDAL_NODATA in a GeoTIFF: `gdal_edit.py -a_nodata`) or fill the hole"
    )]
    Implausible {
        /// the raster's path.
        file: String,
        /// 0-based row, counted from the north (the file's first row).
        row: usize,
        /// 0-based column, counted from the west.
        col: usize,
        /// the height it holds (m).
        z: f64,
        /// [`crate::MAX_HEIGHT`].
        max: f64,
    },
    /// The section needs a cell that holds nodata.
    #[error(
        "{file}: cell (row {row}, column {col}) holds nodata and is needed for the height at ({x}, {y}); fill the hole or move the line"
    )]
    Nodata {
        /// the raster's path.
        file: String,
        /// 0-based row, counted from the north (the file's first row).
        row: usize,
        /// 0-based column, counted from the west.
        col: usize,
        /// map x of the point asked for.
        x: f64,
        /// map y of the point asked for.
        y: f64,
    },
    /// A point of the section lies outside the raster.
    #[error(
        "{file}: the point ({x}, {y}) is outside the raster, which covers x ∈ [{x_min}, {x_max}], y ∈ [{y_min}, {y_max}]"
    )]
    Outside {
        /// the raster's path.
        file: String,
        /// map x of the point.
        x: f64,
        /// map y of the point.
        y: f64,
        /// western edge.
        x_min: f64,
        /// eastern edge.
        x_max: f64,
        /// southern edge.
        y_min: f64,
        /// northern edge.
        y_max: f64,
    },
    /// The section's line or spacing is unusable.
    #[error("{file}: {problem}")]
    Line {
        /// the raster's path.
        file: String,
        /// what is wrong.
        problem: String,
    },
}
