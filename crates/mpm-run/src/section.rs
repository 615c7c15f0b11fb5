//! `section`: a DEM's heights along a straight line in plan, as the CSV a 2D scene's terrain
//! profile reads (`mpm section`).

use std::path::Path;

use crate::error::RunError;

/// A DEM's section ([`section`]): its CSV text and what it spans.
#[derive(Clone, Debug, PartialEq)]
pub struct Section {
    /// the CSV: a header line, then one row per station (station, map x, map y, height).
    pub csv: String,
    /// how many stations.
    pub stations: usize,
    /// the last station's distance from the start (m).
    pub length: f64,
    /// the lowest and highest heights along the line (m).
    pub heights: (f64, f64),
}

/// the heights of the DEM `dem` (ESRI ASCII or GeoTIFF) from map point `from` to `to`, every
/// `spacing` metres (the DEM's cell by default); the DEM is read within the memory this
/// machine has. A DEM that cannot be read, or a line off it, is an [`RunError::Arguments`]
/// naming the cause.
pub fn section(
    dem: &Path,
    from: [f64; 2],
    to: [f64; 2],
    spacing: Option<f64>,
) -> Result<Section, RunError> {
    let stations = mpm_dem::Raster::read_within(dem, crate::limits::available_memory())
        .and_then(|r| r.section(from, to, spacing.unwrap_or(r.cell())))
        .map_err(|e| RunError::Arguments(e.to_string()))?;
    let mut csv = mpm_output::csv::SECTION_HEADER.to_string();
    mpm_output::csv::section(&mut csv, &stations);
    let heights = stations
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.z), b.max(p.z)));
    Ok(Section {
        csv,
        stations: stations.len(),
        length: stations.last().map_or(0.0, |p| p.station),
        heights,
    })
}
